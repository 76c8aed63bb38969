//! Texture-space frames: the paper's construction against hand-computed partials and against
//! MikkTSpace, the handedness, degenerate inputs, and a known bump through the whole path.

use std::f32::consts::PI;

use glam::{Vec2, Vec3, Vec4};
use skinkit_render::frames::{self, FrameMethod, bitangent, tangents, to_object, to_texture, triangle_partials};
use skinkit_render::mesh::Mesh;

const METHODS: [FrameMethod; 2] = [FrameMethod::Paper, FrameMethod::MikkTSpace];

/// A flat grid on z = 0 over [0, 1]^2, facing +z, with `uv = uv_of(x, y)`.
fn plane(n: usize, uv_of: impl Fn(f32, f32) -> Vec2) -> Mesh {
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            m.positions.push(Vec3::new(x, y, 0.0));
            m.normals.push(Vec3::Z);
            m.uvs.push(uv_of(x, y));
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise seen from +z.
            m.indices.extend([at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    m.validate().unwrap();
    m
}

/// skinkit's convention on a plane seen from +z: u to the right, v = 0 at the top (y = 1).
fn standard_plane(n: usize) -> Mesh {
    plane(n, |x, y| Vec2::new(x, 1.0 - y))
}

fn assert_unit_frames(mesh: &Mesh, t: &[Vec4]) {
    assert_eq!(t.len(), mesh.positions.len());
    for (i, (t, n)) in t.iter().zip(&mesh.normals).enumerate() {
        assert!(t.is_finite(), "vertex {i}: {t}");
        assert!((t.truncate().length() - 1.0).abs() < 1e-4, "vertex {i}: {t}");
        assert!(t.truncate().dot(*n).abs() < 1e-4, "vertex {i}: {t} not orthogonal to {n}");
        assert!(t.w == 1.0 || t.w == -1.0, "vertex {i}: {t}");
    }
}

#[test]
fn partials_match_an_affine_parameterisation() {
    // P(u, v) = origin + u a + v b exactly on this triangle, so dP/du = a and dP/dv = b whatever
    // the three UVs (the oracle), here a skewed, non-orthogonal pair.
    let (origin, a, b) = (Vec3::new(1.0, -2.0, 0.5), Vec3::new(2.0, 1.0, 0.0), Vec3::new(1.0, 3.0, 1.0));
    let uv = [Vec2::new(0.1, 0.2), Vec2::new(0.7, 0.25), Vec2::new(0.3, 0.9)];
    let p = uv.map(|t| origin + a * t.x + b * t.y);
    let d = triangle_partials(p, uv).unwrap();
    assert!((d.du - a).length() < 1e-4, "{} vs {a}", d.du);
    assert!((d.dv - b).length() < 1e-4, "{} vs {b}", d.dv);
    // A = du1 dv2 - dv1 du2 by hand: 0.6 * 0.7 - 0.05 * 0.2.
    assert!((d.uv_area2 - (0.6 * 0.7 - 0.05 * 0.2)).abs() < 1e-6);
}

#[test]
fn paper_frame_of_one_triangle_by_hand() {
    // Unit UV edges: dP/du = p1 - p0 = (2, 1, 0), dP/dv = p2 - p0 = (0, 0, -3) (v grows
    // downward in the image, so image-up is +z). Normal: +y. The tangent is dP/du orthogonalised
    // against the normal: +x. Image up (+z) = cross(N, T) * w = cross(y, x) * w = -z * w: w = -1.
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, Vec3::new(2.0, 1.0, 0.0), Vec3::new(0.0, 0.0, -3.0)],
        normals: vec![Vec3::Y; 3],
        uvs: vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)],
        indices: vec![0, 1, 2],
    };
    for t in tangents(&mesh, FrameMethod::Paper) {
        assert!((t - Vec4::new(1.0, 0.0, 0.0, -1.0)).length() < 1e-6, "{t}");
        assert!(bitangent(Vec3::Y, t).angle_between(Vec3::Z) < 1e-6);
    }
}

fn max_angle(a: &[Vec4], b: &[Vec4]) -> f32 {
    a.iter().zip(b).map(|(a, b)| a.truncate().angle_between(b.truncate())).fold(0.0, f32::max)
}

#[test]
fn methods_agree_on_a_planar_grid() {
    let mesh = standard_plane(8);
    let [paper, mikk] = METHODS.map(|m| tangents(&mesh, m));
    assert_unit_frames(&mesh, &paper);
    assert_unit_frames(&mesh, &mikk);
    assert!(max_angle(&paper, &mikk) < 1e-3);
    for (p, m) in paper.iter().zip(&mikk) {
        assert_eq!(p.w, m.w);
        // T = +x (increasing u), B = +y (toward the top of the image), w = +1.
        assert!(p.truncate().angle_between(Vec3::X) < 1e-5 && p.w == 1.0, "{p}");
        assert!(bitangent(Vec3::Z, *p).angle_between(Vec3::Y) < 1e-5);
    }
}

/// An open cylinder around y of radius r, u around (angle 2 pi u), v down its height h = 2 pi r:
/// orthogonal, undistorted UVs, split at the seam u = 0 = 1, analytic radial normals.
fn cylinder(columns: usize, rows: usize) -> Mesh {
    let (r, h) = (1.0, 2.0 * PI);
    let mut m = Mesh::default();
    for j in 0..=rows {
        for i in 0..=columns {
            let (u, v) = (i as f32 / columns as f32, j as f32 / rows as f32);
            let a = 2.0 * PI * u;
            // Seen from outside, u grows to the right: positions go around clockwise from above.
            let radial = Vec3::new(a.sin(), 0.0, a.cos());
            m.positions.push(radial * r + Vec3::Y * h * (1.0 - v));
            m.normals.push(radial);
            m.uvs.push(Vec2::new(u, v));
        }
    }
    let at = |i: usize, j: usize| (j * (columns + 1) + i) as u32;
    for j in 0..rows {
        for i in 0..columns {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
            m.indices.extend([a, c, d, a, d, b]);
        }
    }
    m.validate().unwrap();
    m
}

#[test]
fn methods_agree_on_a_cylinder_with_orthogonal_uvs() {
    let mesh = cylinder(24, 6);
    let [paper, mikk] = METHODS.map(|m| tangents(&mesh, m));
    assert_unit_frames(&mesh, &paper);
    assert_unit_frames(&mesh, &mikk);
    let angle = max_angle(&paper, &mikk);
    assert!(angle < 1e-3, "max angle {angle} rad");
    for (k, (p, m)) in paper.iter().zip(&mikk).enumerate() {
        assert_eq!(p.w, m.w, "vertex {k}");
        assert_eq!(p.w, 1.0, "vertex {k}");
        // The exact tangent of the circle, in the direction of increasing angle.
        let n = mesh.normals[k];
        let exact = Vec3::new(n.z, 0.0, -n.x);
        assert!(p.truncate().angle_between(exact) < 1e-3, "vertex {k}: {p} vs {exact}");
        assert!(bitangent(n, *p).angle_between(Vec3::Y) < 1e-3);
    }
}

#[test]
fn mirrored_uvs_flip_the_handedness() {
    let mesh = plane(4, |x, y| Vec2::new(1.0 - x, 1.0 - y));
    for method in METHODS {
        let t = tangents(&mesh, method);
        assert_unit_frames(&mesh, &t);
        for t in &t {
            assert_eq!(t.w, -1.0, "{method:?}");
            // T follows u (now -x) and B still points to the image top (+y).
            assert!(t.truncate().angle_between(-Vec3::X) < 1e-4, "{method:?} {t}");
            assert!(bitangent(Vec3::Z, *t).angle_between(Vec3::Y) < 1e-4);
        }
    }
}

#[test]
fn degenerate_inputs_give_finite_unit_frames() {
    let mut mesh = standard_plane(2);
    let base = mesh.positions.len() as u32;
    // Zero UV area (all UVs equal), collinear UVs, zero 3-D area, and a triangle whose u
    // direction is along its (given) vertex normal.
    let extra: [([Vec3; 3], [Vec2; 3], Vec3); 4] = [
        ([Vec3::ZERO, Vec3::X, Vec3::Y], [Vec2::splat(0.5); 3], Vec3::Z),
        ([Vec3::ZERO, Vec3::X, Vec3::Y], [Vec2::ZERO, Vec2::new(0.5, 0.5), Vec2::ONE], Vec3::Z),
        ([Vec3::ZERO, Vec3::ZERO, Vec3::ZERO], [Vec2::ZERO, Vec2::X, Vec2::Y], Vec3::Z),
        ([Vec3::ZERO, Vec3::X, Vec3::Y], [Vec2::ZERO, Vec2::X, Vec2::Y], Vec3::X),
    ];
    for (k, (p, uv, n)) in extra.iter().enumerate() {
        mesh.positions.extend(p);
        mesh.uvs.extend(uv);
        mesh.normals.extend([*n; 3]);
        let first = base + 3 * k as u32;
        mesh.indices.extend([first, first + 1, first + 2]);
    }
    for method in METHODS {
        let t = tangents(&mesh, method);
        assert_unit_frames(&mesh, &t);
        // The healthy part is unaffected.
        assert!(t[..9].iter().all(|t| t.truncate().angle_between(Vec3::X) < 1e-4), "{method:?}");
    }
}

#[test]
fn texture_and_object_space_are_inverse() {
    let n = Vec3::new(0.2, -0.3, 0.9).normalize();
    let t = n.any_orthonormal_vector().extend(-1.0);
    let v = Vec3::new(0.3, 0.8, -0.2);
    assert!((to_object(n, t, to_texture(n, t, v)) - v).length() < 1e-6);
}

/// The height of a test bump on the plane, in plane units: asymmetric (off centre, elongated).
fn height(x: f32, y: f32) -> f32 {
    0.05 * (-((x - 0.35) / 0.12).powi(2) - ((y - 0.7) / 0.08).powi(2)).exp()
}

/// A green-up normal map of [`height`] baked the way a baker does it, independent of the frame
/// code: texel (column c, row r) covers u = (c + 0.5) / w, v = (r + 0.5) / h with row 0 at the
/// top, so the point is x = u, y = 1 - v; +x of the map is to the right, +y up the image.
fn baked_normal(size: usize, c: usize, r: usize) -> Vec3 {
    let texel = 1.0 / size as f32;
    let h_at = |c: f32, r: f32| height((c + 0.5) * texel, 1.0 - (r + 0.5) * texel);
    let (c, r) = (c as f32, r as f32);
    let dh_right = (h_at(c + 1.0, r) - h_at(c - 1.0, r)) / (2.0 * texel);
    // One row up is r - 1.
    let dh_up = (h_at(c, r - 1.0) - h_at(c, r + 1.0)) / (2.0 * texel);
    Vec3::new(-dh_right, -dh_up, 1.0).normalize()
}

/// Pushes the baked map through `mesh`'s frames (a plane facing +z) and compares with the true
/// normal of z = height(x, y) at each texel on the bump's flanks.
fn check_bump_through(mesh: &Mesh) {
    let size = 128;
    for method in METHODS {
        let t = tangents(mesh, method);
        // The plane's frame is constant; take vertex 0's.
        let (n, tangent) = (mesh.normals[0], t[0]);
        let mut worst = 0f32;
        let mut checked = 0;
        for r in (4..size - 4).step_by(3) {
            for c in (4..size - 4).step_by(3) {
                let (x, y) = ((c as f32 + 0.5) / size as f32, 1.0 - (r as f32 + 0.5) / size as f32);
                let eps = 1e-3;
                let gx = (height(x + eps, y) - height(x - eps, y)) / (2.0 * eps);
                let gy = (height(x, y + eps) - height(x, y - eps)) / (2.0 * eps);
                if gx.hypot(gy) < 0.05 {
                    continue;
                }
                let truth = Vec3::new(-gx, -gy, 1.0).normalize();
                let got = to_object(n, tangent, baked_normal(size, c, r));
                worst = worst.max(got.angle_between(truth));
                checked += 1;
            }
        }
        assert!(checked > 50, "{checked}");
        // Central differences on a 128 texel map: well under a degree. A flipped v mirrors the
        // tilt in y (measured: 56 degrees worst on these flanks).
        assert!(worst.to_degrees() < 1.0, "{method:?}: worst {} degrees", worst.to_degrees());
    }
}

#[test]
fn known_bump_survives_the_green_up_convention() {
    check_bump_through(&standard_plane(4));
}

#[test]
fn known_bump_survives_an_obj_plane() {
    // OBJ texture coordinates are bottom-origin: vt = (x, y). The loader flips them.
    let text = "\
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
f 1/1/1 2/2/1 3/3/1 4/4/1
";
    let mesh = Mesh::parse_obj(&mut text.as_bytes(), "plane.obj").unwrap().mesh;
    check_bump_through(&mesh);
}

#[test]
fn frames_are_deterministic() {
    let mesh = cylinder(16, 4);
    for method in METHODS {
        assert_eq!(frames::tangents(&mesh, method), frames::tangents(&mesh, method));
    }
}
