//! Mean angular error of each solver on a DiLiGenT object folder (photos, `filenames.txt`,
//! `light_directions.txt`, `light_intensities.txt`, `mask.png`, `normal_gt.png`), over the mask,
//! without detrending (the CLI's `--detrend-block 0`).
//!
//! ```text
//! cargo run --release -p skinkit-capture --example diligent_eval -- DIR [all|8|10|1,5,9,...]
//! ```
//!
//! `8` and `10` pick well-spread lights: the one nearest the camera axis, then repeatedly the
//! light farthest in angle from those picked (the indices are printed). The methods of
//! `solve::solve` run on the photos; the per-pixel robust estimators (the default, trimmed, and
//! the Cauchy and L1 reweightings) through `robust::fit_pixel` on the same readings (channels divided by the light's intensity, Rec. 709
//! luma; a pixel is saturated when a channel reaches 99.5 % of full scale). Times are wall
//! clock for the whole image, a rough guide: the criterion bench `solve` measures throughput.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use skinkit_capture::robust::{Estimator, Lights, RobustConfig, fit_pixel};
use skinkit_capture::solve::{Method, NoProgress, PhotoStack, SolveConfig, solve};
use skinkit_capture::{Rig, import};
use skinkit_maps::io::{read_normal_map, read_photo};
use skinkit_maps::{Grid, Limits, NormalEncoding, NormalMap, Photo, Samples};

const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

type Failure = Box<dyn std::error::Error>;

fn main() -> Result<(), Failure> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(dir) = args.first().map(PathBuf::from) else {
        return Err("usage: diligent_eval DIR [all|8|10|i,j,k,...]".into());
    };
    let object = Object::load(&dir)?;
    let picked = pick(&object.rig, args.get(1).map_or("all", |s| s.as_str()))?;
    let names: Vec<String> = picked.iter().map(|i| (i + 1).to_string()).collect();
    println!("{}: {} lights ({})", dir.display(), picked.len(), names.join(","));
    let methods = [
        ("least squares", Method::LeastSquares),
        ("threshold (old robust)", Method::Threshold),
        ("robust (solve)", Method::Robust),
    ];
    for (name, method) in methods {
        let (error, secs) = object.solve(&picked, method)?;
        println!("{name:>24}: {error:6.2} deg  {secs:6.3} s");
    }
    for (name, estimator) in
        [("trimmed", Estimator::Trimmed), ("trimmed + Cauchy IRLS", Estimator::Cauchy), ("L1 IRLS", Estimator::L1)]
    {
        let config = tuned(RobustConfig { estimator, ..RobustConfig::default() }, &args[2.min(args.len())..])?;
        let (error, secs) = object.fit(&picked, &config)?;
        println!("{name:>24}: {error:6.2} deg  {secs:6.3} s");
    }
    Ok(())
}

/// `config` with the `field=value` overrides of `args` (shadow_rel, trim_dark, trim_bright).
fn tuned(mut config: RobustConfig, args: &[String]) -> Result<RobustConfig, Failure> {
    for arg in args {
        let (field, value) = arg.split_once('=').ok_or("overrides are field=value")?;
        let value: f32 = value.parse()?;
        match field {
            "shadow_rel" => config.shadows.rel = value,
            "trim_dark" => config.trim_dark = value,
            "trim_bright" => config.trim_bright = value,
            other => return Err(format!("unknown field {other}").into()),
        }
    }
    config.validate()?;
    Ok(config)
}

/// A DiLiGenT object: photos in light order, the rig, the mask and the true normals.
struct Object {
    photos: Vec<Photo>,
    rig: Rig,
    mask: Grid<bool>,
    truth: NormalMap,
}

impl Object {
    fn load(dir: &Path) -> Result<Self, Failure> {
        let limits = Limits::default();
        let listing = std::fs::read_to_string(dir.join("filenames.txt"))?;
        let photos = listing
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| read_photo(&dir.join(l.trim()), &limits))
            .collect::<Result<Vec<_>, _>>()?;
        let rig = import::diligent(dir)?;
        let mask_photo = read_photo(&dir.join("mask.png"), &limits)?;
        let mask = Grid::from_vec(mask_photo.width(), mask_photo.height(), nonzero(&mask_photo))?;
        let truth = read_normal_map(&dir.join("normal_gt.png"), NormalEncoding::default(), &limits)?;
        Ok(Object { photos, rig, mask, truth })
    }

    /// Mean error and seconds of `solve::solve` with `method` from the `picked` lights.
    fn solve(&self, picked: &[usize], method: Method) -> Result<(f32, f64), Failure> {
        let photos = picked.iter().map(|&i| self.photos[i].clone()).collect();
        let names = picked.iter().map(|i| format!("{:03}.png", i + 1)).collect();
        let stack = PhotoStack::new(photos, names)?.with_mask(self.mask.clone())?;
        let lights = picked.iter().map(|&i| self.rig.lights()[i].clone()).collect();
        let rig = Rig::new(lights, "subset")?;
        let config = SolveConfig { method, ..SolveConfig::default() };
        let start = Instant::now();
        let solution = solve(&stack, &rig, &config, &NoProgress)?;
        let secs = start.elapsed().as_secs_f64();
        if let Some(floor) = solution.noise {
            println!(
                "{:>24}  noise sigma {:.5} (relative {:.5}), gate {:.4}",
                "", floor.sigma, floor.relative, floor.gate
            );
        }
        Ok((self.error(&solution.normals)?, secs))
    }

    /// Mean error and seconds of `robust::fit_pixel` over the mask from the `picked` lights.
    fn fit(&self, picked: &[usize], config: &RobustConfig) -> Result<(f32, f64), Failure> {
        let dirs: Vec<Vec3> = picked.iter().map(|&i| self.rig.lights()[i].direction()).collect();
        let lights = Lights::new(&dirs)?;
        let (w, h) = self.truth.size();
        let start = Instant::now();
        let normals: Vec<Vec3> = (0..w * h)
            .into_par_iter()
            .map(|p| {
                if !self.mask.as_slice()[p] {
                    return Vec3::ZERO;
                }
                let (r, sat) = self.readings(p, picked);
                fit_pixel(&r, &sat, &lights, config).normal
            })
            .collect();
        let secs = start.elapsed().as_secs_f64();
        let invalid = normals.iter().zip(self.mask.as_slice()).filter(|(n, m)| **m && **n == Vec3::ZERO).count();
        if invalid > 0 {
            eprintln!("  ({invalid} masked pixels invalid)");
        }
        let map = NormalMap::from_unit_grid(Grid::from_vec(w, h, normals)?)?;
        Ok((self.error(&map)?, secs))
    }

    /// Pixel `p`'s luma readings and saturation flags under the `picked` lights.
    fn readings(&self, p: usize, picked: &[usize]) -> (Vec<f32>, Vec<bool>) {
        picked
            .iter()
            .map(|&i| {
                let e = self.rig.lights()[i].intensity();
                let Samples::U16(s) = self.photos[i].samples() else {
                    panic!("DiLiGenT photos are 16-bit RGB");
                };
                let c = &s[3 * p..3 * p + 3];
                let v: f32 =
                    c.iter().zip(LUMA).zip([e.x, e.y, e.z]).map(|((&v, w), e)| w * v as f32 / 65535.0 / e).sum();
                (v, c.iter().any(|&v| v as f32 >= 0.995 * 65535.0))
            })
            .unzip()
    }

    fn error(&self, normals: &NormalMap) -> Result<f32, Failure> {
        Ok(normals.angular_error(&self.truth, Some(&self.mask))?.mean)
    }
}

fn nonzero(photo: &Photo) -> Vec<bool> {
    let step = photo.channels().count();
    match photo.samples() {
        Samples::U8(s) => s.iter().step_by(step).map(|&v| v > 0).collect(),
        Samples::U16(s) => s.iter().step_by(step).map(|&v| v > 0).collect(),
        Samples::F32(s) => s.iter().step_by(step).map(|&v| v > 0.0).collect(),
    }
}

/// The light indices `spec` names: `all`, a count picked well spread, or a 1-based list.
fn pick(rig: &Rig, spec: &str) -> Result<Vec<usize>, Failure> {
    let k = rig.lights().len();
    if spec == "all" {
        return Ok((0..k).collect());
    }
    if spec.contains(',') {
        return spec.split(',').map(|s| Ok(s.trim().parse::<usize>()? - 1)).collect();
    }
    let count: usize = spec.parse()?;
    let dirs = rig.directions();
    let first = (0..k).max_by(|&a, &b| dirs[a].z.total_cmp(&dirs[b].z)).ok_or("no lights")?;
    let mut picked = vec![first];
    while picked.len() < count.min(k) {
        let nearest = |i: usize| picked.iter().map(|&j| dirs[i].dot(dirs[j])).fold(f32::MIN, f32::max);
        let next = (0..k).filter(|i| !picked.contains(i)).min_by(|&a, &b| nearest(a).total_cmp(&nearest(b)));
        picked.push(next.ok_or("no lights left")?);
    }
    picked.sort_unstable();
    Ok(picked)
}
