//! The closed forms of the pre-integrated falloff (`skin::fit`) against equation 1.1 by
//! brute-force quadrature, the blog's prose formulas, and naga for the WGSL twins.

use crate::common::validate;
use skinkit_render::skin::fit::{
    self, BLOG_INV_R_MAX, BLOG_INV_R_MIN, FitGrid, OWN_FIT, OWN_FIT_PARAMS, blog_direct, own_direct, reference_direct,
};
use skinkit_render::skin::profile::{Profile, sphere_integral};

#[test]
fn reference_is_the_sphere_by_brute_force() {
    // The truth the fit is made against, against midpoint sums over the sphere's surface.
    for &k in &[0.0625, 0.25, 1.0] {
        for &x in &[-1.0, -0.3, -0.05, 0.0, 0.1, 0.5, 1.0] {
            let exact = reference_direct(x, k);
            let brute = sphere_integral(&Profile::default(), x, k, 3000);
            for c in 0..3 {
                assert!((exact[c] - brute[c]).abs() < 5e-5, "k {k} x {x} c {c}: {exact:?} vs {brute:?}");
            }
        }
    }
}

fn saturate(x: f32) -> f32 {
    x.clamp(0.0, 1.0)
}

#[test]
fn blog_red_matches_its_prose_at_both_ends() {
    // The post's prose: curve1 = saturate(1.95 NdotL - 0.96) (r = 16 mm); curve0 = lerp(0.65
    // NdotL^2 + 0.045, saturate(1.75 NdotL - 0.76), NdotL^2) (r = 2 mm), NdotL in [0, 1].
    for i in 0..=40 {
        let x = -1.0 + i as f32 / 20.0;
        let n = 0.5 * x + 0.5;
        let curve1 = saturate(1.95 * n - 0.96);
        let lower = 0.65 * n * n + 0.045;
        let curve0 = lower + (saturate(1.75 * n - 0.76) - lower) * (n * n);
        assert!((blog_direct(x, BLOG_INV_R_MIN)[0] - curve1).abs() < 1e-6, "x {x}");
        assert!((blog_direct(x, BLOG_INV_R_MAX)[0] - curve0).abs() < 1e-6, "x {x}");
    }
}

#[test]
fn blog_blends_with_one_minus_the_fourth_power() {
    // "curve = lerp(curve0, curve1, 1 - (1 - curvature)^4)", curvature there the normalised r.
    let (x, inv_r) = (0.1f32, 0.2f32);
    let r = 1.0 / inv_r;
    let s = 1.0 - (1.0 - (r - 2.0) / 14.0).powi(4);
    let (c0, c1) = (blog_direct(x, BLOG_INV_R_MAX), blog_direct(x, BLOG_INV_R_MIN));
    let got = blog_direct(x, inv_r);
    for c in 0..3 {
        assert!((got[c] - (c0[c] + (c1[c] - c0[c]) * s)).abs() < 1e-5, "{got:?}");
    }
    // Outside its range the blog's curve is clamped to its end curves.
    assert_eq!(blog_direct(x, 0.0), c1);
    assert_eq!(blog_direct(x, 1.0), c0);
}

#[test]
fn own_fit_beats_the_blog_over_its_range() {
    let report = fit::fit_report();
    assert_eq!(report.grid, FitGrid::BLOG_RANGE);
    for c in 0..3 {
        assert!(report.own_max[c] < report.blog_max[c], "{report:#?}");
        assert!(report.own_rms[c] < report.blog_rms[c], "{report:#?}");
    }
    // The numbers stated in the module docs (rounded there to two figures).
    let stated_own_max = [0.0095, 0.00125, 0.00057];
    let stated_blog_max = [0.20, 0.018, 0.0075];
    for c in 0..3 {
        assert!((report.own_max[c] / stated_own_max[c] - 1.0).abs() < 0.02, "{report:#?}");
        assert!((report.blog_max[c] / stated_blog_max[c] - 1.0).abs() < 0.02, "{report:#?}");
    }
}

#[test]
fn own_fit_is_close_over_the_whole_range() {
    let report = fit::fit_report_on(&FitGrid::FULL);
    for c in 0..3 {
        assert!(report.own_max[c] < 0.015 && report.own_rms[c] < 0.004, "{report:#?}");
    }
}

#[test]
fn flat_skin_is_clamped_n_dot_l() {
    for i in 0..=200 {
        let x = -1.0 + i as f32 / 100.0;
        for d in own_direct(x, 0.0) {
            assert!((d - x.max(0.0)).abs() < 2e-6, "x {x}: {d}");
        }
    }
    assert_eq!(own_direct(1.0, 0.0), [1.0; 3]);
    assert_eq!(own_direct(-1.0, 0.0), [0.0; 3]);
}

#[test]
fn baked_coefficients_are_the_fit() {
    // Re-run the least squares from its documented start: it must land on the baked constants.
    let samples = fit::reference_samples(&FitGrid::FIT);
    let refit = fit::fit_own_direct(&samples, &fit::OWN_FIT_START);
    for c in 0..3 {
        let baked: [f64; OWN_FIT_PARAMS] = std::array::from_fn(|i| f64::from(OWN_FIT[i][c]));
        let fresh: [f64; OWN_FIT_PARAMS] = std::array::from_fn(|i| refit[i][c]);
        let rms = |p: &[f64; OWN_FIT_PARAMS]| {
            let ss: f64 = samples.iter().map(|s| (fit::own_form(p, s.n_dot_l, s.inv_r) - s.d[c]).powi(2)).sum();
            (ss / samples.len() as f64).sqrt()
        };
        assert!(rms(&baked) <= rms(&fresh) * 1.0001 + 1e-9, "c {c}: baked {} refit {}", rms(&baked), rms(&fresh));
        for i in 0..OWN_FIT_PARAMS {
            assert!((baked[i] - fresh[i]).abs() < 1e-3 * (1.0 + fresh[i].abs()), "c {c} i {i}: {baked:?} vs {fresh:?}");
        }
    }
}

#[test]
fn both_forms_stay_finite_and_in_range_at_extremes() {
    let xs = [-1.0, 1.0, 0.0, -2.0, 2.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
    let ks = [0.0, BLOG_INV_R_MIN, BLOG_INV_R_MAX, 1.0, 5.0, -1.0, f32::NAN, f32::INFINITY];
    for &x in &xs {
        for &k in &ks {
            for d in blog_direct(x, k).into_iter().chain(own_direct(x, k)) {
                assert!(d.is_finite() && (0.0..=1.0001).contains(&d), "x {x} k {k}: {d}");
            }
        }
    }
    // Beyond the fitted range 1/r is clamped to 1 mm^-1.
    assert_eq!(own_direct(0.2, 3.0), own_direct(0.2, 1.0));
}

#[test]
fn wgsl_snippet_validates_in_front_of_a_shader() {
    let caller = "
@fragment
fn fs_main(@location(0) ndl: vec3<f32>, @location(1) inv_r: f32) -> @location(0) vec4<f32> {
    return vec4<f32>(blog_direct(ndl, inv_r) + own_direct(ndl, inv_r), 1.0);
}";
    let module = validate(&format!("{}\n{caller}", fit::SKIN_FIT_WGSL)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(module.entry_points.len(), 1);
    assert!(!fit::SKIN_FIT_WGSL.contains("@group") && !fit::SKIN_FIT_WGSL.contains("@fragment"));
    // A misspelt call is caught, so the check above can fail.
    assert!(validate(&format!("{}\n{}", fit::SKIN_FIT_WGSL, caller.replace("own_direct(", "own_direct2("))).is_err());
}

#[test]
fn wgsl_carries_the_baked_coefficients() {
    let names = ["OWN_A1", "OWN_B1", "OWN_A2", "OWN_B2", "OWN_MIX", "OWN_GAIN_C", "OWN_GAIN_D"];
    for (name, row) in names.iter().zip(OWN_FIT) {
        let line = format!("const {name} = vec3<f32>({:?}, {:?}, {:?});", row[0], row[1], row[2]);
        assert!(fit::SKIN_FIT_WGSL.contains(&line), "missing {line}");
    }
}
