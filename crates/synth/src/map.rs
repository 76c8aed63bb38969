//! A map to grow, in memory: normals or colours, read from and written to image files, grown
//! under a [`SynthConfig`] and replayed through a coordinate map.

use std::path::Path;

use skinkit_maps::io::{self, Limits};
use skinkit_maps::{Channels, ColorMap, Grid, NormalEncoding, NormalMap, Transfer, Vec3};

use crate::{Guards, Result, SynthConfig};

/// An exemplar, a source or an output: a normal map or a colour map (linear RGB).
#[derive(Clone, Debug)]
pub enum Map {
    Normal(NormalMap),
    Color(ColorMap),
}

/// What one synthesis gives, whatever the map's kind.
#[derive(Clone, Debug)]
pub struct Grown {
    /// The grown map, of the exemplar's kind.
    pub map: Map,
    /// For every output texel, the exemplar texel `[x, y]` it copies.
    pub coords: Grid<[u32; 2]>,
    /// What validation changed (clamped levels, sanitised texels).
    pub warnings: Vec<String>,
    /// Wall-clock seconds per level, `[0]` the finest.
    pub level_seconds: Vec<f64>,
    /// The guards' figures (collapse and histogram).
    pub guards: Guards,
}

impl Map {
    /// Reads a normal map stored with `encoding`.
    pub fn read_normals(path: &Path, encoding: NormalEncoding, limits: &Limits) -> Result<Map> {
        Ok(Map::Normal(io::read_normal_map(path, encoding, limits)?))
    }

    /// Reads a colour image as linear RGB through `transfer` (a grey image's value replicated).
    pub fn read_color(path: &Path, transfer: Transfer, limits: &Limits) -> Result<Map> {
        let photo = io::read_photo(path, limits)?.with_transfer(transfer);
        let rgb = photo.channels() == Channels::Rgb;
        let color = Grid::from_fn(photo.width(), photo.height(), |x, y| {
            let i = y * photo.width() + x;
            if rgb {
                Vec3::new(photo.linear(3 * i), photo.linear(3 * i + 1), photo.linear(3 * i + 2))
            } else {
                Vec3::splat(photo.linear(i))
            }
        });
        Ok(Map::Color(color))
    }

    /// Width and height in texels.
    pub fn size(&self) -> (usize, usize) {
        match self {
            Map::Normal(n) => n.size(),
            Map::Color(c) => c.size(),
        }
    }

    /// `normal` or `color`, as reports name the kind.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Map::Normal(_) => "normal",
            Map::Color(_) => "color",
        }
    }

    /// Texels that are the invalid marker (a normal map's zero normals); colour maps have none.
    pub fn invalid_texels(&self) -> usize {
        match self {
            Map::Normal(n) => n.as_slice().len() - n.valid_count(),
            Map::Color(_) => 0,
        }
    }

    /// Writes the map at 16 bits (PNG) or as float (EXR), normals with `encoding`.
    pub fn write(&self, path: &Path, encoding: NormalEncoding) -> skinkit_maps::Result<()> {
        match self {
            Map::Normal(n) => io::write_normal_map(path, n, encoding, 16),
            Map::Color(c) => io::write_color_map(path, c, 16),
        }
    }

    /// Grows this exemplar under `config`, telling `progress` as [`crate::synthesize`] does.
    pub fn grow(&self, config: &SynthConfig, progress: &dyn skinkit_maps::progress::Progress) -> Result<Grown> {
        Ok(match self {
            Map::Normal(n) => {
                let s = crate::synthesize_normals(n, config, progress)?;
                Grown {
                    map: Map::Normal(s.normals),
                    coords: s.coords,
                    warnings: s.warnings,
                    level_seconds: s.level_seconds,
                    guards: s.guards,
                }
            }
            Map::Color(c) => {
                let s = crate::synthesize(c, config, progress)?;
                Grown {
                    map: Map::Color(s.texels),
                    coords: s.coords,
                    warnings: s.warnings,
                    level_seconds: s.level_seconds,
                    guards: s.guards,
                }
            }
        })
    }

    /// This map (of an exemplar's size) laid out by `coords`, as [`crate::replay`].
    pub fn replay(&self, coords: &Grid<[u32; 2]>) -> Result<Map> {
        Ok(match self {
            Map::Normal(n) => Map::Normal(NormalMap::from_unit_grid(crate::replay(coords, n.grid())?)?),
            Map::Color(c) => Map::Color(crate::replay(coords, c)?),
        })
    }
}
