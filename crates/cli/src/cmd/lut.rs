//! `skinkit lut`: build a pre-integrated skin table (Penner and Borshukov 2011) and write it as a
//! float RGB EXR whose header carries its definitions (`skinkit_render::skin::lut_file`).
//!
//! `lut diffuse` is the falloff `D(N.L, 1/r)` of equation 1.1, `lut shadow` the shadow-scattering
//! table `P_S(s, w)` of section 1.6. Both print the definitions they used (the same text the file's
//! attributes hold) and write the file atomically.

use skinkit_maps::format::ImageFormat;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use serde::Serialize;
use skinkit_render::skin::lut::{self, DiffuseLut, DiffuseLutSpec, SpecError};
use skinkit_render::skin::lut_file::{self, LutAttribute};
use skinkit_render::skin::profile::{Domain, Normalisation};
use skinkit_render::skin::shadow::{ShadowLut, ShadowLutSpec};

use crate::flags;
use crate::output::Output;

#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// The diffuse falloff D(N.L, 1/r) of equation 1.1: x = N.L, y = curvature 1/r in 1/mm.
    Diffuse(DiffuseArgs),
    /// The shadow-scattering table P_S(s, w) of section 1.6: x = shadow value, y = penumbra width.
    Shadow(ShadowArgs),
}

/// The ring integral's angular range.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum Integrate {
    /// Over a sphere's surface: keeps the profile's weights (the renderer's default).
    Sphere,
    /// The ring over [-pi, pi]: the paper's equation (the spherical-harmonic form's).
    Full,
    /// [-pi/2, pi/2]: the paper's listing.
    Half,
}

/// How each Gaussian of the diffusion profile is normalised.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum ProfileNormalisation {
    /// 1 / (2 pi v): the radial 2-D Gaussian (d'Eon and Luebke).
    #[value(name = "2d")]
    TwoD,
    /// 1 / sqrt(2 pi v') with v' = 1.414 v: the paper's listing.
    #[value(name = "1d")]
    OneD,
}

#[derive(clap::Args, Debug)]
pub struct DiffuseArgs {
    /// The table to write (.exr, float RGB).
    #[arg(long, value_name = "EXR")]
    pub out: PathBuf,
    /// Columns x rows (at most 4096 each).
    #[arg(long, value_parser = flags::size_at_most(lut::MAX_SIDE as usize), default_value = "256x256", value_name = "WxH")]
    pub size: (usize, usize),
    /// What the profile is integrated over: a sphere, or the paper's ring.
    #[arg(long, value_enum, default_value = "sphere")]
    pub integrate: Integrate,
    /// Normalisation of the profile's Gaussians.
    #[arg(long, value_enum, default_value = "2d")]
    pub normalisation: ProfileNormalisation,
    /// Curvature of the first (top) row, 1/mm.
    #[arg(long, default_value_t = 0.0, value_name = "F", value_parser = curvature)]
    pub inv_r_min: f32,
    /// Curvature of the last row, 1/mm (1 = a 1 mm radius; a head is about 0.01).
    #[arg(long, default_value_t = 1.0, value_name = "F", value_parser = curvature)]
    pub inv_r_max: f32,
}

#[derive(clap::Args, Debug)]
pub struct ShadowArgs {
    /// The table to write (.exr, float RGB).
    #[arg(long, value_name = "EXR")]
    pub out: PathBuf,
    /// Columns x rows (at most 4096 each).
    #[arg(long, value_parser = flags::size_at_most(lut::MAX_SIDE as usize), default_value = "256x256", value_name = "WxH")]
    pub size: (usize, usize),
    /// Penumbra width of the first (top) row, mm (0 to 1000).
    #[arg(long, value_parser = flags::penumbra_mm, default_value_t = ShadowLutSpec::default().w_min_mm, value_name = "MM")]
    pub w_min_mm: f32,
    /// Penumbra width of the last row, mm (0 to 1000).
    #[arg(long, value_parser = flags::penumbra_mm, default_value_t = ShadowLutSpec::default().w_max_mm, value_name = "MM")]
    pub w_max_mm: f32,
    /// Width of the new, sharper penumbra as a fraction of the shadow filter's, in (0, 1].
    #[arg(long, default_value_t = ShadowLutSpec::default().new_penumbra, value_name = "F", value_parser = flags::share)]
    pub new_penumbra: f32,
}

/// A curvature in 1/mm: from 0 (flat) to 1000 (a radius of one micrometre, far under a pore).
fn curvature(text: &str) -> Result<f32, String> {
    flags::number_in::<f32>(0.0, 1000.0, "a curvature in 1/mm")(text)
}

/// What `--json` prints.
#[derive(Serialize)]
struct LutReport {
    path: String,
    width: u32,
    height: u32,
    /// The file's `skinkit.*` attributes: the table's definitions.
    definitions: BTreeMap<String, serde_json::Value>,
    build_seconds: f64,
    write_seconds: f64,
}

pub fn run(command: Command, out: &Output) -> Result<i32> {
    match command {
        Command::Diffuse(args) => run_diffuse(args, out),
        Command::Shadow(args) => run_shadow(args, out),
    }
}

fn run_diffuse(args: DiffuseArgs, out: &Output) -> Result<i32> {
    check_extension(&args.out)?;
    let (width, height) = sides(args.size);
    let spec = DiffuseLutSpec {
        width,
        height,
        normalisation: match args.normalisation {
            ProfileNormalisation::TwoD => Normalisation::TwoD,
            ProfileNormalisation::OneD => Normalisation::OneD,
        },
        domain: match args.integrate {
            Integrate::Sphere => Domain::Sphere,
            Integrate::Full => Domain::Full,
            Integrate::Half => Domain::Half,
        },
        inv_r_min: args.inv_r_min,
        inv_r_max: args.inv_r_max,
    };
    spec.validate().map_err(flag_error)?;
    let started = Instant::now();
    let lut = DiffuseLut::build(&spec).map_err(build_error)?;
    let build_seconds = started.elapsed().as_secs_f64();
    let started = Instant::now();
    lut_file::write_diffuse(&args.out, &lut).context("cannot write the LUT")?;
    let attributes = lut_file::diffuse_attributes(&lut);
    report(out, &args.out, (width, height), &attributes, build_seconds, started.elapsed().as_secs_f64());
    Ok(0)
}

fn run_shadow(args: ShadowArgs, out: &Output) -> Result<i32> {
    check_extension(&args.out)?;
    let (width, height) = sides(args.size);
    let spec = ShadowLutSpec {
        width,
        height,
        w_min_mm: args.w_min_mm,
        w_max_mm: args.w_max_mm,
        new_penumbra: args.new_penumbra,
    };
    spec.validate().map_err(flag_error)?;
    let started = Instant::now();
    let lut = ShadowLut::build(&spec).map_err(build_error)?;
    let build_seconds = started.elapsed().as_secs_f64();
    let started = Instant::now();
    lut_file::write_shadow(&args.out, &lut).context("cannot write the LUT")?;
    let attributes = lut_file::shadow_attributes(&lut);
    report(out, &args.out, (width, height), &attributes, build_seconds, started.elapsed().as_secs_f64());
    Ok(0)
}

/// A table that validated but could not be built.
fn build_error(error: SpecError) -> anyhow::Error {
    anyhow::anyhow!("cannot build the table: {error}")
}

/// Sides as the spec holds them; anything beyond `u32` is refused by validation as too large.
fn sides((w, h): (usize, usize)) -> (u32, u32) {
    (u32::try_from(w).unwrap_or(u32::MAX), u32::try_from(h).unwrap_or(u32::MAX))
}

fn check_extension(path: &Path) -> Result<()> {
    if ImageFormat::of(path) != Some(ImageFormat::Exr) {
        return Err(crate::output::usage(format!("--out {}: tables are written as float .exr files", path.display())));
    }
    Ok(())
}

/// A spec error as the user's flag: `--size 0x256: ...`, `--inv-r-max ...`.
fn flag_error(error: SpecError) -> anyhow::Error {
    let flag = |name: &str| format!("--{}", name.replace('_', "-"));
    let prefix = match &error {
        SpecError::Size { width, height, .. } => format!("--size {width}x{height}"),
        SpecError::Bound { name, .. } | SpecError::Parameter { name, .. } => flag(name),
        SpecError::Inverted { min_name, max_name, .. } => format!("{} / {}", flag(min_name), flag(max_name)),
        _ => "invalid table".to_owned(),
    };
    crate::output::usage(format!("{prefix}: {error}"))
}

fn report(
    out: &Output,
    path: &Path,
    (width, height): (u32, u32),
    attributes: &BTreeMap<String, LutAttribute>,
    build_seconds: f64,
    write_seconds: f64,
) {
    let definitions = attributes
        .iter()
        .map(|(name, value)| {
            let value = match value {
                LutAttribute::Text(t) => serde_json::Value::from(t.as_str()),
                LutAttribute::F32(v) => serde_json::Value::from(f64::from(*v)),
            };
            (name.clone(), value)
        })
        .collect();
    let report =
        LutReport { path: path.display().to_string(), width, height, definitions, build_seconds, write_seconds };
    out.result(&report, || human(&report));
}

fn human(r: &LutReport) -> String {
    let mut text = format!(
        "wrote {} ({}x{}, built in {:.3} s, written in {:.3} s)",
        r.path, r.width, r.height, r.build_seconds, r.write_seconds
    );
    for (name, value) in &r.definitions {
        let value = match value {
            serde_json::Value::String(s) => s.clone(),
            other => other.to_string(),
        };
        text.push_str(&format!("\n  {name}: {value}"));
    }
    text
}
