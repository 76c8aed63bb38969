//! The geometry the passes need: the mesh's bounding sphere, the key light's projection, the
//! frustum and distance tests of TSD's culling, and the mesh's UV stretch.

use glam::{Mat4, Vec3, Vec4};

use crate::shading::{Light, LightKind, Vertex};

/// The bounding sphere of the vertices (centre of the box, largest distance); finite positions
/// only, a unit sphere at the origin when none are.
pub fn bounding_sphere(vertices: &[Vertex]) -> (Vec3, f32) {
    let finite = vertices.iter().map(|v| Vec3::from(v.position)).filter(|p| p.is_finite());
    let (lo, hi) = finite.clone().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
    if !lo.is_finite() {
        return (Vec3::ZERO, 1.0);
    }
    let centre = 0.5 * (lo + hi);
    let radius = finite.map(|p| p.distance(centre)).fold(0.0f32, f32::max);
    (centre, radius.max(1e-6))
}

/// The key light's view-projection bounding the mesh's sphere tightly (the chapter's advice),
/// and the size of one of `map_size` texels in mesh units: orthographic for a directional light,
/// perspective from the light for a point light (a point inside the sphere falls back to a wide
/// frustum looking at the centre).
pub fn light_view_proj(light: &Light, centre: Vec3, radius: f32, map_size: u32) -> (Mat4, f32) {
    match light.kind {
        LightKind::Directional { toward } => {
            let dir = toward.try_normalize().unwrap_or(Vec3::Z);
            let eye = centre + dir * (2.0 * radius);
            let view = Mat4::look_at_rh(eye, centre, any_up(dir));
            let proj = Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.5 * radius, 3.5 * radius);
            (proj * view, 2.0 * radius / map_size.max(1) as f32)
        }
        LightKind::Point { position } => {
            let to_centre = centre - position;
            let distance = to_centre.length();
            let dir = to_centre.try_normalize().unwrap_or(-Vec3::Z);
            let half_angle = if distance > radius * 1.01 { (radius / distance).asin() } else { 80f32.to_radians() };
            let near = (distance - radius).max(radius * 1e-3);
            let far = distance + radius;
            let view = Mat4::look_at_rh(position, position + dir, any_up(dir));
            let proj = Mat4::perspective_rh(2.0 * half_angle, 1.0, near, far);
            let texel = 2.0 * distance.max(radius) * half_angle.tan() / map_size.max(1) as f32;
            (proj * view, texel)
        }
    }
}

fn any_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() < 0.9 { Vec3::Y } else { Vec3::X }
}

/// Whether a sphere is at least partly inside the frustum of `view_proj` (the TSD frustum
/// culling test; planes from the matrix's rows, Gribb-Hartmann, wgpu depth 0..1).
pub(crate) fn sphere_in_frustum(view_proj: Mat4, centre: Vec3, radius: f32) -> bool {
    let m = view_proj.transpose();
    let (r0, r1, r2, r3) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
    let planes = [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2];
    let p = Vec4::new(centre.x, centre.y, centre.z, 1.0);
    planes.iter().all(|plane| {
        let len = plane.truncate().length();
        len == 0.0 || plane.dot(p) / len >= -radius
    })
}

/// The sphere's projected diameter in pixels for an image `height` pixels tall (the TSD distance
/// culling measure); infinite when the camera is inside it.
pub(crate) fn projected_diameter(view_proj: Mat4, eye: Vec3, centre: Vec3, radius: f32, height: u32) -> f32 {
    let distance = eye.distance(centre);
    if distance <= radius {
        return f32::INFINITY;
    }
    radius / distance * focal_from(view_proj) * height as f32
}

/// The vertical focal scale of a perspective view-projection (cot(fov/2)): the length of the
/// matrix's second row in its spatial part.
pub(crate) fn focal_from(view_proj: Mat4) -> f32 {
    view_proj.row(1).truncate().length()
}

/// Per vertex mm per UV unit: the square root of the summed world areas (mm^2) of its triangles
/// over their summed UV areas; vertices of zero-UV-area triangles only take the mesh's mean.
pub fn uv_stretch(vertices: &[Vertex], indices: &[u32], mm_per_unit: f32) -> Vec<f32> {
    let mut world = vec![0.0f64; vertices.len()];
    let mut uv = vec![0.0f64; vertices.len()];
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        if a >= vertices.len() || b >= vertices.len() || c >= vertices.len() {
            continue;
        }
        let p = |i: usize| Vec3::from(vertices[i].position) * mm_per_unit;
        let t = |i: usize| glam::Vec2::from(vertices[i].uv);
        let area_world = 0.5 * (p(b) - p(a)).cross(p(c) - p(a)).length() as f64;
        let area_uv = 0.5 * (t(b) - t(a)).perp_dot(t(c) - t(a)).abs() as f64;
        if !(area_world.is_finite() && area_uv.is_finite()) || area_uv < 1e-14 {
            continue;
        }
        for i in [a, b, c] {
            world[i] += area_world;
            uv[i] += area_uv;
        }
    }
    let (tw, tu) = (world.iter().sum::<f64>(), uv.iter().sum::<f64>());
    let mean = if tu > 0.0 { (tw / tu).sqrt() } else { 1.0 };
    world.iter().zip(&uv).map(|(&w, &u)| if u > 0.0 { (w / u).sqrt() as f32 } else { mean as f32 }).collect()
}
