//! The demo's renders of the sample face map (Haro et al. 2001, section 6):
//!
//! - figure 7 (`super::figure7`): the sample head's face (`skinkit_render::head`), close, with and
//!   without the fine-scale normal map, same light and camera, side by side, with what the
//!   specular lobes add to its highlights;
//! - figure 8: one patch of the map on a flat square under four light directions (azimuths 0, 90,
//!   180 and 270 degrees at 15 degrees elevation, where the fine structure shows), in a 2 x 2 grid.
//! - the skin figure (issue 6): the head wearing the map, close on the subject's right of the nose
//!   (about 60 mm across), where a key light from the left front casts the nose's hard shadow
//!   across the cheek and the upper lip: where scattering shows (the red fringe of the shadow's
//!   edge, pores softened in the light). Drawn with every diffuse method in a 3 x 2 grid:
//!   Lambert, the blog's closed form, our fit (top row); the pre-integrated LUT, texture-space
//!   diffusion, the exact texture-space reference at 1024 texels (bottom row; at 512 its texels
//!   were 0.5 mm on the face, 2.5 pixels here, and its own blocky shadow edge was most of every
//!   method's error). Each method's FLIP mean against the reference is in the report.
//!
//! Every render goes through scene files written next to the images and the same code as
//! `skinkit render`, so `skinkit render demo-out/render/head-skin.toml` redraws a figure.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use glam::{Vec2, Vec3};
use serde::Serialize;
use skinkit_maps::io::{self, Limits, PngLayout};
use skinkit_maps::{Channels, Samples};
use skinkit_render::head;
use skinkit_render::label::{RgbImage, draw_label};
use skinkit_render::mesh::Mesh;
use skinkit_render::renderer::Renderer;

use super::figure7::{Figure7, figure7};
use super::round_trip::{RoundTripFigure, round_trip};
use crate::output::Output;
use crate::render_job::{Job, RenderReport, render};

/// Side of each figure panel, pixels.
pub const PANEL: usize = 768;

/// Elevation of figure 8's lights above the patch, degrees.
pub const PATCH_ELEVATION_DEG: f32 = 15.0;

/// Azimuths of figure 8's four lights, degrees.
const AZIMUTHS_DEG: [f32; 4] = [0.0, 90.0, 180.0, 270.0];

/// What the figures cost and where they are.
#[derive(Serialize)]
pub struct FiguresReport {
    pub figure7: Figure7,
    pub figure8: String,
    pub skin: SkinFigure,
    /// Figure 7's close-up lit from the face height's own normals (when the face has a height).
    pub height_round_trip: Option<RoundTripFigure>,
    pub renders: Vec<RenderReport>,
}

/// The skin figure and each method's error against the reference.
#[derive(Serialize)]
pub struct SkinFigure {
    pub image: String,
    pub methods: Vec<SkinPanel>,
}

/// One method of the skin figure.
#[derive(Serialize)]
pub struct SkinPanel {
    pub method: String,
    pub image: String,
    /// FLIP mean against the reference panel (0 for the reference itself).
    pub flip_mean: f32,
    pub render_seconds: f64,
}

/// The methods of the skin figure: name, effects, extra tables, whether it is the reference.
const SKIN_METHODS: [(&str, &str, &str, bool); 6] = [
    ("lambert", r#"["shadows"]"#, "", false),
    (
        "blog-fit",
        r#"["preintegrated-analytic", "shadows", "shadow-scattering"]"#,
        "[preintegrated]\nanalytic = \"blog\"\n",
        false,
    ),
    (
        "own-fit",
        r#"["preintegrated-analytic", "shadows", "shadow-scattering"]"#,
        "[preintegrated]\nanalytic = \"own\"\n",
        false,
    ),
    ("lut-256", r#"["preintegrated", "shadows", "shadow-scattering"]"#, "", false),
    ("tsd-1x1024", r#"["tsd", "shadows"]"#, "[tsd]\npasses = 1\nsize = 1024\n", false),
    ("reference-1024", r#"["shadows"]"#, "", true),
];

/// Side of the reference's light map in the skin figure.
pub const REFERENCE_TEXELS: u32 = 1024;

/// The skin figure's scene: the head wearing `normal_map`, a warm key light from the left front
/// casting the nose's shadow onto the cheek, a dim fill, `effects` and `tables`.
fn skin_scene(normal_map: &str, effects: &str, tables: &str) -> String {
    format!(
        r#"# Written by `skinkit demo`: the sample head for the skin scattering figure (issue 6).
mesh = "head.obj"
mm_per_unit = 1.0
albedo = [0.80, 0.56, 0.46]
effects = {effects}

[brdf]
diffuse = [1.0, 1.0, 1.0]

[normal_map]
path = "{normal_map}"

[[light]]
kind = "directional"
direction = [0.75, 0.35, 0.55]
colour = [1.0, 0.95, 0.9]
intensity = 5.0
shadows = true

[[light]]
kind = "directional"
direction = [-0.5, 0.2, 0.85]
intensity = 0.4

[[camera]]
position = [-80.0, -15.0, 230.0]
target = [-18.0, -32.0, 30.0]
fov_deg = 15.0

{tables}
[output]
size = [{PANEL}, {PANEL}]
"#
    )
}

/// Patch scene text: the map's patch on a flat square lit from `azimuth_deg` at 30 degrees.
fn patch_scene(normal_map: &str, azimuth_deg: f32) -> String {
    let (elevation, azimuth) = (PATCH_ELEVATION_DEG.to_radians(), azimuth_deg.to_radians());
    let d = Vec3::new(elevation.cos() * azimuth.cos(), elevation.cos() * azimuth.sin(), elevation.sin());
    format!(
        r#"# Written by `skinkit demo`: one patch of the face map under a light at azimuth {azimuth_deg} deg,
# elevation {PATCH_ELEVATION_DEG} deg (figure 8 of Haro et al. 2001).
mesh = "patch.obj"
mm_per_unit = 1.0

[normal_map]
path = "{normal_map}"

[[light]]
kind = "directional"
direction = [{:.6}, {:.6}, {:.6}]
intensity = 10.0

[[camera]]
position = [0.0, 0.0, 60.0]
target = [0.0, 0.0, 0.0]
fov_deg = 20.0

[output]
size = [{PANEL}, {PANEL}]
"#,
        d.x, d.y, d.z
    )
}

/// A flat square of `side` mm in the z = 0 plane facing +z, whose UVs cover `[u0, u1] x [v0, v1]`
/// of the map.
fn patch(side: f32, u: [f32; 2], v: [f32; 2]) -> Mesh {
    let h = side / 2.0;
    Mesh {
        positions: vec![Vec3::new(-h, h, 0.0), Vec3::new(h, h, 0.0), Vec3::new(h, -h, 0.0), Vec3::new(-h, -h, 0.0)],
        normals: vec![Vec3::Z; 4],
        // v = 0 at the top of the image: the top edge of the square gets v0.
        uvs: vec![Vec2::new(u[0], v[0]), Vec2::new(u[1], v[0]), Vec2::new(u[1], v[1]), Vec2::new(u[0], v[1])],
        indices: vec![0, 3, 2, 0, 2, 1],
    }
}

pub fn write_text(path: &Path, text: &str) -> Result<()> {
    io::write_atomic(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(|error| skinkit_maps::Error::Io { path: path.to_owned(), error })
    })
    .context("cannot write the figure's scene")
}

/// Renders the figures of `normal_map` (the stitched face) into `dir`; with the face's texel size
/// in mm, also the round trip of its `height.exr` (beside `normal_map`).
pub fn figures(normal_map: &Path, mm_per_texel: Option<f64>, dir: &Path, out: &Output) -> Result<FiguresReport> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let map = std::path::absolute(normal_map).unwrap_or_else(|_| normal_map.to_owned());
    let map = map.to_string_lossy().replace('\\', "/");
    head::write_sample_head(&dir.join("head.obj"))?;
    // The middle of the forehead: 0.06 of the map's width and as many texels down (12 mm on the
    // sample layout's 0.05 mm texels).
    head::write_obj(&patch(20.0, [0.47, 0.53], [0.12, 0.24]), &dir.join("patch.obj"))?;

    // One device for every render of the figures: shaders and pipelines are built once.
    let renderer = Renderer::new()?;
    let mut renders = Vec::new();
    let mut job = |name: &str, text: String| -> Result<PathBuf> {
        let scene = dir.join(format!("{name}.toml"));
        write_text(&scene, &text)?;
        let image = dir.join(format!("{name}.png"));
        let job = Job { scene, out: Some(image.clone()), size: None, frames: None, reference: None };
        renders.push(render(&job, &renderer, out)?);
        Ok(image)
    };
    let lit: Vec<PathBuf> =
        AZIMUTHS_DEG.iter().map(|&a| job(&format!("patch-{a:03}"), patch_scene(&map, a))).collect::<Result<_>>()?;

    let figure7 = figure7(&map, dir, &renderer, out, &mut renders)?;
    let height_round_trip = match mm_per_texel {
        Some(mm) => {
            let (exr, skin) = (normal_map.with_file_name("height.exr"), dir.join("head-skin.png"));
            Some(round_trip(normal_map, &exr, mm, &skin, (dir, &renderer, out), &mut renders)?)
        }
        None => None,
    };
    let figure8 = dir.join("figure8.png");
    let lit: Vec<(PathBuf, String)> =
        lit.into_iter().zip(AZIMUTHS_DEG).map(|(p, a)| (p, format!("light azimuth {a} deg"))).collect();
    grid(&lit, 2, &figure8)?;

    let mut panels = Vec::new();
    for (name, effects, tables, reference) in SKIN_METHODS {
        let scene = dir.join(format!("skin-{name}.toml"));
        write_text(&scene, &skin_scene(&map, effects, tables))?;
        let image = dir.join(format!("skin-{name}.png"));
        let job = Job {
            scene,
            out: Some(image.clone()),
            size: None,
            frames: None,
            reference: reference.then_some(REFERENCE_TEXELS),
        };
        let report = render(&job, &renderer, out)?;
        let seconds = report.skin_seconds + report.images.iter().map(|i| i.render_seconds).sum::<f64>();
        renders.push(report);
        panels.push((name, image, seconds));
    }
    let skin = skin_figure(&panels, &dir.join("figure-skin.png"))?;
    Ok(FiguresReport { figure7, figure8: figure8.display().to_string(), skin, height_round_trip, renders })
}

/// The skin figure: the six panels in a 3 x 2 grid, each method's FLIP mean against the last.
/// An 8-bit RGB render as RGBA bytes (what FLIP takes) with its size.
pub fn rgba(path: &Path) -> Result<(u32, u32, Vec<u8>)> {
    let photo = io::read_photo(path, &Limits::default())?;
    let Samples::U8(s) = photo.samples() else { bail!("{}: expected an 8-bit render", path.display()) };
    let bytes = s.chunks_exact(3).flat_map(|px| [px[0], px[1], px[2], 255]).collect();
    Ok((photo.width() as u32, photo.height() as u32, bytes))
}

fn skin_figure(panels: &[(&str, PathBuf, f64)], path: &Path) -> Result<SkinFigure> {
    let (_, reference, _) = panels.last().expect("the reference is the last panel");
    let (w, h, reference) = rgba(reference)?;
    let methods = panels
        .iter()
        .map(|(name, image, seconds)| {
            let (_, _, test) = rgba(image)?;
            Ok(SkinPanel {
                method: name.to_string(),
                image: image.display().to_string(),
                flip_mean: skinkit_render::compare::flip_mean(&reference, &test, w, h),
                render_seconds: *seconds,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let images: Vec<(PathBuf, String)> = panels
        .iter()
        .zip(&methods)
        .enumerate()
        .map(|(i, ((name, p, _), m))| {
            let label = match i + 1 == panels.len() {
                true => format!("{name} (the reference)"),
                false => format!("{name}: FLIP {:.3}", m.flip_mean),
            };
            (p.clone(), label)
        })
        .collect();
    grid(&images, 3, path)?;
    Ok(SkinFigure { image: path.display().to_string(), methods })
}

/// Height of the panel labels, pixels.
const LABEL_PX: f32 = 26.0;

/// Tiles same-sized 8-bit RGB PNGs into `columns` columns, each with its label drawn into its
/// top-left corner.
pub fn grid(images: &[(PathBuf, String)], columns: usize, path: &Path) -> Result<()> {
    let photos = images.iter().map(|(p, _)| io::read_photo(p, &Limits::default())).collect::<Result<Vec<_>, _>>()?;
    let (w, h) = (photos[0].width(), photos[0].height());
    let rows = images.len().div_ceil(columns);
    let (gw, gh) = (w * columns, h * rows);
    let mut samples = vec![0u16; gw * gh * 3];
    for (i, photo) in photos.iter().enumerate() {
        let (Samples::U8(s), Channels::Rgb) = (photo.samples(), photo.channels()) else {
            bail!("{}: expected an 8-bit RGB render", images[i].0.display())
        };
        if (photo.width(), photo.height()) != (w, h) {
            bail!("{}: renders of one figure must share a size", images[i].0.display());
        }
        let mut panel = s.to_vec();
        let mut image = RgbImage { pixels: &mut panel, width: w, height: h };
        draw_label(&mut image, 0, 0, &images[i].1, LABEL_PX);
        let (x0, y0) = ((i % columns) * w, (i / columns) * h);
        for y in 0..h {
            for x in 0..w * 3 {
                samples[((y0 + y) * gw + x0) * 3 + x] = panel[y * w * 3 + x] as u16;
            }
        }
    }
    io::write_png(path, gw, gh, PngLayout::Rgb8, &samples).context("cannot write the figure")
}
