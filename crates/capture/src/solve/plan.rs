//! The plan of one solve (built once, shared by the workers) and its all-lights chunk path.

use glam::Vec3;
use rayon::prelude::*;
use skinkit_maps::{Channels, Grid, NormalMap, Transfer};

use super::chunk::{Out, Scratch, accumulate_all, accumulate_rows, residual_factor, take_sized, write_all_lights};
#[cfg(target_arch = "x86_64")]
use super::fused;
use super::solution::{AlbedoTexel, fresh_zeroed_vec3};
use super::sources::{Linearise, Raw, Source, as_f32, as_u8, as_u16, raw_values};
use super::subsets::{SubsetSolve, Subsets, gram_form};
use super::{
    AlbedoMap, BAND_ROWS, CHUNK, DENSE_MAX_LIGHTS, Method, PhotoStack, Progress, Solution, SolveConfig, SolveStats,
};
use crate::{Result, Rig, readings};
use fit::Fit;

// The parts of the plan that extend it with methods of their own: the robust fit and its noise
// floor, and the paths of pixels that drop readings.
mod finish;
mod fit;
mod noise;

/// Everything a worker needs, built once per solve.
pub(super) struct Plan<'a> {
    pub(super) width: usize,
    pub(super) k: usize,
    pub(super) rgb: bool,
    pub(super) robust: bool,
    /// [`Method::Robust`]: pixels whose least squares over their lit readings (all lights, or
    /// the subset left after dropping) leaves a relative residual above
    /// [`crate::robust::AGREEMENT`] are fitted by [`crate::robust::fit_pixel`] ([`Self::finish_fit`]).
    pub(super) fit: Option<Fit>,
    pub(super) config: &'a SolveConfig,
    pub(super) lights: Vec<Vec3>,
    pub(super) sources: Vec<Source<'a>>,
    pub(super) linearise: Linearise<'a>,
    pub(super) full: SubsetSolve,
    /// `full.cols[i] * sources[i].gray_scale`: the folded pseudo-inverse of the fast path.
    pub(super) folded: Vec<[f32; 3]>,
    /// Per light, the scale from raw values to readings (fast path), and ones.
    pub(super) gray_scales: Vec<f32>,
    /// Fast path: `sum_i (raw_i * rr_scales_i)^2 * rr_post` is `sum r^2`. With one scale for all
    /// lights (equal intensities) the scale moves out of the sum (`rr_post = scale^2`, ones
    /// inside), a multiplication per reading fewer; else `rr_post = 1`.
    pub(super) rr_scales: Vec<f32>,
    pub(super) rr_post: f32,
    pub(super) ones: Vec<f32>,
    pub(super) fast_ls: bool,
    /// Whether the fused kernel applies: linear grey photos without an ambient frame.
    pub(super) fused: bool,
    /// Threshold or robust with at most [`DENSE_MAX_LIGHTS`] lights: a chunk's pixels with
    /// dropped readings are grouped by subset and solved a group at a time
    /// ([`Self::finish_subsets`]); else one pixel at a time ([`Self::finish_subset`]). Both give
    /// the same bits.
    pub(super) batch_subsets: bool,
    pub(super) mask: Option<&'a [bool]>,
}

impl<'a> Plan<'a> {
    pub(super) fn new(
        stack: &'a PhotoStack,
        rig: &Rig,
        config: &'a SolveConfig,
        lights: Vec<Vec3>,
        table: Option<&'a [f32]>,
    ) -> Result<Self> {
        let full = SubsetSolve::new(&lights, super::all_lights(lights.len()), config.max_condition);
        super::refuse_ill_conditioned(lights.len(), full.condition, full.usable, config.max_condition)?;
        let first = &stack.photos()[0];
        let linearise = match (first.transfer(), table) {
            (Transfer::Linear, _) => Linearise::Identity,
            (Transfer::Srgb, Some(t)) => Linearise::Table(t),
            (Transfer::Srgb, None) => Linearise::SrgbCurve,
        };
        let sources: Vec<Source> = stack
            .photos()
            .iter()
            .zip(rig.lights())
            .map(|(p, l)| Source::new(p, stack.ambient(), l.intensity(), config))
            .collect();
        let k = lights.len();
        let sources_scales: Vec<f32> = sources.iter().map(|s| s.gray_scale).collect();
        let uniform = sources_scales.iter().all(|s| s.to_bits() == sources_scales[0].to_bits());
        let folded = full.cols.iter().zip(&sources).map(|(c, s)| c.map(|v| v * s.gray_scale)).collect();
        let rgb = first.channels() == Channels::Rgb;
        let robust = config.method.drops_readings();
        let fit = (config.method == Method::Robust).then(|| Fit::new(&lights, config)).transpose()?;
        Ok(Plan {
            width: stack.width(),
            k: lights.len(),
            rgb,
            robust,
            fit,
            config,
            lights,
            sources,
            linearise,
            full,
            folded,
            rr_scales: if uniform { vec![1.0; k] } else { sources_scales.clone() },
            rr_post: if uniform { sources_scales[0] * sources_scales[0] } else { 1.0 },
            gray_scales: sources_scales,
            ones: vec![1.0; k],
            fast_ls: !robust && !rgb && first.transfer() == Transfer::Linear,
            fused: !rgb && first.transfer() == Transfer::Linear && stack.ambient().is_none(),
            batch_subsets: robust && k <= DENSE_MAX_LIGHTS,
            mask: stack.mask().map(|m| m.as_slice()),
        })
    }

    /// Solves every band of rows in parallel and assembles the maps.
    pub(super) fn run(&self, stack: &PhotoStack, progress: &dyn Progress, out: &mut Solution) {
        let (w, h) = stack.size();
        let normals = std::mem::replace(&mut out.normals, NormalMap::flat(0, 0)).into_grid();
        let mut normals = if normals.size() == (w, h) { normals.into_vec() } else { fresh_zeroed_vec3(w * h) };
        let mut confidence = take_sized(std::mem::replace(&mut out.confidence, Grid::filled(0, 0, 0.0)), w, h);
        let albedo = std::mem::replace(&mut out.albedo, AlbedoMap::Gray(Grid::filled(0, 0, 0.0)));
        let stats = match (self.rgb, albedo) {
            (false, albedo) => {
                let mut a = match albedo {
                    AlbedoMap::Gray(g) => take_sized(g, w, h),
                    AlbedoMap::Rgb(_) => f32::fresh(w * h),
                };
                let stats = self.run_bands(progress, &mut normals, &mut a, &mut confidence);
                out.albedo = AlbedoMap::Gray(Grid::from_vec(w, h, a).expect("sized above"));
                stats
            }
            (true, albedo) => {
                let mut a = match albedo {
                    AlbedoMap::Rgb(g) => take_sized(g, w, h),
                    AlbedoMap::Gray(_) => Vec3::fresh(w * h),
                };
                let stats = self.run_bands(progress, &mut normals, &mut a, &mut confidence);
                out.albedo = AlbedoMap::Rgb(Grid::from_vec(w, h, a).expect("sized above"));
                stats
            }
        };
        out.normals = NormalMap::from_unit_grid(Grid::from_vec(w, h, normals).expect("sized above"))
            .expect("solver writes unit or zero normals");
        out.confidence = Grid::from_vec(w, h, confidence).expect("sized above");
        out.stats = stats;
    }

    /// Solves every band of rows in parallel into the output slices (each the image's size).
    pub(super) fn run_bands<A: AlbedoTexel>(
        &self,
        progress: &dyn Progress,
        normals: &mut [Vec3],
        albedo: &mut [A],
        confidence: &mut [f32],
    ) -> SolveStats {
        let (w, h) = (self.width, normals.len() / self.width);
        let subsets = Subsets::new(&self.lights, self.config.max_condition, self.config.cache_capacity);
        progress.start("solve", h as u64);
        let band = BAND_ROWS * w;
        let stats = normals
            .par_chunks_mut(band)
            .zip(albedo.par_chunks_mut(band))
            .zip(confidence.par_chunks_mut(band))
            .enumerate()
            .map_init(
                || Scratch::new(self.k, self.rgb),
                |scratch, (b, ((n, a), c))| {
                    let stats =
                        self.solve_band(b * band, Out { normals: n, albedo: a, confidence: c }, scratch, &subsets);
                    progress.advance((stats.pixels / w) as u64);
                    stats
                },
            )
            .reduce(|| SolveStats::empty(self.k), SolveStats::merge);
        progress.finish();
        stats
    }

    /// Solves the pixels starting at `p0` (a band of whole rows), row by row in chunks.
    pub(super) fn solve_band<A: AlbedoTexel>(
        &self,
        p0: usize,
        out: Out<A>,
        scratch: &mut Scratch,
        subsets: &Subsets,
    ) -> SolveStats {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports AVX2 and FMA, the features `solve_band_avx2` is compiled for.
            return unsafe { self.solve_band_avx2(p0, out, scratch, subsets) };
        }
        self.solve_band_portable(p0, out, scratch, subsets)
    }

    /// [`Self::solve_band`] compiled for AVX2 and FMA (8-wide loops). The kernels use explicit
    /// `mul_add` (exactly rounded everywhere), so this and the portable build give the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn solve_band_avx2<A: AlbedoTexel>(
        &self,
        p0: usize,
        out: Out<A>,
        scratch: &mut Scratch,
        subsets: &Subsets,
    ) -> SolveStats {
        if !self.fused {
            return self.solve_band_portable(p0, out, scratch, subsets);
        }
        let Out { normals, albedo, confidence } = out;
        let Some(albedo) = A::gray_slice(albedo) else {
            return self.solve_band_portable(p0, Out { normals, albedo, confidence }, scratch, subsets);
        };
        let out = Out { normals, albedo, confidence };
        match (self.sources[0].raw, self.robust) {
            (Raw::U8(_), false) => self.solve_band_fused::<u8, false>(p0, out, scratch, subsets),
            (Raw::U8(_), true) => self.solve_band_fused::<u8, true>(p0, out, scratch, subsets),
            (Raw::U16(_), false) => self.solve_band_fused::<u16, false>(p0, out, scratch, subsets),
            (Raw::U16(_), true) => self.solve_band_fused::<u16, true>(p0, out, scratch, subsets),
            (Raw::F32(_), false) => self.solve_band_fused::<f32, false>(p0, out, scratch, subsets),
            (Raw::F32(_), true) => self.solve_band_fused::<f32, true>(p0, out, scratch, subsets),
        }
    }

    /// [`Self::solve_band`] for linear grey photos without an ambient frame: [`fused::step`]
    /// solves [`fused::STEP`] pixels at a time straight from the samples to the output. Steps it
    /// declines (a reading dropped by the robust tests, a masked texel) and the band's last few
    /// pixels go through [`Self::solve_chunk`], whose all-lights arithmetic is the same.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn solve_band_fused<T: fused::Lanes, const ROBUST: bool>(
        &self,
        p0: usize,
        out: Out<f32>,
        scratch: &mut Scratch,
        subsets: &Subsets,
    ) -> SolveStats {
        const STEP: usize = fused::STEP;
        let rows: Vec<&[T]> = self.sources.iter().map(|s| T::of(s.raw)).collect();
        let kernel = fused::Kernel {
            coefs: if ROBUST { &self.full.cols } else { &self.folded },
            scales: if ROBUST { &self.ones } else { &self.rr_scales },
            unit_scales: ROBUST || self.rr_scales.iter().all(|&s| s == 1.0),
            rr_post: if ROBUST { 1.0 } else { self.rr_post },
            gains: &self.gray_scales,
            gram: self.full.gram,
            saturated_at: self.sources[0].saturated_at,
            shadow_abs: self.config.shadow_abs,
            shadow_rel: self.config.shadow_rel,
            // The fused kernel's shadow threshold is from the brightest reading, the reference
            // reading only up to 9 lights (and without saturation, which `step` checks).
            group_subsets: self.batch_subsets && readings::reference_is_brightest(self.k),
        };
        let mut stats = SolveStats::empty(self.k);
        let n_px = out.normals.len();
        stats.pixels = n_px;
        let mut j = 0;
        while j < n_px {
            let n = STEP.min(n_px - j);
            let p = p0 + j;
            let chunk = Out {
                normals: &mut out.normals[j..j + n],
                albedo: &mut out.albedo[j..j + n],
                confidence: &mut out.confidence[j..j + n],
            };
            let inside = self.mask.is_none_or(|m| m[p..p + n].iter().all(|&v| v));
            let solved = if n == STEP && inside {
                fused::step::<T, ROBUST>(&kernel, &rows, p, chunk.normals, chunk.albedo, chunk.confidence)
            } else {
                fused::Step::Declined
            };
            match solved {
                // The robust fit takes over pixels the all-lights solve does not explain.
                fused::Step::Solved(_)
                    if self.fit.as_ref().is_some_and(|f| chunk.confidence.iter().any(|&c| !f.agrees(c))) =>
                {
                    self.solve_chunk(p, chunk, scratch, subsets, &mut stats)
                }
                fused::Step::Solved(invalid) => {
                    stats.lights_used[self.k] += STEP;
                    stats.invalid_count += invalid as usize;
                }
                fused::Step::Subset(bits) => {
                    let mut chunk = chunk;
                    if !self.solve_step_subset(bits, &rows, p, &mut chunk, scratch, subsets, &mut stats) {
                        self.solve_chunk(p, chunk, scratch, subsets, &mut stats)
                    }
                }
                fused::Step::Declined => self.solve_chunk(p, chunk, scratch, subsets, &mut stats),
            }
            j += n;
        }
        stats
    }

    #[inline(always)]
    pub(super) fn solve_band_portable<A: AlbedoTexel>(
        &self,
        p0: usize,
        out: Out<A>,
        scratch: &mut Scratch,
        subsets: &Subsets,
    ) -> SolveStats {
        let mut stats = SolveStats::empty(self.k);
        let n_px = out.normals.len();
        stats.pixels = n_px;
        let mut start = 0;
        while start < n_px {
            let row_end = (start / self.width + 1) * self.width;
            let n = CHUNK.min(row_end - start);
            let chunk = Out {
                normals: &mut out.normals[start..start + n],
                albedo: &mut out.albedo[start..start + n],
                confidence: &mut out.confidence[start..start + n],
            };
            self.solve_chunk(p0 + start, chunk, scratch, subsets, &mut stats);
            start += n;
        }
        stats
    }

    /// Solves the `n <= CHUNK` pixels starting at image pixel `p`.
    #[inline(always)]
    pub(super) fn solve_chunk<A: AlbedoTexel>(
        &self,
        p: usize,
        mut out: Out<A>,
        scratch: &mut Scratch,
        subsets: &Subsets,
        stats: &mut SolveStats,
    ) {
        let n = out.normals.len();
        let inside = self.mask.map(|m| &m[p..p + n]);
        if all_masked(inside, &mut out, stats) {
            return;
        }
        if self.fast_ls {
            self.accumulate_folded(p, n, scratch);
        } else {
            self.load_readings(p, n, scratch);
            self.accumulate_readings(n, scratch);
            if self.robust {
                self.count_dropped(n, scratch);
            }
        }
        let invalid = self.normalise_all(n, scratch);
        let any_dropped = match &self.fit {
            Some(fit) => (0..n).any(|j| scratch.dropped[j] > 0 || !fit.agrees(scratch.conf[j])),
            None => self.robust && scratch.dropped[..n].iter().any(|&d| d > 0),
        };
        if !self.rgb && inside.is_none() && !any_dropped {
            write_all_lights(n, scratch, out);
            stats.lights_used[self.k] += n;
            stats.invalid_count += invalid;
            return;
        }
        let mut local = std::mem::take(&mut scratch.cache);
        let mut pending = 0;
        for j in 0..n {
            if inside.is_some_and(|m| !m[j]) {
                (out.normals[j], out.albedo[j], out.confidence[j]) = (Vec3::ZERO, A::ZERO, 0.0);
                continue;
            }
            if self.batch_subsets && scratch.dropped[j] > 0 {
                scratch.pending[pending] = j as u8;
                pending += 1;
                continue;
            }
            // All-lights least squares, or (robust) the fit where it does not agree.
            let refit = self.fit.as_ref().filter(|f| !f.agrees(scratch.conf[j]));
            let (normal, albedo, confidence, used) = if self.robust && scratch.dropped[j] > 0 {
                let (texel, factor) = self.finish_subset(j, scratch, subsets, &mut local);
                match &self.fit {
                    Some(fit) if !fit.agrees(factor) => self.finish_fit(fit, j, scratch, subsets),
                    _ => texel,
                }
            } else if let Some(fit) = refit {
                self.finish_fit(fit, j, scratch, subsets)
            } else {
                let normal = Vec3::new(scratch.gx[j], scratch.gy[j], scratch.gz[j]);
                let albedo = if self.rgb {
                    self.rgb_albedo(j, self.full_bits(), normal, scratch)
                } else {
                    Vec3::splat(scratch.len[j])
                };
                (normal, albedo, scratch.conf[j], self.k)
            };
            stats.lights_used[used] += 1;
            out.normals[j] = normal;
            out.albedo[j] = A::rgb(albedo);
            out.confidence[j] = confidence;
        }
        if pending > 0 {
            self.finish_subsets(pending, scratch, subsets, &mut local, &mut out, stats);
        }
        scratch.cache = local;
        stats.invalid_count += out.normals.iter().filter(|v| **v == Vec3::ZERO).count();
    }

    /// Turns the all-lights solutions `g` of the chunk into normals (in place), albedo `|g|` and
    /// confidence, vectorised; `|g| <= MIN_ALBEDO` or non-finite gives zeros.
    #[inline(always)]
    pub(super) fn normalise_all(&self, n: usize, s: &mut Scratch) -> usize {
        let m = self.full.gram;
        let mut invalid = 0u32;
        let it = s.gx[..n]
            .iter_mut()
            .zip(&mut s.gy[..n])
            .zip(&mut s.gz[..n])
            .zip(&s.rr[..n])
            .zip(&mut s.len[..n])
            .zip(&mut s.conf[..n]);
        for (((((x, y), z), &rr), len), conf) in it {
            let g = [*x, *y, *z];
            let l = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
            let ok = readings::defines_normal(l);
            invalid += !ok as u32;
            // Selects, not products with zero: a NaN reading must not leak into the normal.
            let inv = if ok { 1.0 / l } else { 0.0 };
            *conf = if ok { residual_factor(rr, gram_form(&m, g)) } else { 0.0 };
            *len = if ok { l } else { 0.0 };
            (*x, *y, *z) = if ok { (g[0] * inv, g[1] * inv, g[2] * inv) } else { (0.0, 0.0, 0.0) };
        }
        invalid as usize
    }

    /// Fast least-squares path for linear grey photos: `g += P'_i * raw_i` with the folded
    /// pseudo-inverse and `rr += (raw_i * rr_scale_i)^2` (times `rr_post` at the end), straight
    /// from the stored samples (the conversion to f32 is exact), or from `s.r` holding raw values
    /// minus the ambient frame's.
    #[inline(always)]
    pub(super) fn accumulate_folded(&self, p: usize, n: usize, s: &mut Scratch) {
        let (folded, scales) = (&self.folded[..], &self.rr_scales[..]);
        let sums = (&mut s.gx, &mut s.gy, &mut s.gz, &mut s.rr);
        let src = |i: usize| self.sources[i].raw;
        match (self.sources[0].raw, self.sources[0].ambient) {
            (Raw::U16(_), None) => accumulate_rows(n, |i| &as_u16(src(i))[p..p + n], sums, folded, scales),
            (Raw::U8(_), None) => accumulate_rows(n, |i| &as_u8(src(i))[p..p + n], sums, folded, scales),
            (Raw::F32(_), None) => accumulate_rows(n, |i| &as_f32(src(i))[p..p + n], sums, folded, scales),
            _ => {
                for (i, src) in self.sources.iter().enumerate() {
                    let out = &mut s.r[i * CHUNK..i * CHUNK + n];
                    match (src.raw, src.ambient) {
                        (Raw::U8(v), a) => raw_values::<u8>(&v[p..p + n], a.map(|a| &as_u8(a)[p..p + n]), out),
                        (Raw::U16(v), a) => raw_values::<u16>(&v[p..p + n], a.map(|a| &as_u16(a)[p..p + n]), out),
                        (Raw::F32(v), a) => raw_values::<f32>(&v[p..p + n], a.map(|a| &as_f32(a)[p..p + n]), out),
                    }
                }
                accumulate_all(n, s, folded, scales);
            }
        }
        let post = self.rr_post;
        s.rr[..n].iter_mut().for_each(|q| *q *= post);
    }

    /// Fills `s.r` (and `s.rgb`, `s.sat`) with every light's readings of the chunk.
    #[inline(always)]
    pub(super) fn load_readings(&self, p: usize, n: usize, s: &mut Scratch) {
        for (i, src) in self.sources.iter().enumerate() {
            let r = &mut s.r[i * CHUNK..i * CHUNK + n];
            let sat = &mut s.sat[i * CHUNK..i * CHUNK + n];
            if self.rgb {
                let rgb = &mut s.rgb[i * CHUNK..i * CHUNK + n];
                src.load_rgb(p, self.linearise, r, rgb, sat);
            } else {
                src.load_gray(p, self.linearise, r, sat);
            }
        }
    }

    /// `g = P r` and `rr = sum r^2` over all lights, from the loaded readings.
    #[inline(always)]
    pub(super) fn accumulate_readings(&self, n: usize, s: &mut Scratch) {
        accumulate_all(n, s, &self.full.cols, &self.ones);
    }
}

/// Counts the chunk's pixels outside the mask (`inside`) into `stats`; when all are outside,
/// writes the invalid marker over the chunk, counts it invalid and returns `true`.
#[inline(always)]
fn all_masked<A: AlbedoTexel>(inside: Option<&[bool]>, out: &mut Out<A>, stats: &mut SolveStats) -> bool {
    let Some(inside) = inside else { return false };
    let n = out.normals.len();
    let masked = inside.iter().filter(|v| !**v).count();
    stats.masked_count += masked;
    if masked == n {
        out.normals.fill(Vec3::ZERO);
        out.albedo.fill(A::ZERO);
        out.confidence.fill(0.0);
        stats.invalid_count += n;
    }
    masked == n
}
