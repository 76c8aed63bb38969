//! `skinkit rig`: make rig files from public light formats or sphere photos, and check them.

use std::path::PathBuf;

use anyhow::{Context, Result};
use serde::Serialize;
use skinkit_capture::session;
use skinkit_capture::solve::SolveConfig;
use skinkit_capture::{Rig, import, sphere};
use skinkit_maps::io;

use crate::output::Output;

#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Convert a public light-calibration format into a rig file.
    Import(ImportArgs),
    /// Calibrate light directions (and intensities) from photos of a mirror (and matte) sphere.
    FromSphere(FromSphereArgs),
    /// Print a rig's lights and conditioning, and refuse a rig that cannot determine normals.
    Check(CheckArgs),
}

#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("source").required(true).args(["diligent", "uw"])))]
pub struct ImportArgs {
    /// A DiLiGenT object folder holding light_directions.txt and light_intensities.txt.
    #[arg(long, value_name = "DIR")]
    pub diligent: Option<PathBuf>,
    /// A UW/Seitz lights.txt (a count line, then one direction per line).
    #[arg(long, value_name = "LIGHTS_TXT")]
    pub uw: Option<PathBuf>,
    /// The rig file to write.
    #[arg(long, value_name = "RIG")]
    pub out: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct FromSphereArgs {
    /// Photos of a mirror (chrome) sphere, one per light, in rig order.
    #[arg(value_name = "PHOTO", required = true)]
    pub photos: Vec<PathBuf>,
    /// Photos of a matte sphere under the same lights (adds relative intensities).
    #[arg(long, value_name = "PHOTO", num_args = 1..)]
    pub matte: Vec<PathBuf>,
    /// The sphere's circle in pixels as `CX,CY,R` (found automatically when absent).
    #[arg(long, value_name = "CX,CY,R")]
    pub circle: Option<String>,
    /// The rig file to write.
    #[arg(long, value_name = "RIG")]
    pub out: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// The rig file to check.
    #[arg(value_name = "RIG")]
    pub rig: PathBuf,
    /// Largest condition number accepted, as `capture --max-condition` [default: 50].
    #[arg(long, value_name = "C", value_parser = crate::solve_flags::condition_limit)]
    pub max_condition: Option<f64>,
}

#[derive(Serialize)]
struct RigSummary {
    rig: String,
    lights: usize,
    condition_number: f64,
    noise_amplification: f64,
    warning: Option<String>,
    /// What capture will correct before solving (ambient subtraction, flat fields).
    corrections: Vec<String>,
}

pub fn run(command: Command, out: &Output) -> Result<i32> {
    match command {
        Command::Import(args) => import_rig(args, out),
        Command::FromSphere(args) => from_sphere(args, out),
        Command::Check(args) => {
            let rig = Rig::load(&args.rig)?;
            let defaults = SolveConfig::default();
            let config =
                SolveConfig { max_condition: args.max_condition.unwrap_or(defaults.max_condition), ..defaults };
            // The very check `capture` makes of a rig before decoding its photos.
            session::check_rig(&args.rig, &rig, None, &config)?;
            summarise(&rig, &args.rig, out)
        }
    }
}

fn import_rig(args: ImportArgs, out: &Output) -> Result<i32> {
    let inputs: Vec<(String, PathBuf)> = match (&args.diligent, &args.uw) {
        (Some(dir), _) => [import::DILIGENT_DIRECTIONS, import::DILIGENT_INTENSITIES, "filenames.txt"]
            .map(|f| ("a file of the DiLiGenT folder".to_owned(), dir.join(f)))
            .into(),
        (_, Some(path)) => vec![("the light file".to_owned(), path.clone())],
        _ => Vec::new(),
    };
    skinkit_maps::gate::output_files(&[("--out", args.out.as_path())], &inputs)?;
    let (rig, source) = match (&args.diligent, &args.uw) {
        (Some(dir), _) => (import::diligent(dir)?, dir),
        (_, Some(path)) => (import::uw_lights(path)?, path),
        _ => unreachable!("clap requires one source"),
    };
    // The check `capture` and `rig check` make (issue 42, D13): no rig is written that they refuse.
    session::check_rig(source, &rig, None, &SolveConfig::default())?;
    save(&rig, &args.out, out)
}

fn from_sphere(args: FromSphereArgs, out: &Output) -> Result<i32> {
    let photos = args.photos.iter().map(|p| ("a mirror-sphere photo".to_owned(), p.clone()));
    let inputs: Vec<_> =
        photos.chain(args.matte.iter().map(|p| ("a matte-sphere photo".to_owned(), p.clone()))).collect();
    skinkit_maps::gate::output_files(&[("--out", args.out.as_path())], &inputs)?;
    let limits = skinkit_maps::Limits::default();
    // The photo's role and place; the library's error names the file.
    let read = |paths: &[PathBuf], kind: &str| -> Result<Vec<_>> {
        let photos = paths.iter().enumerate();
        photos.map(|(i, p)| io::read_photo(p, &limits).with_context(|| format!("{kind} photo {}", i + 1))).collect()
    };
    let mirror = read(&args.photos, "mirror")?;
    let matte = read(&args.matte, "matte")?;
    let locate = match args.circle.as_deref() {
        Some(text) => sphere::Locate::Circle(parse_circle(text)?),
        None => sphere::Locate::Auto,
    };
    let calibration = if matte.is_empty() {
        sphere::mirror(&mirror, &locate)?
    } else {
        // The matte sphere sits elsewhere in its photos: always find it automatically.
        sphere::mirror_and_matte(&mirror, &locate, &matte, &sphere::Locate::Auto)?
    };
    for (i, light) in calibration.lights.iter().enumerate() {
        out.note(format!("light {}: {light:?}", i + 1));
    }
    save(&calibration.rig, &args.out, out)
}

fn parse_circle(text: &str) -> Result<sphere::Circle> {
    let v: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--circle `{text}`: expected three numbers CX,CY,R"))?;
    match v[..] {
        [cx, cy, radius] if radius > 0.0 => Ok(sphere::Circle { cx, cy, radius }),
        _ => anyhow::bail!("--circle `{text}`: expected CX,CY,R with R > 0"),
    }
}

fn save(rig: &Rig, path: &std::path::Path, out: &Output) -> Result<i32> {
    rig.save(path)?;
    summarise(rig, path, out)
}

fn summarise(rig: &Rig, path: &std::path::Path, out: &Output) -> Result<i32> {
    let c = rig.conditioning();
    let summary = RigSummary {
        rig: path.display().to_string(),
        lights: rig.light_count(),
        condition_number: c.condition_number,
        noise_amplification: c.noise_amplification,
        warning: c.warning(),
        corrections: session::corrections(rig, rig.ambient().is_some()),
    };
    if let Some(w) = &summary.warning {
        out.warn(w);
    }
    out.result(&summary, || {
        let corrections =
            if summary.corrections.is_empty() { "none".to_owned() } else { summary.corrections.join(", ") };
        format!(
            "{}: {} lights, condition number {:.3}, noise amplification {:.3}; corrections: {corrections}",
            summary.rig, summary.lights, summary.condition_number, summary.noise_amplification
        )
    });
    Ok(0)
}
