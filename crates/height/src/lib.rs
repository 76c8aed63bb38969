//! Height from normals: integrating a normal map into a displacement (height) map, and the height
//! deliverables artists load (float EXR in millimetres, 16-bit PNG at midlevel 0.5, cavity, bands).
//!
//! A normal `n` says the surface's slopes: `dh/dx = -nx/nz` along columns and, since image rows
//! grow downward while y points up, `dh/drow = +ny/nz` along rows (skinkit's frame, DESIGN.md).
//! Integration is a least-squares problem over the grid's edges: for neighbouring texels `a`, `b`
//! the height step `h_b - h_a` should equal the mean of their two slopes. Its normal equations are
//! the 5-point Poisson equation `L h = D^T g`, solved by one of three [`Integrator`]s:
//!
//! * [`Integrator::Periodic`]: edges wrap around, `L` is diagonal in the discrete Fourier basis
//!   (Frankot-Chellappa in its discrete, least-squares form). For maps that tile (a grown map is
//!   toroidal): the height tiles exactly. A mean slope, which no tiling height can have, is dropped.
//! * [`Integrator::Neumann`]: no edge crosses the border, `L` is diagonal in the DCT-II basis
//!   (Simchony, Chellappa and Shao 1990). For rectangular maps that do not wrap: no bowl.
//! * [`Integrator::Masked`]: edges touching an invalid texel (zero normal, NaN, back-facing) carry
//!   a weight of [`HOLE_WEIGHT`] and ask for the valid texels' mean slope, so holes are filled
//!   smoothly (following the surface's overall tilt) without pulling the valid surface; solved by
//!   conjugate gradients preconditioned by the Neumann solve. Where holes cut the map into
//!   pieces, the pieces' relative heights are that fill's guess: no normal says them.
//!
//! [`integrate`] picks the integrator from the map ([`Integrator::choose`]), converts slopes to
//! millimetres through the map's scale ([`Scale`]) and measures the integrability residual. The
//! deliverables ([`deliver`]) are computed from the resulting [`Height`].

mod buffer;
pub mod compare;
mod dct;
pub mod deliver;
mod error;
mod masked;
mod neumann;
mod poisson;
pub mod round_trip;
mod slopes;
mod transform;
mod tridiagonal;

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use skinkit_maps::{NormalMap, ScalarMap};

pub use error::{Error, Result};
pub use slopes::{MAX_SLOPE, Slopes, TexelCounts};

/// Weight of an edge with an invalid end in the masked solve, against 1 for a valid edge: small,
/// so a hole's fill barely pulls the surface around it, and not so small that conjugate gradients
/// crawl through the fill (measured in the crate's tests and the accuracy stage).
pub const HOLE_WEIGHT: f32 = 0.02;

/// How a normal map is integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub enum Integrator {
    /// Periodic Poisson solve by FFT (the map wraps; the height tiles).
    #[serde(rename = "periodic-fft")]
    Periodic,
    /// Neumann Poisson solve by DCT (a rectangle that does not wrap).
    #[serde(rename = "neumann-dct")]
    Neumann,
    /// Masked Poisson solve by DCT-preconditioned conjugate gradients (invalid texels present).
    #[serde(rename = "masked-pcg")]
    Masked,
}

impl Integrator {
    /// The integrator that is right for a map: periodic when it wraps, masked when any texel is
    /// invalid, Neumann otherwise. A wrapping map with invalid texels is integrated periodically
    /// with the invalid texels' slopes taken as zero (a grown map has none).
    pub fn choose(wraps: bool, invalid_texels: usize) -> Integrator {
        match (wraps, invalid_texels) {
            (true, _) => Integrator::Periodic,
            (false, 0) => Integrator::Neumann,
            (false, _) => Integrator::Masked,
        }
    }

    /// Its name in reports and file headers.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Periodic => "periodic-fft",
            Integrator::Neumann => "neumann-dct",
            Integrator::Masked => "masked-pcg",
        }
    }
}

/// The physical size of a texel, which turns slopes into millimetres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scale {
    /// Millimetres per texel (`mm_per_pixel` of a rig, `mm_per_texel` of an exemplar or layout).
    MmPerTexel(f64),
    /// No scale known: heights are in texel widths.
    Texels,
}

impl Scale {
    /// `Some(mm)` makes a millimetre scale, `None` a texel one.
    ///
    /// # Errors
    /// When `mm` is not finite and positive.
    pub fn from_mm(mm: Option<f64>) -> Result<Scale> {
        match mm {
            None => Ok(Scale::Texels),
            Some(mm) if mm.is_finite() && mm > 0.0 => Ok(Scale::MmPerTexel(mm)),
            Some(mm) => Err(Error::Parameter(format!("mm per texel must be finite and positive, not {mm}"))),
        }
    }

    /// Length of one texel in the output's unit.
    pub fn texel(self) -> f64 {
        match self {
            Scale::MmPerTexel(mm) => mm,
            Scale::Texels => 1.0,
        }
    }

    /// The output's unit: `"mm"` or `"texel"`.
    pub fn unit(self) -> &'static str {
        match self {
            Scale::MmPerTexel(_) => "mm",
            Scale::Texels => "texel",
        }
    }
}

/// What to integrate and how.
#[derive(Clone, Copy, Debug)]
pub struct HeightOptions {
    /// The map wraps around (a grown, toroidal map).
    pub wraps: bool,
    /// The integrator; `None` chooses ([`Integrator::choose`]).
    pub integrator: Option<Integrator>,
    /// The texel's size.
    pub scale: Scale,
    /// Relative residual at which the masked solve stops.
    pub tolerance: f64,
    /// Iterations after which the masked solve stops.
    pub max_iterations: usize,
}

impl Default for HeightOptions {
    fn default() -> Self {
        HeightOptions { wraps: false, integrator: None, scale: Scale::Texels, tolerance: 1e-5, max_iterations: 400 }
    }
}

/// An integrated height map and how it was made.
#[derive(Clone, Debug)]
pub struct Height {
    /// Heights in [`Scale::unit`]s, mean zero over the valid texels.
    pub map: ScalarMap,
    /// Texels that took part (valid normals); invalid ones hold the smooth fill.
    pub valid: Vec<bool>,
    /// What was measured along the way.
    pub report: HeightReport,
}

/// The numbers a report gives about a height map.
#[derive(Clone, Debug, Serialize)]
pub struct HeightReport {
    pub integrator: Integrator,
    /// `"mm"` or `"texel"`.
    pub unit: &'static str,
    /// Millimetres per texel, when known.
    pub mm_per_texel: Option<f64>,
    /// Lowest and highest height over the valid texels, in `unit`.
    pub min: f32,
    pub max: f32,
    /// RMS height about the mean, over the valid texels, in `unit`.
    pub rms: f32,
    /// RMS of the edge residual `(h_b - h_a) - slope` over valid edges, as a slope (unitless): the
    /// part of the normal map no surface has (noise, seams, non-integrable texels).
    pub residual_rms: f64,
    /// The same residual against the RMS slope: 0 for an integrable map.
    pub residual_relative: f64,
    /// Texel counts: valid, and refused by cause.
    pub texels: TexelCounts,
    /// Conjugate-gradient iterations (masked solve only).
    pub iterations: Option<usize>,
    /// Wall time of the integration, in seconds (not serialised: reports keep their times apart,
    /// so that two runs' reports compare equal).
    #[serde(skip)]
    pub seconds: f64,
}

/// Relative residual under which the fused Neumann path measures the residual edge by edge rather
/// than from the spectrum (whose f32 floor, about 3e-4, is then more than 0.1 % of it).
const SPECTRAL_RESIDUAL_FLOOR: f64 = 0.01;

/// Integrates `normals` into a height map.
///
/// # Errors
/// When no texel has a usable normal, or the options are invalid.
pub fn integrate(normals: &NormalMap, options: &HeightOptions) -> Result<Height> {
    let start = Instant::now();
    let (w, h) = normals.size();
    let texel = options.scale.texel();
    // A rectangular map is first tried on the fused Neumann path, which also classifies it.
    let neumann_first = matches!(options.integrator, None | Some(Integrator::Neumann)) && !options.wraps;
    if let Some((heights, m)) = neumann_first.then(|| neumann::integrate_valid(normals, texel)).flatten() {
        let (min, max, rms) = m.moments.centred();
        // The spectral residual loses its digits to cancellation on a nearly integrable map
        // (about 3e-4 of the steps in f32): there it is measured edge by edge.
        let (residual_rms, residual_relative) = if m.residual.1 < SPECTRAL_RESIDUAL_FLOOR {
            Slopes::from_normals(normals).residual(&heights, texel as f32, false)
        } else {
            m.residual
        };
        let report = HeightReport {
            integrator: Integrator::Neumann,
            min,
            max,
            rms,
            residual_rms,
            residual_relative,
            texels: m.counts,
            iterations: None,
            ..HeightReport::new(options.scale, start)
        };
        let map = ScalarMap::from_vec(w, h, heights)?;
        return Ok(Height { map, valid: vec![true; w * h], report });
    }
    let slopes = Slopes::from_normals(normals);
    if slopes.counts.valid == 0 {
        return Err(Error::NoValidTexel { texels: w * h });
    }
    let integrator = options.integrator.unwrap_or(Integrator::choose(options.wraps, slopes.counts.invalid()));
    let (mut heights, iterations) = match integrator {
        Integrator::Periodic => (poisson::solve_periodic(&slopes), None),
        Integrator::Neumann => (poisson::solve_neumann(&slopes), None),
        Integrator::Masked => {
            let (h, it) = masked::solve(&slopes, options.tolerance, options.max_iterations);
            (h, Some(it))
        }
    };
    let wraps = integrator == Integrator::Periodic;
    let (residual_rms, residual_relative) = slopes.residual(&heights, 1.0, wraps);
    let valid = slopes.valid;
    let (min, max, rms) = finish(&mut heights, &valid, w, texel as f32);
    let map = ScalarMap::from_vec(w, h, heights)?;
    let report = HeightReport {
        integrator,
        min,
        max,
        rms,
        residual_rms,
        residual_relative,
        texels: slopes.counts,
        iterations,
        ..HeightReport::new(options.scale, start)
    };
    Ok(Height { map, valid, report })
}

impl HeightReport {
    /// An empty report in `scale`'s unit, timed from `start` (the rest filled by the caller).
    fn new(scale: Scale, start: Instant) -> HeightReport {
        HeightReport {
            integrator: Integrator::Neumann,
            unit: scale.unit(),
            mm_per_texel: match scale {
                Scale::MmPerTexel(mm) => Some(mm),
                Scale::Texels => None,
            },
            min: 0.0,
            max: 0.0,
            rms: 0.0,
            residual_rms: 0.0,
            residual_relative: 0.0,
            texels: TexelCounts::default(),
            iterations: None,
            seconds: start.elapsed().as_secs_f64(),
        }
    }
}

/// Sum, sum of squares, count, minimum and maximum of some texels.
#[derive(Clone, Copy)]
pub(crate) struct Moments {
    sum: f64,
    squares: f64,
    n: usize,
    lo: f32,
    hi: f32,
}

impl Moments {
    const EMPTY: Moments = Moments { sum: 0.0, squares: 0.0, n: 0, lo: f32::INFINITY, hi: f32::NEG_INFINITY };

    /// The moments of every value of `v`, in eight running sums (and extremes) per lane, combined
    /// in a fixed order; written lane by lane so that it vectorises.
    fn of(v: &[f32]) -> Moments {
        const LANES: usize = 8;
        let (mut sum, mut squares) = ([0f64; LANES], [0f64; LANES]);
        let (mut lo, mut hi) = ([f32::INFINITY; LANES], [f32::NEG_INFINITY; LANES]);
        let mut chunks = v.chunks_exact(LANES);
        for c in chunks.by_ref() {
            for i in 0..LANES {
                let x = c[i];
                sum[i] += f64::from(x);
                squares[i] += f64::from(x) * f64::from(x);
                lo[i] = if x < lo[i] { x } else { lo[i] };
                hi[i] = if x > hi[i] { x } else { hi[i] };
            }
        }
        for (i, &x) in chunks.remainder().iter().enumerate() {
            sum[i] += f64::from(x);
            squares[i] += f64::from(x) * f64::from(x);
            lo[i] = lo[i].min(x);
            hi[i] = hi[i].max(x);
        }
        let lo = lo.iter().fold(f32::INFINITY, |a, &b| a.min(b));
        let hi = hi.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b));
        Moments { sum: sum.iter().sum(), squares: squares.iter().sum(), n: v.len(), lo, hi }
    }

    /// Minimum and maximum about the mean, and the RMS about it.
    fn centred(self) -> (f32, f32, f32) {
        if self.n == 0 {
            return (0.0, 0.0, 0.0);
        }
        let mean = self.sum / self.n as f64;
        let variance = (self.squares / self.n as f64 - mean * mean).max(0.0);
        ((f64::from(self.lo) - mean) as f32, (f64::from(self.hi) - mean) as f32, variance.sqrt() as f32)
    }

    fn add(self, o: Moments) -> Moments {
        Moments {
            sum: self.sum + o.sum,
            squares: self.squares + o.squares,
            n: self.n + o.n,
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }
}

/// Scales `h` by `texel`, shifts it to mean zero over its valid texels and returns their minimum,
/// maximum and RMS. Sums per row in f64, then in row order: the same bits at any thread count.
fn finish(h: &mut [f32], valid: &[bool], width: usize, texel: f32) -> (f32, f32, f32) {
    let rows: Vec<Moments> = h
        .par_chunks_mut(width.max(1))
        .zip(valid.par_chunks(width.max(1)))
        .map(|(row, ok)| {
            let mut m = Moments::EMPTY;
            for (v, _) in row.iter_mut().zip(ok).filter(|(_, ok)| **ok) {
                *v *= texel;
                m = m.add(Moments { sum: f64::from(*v), squares: f64::from(*v) * f64::from(*v), n: 1, lo: *v, hi: *v });
            }
            m
        })
        .collect();
    let m = rows.iter().fold(Moments::EMPTY, |a, r| a.add(*r));
    if m.n == 0 {
        return (0.0, 0.0, 0.0);
    }
    let mean = m.sum / m.n as f64;
    let shift = mean as f32;
    h.par_chunks_mut(width.max(1)).zip(valid.par_chunks(width.max(1))).for_each(|(row, ok)| {
        // Invalid texels (the fill) were not scaled above.
        row.iter_mut().zip(ok).for_each(|(v, ok)| *v = if *ok { *v - shift } else { *v * texel - shift });
    });
    let variance = (m.squares / m.n as f64 - mean * mean).max(0.0);
    (m.lo - shift, m.hi - shift, variance.sqrt() as f32)
}
