//! Order-2 SH for ambient light on skin (`skin::sh`) against closed forms (Funk-Hecke,
//! Ramamoorthi-Hanrahan) and brute-force 2-D integration over the sphere.

// Index loops over bands and channels mirror the formulas' subscripts.
#![allow(clippy::needless_range_loop)]

use crate::common::validate;
use glam::Vec3;
use rayon::prelude::*;
use skinkit_render::skin::fit::reference_direct;
use skinkit_render::skin::sh::{
    self, LAMBERT_ZONAL, SH9, Sh9, ShError, ZonalTable, basis, blog_zonal, index, latlong_direction, skin_irradiance,
    skin_zonal, zonal_factors,
};

const PI: f64 = std::f64::consts::PI;

/// Midpoint directions and solid angles of a `2m x m` theta-phi grid about the pole `axis`
/// (not the latlong's pole, so it is an independent quadrature).
fn sphere_grid(m: usize, axis: Vec3) -> Vec<(Vec3, f64)> {
    let axis = axis.normalize();
    let t1 = axis.any_orthonormal_vector();
    let t2 = axis.cross(t1);
    let (dt, dp) = (PI / m as f64, PI / m as f64);
    let mut out = Vec::with_capacity(2 * m * m);
    for i in 0..m {
        let t = (i as f64 + 0.5) * dt;
        let area = (t - 0.5 * dt).cos() - (t + 0.5 * dt).cos();
        for j in 0..2 * m {
            let p = (j as f64 + 0.5) * dp;
            let w = axis * t.cos() as f32 + (t1 * p.cos() as f32 + t2 * p.sin() as f32) * t.sin() as f32;
            out.push((w, area * dp));
        }
    }
    out
}

fn latlong(width: usize, height: usize, f: impl Fn(Vec3) -> [f32; 3]) -> Vec<[f32; 3]> {
    (0..height)
        .flat_map(|r| (0..width).map(move |c| (r, c)))
        .map(|(r, c)| f(latlong_direction(width, height, c, r)))
        .collect()
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

#[test]
fn basis_is_orthonormal_by_quadrature() {
    let grid = sphere_grid(200, Vec3::new(0.3, 0.5, 0.8));
    for i in 0..SH9 {
        for j in 0..SH9 {
            let s: f64 = grid.iter().map(|(w, a)| f64::from(basis(*w)[i] * basis(*w)[j]) * a).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((s - want).abs() < 1e-4, "<Y{i}, Y{j}> = {s}");
        }
    }
    assert_eq!(index(0, 0), 0);
    assert_eq!(index(1, -1), 1);
    assert_eq!(index(2, 2), 8);
    assert_eq!(sh::y(2, 0, Vec3::Z), 0.315_391_57 * 2.0);
    assert_eq!(sh::y(3, 0, Vec3::Z), 0.0);
}

#[test]
fn constant_environment_projects_and_lights_as_pi_l() {
    let rgb = [0.2, 0.5, 1.5];
    // Texel centres sample the basis, so band 2 picks up O(texel^2): 2e-5 of L00 at 256 x 128.
    let (w, h) = (256, 128);
    let sh = Sh9::project_latlong(w, h, &latlong(w, h, |_| rgb)).unwrap();
    let closed = Sh9::constant(rgb);
    for i in 0..SH9 {
        for c in 0..3 {
            let tol = 1e-4 * (1.0 + closed.coeffs[0][c]);
            assert!((sh.coeffs[i][c] - closed.coeffs[i][c]).abs() < tol, "{i} {c}: {:?}", sh.coeffs[i]);
        }
    }
    for (n, _) in sphere_grid(6, Vec3::new(1.0, 2.0, 3.0)) {
        let e = closed.irradiance_lambert(n);
        for c in 0..3 {
            assert!(close(e[c], std::f32::consts::PI * rgb[c], 1e-6), "{n}: {e:?}");
        }
    }
}

#[test]
fn single_texel_projects_to_the_basis_at_its_centre() {
    let (w, h, col, row) = (16, 8, 5, 2);
    let mut texels = vec![[0.0; 3]; w * h];
    texels[row * w + col] = [1.0, 2.0, 3.0];
    let sh = Sh9::project_latlong(w, h, &texels).unwrap();
    let d = latlong_direction(w, h, col, row);
    let dt = PI / h as f64;
    let omega = (2.0 * PI / w as f64) * ((row as f64 * dt).cos() - ((row + 1) as f64 * dt).cos());
    for i in 0..SH9 {
        for c in 0..3 {
            let want = basis(d)[i] as f64 * omega * (c + 1) as f64;
            assert!((f64::from(sh.coeffs[i][c]) - want).abs() < 1e-6, "{i} {c}");
        }
    }
}

#[test]
fn clamped_cosine_lobe_projects_by_funk_hecke() {
    // L(w) = max(0, d . w): L_lm = A_l Y_lm(d) with Lambert's A_l.
    let d = Vec3::new(0.4, 0.7, -0.5).normalize();
    let (w, h) = (512, 256);
    let sh = Sh9::project_latlong(w, h, &latlong(w, h, |x| [d.dot(x).max(0.0); 3])).unwrap();
    let y = basis(d);
    for i in 0..SH9 {
        let l = if i == 0 {
            0
        } else if i < 4 {
            1
        } else {
            2
        };
        let want = LAMBERT_ZONAL[l] * y[i];
        assert!((sh.coeffs[i][0] - want).abs() < 2e-4, "{i}: {} vs {want}", sh.coeffs[i][0]);
    }
}

#[test]
fn gradient_closed_form_is_its_projection() {
    let (sky, ground, up) = ([0.3, 0.5, 0.9], [0.2, 0.1, 0.05], Vec3::new(0.1, 1.0, 0.2));
    let closed = Sh9::gradient(sky, ground, up);
    let u = up.normalize();
    let (w, h) = (256, 128);
    let map = latlong(w, h, |x| {
        let t = 0.5 * (1.0 + u.dot(x));
        std::array::from_fn(|c| ground[c] + (sky[c] - ground[c]) * t)
    });
    let sh = Sh9::project_latlong(w, h, &map).unwrap();
    for i in 0..SH9 {
        for c in 0..3 {
            assert!(
                (sh.coeffs[i][c] - closed.coeffs[i][c]).abs() < 1e-4,
                "{i} {c}: {:?} vs {:?}",
                sh.coeffs[i],
                closed.coeffs[i]
            );
        }
    }
    assert_eq!(closed.eval(u).map(|v| (v * 1e4).round()), sky.map(|v| (v * 1e4f32).round()));
}

#[test]
fn lambert_factors_by_quadrature_are_the_closed_form() {
    let a = zonal_factors(|c| [c.max(0.0); 3], sh::ZONAL_STEPS);
    for l in 0..3 {
        let closed = [PI, 2.0 * PI / 3.0, PI / 4.0][l];
        assert!((a[l][0] - closed).abs() < 1e-12, "l {l}: {:?}", a[l]);
    }
    let flat = skin_zonal(0.0);
    for l in 0..3 {
        for c in 0..3 {
            assert!(close(flat[l][c], LAMBERT_ZONAL[l], 1e-6), "{flat:?}");
        }
    }
}

/// D per channel tabulated on `n + 1` even cosines, linear in between: an independent
/// discretisation of the kernel for the 2-D quadratures.
struct CosTable(Vec<[f64; 3]>);

impl CosTable {
    fn new(inv_r: f64, n: usize) -> Self {
        Self((0..=n).into_par_iter().map(|i| reference_direct(-1.0 + 2.0 * i as f64 / n as f64, inv_r)).collect())
    }
    fn at(&self, c: f64) -> [f64; 3] {
        let n = self.0.len() - 1;
        let x = ((c.clamp(-1.0, 1.0) + 1.0) * 0.5 * n as f64).min(n as f64 - 1e-9);
        let i = x.floor() as usize;
        let t = x - i as f64;
        std::array::from_fn(|k| self.0[i][k] * (1.0 - t) + self.0[i + 1][k] * t)
    }
}

#[test]
fn skin_factors_match_a_2d_sphere_integral() {
    // A_l = int D(n . w) P_l(n . w) dw, brute force over a grid whose pole is not n.
    let n = Vec3::new(0.6, -0.3, 0.74).normalize();
    let grid = sphere_grid(300, Vec3::new(-0.2, 0.9, 0.4));
    for inv_r in [0.25f32, 1.0] {
        let table = CosTable::new(f64::from(inv_r), 4000);
        let mut brute = [[0.0f64; 3]; 3];
        for (w, a) in &grid {
            let c = f64::from(n.dot(*w));
            let d = table.at(c);
            for (l, p) in [1.0, c, 0.5 * (3.0 * c * c - 1.0)].into_iter().enumerate() {
                for k in 0..3 {
                    brute[l][k] += d[k] * p * a;
                }
            }
        }
        let ours = skin_zonal(inv_r);
        for l in 0..3 {
            for k in 0..3 {
                assert!((f64::from(ours[l][k]) - brute[l][k]).abs() < 2e-4, "1/r {inv_r} l {l}: {ours:?} vs {brute:?}");
            }
        }
        // The skin moves light below the horizon and keeps it: a sphere under uniform light stays
        // uniform, so A_0 is Lambert's pi, and A_1 falls below Lambert's 2 pi / 3.
        for k in 0..3 {
            assert!((ours[0][k] - LAMBERT_ZONAL[0]).abs() < 1e-4, "{ours:?}");
        }
        assert!(ours[1][0] < LAMBERT_ZONAL[1] - 0.05, "{ours:?}");
    }
}

#[test]
fn skin_irradiance_matches_brute_force_for_a_band_limited_sky() {
    // A sky gradient plus a band-2 lobe along another axis: the radiance has no band above 2,
    // so the order-2 SH product is exact and any difference is an error of A_l or of the sums.
    let (up, v) = (Vec3::new(0.1, 1.0, 0.2).normalize(), Vec3::new(1.0, 0.0, -0.3).normalize());
    let radiance = |w: Vec3| -> [f32; 3] {
        let q = v.dot(w) * v.dot(w);
        let t = up.dot(w);
        [0.6 + 0.4 * t + 0.5 * q, 0.5 + 0.3 * t + 0.2 * q, 0.4 + 0.35 * t + 0.1 * q]
    };
    let (w, h) = (256, 128);
    let sh = Sh9::project_latlong(w, h, &latlong(w, h, radiance)).unwrap();
    let grid = sphere_grid(300, Vec3::new(0.3, 0.2, 0.9));
    let inv_r = 0.5f32;
    let table = CosTable::new(f64::from(inv_r), 4000);
    for n in [Vec3::Y, Vec3::new(0.5, -0.2, 0.8).normalize(), -up] {
        let mut brute = [0.0f64; 3];
        for (x, a) in &grid {
            let (l, d) = (radiance(*x), table.at(f64::from(n.dot(*x))));
            for c in 0..3 {
                brute[c] += f64::from(l[c]) * d[c] * a;
            }
        }
        let ours = skin_irradiance(&sh, n, inv_r);
        for c in 0..3 {
            assert!((f64::from(ours[c]) - brute[c]).abs() < 1e-3 * (1.0 + brute[c]), "{n}: {ours:?} vs {brute:?}");
        }
    }
}

#[test]
fn zonal_table_samples_and_lays_out() {
    let table = ZonalTable::build(0.0, 1.0, 5).unwrap();
    assert_eq!(table.rows.len(), 5);
    assert_eq!(table.rows[2], skin_zonal(0.5));
    let mid = table.sample(0.375);
    for l in 0..3 {
        for c in 0..3 {
            let want = 0.5 * (table.rows[1][l][c] + table.rows[2][l][c]);
            assert!((mid[l][c] - want).abs() < 1e-6);
        }
    }
    assert_eq!(table.sample(-3.0), table.rows[0]);
    assert_eq!(table.sample(9.0), table.rows[4]);
    assert_eq!(table.sample(f32::NAN), table.rows[0]);
    let texels = table.texels();
    assert_eq!(texels.len(), 15);
    assert_eq!(texels[2 * 5 + 3], [table.rows[3][2][0], table.rows[3][2][1], table.rows[3][2][2], 1.0]);
    assert!(matches!(ZonalTable::build(0.5, 0.5, 5), Err(ShError::BadTable { .. })));
    assert!(matches!(ZonalTable::build(0.0, 1.0, 1), Err(ShError::BadTable { .. })));
    assert!(matches!(ZonalTable::build(f32::NAN, 1.0, 4), Err(ShError::BadTable { .. })));
}

#[test]
fn bad_maps_are_refused() {
    assert_eq!(Sh9::project_latlong(0, 4, &[]), Err(ShError::EmptyMap { width: 0, height: 4 }));
    let err = Sh9::project_latlong(4, 2, &[[0.0; 3]; 7]).unwrap_err();
    assert_eq!(err.to_string(), "environment map is 4x2 but has 7 texels (expected 8)");
}

#[test]
fn factors_stay_finite_at_extremes() {
    for inv_r in [0.0, 1.0, 5.0, -1.0, f32::NAN, f32::INFINITY] {
        for a in skin_zonal(inv_r).into_iter().chain(blog_zonal(inv_r)).flatten() {
            assert!(a.is_finite() && a > 0.0, "1/r {inv_r}: {a}");
        }
    }
    assert_eq!(skin_zonal(f32::NAN), skin_zonal(0.0));
}

#[test]
fn blog_zonal_is_lambert_at_16_mm_and_close_to_ours_over_its_range() {
    let at16 = blog_zonal(0.0625);
    for l in 0..2 {
        for c in 0..3 {
            assert!(close(at16[l][c], LAMBERT_ZONAL[l], 0.006), "{at16:?}");
        }
    }
    let mut worst = [[0.0f32; 3]; 2];
    for i in 0..=14 {
        let inv_r = 0.0625 + (0.5 - 0.0625) * i as f32 / 14.0;
        let (blog, ours) = (blog_zonal(inv_r), skin_zonal(inv_r));
        for l in 0..2 {
            for c in 0..3 {
                worst[l][c] = worst[l][c].max((blog[l][c] / ours[l][c] - 1.0).abs());
            }
        }
        println!("1/r {inv_r:.4}: blog {:?} ours {:?}", &blog[..2], &ours[..2]);
    }
    // The errors stated in the module docs: the blog follows a table with more red scattering.
    let stated = [[0.154, 0.0104, 0.00334], [0.0195, 0.00314, 0.00097]];
    for l in 0..2 {
        for c in 0..3 {
            assert!((worst[l][c] / stated[l][c] - 1.0).abs() < 0.05, "{worst:?}");
        }
    }
}

#[test]
fn wgsl_snippet_validates_in_front_of_a_shader() {
    let caller = "
struct Ambient { coeffs: array<vec4<f32>, 9> }
@group(0) @binding(0) var<uniform> ambient: Ambient;
@fragment
fn fs_main(@location(0) n: vec3<f32>, @location(1) inv_r: f32) -> @location(0) vec4<f32> {
    let skin = sh9_convolve_rgb(ambient.coeffs, blog_zonal(inv_r), n, n, n);
    return vec4<f32>(skin + sh9_convolve(ambient.coeffs, sh9_lambert_zonal(), n), 1.0);
}";
    let module = validate(&format!("{}\n{caller}", sh::SKIN_SH_WGSL)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(module.entry_points.len(), 1);
    assert!(!sh::SKIN_SH_WGSL.contains("@group") && !sh::SKIN_SH_WGSL.contains("@fragment"));
    assert!(validate(&format!("{}\n{}", sh::SKIN_SH_WGSL, caller.replace("sh9_convolve(", "sh9_convolved("))).is_err());
}

#[test]
fn blog_zonal_follows_the_listing_normalisation() {
    // The interpretation in the module docs: the blog's factors are those of the 1-D
    // normalised profile over the full ring, within 3% (A_0 red is the worst).
    use skinkit_render::skin::profile::{Domain, Normalisation, Profile, ring_integral};
    let listing = Profile::new(Normalisation::OneD);
    let mut worst = 0.0f64;
    for i in 0..=7 {
        let inv_r = 0.0625 + (0.5 - 0.0625) * f64::from(i) / 7.0;
        let theirs = zonal_factors(|c| ring_integral(&listing, Domain::Full, c, inv_r, 8192), sh::ZONAL_STEPS);
        let blog = blog_zonal(inv_r as f32);
        for l in 0..2 {
            for c in 0..3 {
                worst = worst.max((f64::from(blog[l][c]) / theirs[l][c] - 1.0).abs());
            }
        }
    }
    assert!(worst < 0.031, "{worst}");
}

#[test]
fn per_channel_normals_pick_each_channel() {
    let sh = Sh9::gradient([1.0, 0.5, 0.2], [0.1, 0.2, 0.3], Vec3::Y);
    let zonal = skin_zonal(0.5);
    let normals = [Vec3::Y, Vec3::X, -Vec3::Y];
    let got = sh.convolve_per_channel(normals, &zonal);
    for c in 0..3 {
        assert_eq!(got[c], sh.convolve(normals[c], &zonal)[c]);
    }
    assert_eq!(sh.convolve_per_channel([Vec3::Z; 3], &zonal), sh.convolve(Vec3::Z, &zonal));
}

#[test]
fn the_tables_samples_interpolate_the_factors_closely() {
    // The table's resolution stated in `ZonalTable`'s docs: 33 samples over [0, 1] mm^-1.
    let table = ZonalTable::build(0.0, 1.0, 33).unwrap();
    let mut worst = 0.0f32;
    for i in 0..32 {
        let inv_r = (i as f32 + 0.5) / 32.0;
        let (lerped, exact) = (table.sample(inv_r), skin_zonal(inv_r));
        for l in 0..3 {
            for c in 0..3 {
                worst = worst.max((lerped[l][c] / exact[l][c] - 1.0).abs());
            }
        }
    }
    eprintln!("33 samples: worst relative error {worst:.2e}");
    assert!(worst < 1.1e-3, "{worst}");
}
