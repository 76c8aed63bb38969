//! The shadow thresholds, and the paths of pixels that drop readings: one pixel at a time,
//! grouped by subset, or a fused step of one subset.

use std::collections::HashMap;

use glam::Vec3;

use super::Plan;
use crate::readings;
use crate::solve::chunk::{Out, Scratch, residual_factor};
#[cfg(target_arch = "x86_64")]
use crate::solve::fused;
use crate::solve::solution::AlbedoTexel;
use crate::solve::subsets::{SubsetSolve, Subsets};
use crate::solve::{CHUNK, MAX_LIGHTS, SolveStats};

impl Plan<'_> {
    /// Counts, per pixel, the readings that are shadowed or saturated (`s.dropped`), after
    /// [`Self::shadow_thresholds`].
    #[inline(always)]
    pub(in crate::solve) fn count_dropped(&self, n: usize, s: &mut Scratch) {
        self.shadow_thresholds(n, s);
        s.dropped[..n].fill(0);
        for i in 0..self.k {
            let r = &s.r[i * CHUNK..i * CHUNK + n];
            let sat = &s.sat[i * CHUNK..i * CHUNK + n];
            for (((d, &t), &v), &q) in s.dropped[..n].iter_mut().zip(&s.top[..n]).zip(r).zip(sat) {
                *d += ((v < t) as u32) | q as u32;
            }
        }
        if self.batch_subsets {
            // The same test as `usable_bits` (a NaN reading is neither dropped nor usable).
            s.bits[..n].fill(0);
            for i in 0..self.k {
                let r = &s.r[i * CHUNK..i * CHUNK + n];
                let sat = &s.sat[i * CHUNK..i * CHUNK + n];
                for (((b, &t), &v), &q) in s.bits[..n].iter_mut().zip(&s.top[..n]).zip(r).zip(sat) {
                    *b |= (((v >= t) & (q == 0)) as u32) << i;
                }
            }
        }
    }

    /// The shadow threshold of each pixel (`s.top`): [`readings::shadow_floor`] of its
    /// reference reading, the brightest usable (finite, unsaturated) one when the rig has at most
    /// 9 lights (a vectorised maximum; the fused kernel takes the same), else the 90th percentile
    /// by selection ([`readings::shadow_reference`]).
    #[inline(always)]
    pub(in crate::solve) fn shadow_thresholds(&self, n: usize, s: &mut Scratch) {
        let top = &mut s.top[..n];
        if readings::reference_is_brightest(self.k) {
            top.fill(f32::NEG_INFINITY);
            for i in 0..self.k {
                let (r, sat) = (&s.r[i * CHUNK..i * CHUNK + n], &s.sat[i * CHUNK..i * CHUNK + n]);
                for ((t, &v), &q) in top.iter_mut().zip(r).zip(sat) {
                    *t = t.max(if q == 0 && v.is_finite() { v } else { f32::NEG_INFINITY });
                }
            }
        } else {
            let mut usable = [0.0f32; MAX_LIGHTS];
            for (j, t) in top.iter_mut().enumerate() {
                let mut m = 0;
                for i in 0..self.k {
                    let v = s.r[i * CHUNK + j];
                    if s.sat[i * CHUNK + j] == 0 && v.is_finite() {
                        usable[m] = v;
                        m += 1;
                    }
                }
                *t = readings::shadow_reference(&mut usable[..m]);
            }
        }
        let shadows = self.config.shadows();
        for t in top {
            // In f32 bit for bit (see `shadow_floor`).
            *t = readings::shadow_floor(shadows, *t as f64) as f32;
        }
    }

    /// A fused step whose [`fused::STEP`] pixels at `p` all use the lights `bits`, solved in
    /// registers with that subset's columns ([`fused::subset_step`]) into `out`. Returns false,
    /// having counted nothing, when the chunk path must solve the step instead: with
    /// [`Method::Robust`](crate::solve::Method::Robust), when a pixel's subset fit does not agree ([`super::fit::Fit::agrees`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[allow(clippy::too_many_arguments)]
    pub(in crate::solve) fn solve_step_subset<T: fused::Lanes>(
        &self,
        bits: u32,
        rows: &[&[T]],
        p: usize,
        out: &mut Out<f32>,
        scratch: &mut Scratch,
        subsets: &Subsets,
        stats: &mut SolveStats,
    ) -> bool {
        let used = bits.count_ones() as usize;
        let subset = if used < self.config.min_lights {
            None
        } else {
            Some(subsets.get(bits as u128, &mut scratch.cache)).filter(|s| s.usable)
        };
        let Some(subset) = subset else {
            if self.fit.is_some() {
                return false;
            }
            out.normals.fill(Vec3::ZERO);
            out.albedo.fill(0.0);
            out.confidence.fill(0.0);
            stats.lights_used[used] += fused::STEP;
            stats.invalid_count += fused::STEP;
            return true;
        };
        let sk = fused::SubsetKernel {
            bits,
            cols: &subset.cols,
            gains: &self.gray_scales,
            gram: subset.gram,
            weight: self.subset_weight(used, subset),
            gate: self.fit.as_ref().map_or(0.0, |f| f.gate),
        };
        let (invalid, disagree) = fused::subset_step(&sk, rows, p, out.normals, out.albedo, out.confidence);
        if self.fit.is_some() && disagree != 0 {
            return false;
        }
        stats.lights_used[used] += fused::STEP;
        stats.invalid_count += invalid as usize;
        true
    }

    /// The bitmask of usable lights of pixel `j` (robust mode, after [`Self::count_dropped`]).
    pub(in crate::solve) fn usable_bits(&self, j: usize, s: &Scratch) -> u128 {
        let threshold = s.top[j];
        (0..self.k).fold(0u128, |bits, i| {
            let ok = s.r[i * CHUNK + j] >= threshold && s.sat[i * CHUNK + j] == 0;
            bits | ((ok as u128) << i)
        })
    }

    /// Normal, albedo, confidence and lights used for pixel `j`, solved from its usable lights,
    /// and the residual factor of that fit (0 when invalid) that [`super::fit::Fit::agrees`] tests.
    pub(in crate::solve) fn finish_subset(
        &self,
        j: usize,
        s: &Scratch,
        subsets: &Subsets,
        local: &mut HashMap<u128, SubsetSolve>,
    ) -> ((Vec3, Vec3, f32, usize), f32) {
        let invalid = |used| ((Vec3::ZERO, Vec3::ZERO, 0.0, used), 0.0);
        let bits = self.usable_bits(j, s);
        let used = bits.count_ones() as usize;
        if used < self.config.min_lights {
            return invalid(used);
        }
        let subset = subsets.get(bits, local);
        if !subset.usable {
            return invalid(used);
        }
        let (g, rr) = self.solve_subset(j, bits, subset, s);
        let len = Vec3::from(g).length();
        if !readings::defines_normal(len) {
            return invalid(used);
        }
        let normal = Vec3::from(g) / len;
        let factor = residual_factor(rr, subset.fitted_sq(g));
        let confidence = self.subset_weight(used, subset) * factor;
        let albedo = if self.rgb { self.rgb_albedo(j, bits, normal, s) } else { Vec3::splat(len) };
        ((normal, albedo, confidence, used), factor)
    }

    /// [`Self::finish_subset`] for the `count` pixels listed in `s.pending` (robust, at most
    /// [`DENSE_MAX_LIGHTS`](crate::solve::DENSE_MAX_LIGHTS) lights, `s.bits` filled), written to `out`: the pixels are grouped by
    /// their subset (usually one or two per chunk, as shadows are coherent) and each group is
    /// solved with that subset's columns in registers, in the same operations and order as
    /// [`Self::solve_subset`], so the bits match the per-pixel path. With
    /// [`Method::Robust`](crate::solve::Method::Robust), the pixels whose subset fit
    /// [`super::fit::Fit::agrees`] rejects are then fitted one at a time.
    pub(in crate::solve) fn finish_subsets<A: AlbedoTexel>(
        &self,
        mut count: usize,
        s: &mut Scratch,
        subsets: &Subsets,
        local: &mut HashMap<u128, SubsetSolve>,
        out: &mut Out<A>,
        stats: &mut SolveStats,
    ) {
        while count > 0 {
            let bits = s.bits[s.pending[0] as usize];
            // Split the pending pixels into this subset's group and the rest (kept in place:
            // the rest's write index never passes the read index).
            let (mut grouped, mut rest) = (0, 0);
            for t in 0..count {
                let j = s.pending[t];
                if s.bits[j as usize] == bits {
                    s.group[grouped] = j;
                    grouped += 1;
                } else {
                    s.pending[rest] = j;
                    rest += 1;
                }
            }
            let refits = s.refits;
            self.solve_group(bits, grouped, s, subsets, local, out);
            stats.lights_used[bits.count_ones() as usize] += grouped - (s.refits - refits);
            count = rest;
        }
        let Some(fit) = &self.fit else { return };
        for t in 0..std::mem::take(&mut s.refits) {
            let j = s.refit[t] as usize;
            let (normal, albedo, confidence, used) = self.finish_fit(fit, j, s, subsets);
            stats.lights_used[used] += 1;
            out.normals[j] = normal;
            out.albedo[j] = A::rgb(albedo);
            out.confidence[j] = confidence;
        }
    }

    /// Solves the `m` pixels of `s.group`, whose usable lights are `bits`, into `out`; with a
    /// robust fit, lists those whose fit does not agree in `s.refit`.
    pub(in crate::solve) fn solve_group<A: AlbedoTexel>(
        &self,
        bits: u32,
        m: usize,
        s: &mut Scratch,
        subsets: &Subsets,
        local: &mut HashMap<u128, SubsetSolve>,
        out: &mut Out<A>,
    ) {
        let used = bits.count_ones() as usize;
        let subset = if used < self.config.min_lights { None } else { Some(subsets.get(bits as u128, local)) };
        let Some(subset) = subset.filter(|s| s.usable) else {
            for t in 0..m {
                let j = s.group[t] as usize;
                (out.normals[j], out.albedo[j], out.confidence[j]) = (Vec3::ZERO, A::ZERO, 0.0);
                if self.fit.is_some() {
                    s.refit[s.refits] = j as u8;
                    s.refits += 1;
                }
            }
            return;
        };
        {
            let Scratch { r, group, bx, by, bz, brr, .. } = &mut *s;
            let group = &group[..m];
            let (gx, gy, gz, rr) = (&mut bx[..m], &mut by[..m], &mut bz[..m], &mut brr[..m]);
            gx.fill(0.0);
            gy.fill(0.0);
            gz.fill(0.0);
            rr.fill(0.0);
            let lights = (0..self.k).filter(|i| bits >> i & 1 == 1);
            for (i, c) in lights.zip(&subset.cols) {
                let row: &[f32; CHUNK] = r[i * CHUNK..(i + 1) * CHUNK].try_into().expect("CHUNK readings per light");
                for t in 0..m {
                    // `& (CHUNK - 1)`: a no-op (pixels index a chunk) that drops the bounds check.
                    let v = row[group[t] as usize & (CHUNK - 1)];
                    gx[t] += c[0] * v;
                    gy[t] += c[1] * v;
                    gz[t] += c[2] * v;
                    rr[t] += v * v;
                }
            }
        }
        let weight = self.subset_weight(used, subset);
        for t in 0..m {
            let j = s.group[t] as usize;
            let g = [s.bx[t], s.by[t], s.bz[t]];
            let len = Vec3::from(g).length();
            let (normal, albedo, confidence, factor) = if readings::defines_normal(len) {
                let normal = Vec3::from(g) / len;
                let factor = residual_factor(s.brr[t], subset.fitted_sq(g));
                let albedo = if self.rgb { self.rgb_albedo(j, bits as u128, normal, s) } else { Vec3::splat(len) };
                (normal, albedo, weight * factor, factor)
            } else {
                (Vec3::ZERO, Vec3::ZERO, 0.0, 0.0)
            };
            if self.fit.as_ref().is_some_and(|f| !f.agrees(factor)) {
                s.refit[s.refits] = j as u8;
                s.refits += 1;
            }
            out.normals[j] = normal;
            out.albedo[j] = A::rgb(albedo);
            out.confidence[j] = confidence;
        }
    }

    /// The confidence factors of a pixel solved from `used` lights forming `subset`: the
    /// fraction of lights used times `min(1, cond(L_all) / cond(L_used))`.
    pub(in crate::solve) fn subset_weight(&self, used: usize, subset: &SubsetSolve) -> f32 {
        used as f32 / self.k as f32 * (self.full.condition / subset.condition).min(1.0) as f32
    }

    pub(in crate::solve) fn full_bits(&self) -> u128 {
        crate::solve::all_lights(self.k)
    }

    /// `g = P_S r_S` and `sum r_S^2` for pixel `j` over the lights in `bits`.
    pub(in crate::solve) fn solve_subset(
        &self,
        j: usize,
        bits: u128,
        subset: &SubsetSolve,
        s: &Scratch,
    ) -> ([f32; 3], f32) {
        let (mut g, mut rr) = ([0.0f32; 3], 0.0f32);
        let used = (0..self.k).filter(|i| bits >> i & 1 == 1);
        for (i, c) in used.zip(&subset.cols) {
            let v = s.r[i * CHUNK + j];
            g = [g[0] + c[0] * v, g[1] + c[1] * v, g[2] + c[2] * v];
            rr += v * v;
        }
        (g, rr)
    }

    /// Per-channel least-squares albedo `sum r_ci d_i / sum d_i^2`, `d_i = n . L_i`, over `bits`.
    pub(in crate::solve) fn rgb_albedo(&self, j: usize, bits: u128, normal: Vec3, s: &Scratch) -> Vec3 {
        let (mut num, mut den) = (Vec3::ZERO, 0.0f32);
        for (i, l) in self.lights.iter().enumerate().filter(|(i, _)| bits >> i & 1 == 1) {
            let d = normal.dot(*l);
            num += Vec3::from(s.rgb[i * CHUNK + j]) * d;
            den += d * d;
        }
        if den > 0.0 { (num / den).max(Vec3::ZERO) } else { Vec3::ZERO }
    }
}
