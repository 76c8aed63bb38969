//! A scene whose normal map is a set of UDIM tiles (`[normal_map] path = "normal.<UDIM>.png"`,
//! what `skinkit face` writes for a mesh over several tiles; issue 41). The tiles on disk are
//! joined into one atlas texture ([`skinkit_maps::udim::Atlas::join`], flat normals where the
//! atlas has no tile) and the mesh's UVs are carried into it ([`Atlas::to_atlas`], affine), so
//! the renderer, the texture-space passes and the glTF export see one map over `[0, 1]^2` and a
//! bilinear fetch across a tile boundary reads the two tiles' neighbouring texels.
//!
//! The frames are computed from the mesh's own UVs before they are carried: an affine map that
//! scales `u` and `v` keeps each tangent's direction.

use glam::{Vec2, Vec3};
use skinkit_maps::io::{self, Limits};
use skinkit_maps::udim::{self, Atlas};
use skinkit_maps::{Grid, NormalEncoding, NormalMap};

use crate::load::{LoadError, Result};
use crate::scene::{NormalMapSpec, Scene};

const FIELD: &str = "normal_map.path";

/// The tiles `spec.path` (a pattern with [`udim::TOKEN`]) names, joined into one map, and the
/// atlas they make.
///
/// # Errors
/// No tile on disk, an unreadable tile, or tiles of different sizes (each error names the
/// scene's field and the tile's file).
pub(crate) fn read_tiles(scene: &Scene, spec: &NormalMapSpec, limits: &Limits) -> Result<(NormalMap, Atlas)> {
    let map_error = |error| LoadError::Map { file: scene.name(), field: FIELD, error };
    let files = udim::find_tiles(&spec.path).map_err(map_error)?;
    if files.is_empty() {
        let hint = format!(
            " (no file matches it with a tile number from 1001 to 1999 for {}){}",
            udim::TOKEN,
            spec.made_by.as_deref().map(|m| format!("; make it first: {m}")).unwrap_or_default()
        );
        return Err(LoadError::Missing {
            file: scene.name(),
            field: FIELD,
            path: spec.path.display().to_string(),
            hint,
        });
    }
    let mut tiles: Vec<(u32, Grid<Vec3>)> = Vec::with_capacity(files.len());
    for (number, path) in &files {
        let grid =
            io::read_normal_map(path, NormalEncoding { green: spec.green }, limits).map_err(map_error)?.into_grid();
        let (first, first_size) = tiles.first().map_or((*number, grid.size()), |(n, g)| (*n, g.size()));
        if grid.size() != first_size {
            let reason = format!(
                "{}: UDIM tile {number} is {:?} texels but tile {first} is {first_size:?}; every tile must be one size",
                path.display(),
                grid.size(),
            );
            return Err(LoadError::Unsupported { file: scene.name(), field: FIELD.into(), reason });
        }
        tiles.push((*number, grid));
    }
    let (w, h) = tiles[0].1.size();
    let numbers: Vec<u32> = tiles.iter().map(|t| t.0).collect();
    let atlas = Atlas::of_tiles(&numbers, w, h).map_err(map_error)?;
    let joined = atlas.join(&tiles, Vec3::Z).map_err(map_error)?;
    Ok((NormalMap::from_grid(joined), atlas))
}

/// The mesh's UVs carried into `atlas`'s.
pub(crate) fn carry_uvs(uvs: &mut [Vec2], atlas: &Atlas) {
    for uv in uvs {
        let [u, v] = atlas.to_atlas([f64::from(uv.x), f64::from(uv.y)]);
        *uv = Vec2::new(u as f32, v as f32);
    }
}
