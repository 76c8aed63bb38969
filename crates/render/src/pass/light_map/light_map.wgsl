// TSD's light map (vertex stage in tsd.wgsl). Part of the module that src/pass/mod.rs assembles.

// The light map's uniforms (`LightMapUniforms` in src/pass/light_map/mod.rs).
struct LightMapUniforms {
    // Light-map side in texels.
    size: f32,
    // The kernel's base radius in mm (derived from the scattering profile).
    kernel_mm: f32,
    // Growth of the kernel with curvature, in mm.
    curvature_gain: f32,
    // The largest kernel radius in texels (alpha stores radius / max_radius).
    max_radius: f32,
    // 1: the kernel size comes from the kernel map.
    kernel_from_map: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

struct LightMapOut {
    // Irradiance, and the kernel size in alpha.
    @location(0) light: vec4<f32>,
    // The kernel's widening along u and v: the mean mm per texel the kernel size assumed over
    // the mm a texel spans along each axis (1 with an artist's kernel map, given in texels).
    @location(1) stretch: vec4<f32>,
}

// Diffuse irradiance of every light at the texel (the key light through its shadow map), the
// blur kernel size in alpha (never 1: the cleared value marks unwritten texels for dilation),
// and the stretch map.
@fragment
fn fs_light_map(input: TextureSpaceOut) -> LightMapOut {
    let geo_n = normalize_or(input.frame_n, vec3<f32>(0.0, 0.0, 1.0));
    let n = to_object(decode_normal(textureSampleLevel(normal_map, map_sampler, input.uv, 0.0)), input.frame_t,
        input.frame_b, geo_n);
    var e = vec3<f32>(0.0);
    let key = globals.scene.key_light;
    let count = min(globals.scene.light_count, MAX_LIGHTS);
    for (var i = 0u; i < count; i++) {
        var visibility = vec3<f32>(1.0);
        if SHADOWS && i == key {
            let s = shadow_visibility(input.world, geo_n, input.frame_t, input.frame_b);
            visibility = s * translucent_transmittance(input.world, geo_n);
        }
        e += light_irradiance(i, input.world) * max(dot(n, light_direction(i, input.world)), 0.0) * visibility;
    }
    var k = 0.0;
    var widening = vec2<f32>(1.0);
    if globals.light_map.kernel_from_map == 1u {
        k = textureSampleLevel(kernel_map, map_sampler, input.uv, 0.0).r;
    } else {
        let inv_r = max(input.skin.x, 0.0);
        let texel_mm = max(input.skin.y, 1e-6) / globals.light_map.size;
        let radius = globals.light_map.kernel_mm * (1.0 + globals.light_map.curvature_gain * inv_r) / texel_mm;
        k = radius / globals.light_map.max_radius;
        // The mm one texel spans along u (x) and v (y) of this triangle.
        let along = vec2<f32>(length(dpdx(input.world)), length(dpdy(input.world))) * globals.scene.mm_per_unit;
        widening = clamp(texel_mm / max(along, vec2<f32>(1e-9)), vec2<f32>(0.125), vec2<f32>(8.0));
    }
    var out: LightMapOut;
    out.light = vec4<f32>(e, clamp(k, 0.0, 0.999));
    out.stretch = vec4<f32>(widening, 0.0, 1.0);
    return out;
}
