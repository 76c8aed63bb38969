//! Property tests (proptest) of the renderer's CPU kernels:
//! - tangent frames ([`tangents`], both methods) on random meshes: finite, unit, orthogonal to
//!   the normal, handedness ±1; on random planar meshes with an affine UV map, the exact frame
//!   (the rotated `+x` tangent and `+y` image-up bitangent, or their mirror);
//! - Lafortune lobes: finite and non-negative for any directions and parameters, non-finite
//!   ones included ([`lobe_power`] capped at [`LOBE_CEILING`]);
//! - table lookups ([`DiffuseLut::sample`], [`ShadowLut::sample`]) anywhere inside and outside
//!   the table, NaN and infinities included: finite, within the table's per-channel range, and
//!   the texel itself at a texel's centre.
//!
//! `PROPTEST_CASES=N` runs N cases of each; `PROPTEST_RNG_SEED=S` other cases than the default seed.

use glam::{Mat3, Vec2, Vec3};
use proptest::prelude::*;
use proptest::test_runner::Config;
use skinkit_render::brdf::{LOBE_CEILING, Lafortune, Lobe, lobe_power};
use skinkit_render::frames::{FrameMethod, bitangent, tangents};
use skinkit_render::mesh::Mesh;
use skinkit_render::skin::lut::{DiffuseLut, DiffuseLutSpec};
use skinkit_render::skin::shadow::{ShadowLut, ShadowLutSpec};

/// `cases` cases from this suite's fixed seed (`PROPTEST_CASES`, `PROPTEST_RNG_SEED` override).
fn config(cases: u32) -> Config {
    skinkit_testkit::proptest_config(cases, 0x5eed_4e4d)
}

fn vec3(r: f32) -> impl Strategy<Value = Vec3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Any f32 a file or a fit could produce, the awkward ones weighted up.
fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -1.0e3f32..1.0e3,
        2 => -2.0f32..2.0,
        1 => prop::num::f32::ANY,
        1 => prop::sample::select(vec![0.0, -0.0, 1.0, 1.0e30, -1.0e30, f32::INFINITY, f32::NEG_INFINITY, f32::NAN]),
    ]
}

fn any_vec3() -> impl Strategy<Value = Vec3> {
    (any_f32(), any_f32(), any_f32()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A random mesh: 3..40 vertices in a unit box, UVs in [0, 1] snapped to a coarse grid one time in
/// four (zero-UV-area triangles), 1..60 triangles over them (some degenerate), normals either
/// area-weighted (what the loaders compute) or random unit vectors.
fn mesh() -> impl Strategy<Value = Mesh> {
    (3usize..40, any::<bool>(), any::<bool>()).prop_flat_map(|(n, snap, computed)| {
        let uv = (0.0f32..1.0, 0.0f32..1.0).prop_map(move |(u, v)| {
            if snap { Vec2::new((u * 2.0).round() / 2.0, (v * 2.0).round() / 2.0) } else { Vec2::new(u, v) }
        });
        let normal = vec3(1.0).prop_map(|v| v.try_normalize().unwrap_or(Vec3::Z));
        (
            prop::collection::vec(vec3(1.0), n),
            prop::collection::vec(uv, n),
            prop::collection::vec(normal, n),
            prop::collection::vec(0..n as u32, 3..180).prop_map(|mut i| {
                i.truncate(i.len() / 3 * 3);
                i
            }),
        )
            .prop_map(move |(positions, uvs, normals, indices)| {
                let mut mesh = Mesh { positions, normals, uvs, indices };
                if computed {
                    mesh.normals = mesh.area_weighted_normals();
                }
                mesh
            })
    })
}

fn method() -> impl Strategy<Value = FrameMethod> {
    prop_oneof![Just(FrameMethod::Paper), Just(FrameMethod::MikkTSpace)]
}

/// Rotation from three angles.
fn rotation() -> impl Strategy<Value = Mat3> {
    (0.0f32..6.3, 0.0f32..6.3, 0.0f32..6.3).prop_map(|(a, b, c)| Mat3::from_euler(glam::EulerRot::ZYX, a, b, c))
}

proptest! {
    #![proptest_config(config(128))]

    #[test]
    fn tangent_frames_are_finite_and_orthonormal(mesh in mesh(), method in method()) {
        prop_assert!(mesh.validate().is_ok());
        let frames = tangents(&mesh, method);
        prop_assert_eq!(frames.len(), mesh.positions.len());
        for (v, (t, n)) in frames.iter().zip(&mesh.normals).enumerate() {
            let n = n.normalize();
            let b = bitangent(n, *t);
            prop_assert!(t.is_finite() && t.w.abs() == 1.0, "{:?} vertex {}: {}", method, v, t);
            prop_assert!((t.truncate().length() - 1.0).abs() < 1e-4, "{:?} vertex {}: |T| = {}", method, v, t.truncate().length());
            prop_assert!(t.truncate().dot(n).abs() < 1e-4, "{:?} vertex {}: T.N = {}", method, v, t.truncate().dot(n));
            prop_assert!((b.length() - 1.0).abs() < 1e-4 && b.dot(n).abs() < 1e-4, "{:?} vertex {}: B = {}", method, v, b);
        }
    }

    /// Points of a plane (rotated by `r`) whose UVs are `u = s x + a`, `v = -s y + b` (v grows
    /// down the image, so image-up is +y): every vertex of a proper triangle has `T = r x`,
    /// `B = r y`, `w = +1`; mirrored (`u = -s x`), `T = -r x`, `B = r y`, `w = -1`.
    #[test]
    fn planar_meshes_get_the_exact_frame(
        points in prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0), 3..30),
        tris in prop::collection::vec((0usize..30, 0usize..30, 0usize..30), 1..40),
        r in rotation(),
        scale in 0.2f32..5.0,
        mirrored in any::<bool>(),
        method in method(),
    ) {
        let n = points.len();
        let su = if mirrored { -scale } else { scale };
        let mut indices = Vec::new();
        let mut used = vec![false; n];
        for (a, b, c) in tris {
            let (a, b, c) = (a % n, b % n, c % n);
            let (pa, pb, pc) = (Vec2::from(points[a]), Vec2::from(points[b]), Vec2::from(points[c]));
            // Proper triangles only, wound counter-clockwise seen from +z (the normal's side).
            let area = (pb - pa).perp_dot(pc - pa);
            if area.abs() < 1e-2 {
                continue;
            }
            let tri = if area > 0.0 { [a, b, c] } else { [a, c, b] };
            indices.extend(tri.map(|i| i as u32));
            tri.iter().for_each(|&i| used[i] = true);
        }
        prop_assume!(!indices.is_empty());
        let mesh = Mesh {
            positions: points.iter().map(|&(x, y)| r * Vec3::new(x, y, 0.0)).collect(),
            normals: vec![r * Vec3::Z; n],
            uvs: points.iter().map(|&(x, y)| Vec2::new(su * x + 0.5, -scale * y + 0.5)).collect(),
            indices,
        };
        let (tx, by, w) = if mirrored { (-(r * Vec3::X), r * Vec3::Y, -1.0) } else { (r * Vec3::X, r * Vec3::Y, 1.0) };
        for (v, t) in tangents(&mesh, method).iter().enumerate().filter(|(v, _)| used[*v]) {
            let b = bitangent(mesh.normals[v], *t);
            prop_assert!((t.truncate() - tx).length() < 1e-3 && t.w == w, "{:?} vertex {}: T {} (expected {}, w {})", method, v, t, tx, w);
            prop_assert!((b - by).length() < 1e-3, "{:?} vertex {}: B {} (expected {})", method, v, b, by);
        }
    }

    #[test]
    fn lafortune_is_finite_and_non_negative(
        diffuse in (0.0f32..10.0, 0.0f32..10.0, 0.0f32..10.0),
        lobes in prop::collection::vec((any_vec3(), any_vec3(), any_vec3(), any_vec3()), 0..4),
        l in any_vec3(),
        v in any_vec3(),
    ) {
        let brdf = Lafortune {
            diffuse: Vec3::new(diffuse.0, diffuse.1, diffuse.2),
            lobes: lobes.into_iter().map(|(cx, cy, cz, n)| Lobe { cx, cy, cz, n }).collect(),
        };
        for lobe in &brdf.lobes {
            let f = lobe.eval(l, v);
            prop_assert!(f.is_finite() && f.min_element() >= 0.0 && f.max_element() <= LOBE_CEILING, "lobe {:?}: {}", lobe, f);
        }
        let f = brdf.eval(l, v);
        prop_assert!(f.is_finite() && f.min_element() >= 0.0, "{} for l {} v {}", f, l, v);
        let skin = Lafortune::skin().eval(l, v);
        prop_assert!(skin.is_finite() && skin.min_element() >= 0.0, "skin: {} for l {} v {}", skin, l, v);
    }

    #[test]
    fn lobe_power_is_within_zero_and_the_ceiling(base in any_f32(), n in any_f32()) {
        let p = lobe_power(base, n);
        prop_assert!((0.0..=LOBE_CEILING).contains(&p), "{}^{} = {}", base, n, p);
        if base > 0.0 && base.is_finite() && n.is_finite() && n >= 0.0 {
            let exact = f64::from(base).powf(f64::from(n)).min(f64::from(LOBE_CEILING));
            prop_assert!((f64::from(p) - exact).abs() <= 1e-5 * exact.max(1e-30) + 1e-30, "{}^{} = {} vs {}", base, n, p, exact);
        }
    }
}

/// A small table with random texels and a valid random spec.
fn diffuse_table() -> impl Strategy<Value = DiffuseLut> {
    (1u32..12, 1u32..12, 0.0f32..2.0, 0.01f32..3.0).prop_flat_map(|(w, h, lo, span)| {
        let spec =
            DiffuseLutSpec { width: w, height: h, inv_r_min: lo, inv_r_max: lo + span, ..DiffuseLutSpec::default() };
        prop::collection::vec((-5.0f32..5.0, 0.0f32..1.0, -1.0e3f32..1.0e3), (w * h) as usize)
            .prop_map(move |t| DiffuseLut { spec, texels: t.into_iter().map(|(a, b, c)| [a, b, c]).collect() })
    })
}

fn channel_range(texels: &[[f32; 3]], k: usize) -> (f32, f32) {
    texels.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), t| (lo.min(t[k]), hi.max(t[k])))
}

fn in_table_range(texels: &[[f32; 3]], s: [f32; 3]) -> bool {
    (0..3).all(|k| {
        let (lo, hi) = channel_range(texels, k);
        let slack = 1e-5 * lo.abs().max(hi.abs()).max(1.0);
        s[k].is_finite() && s[k] >= lo - slack && s[k] <= hi + slack
    })
}

/// Built tables (small, so building takes milliseconds) sampled by the last property.
fn built() -> &'static (DiffuseLut, ShadowLut) {
    static TABLES: std::sync::OnceLock<(DiffuseLut, ShadowLut)> = std::sync::OnceLock::new();
    TABLES.get_or_init(|| {
        let d = DiffuseLut::build(&DiffuseLutSpec { width: 32, height: 16, ..DiffuseLutSpec::default() }).unwrap();
        let s = ShadowLut::build(&ShadowLutSpec { width: 32, height: 16, ..ShadowLutSpec::default() }).unwrap();
        (d, s)
    })
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn lookups_anywhere_stay_in_the_tables_range(table in diffuse_table(), a in any_f32(), b in any_f32(), i in 0u32..12, j in 0u32..12) {
        let s = table.sample(a, b);
        prop_assert!(in_table_range(&table.texels, s), "sample({}, {}) = {:?}", a, b, s);
        // At a texel's centre the sample is that texel.
        let spec = table.spec;
        let (i, j) = (i % spec.width, j % spec.height);
        let at = table.sample(spec.n_dot_l_at(i), spec.inv_r_at(j));
        let want = table.texel(i, j);
        for k in 0..3 {
            prop_assert!((at[k] - want[k]).abs() <= 1e-3 * want[k].abs().max(1.0), "texel ({}, {}): {:?} vs {:?}", i, j, at, want);
        }
    }

    #[test]
    fn built_tables_give_finite_values_in_zero_one_anywhere(a in any_f32(), b in any_f32()) {
        let (diffuse, shadow) = built();
        for (name, s) in [("diffuse", diffuse.sample(a, b)), ("shadow", shadow.sample(a, b))] {
            prop_assert!(s.iter().all(|v| v.is_finite() && (-1e-6..=1.0 + 1e-6).contains(v)), "{}({}, {}) = {:?}", name, a, b, s);
        }
        prop_assert!(in_table_range(&diffuse.texels, diffuse.sample(a, b)));
        prop_assert!(in_table_range(&shadow.texels, shadow.sample(a, b)));
    }
}
