//! The pre-integrated tables (`skin::lut`, `skin::shadow`) and their files against independent
//! oracles: adaptive Simpson quadrature of equation 1.1 and of the shadow convolution over the
//! whole profile (`Profile::eval`, `Profile::marginal`), split at the clamp's kinks and around
//! each Gaussian's width, and closed forms at the limits (flat skin, very curved skin, w = 0).
//!
//! Over 600 lines: the quadrature oracles (adaptive Simpson with its split points) are written
//! here independently of the crate, and every table and file format is checked against them.

use std::f64::consts::{FRAC_PI_2, PI};

use skinkit_render::skin::lut::{DiffuseLut, DiffuseLutSpec, SpecError};
use skinkit_render::skin::lut_file::{self, LutAttribute, LutFileError};
use skinkit_render::skin::profile::{Domain, Normalisation, Profile, VARIANCES_MM2, WEIGHTS};
use skinkit_render::skin::shadow::{MAX_PENUMBRA_MM, ShadowLut, ShadowLutSpec};

// ---------------------------------------------------------------------------------------------
// The oracle: adaptive Simpson on vector integrands.

/// `int_a^b f` per component by adaptive Simpson to absolute tolerance `tol`.
fn simpson<const N: usize>(f: &impl Fn(f64) -> [f64; N], a: f64, b: f64, tol: f64) -> [f64; N] {
    let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
    let whole = simpson_rule(a, b, &fa, &fm, &fb);
    simpson_step(f, a, b, fa, fm, fb, whole, tol, 48)
}

fn simpson_rule<const N: usize>(a: f64, b: f64, fa: &[f64; N], fm: &[f64; N], fb: &[f64; N]) -> [f64; N] {
    std::array::from_fn(|k| (b - a) / 6.0 * (fa[k] + 4.0 * fm[k] + fb[k]))
}

#[allow(clippy::too_many_arguments)]
fn simpson_step<const N: usize>(
    f: &impl Fn(f64) -> [f64; N],
    a: f64,
    b: f64,
    fa: [f64; N],
    fm: [f64; N],
    fb: [f64; N],
    whole: [f64; N],
    tol: f64,
    depth: u32,
) -> [f64; N] {
    let m = 0.5 * (a + b);
    let (flm, frm) = (f(0.5 * (a + m)), f(0.5 * (m + b)));
    let left = simpson_rule(a, m, &fa, &flm, &fm);
    let right = simpson_rule(m, b, &fm, &frm, &fb);
    let err = (0..N).map(|k| (left[k] + right[k] - whole[k]).abs()).fold(0.0, f64::max);
    if depth == 0 || err <= 15.0 * tol {
        return std::array::from_fn(|k| left[k] + right[k] + (left[k] + right[k] - whole[k]) / 15.0);
    }
    let l = simpson_step(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1);
    let r = simpson_step(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1);
    std::array::from_fn(|k| l[k] + r[k])
}

/// `int f` over `[lo, hi]` split at `breaks` (those inside), each piece adaptively.
fn piecewise<const N: usize>(f: &impl Fn(f64) -> [f64; N], lo: f64, hi: f64, breaks: &[f64], tol: f64) -> [f64; N] {
    let mut points: Vec<f64> = breaks.iter().copied().filter(|&b| b > lo && b < hi).collect();
    points.extend([lo, hi]);
    points.sort_by(f64::total_cmp);
    points.dedup();
    let mut sum = [0.0; N];
    for pair in points.windows(2) {
        let piece = simpson(f, pair[0], pair[1], tol);
        for k in 0..N {
            sum[k] += piece[k];
        }
    }
    sum
}

/// Breakpoints at a few multiples of each Gaussian's width `sqrt(v) * scale` about 0.
fn gaussian_breaks(scale: f64) -> Vec<f64> {
    let mut b = vec![0.0];
    for v in VARIANCES_MM2 {
        for m in [0.5, 1.0, 2.0, 4.0, 8.0] {
            b.extend([m * v.sqrt() * scale, -m * v.sqrt() * scale]);
        }
    }
    b
}

/// Equation 1.1 by adaptive quadrature of the whole profile along the ring.
fn diffuse_oracle(normalisation: Normalisation, domain: Domain, n_dot_l: f64, inv_r: f64) -> [f64; 3] {
    if inv_r == 0.0 {
        return [n_dot_l.max(0.0); 3];
    }
    let profile = Profile::new(normalisation);
    let theta = n_dot_l.clamp(-1.0, 1.0).acos();
    let r = 1.0 / inv_r;
    let f = |x: f64| {
        let weight = profile.eval(2.0 * r * (0.5 * x).sin());
        let cosine = (theta + x).cos().max(0.0);
        [cosine * weight[0], cosine * weight[1], cosine * weight[2], weight[0], weight[1], weight[2]]
    };
    let half = domain.half_extent();
    let mut breaks = gaussian_breaks(inv_r);
    breaks.extend([-FRAC_PI_2 - theta, FRAC_PI_2 - theta, 3.0 * FRAC_PI_2 - theta]);
    // Tolerance relative to the denominator's scale (the kernel's peak times its width).
    let peak = profile.eval(0.0);
    let scale = peak.iter().fold(f64::INFINITY, |m, &p| m.min(p)) * (VARIANCES_MM2[0].sqrt() * inv_r).min(half);
    let sums = piecewise(&f, -half, half, &breaks, 1e-10 * scale);
    std::array::from_fn(|c| sums[c] / sums[c + 3])
}

/// The lit share of a unit disc whose centre is `t` radii from a straight edge (lit side `t > 0`),
/// by quadrature of the chord lengths (`x = sin(phi)`, so the integrand is smooth).
fn disc_share(t: f64) -> f64 {
    let chord = |phi: f64| [2.0 * phi.cos() * phi.cos()];
    let half_pi = std::f64::consts::FRAC_PI_2;
    piecewise(&chord, (-t.clamp(-1.0, 1.0)).asin(), half_pi, &[], 1e-13)[0] / std::f64::consts::PI
}

/// `P_S(s, w)` by adaptive quadrature of the ramp against the profile's marginal, the edge found
/// from the disc's share by bisection, the ends stretched to 0 and 1.
fn shadow_oracle(s: f64, w: f64, new_penumbra: f64) -> [f64; 3] {
    let (lo, hi, p) =
        (shadow_raw(0.0, w, new_penumbra), shadow_raw(1.0, w, new_penumbra), shadow_raw(s, w, new_penumbra));
    std::array::from_fn(|c| if hi[c] - lo[c] > 1e-9 { (p[c] - lo[c]) / (hi[c] - lo[c]) } else { p[c] })
}

fn shadow_raw(s: f64, w: f64, new_penumbra: f64) -> [f64; 3] {
    let profile = Profile::default();
    let (mut t0, mut t1) = (-1.0f64, 1.0f64);
    for _ in 0..50 {
        let mid = 0.5 * (t0 + t1);
        if disc_share(mid) < s { t0 = mid } else { t1 = mid }
    }
    let y = 0.5 * (t0 + t1) * 0.5 * w;
    let a = new_penumbra * w;
    let ramp = |z: f64| {
        if a > 0.0 {
            (0.5 + z / a).clamp(0.0, 1.0)
        } else if z > 0.0 {
            1.0
        } else {
            0.0
        }
    };
    let f = |x: f64| {
        let m = profile.marginal(x);
        let p = ramp(y + x);
        [p * m[0], p * m[1], p * m[2], m[0], m[1], m[2]]
    };
    let mut breaks = gaussian_breaks(1.0);
    breaks.extend([-0.5 * a - y, 0.5 * a - y, -y]);
    let reach = 9.0 * VARIANCES_MM2[5].sqrt();
    let sums = piecewise(&f, -reach - y.abs() - a, reach + y.abs() + a, &breaks, 1e-12);
    std::array::from_fn(|c| sums[c] / sums[c + 3])
}

// ---------------------------------------------------------------------------------------------
// Helpers.

fn configs() -> [(Normalisation, Domain); 4] {
    [
        (Normalisation::TwoD, Domain::Full),
        (Normalisation::TwoD, Domain::Half),
        (Normalisation::OneD, Domain::Full),
        (Normalisation::OneD, Domain::Half),
    ]
}

/// [`configs`] and the sphere, for the checks that need no ring oracle.
fn every_domain() -> Vec<(Normalisation, Domain)> {
    let mut all = configs().to_vec();
    all.extend([(Normalisation::TwoD, Domain::Sphere), (Normalisation::OneD, Domain::Sphere)]);
    all
}

fn diffuse_spec(size: u32, normalisation: Normalisation, domain: Domain) -> DiffuseLutSpec {
    DiffuseLutSpec { width: size, height: size, normalisation, domain, ..DiffuseLutSpec::default() }
}

/// Largest |texel - oracle| over the texels `(i, j)` picked by `every`.
fn diffuse_error(lut: &DiffuseLut, every: u32) -> f64 {
    let s = lut.spec;
    let mut worst = 0.0f64;
    for j in (0..s.height).step_by(every as usize).chain([s.height - 1]) {
        for i in (0..s.width).step_by(every as usize).chain([0, s.width - 1]) {
            let want = diffuse_oracle(s.normalisation, s.domain, f64::from(s.n_dot_l_at(i)), f64::from(s.inv_r_at(j)));
            let got = lut.texel(i, j);
            for c in 0..3 {
                worst = worst.max((f64::from(got[c]) - want[c]).abs());
            }
        }
    }
    worst
}

fn assert_monotonic_rows(texels: &[[f32; 3]], width: u32, what: &str) {
    for (j, row) in texels.chunks(width as usize).enumerate() {
        for (i, pair) in row.windows(2).enumerate() {
            for (c, (before, after)) in pair[0].iter().zip(pair[1]).enumerate() {
                assert!(
                    after >= before - 1e-7,
                    "{what}: row {j}, channel {c} decreases from column {i} ({before}) to {} ({after})",
                    i + 1
                );
            }
        }
    }
}

fn assert_unit_range(v: [f32; 3], what: &str) {
    for c in v {
        assert!(c.is_finite() && (0.0..=1.0).contains(&c), "{what}: {v:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// The diffuse table.

#[test]
fn profile_weights_sum_to_one_per_channel() {
    for c in 0..3 {
        let sum: f64 = WEIGHTS.iter().map(|w| w[c]).sum();
        assert!((sum - 1.0).abs() < 1e-12, "channel {c} sums to {sum}");
    }
}

#[test]
fn the_oracle_is_equation_1_1_as_profile_defines_it() {
    // Where the kernel is wide (r = 1 mm), main's midpoint ring integral converges well: the two
    // definitions must agree.
    for (normalisation, domain) in configs() {
        for n_dot_l in [-1.0, -0.4, 0.0, 0.3, 1.0] {
            let profile = Profile::new(normalisation);
            let want = skinkit_render::skin::profile::ring_integral(&profile, domain, n_dot_l, 1.0, 200_000);
            let got = diffuse_oracle(normalisation, domain, n_dot_l, 1.0);
            for c in 0..3 {
                assert!((got[c] - want[c]).abs() < 1e-6, "{n_dot_l}: {got:?} vs {want:?}");
            }
        }
    }
}

#[test]
fn diffuse_matches_quadrature_over_the_whole_table() {
    for (normalisation, domain) in configs() {
        let lut = DiffuseLut::build(&diffuse_spec(64, normalisation, domain)).unwrap();
        let err = diffuse_error(&lut, 1);
        eprintln!("diffuse 64x64 {} {}: max error {err:.3e}", normalisation.name(), domain.name());
        assert!(err < 1e-3, "{} {}: max error {err}", normalisation.name(), domain.name());
    }
}

#[test]
fn diffuse_matches_quadrature_at_256_spot_checks() {
    let lut = DiffuseLut::build(&diffuse_spec(256, Normalisation::TwoD, Domain::Full)).unwrap();
    let err = diffuse_error(&lut, 17);
    eprintln!("diffuse 256x256 2d full (every 17th texel): max error {err:.3e}");
    assert!(err < 1e-3, "max error {err}");
}

#[test]
fn diffuse_resolves_the_narrow_kernels_of_nearly_flat_skin() {
    // 1/r up to 1e-3 /mm: the angular width of the narrowest Gaussian is 8e-5 rad.
    for (normalisation, domain) in configs() {
        let spec = DiffuseLutSpec { inv_r_max: 1e-3, ..diffuse_spec(48, normalisation, domain) };
        let err = diffuse_error(&DiffuseLut::build(&spec).unwrap(), 1);
        eprintln!("diffuse 48x48 1/r <= 1e-3 {} {}: max error {err:.3e}", normalisation.name(), domain.name());
        assert!(err < 1e-3, "{} {}: max error {err}", normalisation.name(), domain.name());
    }
}

#[test]
fn sphere_table_matches_brute_force_over_the_surface() {
    // The table integrates in the chord with the azimuth in closed form; the brute force sums
    // midpoints of the polar angle and the azimuth over the sphere's surface.
    use skinkit_render::skin::profile::sphere_integral;
    let spec = DiffuseLutSpec { width: 24, height: 21, ..diffuse_spec(24, Normalisation::TwoD, Domain::Sphere) };
    let lut = DiffuseLut::build(&spec).unwrap();
    let profile = Profile::default();
    let mut worst = 0.0f64;
    for j in [2, 5, 10, 20] {
        let inv_r = f64::from(spec.inv_r_at(j));
        for i in (0..24).step_by(3).chain([23]) {
            let n_dot_l = f64::from(spec.n_dot_l_at(i));
            let want = sphere_integral(&profile, n_dot_l, inv_r, 4000);
            for (c, got) in lut.texel(i, j).into_iter().enumerate() {
                worst = worst.max((f64::from(got) - want[c]).abs());
            }
        }
    }
    eprintln!("sphere 24x21 against brute force: max error {worst:.2e}");
    assert!(worst < 5e-4, "max error {worst}");
}

#[test]
fn the_sphere_keeps_the_profiles_weights_where_the_ring_does_not() {
    // On a gently curved sphere the light past the terminator is the 2-D profile's share beyond a
    // straight edge (the marginal), not the ring's, which over-weights the narrow Gaussians by
    // 1 / sqrt(2 pi v): at N.L = 0 both sides of the edge then see half the light of a
    // tilted plane, so D(0) tends to the marginal's first moment over the lit side, per channel.
    let inv_r = 0.01;
    let sphere = DiffuseLut::build(&DiffuseLutSpec {
        inv_r_min: inv_r as f32,
        inv_r_max: 1.0,
        ..diffuse_spec(65, Normalisation::TwoD, Domain::Sphere)
    })
    .unwrap();
    // sum w_i sqrt(v_i / 2 pi) / r: int_0^inf x g_i(x) dx / r with x the arc length, N.L = x / r.
    let want: [f64; 3] = std::array::from_fn(|c| {
        (0..6).map(|i| WEIGHTS[i][c] * (VARIANCES_MM2[i] / (2.0 * PI)).sqrt()).sum::<f64>() * inv_r
    });
    let got = sphere.texel(32, 0);
    for c in 0..3 {
        assert!((f64::from(got[c]) - want[c]).abs() < 0.02 * want[c], "channel {c}: {got:?} vs {want:?}");
    }
}

#[test]
fn flat_row_is_the_clamped_cosine() {
    for (normalisation, domain) in every_domain() {
        let lut = DiffuseLut::build(&diffuse_spec(64, normalisation, domain)).unwrap();
        for i in 0..64 {
            let want = lut.spec.n_dot_l_at(i).max(0.0);
            for c in lut.texel(i, 0) {
                assert!((c - want).abs() <= 1e-6, "column {i}: {c} vs {want}");
            }
        }
    }
}

#[test]
fn diffuse_rows_are_monotonic_in_n_dot_l() {
    for (normalisation, domain) in every_domain() {
        let lut = DiffuseLut::build(&diffuse_spec(64, normalisation, domain)).unwrap();
        assert_monotonic_rows(&lut.texels, 64, &format!("{} {}", normalisation.name(), domain.name()));
    }
    let lut = DiffuseLut::build(&DiffuseLutSpec::default()).unwrap();
    assert_monotonic_rows(&lut.texels, 256, "default 256x256");
}

#[test]
fn very_curved_skin_averages_the_clamped_cosine_over_the_ring() {
    // r = 0.1 um: the profile is flat over the ring, so D is the ring average of max(0, cos):
    // 1/pi over the full ring, (1 + N.L)/pi over [-pi/2, pi/2], and over a sphere the sphere's
    // average, 1/4. The kernel varies by (2r)^2 / (2 v_min) = 3e-6 over the ring.
    for (normalisation, domain) in every_domain() {
        let spec = DiffuseLutSpec { inv_r_max: 1e4, ..diffuse_spec(32, normalisation, domain) };
        let lut = DiffuseLut::build(&spec).unwrap();
        for i in 0..32 {
            let n_dot_l = f64::from(spec.n_dot_l_at(i));
            let want = match domain {
                Domain::Full => 1.0 / PI,
                Domain::Half => (1.0 + n_dot_l) / PI,
                Domain::Sphere => 0.25,
            };
            for c in lut.texel(i, 31) {
                assert!(
                    (f64::from(c) - want).abs() < 2e-5,
                    "{} {} column {i}: {c} vs {want}",
                    normalisation.name(),
                    domain.name()
                );
            }
        }
    }
}

#[test]
fn diffuse_stays_finite_at_the_extremes() {
    // Curvatures up to 1e6 /mm in the table itself.
    for (normalisation, domain) in every_domain() {
        let spec = DiffuseLutSpec { inv_r_max: 1e6, ..diffuse_spec(16, normalisation, domain) };
        let lut = DiffuseLut::build(&spec).unwrap();
        for (k, t) in lut.texels.iter().enumerate() {
            assert_unit_range(*t, &format!("texel {k}"));
        }
    }
    let lut = DiffuseLut::build(&diffuse_spec(32, Normalisation::TwoD, Domain::Full)).unwrap();
    let n_dot_ls = [-1.0, 1.0, 0.0, -2.0, 2.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
    let inv_rs = [0.0, 1.0, 1e6, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MIN_POSITIVE];
    for n in n_dot_ls {
        for q in inv_rs {
            assert_unit_range(lut.sample(n, q), &format!("sample({n}, {q})"));
        }
    }
    // Beyond the range reads as the range's end.
    assert_eq!(lut.sample(0.3, 1e6), lut.sample(0.3, 1.0));
    assert_eq!(lut.sample(0.3, -5.0), lut.sample(0.3, 0.0));
}

#[test]
fn sample_is_a_gpu_bilinear_clamp_to_edge_read() {
    let lut = DiffuseLut::build(&diffuse_spec(16, Normalisation::TwoD, Domain::Full)).unwrap();
    let s = lut.spec;
    // At texel centres the sample is the texel.
    for (i, j) in [(0, 0), (5, 7), (15, 15), (3, 15)] {
        let got = lut.sample(s.n_dot_l_at(i), s.inv_r_at(j));
        let want = lut.texel(i, j);
        for c in 0..3 {
            assert!((got[c] - want[c]).abs() < 1e-6, "({i}, {j}): {got:?} vs {want:?}");
        }
    }
    // Halfway between four centres it is their mean.
    let n = 0.5 * (s.n_dot_l_at(4) + s.n_dot_l_at(5));
    let q = 0.5 * (s.inv_r_at(9) + s.inv_r_at(10));
    let got = lut.sample(n, q);
    for c in 0..3 {
        let want = 0.25 * (lut.texel(4, 9)[c] + lut.texel(5, 9)[c] + lut.texel(4, 10)[c] + lut.texel(5, 10)[c]);
        assert!((got[c] - want).abs() < 1e-6, "{got:?} vs {want}");
    }
    // N.L = +-1 lie beyond the outer texel centres: clamp to edge.
    assert_eq!(lut.sample(1.0, 0.0), lut.texel(15, 0));
    assert_eq!(lut.sample(-1.0, 1.0), lut.texel(0, 15));
}

#[test]
fn v_for_follows_the_documented_layout() {
    let spec = DiffuseLutSpec { height: 5, inv_r_min: 0.2, inv_r_max: 1.0, ..DiffuseLutSpec::default() };
    // Rows hold 0.2, 0.4, 0.6, 0.8, 1.0 at v = 0.1, 0.3, 0.5, 0.7, 0.9.
    for (j, v) in [0.1f32, 0.3, 0.5, 0.7, 0.9].into_iter().enumerate() {
        assert!((spec.inv_r_at(j as u32) - (0.2 + 0.2 * j as f32)).abs() < 1e-6);
        assert!((spec.v_for(spec.inv_r_at(j as u32)) - v).abs() < 1e-6, "row {j}");
    }
    assert!((spec.v_for(0.5) - 0.4).abs() < 1e-6);
    assert_eq!(spec.v_for(f32::NAN), spec.v_for(0.2));
    assert_eq!(spec.v_for(50.0), spec.v_for(1.0));
    let one_row = DiffuseLutSpec { height: 1, ..spec };
    assert_eq!(one_row.v_for(0.7), 0.5);
    assert_eq!(one_row.inv_r_at(0), 0.2);
    // Columns: N.L = 2u - 1 at u = (i + 0.5) / width.
    let wide = DiffuseLutSpec { width: 4, ..spec };
    assert_eq!([0, 1, 2, 3].map(|i| wide.n_dot_l_at(i)), [-0.75, -0.25, 0.25, 0.75]);
}

#[test]
fn diffuse_spec_validation_names_the_problem() {
    let ok = DiffuseLutSpec::default();
    assert!(ok.validate().is_ok());
    let cases: [(DiffuseLutSpec, &str); 6] = [
        (DiffuseLutSpec { width: 0, ..ok }, "0x256"),
        (DiffuseLutSpec { height: 5000, ..ok }, "256x5000"),
        (DiffuseLutSpec { inv_r_min: 2.0, ..ok }, "inv_r_max (1) must be greater than inv_r_min (2)"),
        (DiffuseLutSpec { inv_r_min: -1.0, ..ok }, "inv_r_min = -1"),
        (DiffuseLutSpec { inv_r_max: f32::NAN, ..ok }, "inv_r_max = NaN"),
        (DiffuseLutSpec { inv_r_max: f32::INFINITY, ..ok }, "inv_r_max = inf"),
    ];
    for (spec, needle) in cases {
        let err = DiffuseLut::build(&spec).unwrap_err();
        assert!(err.to_string().contains(needle), "`{err}` lacks `{needle}`");
    }
    assert!(matches!(DiffuseLutSpec { width: 4097, ..ok }.validate(), Err(SpecError::Size { .. })));
    assert!(DiffuseLutSpec { width: 4096, height: 1, ..ok }.validate().is_ok());
}

#[test]
fn cache_keys_follow_every_parameter() {
    let base = DiffuseLutSpec::default();
    let variants = [
        DiffuseLutSpec { width: 128, ..base },
        DiffuseLutSpec { height: 128, ..base },
        DiffuseLutSpec { normalisation: Normalisation::OneD, ..base },
        DiffuseLutSpec { domain: Domain::Half, ..base },
        DiffuseLutSpec { inv_r_min: 0.001, ..base },
        DiffuseLutSpec { inv_r_max: 1.0001, ..base },
    ];
    for v in variants {
        assert_ne!(v.cache_key(), base.cache_key(), "{v:?}");
    }
    assert_eq!(DiffuseLutSpec::default().cache_key(), base.cache_key());
    let shadow = ShadowLutSpec::default();
    for v in [
        ShadowLutSpec { w_min_mm: 0.0, ..shadow },
        ShadowLutSpec { w_max_mm: 10.0, ..shadow },
        ShadowLutSpec { new_penumbra: 0.5, ..shadow },
        ShadowLutSpec { width: 8, ..shadow },
    ] {
        assert_ne!(v.cache_key(), shadow.cache_key(), "{v:?}");
    }
}

#[test]
fn builds_are_deterministic() {
    let spec = diffuse_spec(32, Normalisation::OneD, Domain::Full);
    assert_eq!(DiffuseLut::build(&spec).unwrap(), DiffuseLut::build(&spec).unwrap());
}

// ---------------------------------------------------------------------------------------------
// The shadow table.

fn shadow_error(lut: &ShadowLut, every: u32) -> f64 {
    let s = lut.spec;
    let mut worst = 0.0f64;
    for j in (0..s.height).step_by(every as usize).chain([s.height - 1]) {
        for i in (0..s.width).step_by(every as usize).chain([0, s.width - 1]) {
            let want = shadow_oracle(f64::from(s.s_at(i)), f64::from(s.w_at(j)), f64::from(s.new_penumbra));
            let got = lut.texel(i, j);
            for c in 0..3 {
                worst = worst.max((f64::from(got[c]) - want[c]).abs());
            }
        }
    }
    worst
}

#[test]
fn shadow_matches_quadrature_over_the_whole_table() {
    for spec in [
        ShadowLutSpec { width: 64, height: 64, ..ShadowLutSpec::default() },
        ShadowLutSpec { width: 48, height: 48, w_min_mm: 0.0, w_max_mm: 4.0, new_penumbra: 0.1 },
        ShadowLutSpec { width: 48, height: 48, w_min_mm: 1.0, w_max_mm: 100.0, new_penumbra: 1.0 },
    ] {
        let err = shadow_error(&ShadowLut::build(&spec).unwrap(), 1);
        eprintln!("shadow {spec:?}: max error {err:.3e}");
        assert!(err < 1e-3, "{spec:?}: max error {err}");
    }
    let err = shadow_error(&ShadowLut::build(&ShadowLutSpec::default()).unwrap(), 17);
    eprintln!("shadow 256x256 default (every 17th texel): max error {err:.3e}");
    assert!(err < 1e-3, "default: max error {err}");
}

#[test]
fn shadow_ends_are_dark_and_lit_and_the_shadow_side_reddens() {
    let lut = ShadowLut::build(&ShadowLutSpec::default()).unwrap();
    let s = lut.spec;
    for j in 0..s.height {
        let w = s.w_at(j);
        let (dark, lit) = (lut.sample(0.0, w), lut.sample(1.0, w));
        // Column centres sit half a column inside the ends, so allow what that half column moves.
        for c in 0..3 {
            assert!(dark[c] >= 0.0 && dark[c] < 0.02 && lit[c] > 0.98 && lit[c] <= 1.0, "w {w}: {dark:?} {lit:?}");
        }
        // On the edge itself, half the light in every channel (the profile is symmetric).
        let edge = lut.sample(0.5, w);
        assert!(edge.iter().all(|&c| (c - 0.5).abs() < 0.01), "w {w}: {edge:?}");
    }
    // Within the disc on the shadow side, red scatters furthest in and blue least; on the lit
    // side red has lost the most.
    for w in [2.0, 5.0, 10.0] {
        let (shadow_side, lit_side) = (lut.sample(0.3, w), lut.sample(0.7, w));
        assert!(shadow_side[0] > shadow_side[1] && shadow_side[1] >= shadow_side[2], "w {w}: {shadow_side:?}");
        assert!(lit_side[0] < lit_side[1] && lit_side[1] <= lit_side[2], "w {w}: {lit_side:?}");
    }
}

#[test]
fn shadow_rows_are_monotonic_in_s() {
    let lut = ShadowLut::build(&ShadowLutSpec::default()).unwrap();
    assert_monotonic_rows(&lut.texels, 256, "shadow default");
    let spec = ShadowLutSpec { width: 64, height: 64, w_min_mm: 0.0, w_max_mm: 2.0, new_penumbra: 0.05 };
    assert_monotonic_rows(&ShadowLut::build(&spec).unwrap().texels, 64, "shadow narrow");
}

#[test]
fn shadow_stays_finite_at_the_extremes() {
    // The widest table the spec allows; samples beyond it (below) are clamped.
    let spec = ShadowLutSpec { width: 32, height: 32, w_min_mm: 0.0, w_max_mm: MAX_PENUMBRA_MM, new_penumbra: 0.25 };
    let lut = ShadowLut::build(&spec).unwrap();
    for t in &lut.texels {
        assert_unit_range(*t, "texel");
    }
    // A zero-width penumbra cannot say where the edge is: half the light, whatever s.
    for i in 0..32 {
        for c in lut.texel(i, 0) {
            assert!((c - 0.5).abs() < 1e-6, "w = 0, column {i}: {c}");
        }
    }
    let values = [0.0, 1.0, 0.5, -1.0, 2.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
    let widths = [0.0, 1e6, 1e9, -5.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
    for s in values {
        for w in widths {
            assert_unit_range(lut.sample(s, w), &format!("sample({s}, {w})"));
        }
    }
}

#[test]
fn shadow_spec_validation_names_the_problem() {
    let ok = ShadowLutSpec::default();
    assert!(ok.validate().is_ok());
    let cases: [(ShadowLutSpec, &str); 6] = [
        (ShadowLutSpec { height: 0, ..ok }, "256x0"),
        (ShadowLutSpec { width: 9000, ..ok }, "9000x256"),
        (ShadowLutSpec { w_max_mm: 0.1, ..ok }, "w_max_mm (0.1) must be greater than w_min_mm (0.5)"),
        (ShadowLutSpec { w_min_mm: f32::NAN, ..ok }, "w_min_mm = NaN"),
        (ShadowLutSpec { new_penumbra: 0.0, ..ok }, "new_penumbra = 0"),
        (ShadowLutSpec { new_penumbra: 1.5, ..ok }, "new_penumbra = 1.5"),
    ];
    for (spec, needle) in cases {
        let err = ShadowLut::build(&spec).unwrap_err();
        assert!(err.to_string().contains(needle), "`{err}` lacks `{needle}`");
    }
}

// ---------------------------------------------------------------------------------------------
// Files.

#[test]
fn diffuse_file_round_trips_pixels_and_definitions() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("diffuse.exr");
    let spec = DiffuseLutSpec {
        width: 24,
        height: 10,
        normalisation: Normalisation::OneD,
        domain: Domain::Half,
        inv_r_min: 0.0,
        inv_r_max: 0.5,
    };
    let lut = DiffuseLut::build(&spec).unwrap();
    lut_file::write_diffuse(&path, &lut).unwrap();
    let image = lut_file::read(&path).unwrap();
    assert_eq!((image.width, image.height), (24, 10));
    assert_eq!(image.texels, lut.texels, "row 0 of the file is row 0 of the table");
    assert_eq!(image.text("skinkit.table"), Some("diffuse"));
    assert_eq!(image.text("skinkit.normalisation"), Some("1d"));
    assert_eq!(image.text("skinkit.domain"), Some("half"));
    assert_eq!(image.float("skinkit.inv_r_min"), Some(0.0));
    assert_eq!(image.float("skinkit.inv_r_max"), Some(0.5));
    assert_eq!(image.text("skinkit.cache_key"), Some(lut.cache_key().as_str()));
    assert!(image.text("skinkit.x").is_some_and(|x| x.contains("n_dot_l * 0.5 + 0.5")));
    assert!(matches!(image.attributes.get("skinkit.inv_r_max"), Some(LutAttribute::F32(_))));
    // No temporary file is left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // The table comes back whole, spec included; it is not a shadow table.
    assert!(image.clone().into_shadow("diffuse.exr").unwrap_err().to_string().contains("not a shadow table"));
    assert_eq!(image.into_diffuse("diffuse.exr").unwrap(), lut);
}

#[test]
fn shadow_file_round_trips_pixels_and_definitions() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shadow.exr");
    let spec = ShadowLutSpec { width: 20, height: 6, ..ShadowLutSpec::default() };
    let lut = ShadowLut::build(&spec).unwrap();
    lut_file::write_shadow(&path, &lut).unwrap();
    let image = lut_file::read(&path).unwrap();
    assert_eq!((image.width, image.height), (20, 6));
    assert_eq!(image.texels, lut.texels);
    assert_eq!(image.text("skinkit.table"), Some("shadow"));
    assert_eq!(image.text("skinkit.filter"), Some("disc"));
    assert_eq!(image.text("skinkit.profile_slice"), Some("marginal"));
    assert_eq!(image.float("skinkit.w_min_mm"), Some(0.5));
    assert_eq!(image.float("skinkit.w_max_mm"), Some(32.0));
    assert_eq!(image.float("skinkit.new_penumbra"), Some(0.05));
    assert_eq!(image.into_shadow("shadow.exr").unwrap(), lut);
}

#[test]
fn unreadable_files_name_themselves() {
    let err = lut_file::decode(b"not an exr", "bogus.exr").unwrap_err();
    assert!(matches!(err, LutFileError::Decode { .. }) && err.to_string().contains("bogus.exr"), "{err}");
    let err = lut_file::read(std::path::Path::new("/nonexistent/lut.exr")).unwrap_err();
    assert!(err.to_string().contains("/nonexistent/lut.exr"), "{err}");
    let dir = tempfile::tempdir().unwrap();
    let lut = DiffuseLut::build(&diffuse_spec(4, Normalisation::TwoD, Domain::Full)).unwrap();
    let err = lut_file::write_diffuse(&dir.path().join("missing/lut.exr"), &lut).unwrap_err();
    assert!(err.to_string().contains("missing"), "{err}");
}

/// Issue 42, D14: at the widest penumbra a table may cover the fully lit column stays lit in
/// every row (at `1e30` mm the lower rows read 0: lit skin as shadow), and wider is refused.
#[test]
fn d14_the_widest_shadow_table_keeps_lit_skin_lit_and_wider_is_refused() {
    use skinkit_render::skin::shadow::MAX_PENUMBRA_MM;
    let spec = ShadowLutSpec { width: 32, height: 64, w_max_mm: MAX_PENUMBRA_MM, ..ShadowLutSpec::default() };
    let lut = ShadowLut::build(&spec).unwrap();
    for j in 0..spec.height {
        let lit = lut.texel(spec.width - 1, j);
        assert!(lit.iter().all(|&c| c > 0.9), "row {j} (w {} mm): the lit column reads {lit:?}", spec.w_at(j));
    }
    let wider = ShadowLutSpec { w_max_mm: 1e30, ..ShadowLutSpec::default() };
    let e = ShadowLut::build(&wider).unwrap_err().to_string();
    assert!(e.contains("w_max_mm") && e.contains("at most 1000 mm"), "{e}");
}
