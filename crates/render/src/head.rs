//! The sample head for `skinkit samples`: a smooth, low-poly, closed head-like surface with UVs,
//! made from formulas (no face mesh may be copied into the project). Haro et al. 2001 render a
//! low-poly face mesh carrying the grown normal map (section 5, figure 7); this head plays its
//! part for the sample face map.
//!
//! # Geometry
//! A deformed ellipsoid in millimetres ([`HEAD_MM_PER_UNIT`] = 1): 150 mm wide, 210 mm tall,
//! 190 mm deep before the features, centred on the origin, +y up, the face looking along +z
//! (toward the default camera). The jaw tapers, and Gaussian offsets along the radius add a brow
//! ridge, eye sockets, a nose, cheeks, lips, a chin and ears.
//!
//! # UV unwrap
//! Cylindrical: `u` runs around the head, `v` from the crown (`v = 0`, top of the image) to below
//! the chin (`v = 1`). It matches `samples/face/layout.toml`: the face is centred on `u = 0.5`
//! (the subject's right on the left of the map), the ears sit at `u = 0.1` and `0.9`, the
//! hairline near `v = 0.05` and the chin near `v = 0.85-0.95`, with the forehead (`v = 0.14`),
//! nose (`0.47`) and cheeks (`u = 0.27, 0.73`, `v = 0.6`) where the layout puts them. The face
//! therefore gets most of the map: azimuth is `pi * f(2u - 1)` with an odd polynomial `f` that is
//! slow around the front, and the polar angle is piecewise linear in `v` (40 degrees over the
//! crown cap `v < 0.05`, 105 over the face, 35 below the chin). The seam is at the back
//! (`u = 0 = 1`); the poles are fans whose vertices carry the middle `u` of their column.

use std::f32::consts::PI;
use std::io::Write;
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::mesh::Mesh;

/// Millimetres per unit of the sample head.
pub const HEAD_MM_PER_UNIT: f32 = 1.0;

/// Columns around the head.
pub const HEAD_COLUMNS: usize = 128;

/// Rows from crown to bottom.
pub const HEAD_ROWS: usize = 96;

/// A radial Gaussian offset in UV space: `amp * exp(-((du/su)^2 + (dv/sv)^2) / 2)`.
struct Feature {
    at: [f32; 2],
    sigma: [f32; 2],
    amp: f32,
}

const fn f(u: f32, v: f32, su: f32, sv: f32, amp: f32) -> Feature {
    Feature { at: [u, v], sigma: [su, sv], amp }
}

/// The face, placed on the layout's UV positions (see the module docs).
const FEATURES: &[Feature] = &[
    f(0.5, 0.30, 0.12, 0.025, 0.035),  // brow ridge
    f(0.41, 0.37, 0.035, 0.03, -0.05), // eye socket (subject's right)
    f(0.59, 0.37, 0.035, 0.03, -0.05), // eye socket (subject's left)
    f(0.5, 0.40, 0.022, 0.06, 0.07),   // nose bridge
    f(0.5, 0.48, 0.03, 0.035, 0.16),   // nose tip
    f(0.29, 0.58, 0.05, 0.05, 0.05),   // cheek
    f(0.71, 0.58, 0.05, 0.05, 0.05),   // cheek
    f(0.5, 0.66, 0.04, 0.02, 0.03),    // lips
    f(0.5, 0.86, 0.05, 0.04, 0.06),    // chin
    f(0.1, 0.45, 0.02, 0.05, 0.08),    // ear
    f(0.9, 0.45, 0.02, 0.05, 0.08),    // ear
];

/// The sample head: `2 * HEAD_COLUMNS + (HEAD_ROWS - 1) * (HEAD_COLUMNS + 1)` vertices (12511),
/// counter-clockwise triangles seen from outside, area-weighted normals welded across the seam
/// and the poles.
pub fn sample_head() -> Mesh {
    let (nu, nv) = (HEAD_COLUMNS, HEAD_ROWS);
    let mut mesh = Mesh::default();
    let mut weld = Vec::new();
    let rows: Vec<u32> = (0..=nv).map(|j| push_row(&mut mesh, &mut weld, j, nu, nv)).collect();
    for j in 0..nv {
        for i in 0..nu {
            push_quad(&mut mesh, &rows, i, j, nv);
        }
    }
    mesh.normals = welded_normals(&mesh, &weld, nu + 1);
    mesh
}

/// Appends row `j` and returns the index of its first vertex. `weld` gets, per vertex, an id
/// shared by vertices at the same place (a pole, or the seam columns 0 and `nu`).
fn push_row(mesh: &mut Mesh, weld: &mut Vec<usize>, j: usize, nu: usize, nv: usize) -> u32 {
    let first = mesh.positions.len() as u32;
    let v = j as f32 / nv as f32;
    let pole = j == 0 || j == nv;
    let columns = if pole { nu } else { nu + 1 };
    for i in 0..columns {
        let u = if pole { (i as f32 + 0.5) / nu as f32 } else { i as f32 / nu as f32 };
        // The seam column repeats column 0's position exactly.
        let u_geo = if i == nu { 0.0 } else { u };
        mesh.positions.push(if pole { pole_position(j == 0) } else { surface(u_geo, v) });
        mesh.uvs.push(Vec2::new(u, v));
        weld.push(if pole { j * (nu + 1) } else { j * (nu + 1) + i % nu });
    }
    first
}

/// Two triangles of the quad below-right of grid point `(i, j)`, one at the poles.
fn push_quad(mesh: &mut Mesh, rows: &[u32], i: usize, j: usize, nv: usize) {
    let i = i as u32;
    let (a, b) = (rows[j] + i, rows[j] + i + 1);
    let (c, d) = (rows[j + 1] + i, rows[j + 1] + i + 1);
    if j == 0 {
        // a is the crown vertex of column i.
        mesh.indices.extend([a, c, d]);
    } else if j + 1 == nv {
        // c is the bottom vertex of column i.
        mesh.indices.extend([a, c, b]);
    } else {
        mesh.indices.extend([a, c, d, a, d, b]);
    }
}

fn pole_position(top: bool) -> Vec3 {
    if top { Vec3::new(0.0, 105.0, 0.0) } else { Vec3::new(0.0, -105.0, 0.0) }
}

/// Azimuth (0 toward +z, positive toward +x) for `u`: slow across the face, ears at `u = 0.1, 0.9`.
fn azimuth(u: f32) -> f32 {
    let s = 2.0 * u - 1.0;
    // f(s) = 0.55 s + 0.45 s^9: odd, increasing, f(±1) = ±1, f(±0.8) ≈ ±0.5.
    PI * (0.55 * s + 0.45 * s.powi(9))
}

/// Polar angle from +y for `v`, piecewise linear through the layout's hairline and chin.
fn polar(v: f32) -> f32 {
    let knots = [(0.0, 0.0), (0.05, 40.0), (0.95, 145.0), (1.0, 180.0)];
    let k = knots.windows(2).find(|w| v <= w[1].0).unwrap_or(&knots[2..4]);
    let ((v0, t0), (v1, t1)) = (k[0], k[1]);
    let deg: f32 = t0 + (t1 - t0) * ((v - v0) / (v1 - v0)).clamp(0.0, 1.0);
    deg.to_radians()
}

/// The head surface at `(u, v)`.
fn surface(u: f32, v: f32) -> Vec3 {
    let (alpha, theta) = (azimuth(u), polar(v));
    let dir = Vec3::new(theta.sin() * alpha.sin(), theta.cos(), theta.sin() * alpha.cos());
    // The jaw narrows below the cheekbones.
    let taper = 1.0 - 0.22 * smoothstep(95f32.to_radians(), 150f32.to_radians(), theta);
    let radii = Vec3::new(75.0 * taper, 105.0, 95.0);
    dir * radii * (1.0 + relief(u, v))
}

fn relief(u: f32, v: f32) -> f32 {
    FEATURES
        .iter()
        .map(|f| {
            let du = (u - f.at[0]) / f.sigma[0];
            let dv = (v - f.at[1]) / f.sigma[1];
            f.amp * (-0.5 * (du * du + dv * dv)).exp()
        })
        .sum()
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Area-weighted normals summed over vertices that share a weld id (ids are `< ids_per_row *
/// rows`), so the seam and the poles shade smoothly.
fn welded_normals(mesh: &Mesh, weld: &[usize], ids_per_row: usize) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; ids_per_row * (HEAD_ROWS + 1)];
    for t in 0..mesh.triangle_count() {
        let [a, b, c] = mesh.triangle(t);
        let p = [a, b, c].map(|k| mesh.positions[k]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        for k in [a, b, c] {
            sums[weld[k]] += n;
        }
    }
    weld.iter().map(|&id| sums[id].try_normalize().unwrap_or(Vec3::Y)).collect()
}

/// Writes `mesh` as an OBJ file (positions, `vt` with `v` flipped back to OBJ's bottom origin,
/// normals, `f a/a/a`), atomically. Numbers use Rust's shortest round-trip formatting.
///
/// # Errors
/// When the file cannot be written.
pub fn write_obj(mesh: &Mesh, path: &Path) -> skinkit_maps::Result<()> {
    skinkit_maps::io::write_atomic(path, |w| {
        obj_text(mesh, w).map_err(|error| skinkit_maps::Error::Io { path: path.to_owned(), error })
    })
}

/// Writes `mesh` as OBJ text to `w` (see [`write_obj`]).
///
/// # Errors
/// When `w` fails.
pub(crate) fn obj_text(mesh: &Mesh, w: &mut impl Write) -> std::io::Result<()> {
    writeln!(w, "# skinkit sample head: {} mm per unit", HEAD_MM_PER_UNIT)?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for t in &mesh.uvs {
        writeln!(w, "vt {} {}", t.x, 1.0 - t.y)?;
    }
    for n in &mesh.normals {
        writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] + 1, tri[1] + 1, tri[2] + 1];
        writeln!(w, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?;
    }
    Ok(())
}
