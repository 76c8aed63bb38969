//! The height's round trip in a render (issue 40): figure 7's close-up of the head drawn with the
//! face's normal map, with the normals of the face's integrated height (what a displacement or a
//! bump from `height.exr` shows), and with the normal map seen through the same central
//! differences; FLIP between them says how much of what a viewer sees the height keeps, and
//! the last pair isolates what no surface has (non-integrable texels) from the differencing.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;
use skinkit_height::compare::normals_of;
use skinkit_height::round_trip::as_central_differences;
use skinkit_maps::io::{self, Limits};
use skinkit_maps::{NormalEncoding, NormalMap, Vec3};
use skinkit_render::renderer::Renderer;

use super::figure7::face_scene;
use super::figures::{grid, rgba, write_text};
use crate::output::Output;
use crate::render_job::{Job, RenderReport, render};

/// What the round trip's renders show.
#[derive(Serialize)]
pub struct RoundTripFigure {
    pub image: String,
    /// FLIP mean of the render lit from the height's normals against the normal-mapped render.
    pub flip_height_vs_map: f32,
    /// FLIP mean of the same against the render of the map through central differences: the
    /// part only non-integrable texels make.
    pub flip_height_vs_differenced_map: f32,
    /// FLIP mean of the differenced map's render against the normal-mapped render: the part the
    /// differencing's [1 2 1] / 4 filter makes.
    pub flip_differenced_vs_map: f32,
}

/// Draws figure 7's close-up lit from the normals of `height_exr` (millimetres, `mm_per_texel`)
/// and from `map` through central differences, beside the normal-mapped `skin_render` already in
/// `dir`, and compares them.
pub fn round_trip(
    map: &Path,
    height_exr: &Path,
    mm_per_texel: f64,
    skin_render: &Path,
    (dir, renderer, out): (&Path, &Renderer, &Output),
    renders: &mut Vec<RenderReport>,
) -> Result<RoundTripFigure> {
    let limits = Limits::default();
    let normals = io::read_normal_map(map, NormalEncoding::default(), &limits).context("cannot read the normal map")?;
    let heights = io::read_exr_channel(height_exr, "Y", &limits).context("cannot read the height map")?;
    let mut from_height = normals_of(&heights, mm_per_texel as f32, false).into_grid();
    // Texels without a normal stay without one (the height there is the integrator's fill).
    for (n, &m) in from_height.as_mut_slice().iter_mut().zip(normals.as_slice()) {
        if m == Vec3::ZERO {
            *n = Vec3::ZERO;
        }
    }
    let mut draw = |name: &str, normals: &NormalMap| -> Result<PathBuf> {
        let file = dir.join(format!("{name}.png"));
        io::write_normal_map(&file, normals, NormalEncoding::default(), 16)
            .context("cannot write the round trip's normal map")?;
        let scene = dir.join(format!("head-{name}.toml"));
        write_text(&scene, &face_scene(Some(&file.to_string_lossy().replace('\\', "/")), true))?;
        let image = dir.join(format!("head-{name}.png"));
        let job = Job { scene, out: Some(image.clone()), size: None, frames: None, reference: None };
        renders.push(render(&job, renderer, out)?);
        Ok(image)
    };
    let height = draw("height-normals", &NormalMap::from_grid(from_height))?;
    let differenced = draw("differenced-normals", &as_central_differences(&normals, false))?;
    let (map_px, height_px, diff_px) = (rgba(skin_render)?, rgba(&height)?, rgba(&differenced)?);
    let flip =
        |a: &(u32, u32, Vec<u8>), b: &(u32, u32, Vec<u8>)| skinkit_render::compare::flip_mean(&a.2, &b.2, a.0, a.1);
    let figure = RoundTripFigure {
        image: dir.join("figure-height-round-trip.png").display().to_string(),
        flip_height_vs_map: flip(&map_px, &height_px),
        flip_height_vs_differenced_map: flip(&diff_px, &height_px),
        flip_differenced_vs_map: flip(&map_px, &diff_px),
    };
    let panels = [
        (skin_render.to_owned(), "the normal map".to_owned()),
        (height, format!("the height's normals: FLIP {:.3}", figure.flip_height_vs_map)),
    ];
    grid(&panels, 2, Path::new(&figure.image))?;
    Ok(figure)
}
