//! `skinkit height`: a normal map made anywhere (a capture, a baker, a sculpting tool) ->
//! height (displacement) in millimetres, with the 16-bit PNG, cavity and band files artists load.

use skinkit_maps::format::ImageFormat;
use std::path::PathBuf;

use anyhow::{Context, Result};
use serde::Serialize;
use skinkit_height::deliver::{self, ExrStorage, PngScale};
use skinkit_height::{HeightOptions, HeightReport, Integrator, Scale};
use skinkit_maps::{Limits, OutputSet, io};

use crate::flags;
use crate::flags::Green;
use crate::output::Output;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Normal map to integrate (PNG, TIFF or EXR; tangent or camera space, z toward the viewer).
    #[arg(value_name = "NORMAL_MAP")]
    pub map: PathBuf,
    /// Height output: `.exr` (float, one channel Y, in mm with --mm-per-texel) or `.png` (16-bit,
    /// midlevel 0.5, the scale in the report and the file).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Green channel convention of the normal map (`down` for DirectX / Unreal bakes).
    #[arg(long, value_enum, default_value_t = Green::Up)]
    pub green: Green,
    /// Size of a texel in millimetres; without it heights are in texel widths (and say so).
    #[arg(long, value_name = "MM", value_parser = flags::positive_mm)]
    pub mm_per_texel: Option<f64>,
    /// The map tiles (a grown map): integrate periodically, so the height tiles too.
    #[arg(long)]
    pub wrap: bool,
    /// Integrator; `auto` takes periodic with --wrap, masked when texels are invalid, else Neumann.
    #[arg(long, value_enum, default_value_t = IntegratorArg::Auto)]
    pub integrator: IntegratorArg,
    /// Also write the height as a 16-bit PNG at midlevel 0.5 (Blender's Displacement node:
    /// Midlevel 0.5, Scale as reported).
    #[arg(long, value_name = "FILE")]
    pub png: Option<PathBuf>,
    /// Also write the cavity map (16-bit PNG: 0.5 at the local surface, pores and furrows darker).
    #[arg(long, value_name = "FILE")]
    pub cavity: Option<PathBuf>,
    /// Also write three wavelength bands of the height as R, G, B of one float EXR (they sum to
    /// the height; the limits are in its header).
    #[arg(long, value_name = "FILE")]
    pub bands: Option<PathBuf>,
    /// ZIP-compress the EXR files (lossless).
    #[arg(long)]
    pub zip: bool,
    /// Store the EXR files as half floats.
    #[arg(long)]
    pub half: bool,
}

/// `--integrator` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum IntegratorArg {
    Auto,
    Periodic,
    Neumann,
    Masked,
}

impl IntegratorArg {
    fn chosen(self) -> Option<Integrator> {
        match self {
            IntegratorArg::Auto => None,
            IntegratorArg::Periodic => Some(Integrator::Periodic),
            IntegratorArg::Neumann => Some(Integrator::Neumann),
            IntegratorArg::Masked => Some(Integrator::Masked),
        }
    }
}

/// What `skinkit height` reports.
#[derive(Serialize)]
struct Report {
    map: String,
    out: String,
    width: usize,
    height: usize,
    #[serde(flatten)]
    result: HeightReport,
    /// How to load the 16-bit PNG (when one was written).
    png: Option<PngScale>,
    /// Seconds of the integration.
    seconds: f64,
}

pub fn run(args: Args, out: &Output) -> Result<i32> {
    let outputs = [
        ("--out", Some(&args.out)),
        ("--png", args.png.as_ref()),
        ("--cavity", args.cavity.as_ref()),
        ("--bands", args.bands.as_ref()),
    ];
    skinkit_maps::gate::output_files(
        &skinkit_maps::gate::given(&outputs),
        &[("the normal map".into(), args.map.clone())],
    )?;
    check_extensions(&args)?;
    let normals = io::read_normal_map(&args.map, args.green.encoding(), &Limits::default())?;
    let options = HeightOptions {
        wraps: args.wrap,
        integrator: args.integrator.chosen(),
        scale: Scale::from_mm(args.mm_per_texel)?,
        ..HeightOptions::default()
    };
    let context = || format!("cannot integrate {}", args.map.display());
    let height = skinkit_height::integrate(&normals, &options).with_context(context)?;
    let storage = ExrStorage { zip: args.zip, half: args.half };
    let mut set = OutputSet::files();
    let mut png = None;
    set.write_file(&args.out, |p| {
        deliver::write_height(p, &height, storage).map(|s| png = s).map_err(skinkit_maps::Error::from)
    })
    .context("cannot write the height map")?;
    if let Some(path) = &args.png {
        set.write_file(path, |p| {
            deliver::write_png16(p, &height).map(|s| png = Some(s)).map_err(skinkit_maps::Error::from)
        })
        .context("cannot write the height PNG")?;
    }
    if args.cavity.is_some() || args.bands.is_some() {
        let bands = deliver::bands(&height);
        if let Some(path) = &args.cavity {
            let cavity = deliver::cavity(&bands);
            set.write_file(path, |p| deliver::write_cavity_png(p, &cavity).map_err(skinkit_maps::Error::from))
                .context("cannot write the cavity map")?;
        }
        if let Some(path) = &args.bands {
            set.write_file(path, |p| {
                deliver::write_bands_exr(p, &height, &bands, storage).map_err(skinkit_maps::Error::from)
            })
            .context("cannot write the height bands")?;
        }
    }
    out.swept(&set.commit().context("cannot finish writing the height outputs")?);
    let (width, rows) = normals.size();
    let seconds = height.report.seconds;
    let report = Report {
        map: args.map.display().to_string(),
        out: args.out.display().to_string(),
        width,
        height: rows,
        result: height.report,
        png,
        seconds,
    };
    out.result(&report, || human(&report));
    Ok(0)
}

/// Refuses, before any work, outputs whose extension does not match what is written there.
fn check_extensions(args: &Args) -> Result<()> {
    use ImageFormat::{Exr, Png};
    let wanted = [
        ("--out", Some(&args.out), &[Exr, Png][..]),
        ("--png", args.png.as_ref(), &[Png][..]),
        ("--cavity", args.cavity.as_ref(), &[Png][..]),
        ("--bands", args.bands.as_ref(), &[Exr][..]),
    ];
    for (flag, path, allowed) in wanted {
        if let Some(path) = path
            && !ImageFormat::is_one_of(path, allowed)
        {
            let message = format!("{}: {flag} is written as {}", path.display(), ImageFormat::extensions(allowed));
            return Err(crate::output::usage(message));
        }
    }
    Ok(())
}

fn human(r: &Report) -> String {
    let h = &r.result;
    let mut s = format!(
        "{}: {}x{} integrated ({}) from {:.4} to {:.4} {} (RMS {:.4}), residual {:.4} of the RMS slope",
        r.out,
        r.width,
        r.height,
        h.integrator.name(),
        h.min,
        h.max,
        h.unit,
        h.rms,
        h.residual_relative
    );
    if h.texels.invalid() > 0 {
        s += &format!("; {} texels invalid, filled", h.texels.invalid());
    }
    if let Some(p) = &r.png {
        s += &format!("; PNG midlevel {} scale {} {}", p.midlevel, p.scale, p.unit);
    }
    s
}
