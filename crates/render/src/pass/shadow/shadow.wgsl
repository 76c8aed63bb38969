// The key light's shadow map: the depth pass (vs_shadow) and the filtered lookup the base and
// light-map passes read it with. Part of the module that src/pass/mod.rs assembles.

// The shadow map's uniforms (`ShadowUniforms` in src/pass/shadow/mod.rs).
struct ShadowUniforms {
    // The key light's view-projection.
    view_proj: mat4x4<f32>,
    // 1 / shadow map side.
    inv_size: f32,
    // Filter taps: per side of the box, or in all on shadow scattering's disc.
    taps: f32,
    // One shadow-map texel in mesh units.
    texel: f32,
    // Normal offset in texels.
    normal_offset: f32,
    // Shadow scattering's disc of taps on the receiver: its radius in mesh units.
    disc_radius: f32,
    pad0: f32,
    pad1: f32,
    pad2: f32,
}

// The key light's shadow map coordinates of `world`: uv (row 0 at the top) and depth.
fn shadow_coords(world: vec3<f32>) -> vec3<f32> {
    let clip = globals.shadow.view_proj * vec4<f32>(world, 1.0);
    let ndc = clip.xyz / clip.w;
    return vec3<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5, ndc.z);
}

// Box-filtered shadow test (filter x filter taps, nearest compare): across a straight edge this
// is a linear ramp. The lookup point is pushed
// along the geometric normal by `shadow.w` texels (normal-offset bias), and each tap compares
// against the receiver's own plane at that tap (receiver-plane depth bias: the depth gradient of
// the surface in shadow-map space, from its tangent frame), so a wide filter does not shadow a
// sloped receiver with itself.
fn shadow_visibility(world: vec3<f32>, geo_n: vec3<f32>, t: vec3<f32>, b: vec3<f32>) -> f32 {
    let origin = world + geo_n * (globals.shadow.texel * globals.shadow.normal_offset);
    let p = shadow_coords(origin);
    if p.z <= 0.0 || p.z >= 1.0 || p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0 {
        return 1.0;
    }
    let step = globals.shadow.texel;
    let pt = shadow_coords(origin + t * step) - p;
    let pb = shadow_coords(origin + b * step) - p;
    // Solve [pt.xy pb.xy] * (a, c) = offset for the depth change dz = a pt.z + c pb.z.
    let det = pt.x * pb.y - pt.y * pb.x;
    var gradient = vec2<f32>(0.0);
    if abs(det) > 1e-12 {
        gradient = vec2<f32>(pb.y * pt.z - pt.y * pb.z, pt.x * pb.z - pb.x * pt.z) / det;
    }
    // At grazing angles the plane is nearly edge-on: cap the slope (the light's N.L is near 0
    // there anyway).
    let cap = 8.0 * length(vec2<f32>(pt.z, pb.z)) / max(length(pt.xy), 1e-12);
    let g_len = length(gradient);
    if g_len > cap {
        gradient = gradient * (cap / g_len);
    }
    let taps = i32(globals.shadow.taps);
    let h = (taps - 1) / 2;
    let epsilon = 2.0 * globals.shadow.inv_size * abs(pt.z) / max(length(pt.xy), 1e-12) + 1e-6;
    var sum = 0.0;
    for (var j = -h; j <= h; j++) {
        for (var i = -h; i <= h; i++) {
            let offset = vec2<f32>(f32(i), f32(j)) * globals.shadow.inv_size;
            let depth = p.z + dot(gradient, offset) - epsilon;
            sum += textureSampleCompareLevel(shadow_map, shadow_sampler, p.xy + offset, depth);
        }
    }
    return sum / f32(taps * taps);
}

// Shadow scattering's visibility: the lit share of a disc of `disc_radius` on the receiver's
// tangent plane, `taps` taps on a golden-angle spiral (equal areas). Each tap compares its own
// depth, so a sloped receiver needs no plane bias and the penumbra's width in mm does not depend
// on the light's slope. The disc is pushed toward the light (a depth bias that does not move the
// edge sideways, as a normal offset would): `normal_offset` texels, scaled by the receiver's
// slope to the light, plus r^2 / (2 CONCAVE_RADIUS_MM) at radius r so a receiver curving toward
// the light (a fold, an eye socket) does not shadow itself.
const CONCAVE_RADIUS_MM: f32 = 25.0;
const GOLDEN_ANGLE: f32 = 2.39996323;
fn disc_visibility(world: vec3<f32>, geo_n: vec3<f32>, l: vec3<f32>) -> f32 {
    let c = clamp(dot(geo_n, l), 0.1, 1.0);
    let slope = sqrt(1.0 - c * c) / c;
    let origin = world + l * (globals.shadow.texel * globals.shadow.normal_offset * (1.0 + slope));
    let e1 = any_perpendicular(geo_n);
    let e2 = cross(geo_n, e1);
    // Clip coordinates are linear in the tap's offsets: project the origin and the three
    // directions once.
    let radius = globals.shadow.disc_radius;
    let m = globals.shadow.view_proj;
    let c0 = m * vec4<f32>(origin, 1.0);
    let c1 = m * vec4<f32>(e1 * radius, 0.0);
    let c2 = m * vec4<f32>(e2 * radius, 0.0);
    let c3 = m * vec4<f32>(l * (radius * radius * globals.scene.mm_per_unit / (2.0 * CONCAVE_RADIUS_MM)), 0.0);
    let count = max(u32(globals.shadow.taps), 1u);
    // The spiral's angle advances by the golden angle: a fixed rotation of (cos, sin).
    let turn = vec2<f32>(cos(GOLDEN_ANGLE), sin(GOLDEN_ANGLE));
    var dir = vec2<f32>(1.0, 0.0);
    var sum = 0.0;
    for (var k = 0u; k < count; k++) {
        let r2 = (f32(k) + 0.5) / f32(count);
        let r = sqrt(r2);
        let clip = c0 + c1 * (r * dir.x) + c2 * (r * dir.y) + c3 * r2;
        dir = vec2<f32>(dir.x * turn.x - dir.y * turn.y, dir.x * turn.y + dir.y * turn.x);
        let ndc = clip.xyz / clip.w;
        let p = vec3<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5, ndc.z);
        if p.z <= 0.0 || p.z >= 1.0 || p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0 {
            sum += 1.0;
        } else {
            sum += textureSampleCompareLevel(shadow_map, shadow_sampler, p.xy, p.z);
        }
    }
    return sum / f32(count);
}

@vertex
fn vs_shadow(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return globals.shadow.view_proj * vec4<f32>(position, 1.0);
}
