//! `skinkit samples`: regenerates the bundled sample molds bit for bit.
//!
//! Each region (the paper's figures 2-3: forehead, forehead edge, nose, cheek) is a synthetic skin
//! heightfield from the `heightfield` crate, rendered under the paper's 8-light turntable rig as
//! 16-bit photos with cast shadows and mild sensor noise. A region folder is a capture session:
//! `rig.toml`, `01.png` .. `08.png`, and `truth.png` (the exact normals, 16-bit, green-up).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;
use skinkit_capture::Rig;
use skinkit_heightfield::{self as hf, SkinParams};
use skinkit_maps::io::{self, PngLayout};
use skinkit_maps::{NormalEncoding, Samples, Vec3};

use crate::output::Output;
use skinkit_maps::progress::Progress;

/// The sample regions and the heightfield preset each uses.
pub const REGIONS: &[&str] = &["forehead", "forehead-edge", "nose", "cheek"];

/// Elevation of the turntable lamp above the mold plane, in degrees (see calibration/turntable-8.toml).
pub const TURNTABLE_ELEVATION_DEG: f64 = 45.0;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Folder to write the region folders into.
    #[arg(long, default_value = "samples/molds", value_name = "DIR")]
    pub out: PathBuf,
    /// Side of each square sample in pixels.
    #[arg(long, default_value_t = 256, value_name = "PIXELS",
          value_parser = crate::flags::square_side(1, hf::params::MAX_TEXELS))]
    pub size: usize,
    /// Seed of the heightfields and the sensor noise.
    #[arg(long, default_value_t = 2001)]
    pub seed: u64,
    /// Also write the sample head (OBJ, millimetres, derived from MakeHuman's base mesh, UVs laid
    /// out like samples/face/layout.toml) to this file; `--head-only` skips the molds.
    #[arg(long, value_name = "FILE")]
    pub head: Option<PathBuf>,
    /// Write only the head (needs `--head`).
    #[arg(long, requires = "head")]
    pub head_only: bool,
}

#[derive(Serialize)]
struct Written {
    /// A mold region, or "head".
    region: String,
    /// The region's folder, or the head's OBJ file.
    folder: String,
    /// Pixels of a mold, vertices of the head.
    width: usize,
    /// Pixels of a mold, triangles of the head.
    height: usize,
}

/// The heightfield preset of a sample region.
pub fn preset(region: &str, size: usize, seed: u64) -> Result<SkinParams> {
    Ok(match region {
        "forehead" => SkinParams::forehead(size, size, seed),
        "forehead-edge" => SkinParams::forehead_edge(size, size, seed),
        "nose" => SkinParams::nose(size, size, seed),
        "cheek" => SkinParams::cheek(size, size, seed),
        other => anyhow::bail!("unknown sample region `{other}` (known: {})", REGIONS.join(", ")),
    })
}

/// How the samples are photographed: silicone-grey albedo, cast shadows, 0.2% sensor noise,
/// 16-bit quantisation.
fn render_config(seed: u64) -> hf::RenderConfig {
    hf::RenderConfig {
        albedo: hf::Albedo::Constant(Vec3::splat(0.8)),
        shadows: true,
        specular: None,
        ambient: Vec3::ZERO,
        noise_sigma: 0.002,
        exposure: 1.0,
        channels: skinkit_maps::Channels::Gray,
        format: hf::Quantise::U16,
        seed,
    }
}

/// Lights of a rig as the renderer wants them.
pub fn render_lights(rig: &Rig) -> Vec<hf::RenderLight> {
    rig.lights()
        .iter()
        .map(|l| hf::RenderLight { direction: l.direction(), intensity: l.intensity(), position: l.position() })
        .collect()
}

/// Renders one region into `dir`.
fn write_region(region: &str, dir: &Path, args: &Args, rig: &Rig) -> Result<()> {
    let region_index = REGIONS.iter().position(|r| *r == region).unwrap_or(0) as u64;
    let region_seed = args.seed ^ ((region_index + 1) * 0x9E37_79B9);
    let field = hf::generate(&preset(region, args.size, region_seed)?)?;
    let photos = hf::render(&field, &render_lights(rig), &render_config(region_seed))?;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    for (i, photo) in photos.iter().enumerate() {
        let Samples::U16(samples) = photo.samples() else { anyhow::bail!("renderer did not produce 16-bit samples") };
        io::write_png(
            &dir.join(format!("{:02}.png", i + 1)),
            photo.width(),
            photo.height(),
            PngLayout::Gray16,
            samples,
        )?;
    }
    io::write_normal_map(&dir.join("truth.png"), &field.normals, NormalEncoding::default(), 16)?;
    // The photo pixel is the field's texel: captures of the samples give heights in mm.
    let rig = rig.clone().with_mm_per_pixel(Some(field.mm_per_texel as f32), region)?;
    rig.save(&dir.join("rig.toml"))?;
    Ok(())
}

/// The paper's rig as the samples use it.
pub fn turntable() -> Rig {
    Rig::turntable(8, TURNTABLE_ELEVATION_DEG, 1.0).expect("8 lights at 45 degrees are a valid rig")
}

pub fn run(args: Args, out: &Output) -> Result<i32> {
    let rig = turntable();
    let mut written = Vec::new();
    if let Some(path) = &args.head {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        }
        let mesh = skinkit_render::head::sample_head();
        skinkit_render::head::write_sample_head(path)?;
        written.push(Written {
            region: "head".into(),
            folder: path.display().to_string(),
            width: mesh.positions.len(),
            height: mesh.indices.len() / 3,
        });
    }
    let regions = if args.head_only { &[][..] } else { REGIONS };
    let bar = out.progress(regions.len() as u64, "samples");
    for region in regions {
        let dir = args.out.join(region);
        write_region(region, &dir, &args, &rig)?;
        bar.advance(1);
        written.push(Written {
            region: region.to_string(),
            folder: dir.display().to_string(),
            width: args.size,
            height: args.size,
        });
    }
    bar.clear();
    out.result(&written, || {
        written.iter().map(|w| format!("{}: {}", w.region, w.folder)).collect::<Vec<_>>().join("\n")
    });
    Ok(0)
}
