//! Removal of a mold's low-frequency tilt (Haro et al. 2001, section 3).
//!
//! Molds are not flat (those from the nose least of all), so their normals carry a slowly varying
//! tilt that bump mapping must not see. The paper computes "the average normal over a 50 by 50
//! pixel block centered at each pixel", finds the rotation mapping that mean back to the
//! perpendicular of the map plane (+Z) and applies it to the pixel's normal.
//!
//! *Centred* block: a block of `block` texels has `half = block / 2` texels on each side of the
//! centre, so the window is `2 * half + 1` wide (block 50 and block 51 both average 51 x 51
//! texels, exactly centred). Near the borders the window is the part of it inside the map.
//! Invalid texels (`(0, 0, 0)`) stay invalid and are left out of the means. Where the mean
//! vanishes (no valid texel, or normals that cancel: `|sum| < 1e-6 * count`) the normal is left
//! unchanged.
//!
//! Cost does not grow with the block: block sums come from separable running sums. The image is
//! cut into a few bands of rows processed in parallel; each band keeps, per column, the sum over
//! the rows of its window (updated by one entering and one leaving row per output row), slides a
//! window along that row of column sums, and rotates the row's normals, so everything a row needs
//! is in cache. The sums are exact integers (normals in fixed point, `2^-29` steps, well below f32
//! resolution near unit length), so they do not depend on the order of the updates: results are
//! bitwise identical whatever the banding or the thread count. Extra memory: the output map
//! (12 bytes a texel, 192 MiB for 4096 x 4096) and a few rows of sums per band.

use glam::{DMat3, DVec3, Vec3};
use rayon::prelude::*;
use skinkit_maps::NormalMap;

use crate::solve::fresh_zeroed_vec3;

/// A mean whose length is below this fraction of the texel count counts as vanishing.
const VANISHING: f64 = 1e-6;
/// Fixed-point scale of the normal components in the block sums (`|n| <= 1` fits an `i32`).
const FIXED: f32 = (1u32 << 29) as f32;
/// Parallel bands per worker thread (each band first sums the rows above its first row).
const BANDS_PER_THREAD: usize = 2;
/// Fewest rows in a band.
const MIN_BAND_ROWS: usize = 16;

/// Rotates every valid normal by the rotation taking the mean normal of the `block`-wide window
/// centred on it to +Z. `block == 0` leaves the map unchanged.
///
/// # Example
/// ```
/// use skinkit_maps::{NormalMap, Grid, Vec3};
/// let tilted = Vec3::new(0.3, -0.2, 0.9).normalize();
/// let mut map = NormalMap::from_grid(Grid::filled(8, 8, tilted));
/// skinkit_capture::detrend::detrend(&mut map, 50);
/// assert!((map.get(3, 4) - Vec3::Z).length() < 1e-6);
/// ```
pub fn detrend(normals: &mut NormalMap, block: usize) {
    if block == 0 || normals.as_slice().is_empty() {
        return;
    }
    let half = block / 2;
    let (w, h) = normals.size();
    let input = normals.as_slice();
    let bands = rayon::current_num_threads() * BANDS_PER_THREAD;
    let band_rows = h.div_ceil(bands).max(MIN_BAND_ROWS);
    let mut output = fresh_zeroed_vec3(w * h);
    output
        .par_chunks_mut(band_rows * w)
        .enumerate()
        .for_each(|(b, out)| detrend_band(input, w, h, b * band_rows, out, half));
    let grid = skinkit_maps::Grid::from_vec(w, h, output).expect("sized above");
    *normals = NormalMap::from_unit_grid(grid).expect("rotations keep normals unit");
}

/// One texel's contribution to the block sums: fixed-point normal and a count (zero if invalid).
#[inline(always)]
fn fixed(n: Vec3) -> [i64; 4] {
    if n == Vec3::ZERO {
        [0; 4]
    } else {
        // Truncation is odd-symmetric, so opposite normals cancel exactly.
        [(n.x * FIXED) as i32 as i64, (n.y * FIXED) as i32 as i64, (n.z * FIXED) as i32 as i64, 1]
    }
}

/// Adds (`ADD`) or subtracts one input row's fixed-point terms to the column sums.
#[inline(always)]
fn update_columns<const ADD: bool>(cols: &mut [[i64; 4]], row: &[Vec3]) {
    for (c, &n) in cols.iter_mut().zip(row) {
        let t = fixed(n);
        for (a, v) in c.iter_mut().zip(t) {
            if ADD { *a += v } else { *a -= v }
        }
    }
}

/// Detrends the rows `y0..` of `out` (whole rows) from `input` (the full `w x h` map), with the
/// AVX2 build where the CPU has it (the arithmetic has no fused operations, so the same bits).
fn detrend_band(input: &[Vec3], w: usize, h: usize, y0: usize, out: &mut [Vec3], half: usize) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, the feature `detrend_band_avx2` is compiled for.
        return unsafe { detrend_band_avx2(input, w, h, y0, out, half) };
    }
    detrend_band_portable(input, w, h, y0, out, half)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn detrend_band_avx2(input: &[Vec3], w: usize, h: usize, y0: usize, out: &mut [Vec3], half: usize) {
    detrend_band_portable(input, w, h, y0, out, half)
}

/// Block sums of one row, structure of arrays: components (unscaled) and counts.
struct RowSums {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    count: Vec<f64>,
}

#[inline(always)]
fn detrend_band_portable(input: &[Vec3], w: usize, h: usize, y0: usize, out: &mut [Vec3], half: usize) {
    let row = |y: usize| &input[y * w..(y + 1) * w];
    let mut cols = vec![[0i64; 4]; w];
    let mut sums = RowSums { x: vec![0.0; w], y: vec![0.0; w], z: vec![0.0; w], count: vec![0.0; w] };
    for y in y0.saturating_sub(half)..(y0 + half + 1).min(h) {
        update_columns::<true>(&mut cols, row(y));
    }
    for (dy, out_row) in out.chunks_mut(w).enumerate() {
        let y = y0 + dy;
        if dy > 0 {
            if y + half < h {
                update_columns::<true>(&mut cols, row(y + half));
            }
            if y > half {
                update_columns::<false>(&mut cols, row(y - half - 1));
            }
        }
        slide_row(&cols, &mut sums, half);
        rotate_row(row(y), &sums, out_row);
    }
}

/// Slides the window along one row of column sums: the block sums of every texel of the row.
#[inline(always)]
fn slide_row(cols: &[[i64; 4]], sums: &mut RowSums, half: usize) {
    let w = cols.len();
    let mut acc = [0i64; 4];
    for c in &cols[..(half + 1).min(w)] {
        acc = std::array::from_fn(|i| acc[i] + c[i]);
    }
    let scale = 1.0 / FIXED as f64;
    for x in 0..w {
        sums.x[x] = acc[0] as f64 * scale;
        sums.y[x] = acc[1] as f64 * scale;
        sums.z[x] = acc[2] as f64 * scale;
        sums.count[x] = acc[3] as f64;
        if x + half + 1 < w {
            let c = cols[x + half + 1];
            acc = std::array::from_fn(|i| acc[i] + c[i]);
        }
        if x >= half {
            let c = cols[x - half];
            acc = std::array::from_fn(|i| acc[i] - c[i]);
        }
    }
}

/// Rotates one row's normals by their block means ([`rotate_by_mean`] without branches, so the
/// loop vectorises; the selects keep NaN from the unused branch out of the result).
#[inline(always)]
fn rotate_row(row: &[Vec3], sums: &RowSums, out: &mut [Vec3]) {
    let it = row.iter().zip(out.iter_mut()).zip(&sums.x).zip(&sums.y).zip(&sums.z).zip(&sums.count);
    for (((((&n, o), &sx), &sy), &sz), &count) in it {
        let nd = n.as_dvec3();
        let len = (sx * sx + sy * sy + sz * sz).sqrt();
        let keep = n == Vec3::ZERO || count < 0.5 || len <= VANISHING * count;
        let inv = 1.0 / len;
        let m = DVec3::new(sx * inv, sy * inv, sz * inv);
        let d = m.x * nd.x + m.y * nd.y;
        let t = d / (1.0 + m.z) + nd.z;
        let rotated = DVec3::new(nd.x - m.x * t, nd.y - m.y * t, d + m.z * nd.z);
        let flipped = DVec3::new(nd.x, -nd.y, -nd.z);
        let r = if m.z < -1.0 + 1e-12 { flipped } else { rotated };
        *o = if keep { n } else { r.as_vec3() };
    }
}

/// The texel's contribution to a block sum in floating point (zero for an invalid texel).
#[cfg(test)]
fn term(n: Vec3) -> [f64; 4] {
    if n == Vec3::ZERO { [0.0; 4] } else { [n.x as f64, n.y as f64, n.z as f64, 1.0] }
}

#[cfg(test)]
fn add(acc: &mut [f64; 4], t: [f64; 4], sign: f64) {
    for (a, v) in acc.iter_mut().zip(t) {
        *a += sign * v;
    }
}

/// `n` rotated by the rotation taking the block mean (from its sums) to +Z (the oracle of
/// [`rotate_row`]).
#[cfg(test)]
fn rotate_by_mean(n: Vec3, sum: &[f64; 4]) -> Vec3 {
    let s = DVec3::new(sum[0], sum[1], sum[2]);
    let len = s.length();
    if n == Vec3::ZERO || sum[3] < 0.5 || len <= VANISHING * sum[3] {
        return n;
    }
    rotate_to_z(s / len, n.as_dvec3()).as_vec3()
}

#[cfg(test)]
/// `rotation_to_z(m) * n` without forming the matrix: with `d = mx nx + my ny` and
/// `t = d / (1 + mz) + nz`, the rows of [`rotation_to_z`] give `(nx - mx t, ny - my t, d + mz nz)`.
#[inline(always)]
fn rotate_to_z(m: DVec3, n: DVec3) -> DVec3 {
    if m.z < -1.0 + 1e-12 {
        return DVec3::new(n.x, -n.y, -n.z);
    }
    let d = m.x * n.x + m.y * n.y;
    let t = d / (1.0 + m.z) + n.z;
    DVec3::new(n.x - m.x * t, n.y - m.y * t, d + m.z * n.z)
}

/// The rotation taking the unit vector `m` to +Z about the axis `m x z` (no trigonometry):
/// `R = [[1 - mx^2/(1+mz), -mx my/(1+mz), -mx], [-mx my/(1+mz), 1 - my^2/(1+mz), -my], [mx, my, mz]]`
/// (rows). When `m` is (nearly) `-Z` the axis is undefined and a half turn about x is used.
pub fn rotation_to_z(m: DVec3) -> DMat3 {
    if m.z < -1.0 + 1e-12 {
        return DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0));
    }
    let k = 1.0 / (1.0 + m.z);
    let xy = -m.x * m.y * k;
    DMat3::from_cols(
        DVec3::new(1.0 - m.x * m.x * k, xy, m.x),
        DVec3::new(xy, 1.0 - m.y * m.y * k, m.y),
        DVec3::new(-m.x, -m.y, m.z),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use skinkit_maps::Grid;

    fn tilt(degrees: f32, azimuth: f32) -> Vec3 {
        let (t, a) = (degrees.to_radians(), azimuth.to_radians());
        Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos())
    }

    #[test]
    fn rotation_maps_mean_to_z_and_is_orthonormal() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..200 {
            let m = DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
                .normalize();
            let r = rotation_to_z(m);
            assert!((r * m - DVec3::Z).length() < 1e-9, "{m}");
            assert!((r.transpose() * r - DMat3::IDENTITY).to_cols_array().iter().all(|v| v.abs() < 1e-9));
            assert!((r.determinant() - 1.0).abs() < 1e-9);
        }
        let r = rotation_to_z(-DVec3::Z);
        assert_eq!(r * -DVec3::Z, DVec3::Z);
        // The matrix-free product used per texel is the same rotation.
        for _ in 0..200 {
            let mut v = || {
                DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
                    .normalize()
            };
            let (m, n) = (v(), v());
            assert!((rotate_to_z(m, n) - rotation_to_z(m) * n).length() < 1e-12);
        }
        assert_eq!(rotate_to_z(-DVec3::Z, DVec3::X), rotation_to_z(-DVec3::Z) * DVec3::X);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn tilted_planes_come_out_flat() {
        for (deg, az) in [(5.0, 0.0), (20.0, 130.0), (45.0, 250.0), (60.0, 33.0), (89.0, 90.0)] {
            let mut map = NormalMap::from_grid(Grid::filled(37, 23, tilt(deg, az)));
            detrend(&mut map, 50);
            for n in map.as_slice() {
                assert!((*n - Vec3::Z).length() < 1e-6, "tilt {deg}: {n}");
            }
        }
    }

    /// Brute-force block mean and rotation, the oracle for the running sums.
    fn brute(map: &NormalMap, block: usize) -> Vec<Vec3> {
        let (w, h) = map.size();
        let half = block / 2;
        let mut out = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0.0f64; 4];
                for yy in y.saturating_sub(half)..(y + half + 1).min(h) {
                    for xx in x.saturating_sub(half)..(x + half + 1).min(w) {
                        add(&mut sum, term(map.get(xx, yy)), 1.0);
                    }
                }
                out.push(rotate_by_mean(map.get(x, y), &sum));
            }
        }
        out
    }

    fn random_map(w: usize, h: usize, seed: u64) -> NormalMap {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let data = (0..w * h)
            .map(|_| {
                if rng.random_bool(0.2) {
                    Vec3::ZERO
                } else {
                    tilt(rng.random_range(0.0..50.0), rng.random_range(0.0..360.0))
                }
            })
            .collect();
        NormalMap::from_vec(w, h, data).unwrap()
    }

    #[test]
    fn running_sums_match_brute_force() {
        for (w, h, block) in [(70, 45, 9), (70, 45, 10), (130, 17, 1), (33, 80, 31), (5, 4, 200)] {
            let map = random_map(w, h, (w * h + block) as u64);
            let expected = brute(&map, block);
            let mut got = map.clone();
            detrend(&mut got, block);
            for (i, (a, b)) in got.as_slice().iter().zip(&expected).enumerate() {
                assert_eq!(*a == Vec3::ZERO, *b == Vec3::ZERO, "texel {i}");
                assert!((*a - *b).length() < 1e-5, "{w}x{h} block {block} texel {i}: {a} vs {b}");
            }
            assert_eq!(got.valid_count(), map.valid_count());
        }
    }

    #[test]
    fn results_do_not_depend_on_thread_count() {
        let map = random_map(57, 300, 11);
        let with = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut m = map.clone();
            pool.install(|| detrend(&mut m, 40));
            m.as_slice().iter().flat_map(|v| v.to_array()).map(f32::to_bits).collect::<Vec<u32>>()
        };
        let one = with(1);
        assert_eq!(one, with(3));
        assert_eq!(one, with(8));
    }

    #[test]
    fn degenerate_maps() {
        let mut empty = NormalMap::from_grid(Grid::filled(6, 5, Vec3::ZERO));
        detrend(&mut empty, 50);
        assert_eq!(empty.valid_count(), 0);
        let mut one = NormalMap::from_grid(Grid::filled(1, 1, tilt(30.0, 10.0)));
        detrend(&mut one, 50);
        assert!((one.get(0, 0) - Vec3::Z).length() < 1e-6);
        let mut untouched = random_map(9, 9, 3);
        let before = untouched.clone();
        detrend(&mut untouched, 0);
        assert_eq!(untouched, before);
        // Two opposite normals cancel: the mean vanishes and both stay as they were.
        let a = tilt(80.0, 0.0);
        let b = Vec3::new(-a.x, -a.y, -a.z);
        let mut cancel = NormalMap::from_vec(2, 1, vec![a, b]).unwrap();
        detrend(&mut cancel, 10);
        assert!((cancel.get(0, 0) - a).length() < 1e-7 && (cancel.get(1, 0) - b).length() < 1e-7);
    }

    /// Normals of the height field `z(x, y)` sampled by central differences (row index against y).
    fn normals_of(w: usize, h: usize, z: impl Fn(f64, f64) -> f64 + Sync) -> NormalMap {
        let grid = Grid::from_fn(w, h, |x, y| {
            let (x, y) = (x as f64, -(y as f64));
            let e = 1e-3;
            let dx = (z(x + e, y) - z(x - e, y)) / (2.0 * e);
            let dy = (z(x, y + e) - z(x, y - e)) / (2.0 * e);
            DVec3::new(-dx, -dy, 1.0).normalize().as_vec3()
        });
        NormalMap::from_grid(grid)
    }

    fn detail(x: f64, y: f64) -> f64 {
        0.12 * ((x * 0.9).sin() * (y * 0.7).cos() + 0.5 * (0.5 * x + 1.3 * y).sin())
    }

    /// Error of `field` against the detail-only field, both detrended, away from the borders.
    fn detail_error(mut field: NormalMap, block: usize) -> skinkit_maps::normal::AngularStats {
        let (w, h) = field.size();
        let mut only = normals_of(w, h, detail);
        detrend(&mut field, block);
        detrend(&mut only, block);
        let interior = Grid::from_fn(w, h, |x, y| (25..w - 25).contains(&x) && (25..h - 25).contains(&y));
        field.angular_error(&only, Some(&interior)).unwrap()
    }

    #[test]
    fn recovers_fine_detail_of_a_rigidly_tilted_mold() {
        // Skin-like bumps (slopes up to ~10 deg) on a mold tilted rigidly by 60 deg: every normal
        // turns by the same rotation, which detrend undoes up to a second-order twist about z.
        let (w, h) = (160, 120);
        let tilt_rotation = DMat3::from_axis_angle(DVec3::new(0.6, 0.8, 0.0), 60f64.to_radians());
        let tilted = normals_of(w, h, detail).grid().map(|n| (tilt_rotation * n.as_dvec3()).as_vec3());
        let stats = detail_error(NormalMap::from_grid(tilted), 50);
        println!("rigid 60 deg tilt: detail error mean {:.4} max {:.4} deg", stats.mean, stats.max);
        assert!(stats.mean < 0.01 && stats.max < 0.05, "{stats:?}");
    }

    #[test]
    fn recovers_fine_detail_under_height_tilt_and_bulge() {
        // A 42 deg height ramp plus a dome (radius of curvature 1000 texels) added to the bumps.
        // Adding a ramp to a height shears the bumps' normals rather than rotating them, by about
        // slope * (1 - cos tilt) ~ 2 deg here, and the dome bends the block mean; both stay small
        // against the 42 deg removed.
        let (w, h) = (160, 120);
        let base = |x: f64, y: f64| 0.84 * x - 0.3 * y + ((x - 80.0).powi(2) + (y + 60.0).powi(2)) / 2000.0;
        let field = normals_of(w, h, |x, y| base(x, y) + detail(x, y));
        let before = field.angular_error(&normals_of(w, h, detail), None).unwrap();
        let stats = detail_error(field, 50);
        println!(
            "height tilt: detail error before {:.2}, after mean {:.3} max {:.3} deg",
            before.mean, stats.mean, stats.max
        );
        assert!(before.mean > 35.0);
        assert!(stats.mean < 2.0 && stats.max < 4.0, "{stats:?}");
    }
}
