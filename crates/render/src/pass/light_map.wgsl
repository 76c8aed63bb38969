// TSD's light map (vertex stage in tsd.wgsl). Part of the module that src/pass/mod.rs assembles.

// Diffuse irradiance of every light at the texel (the key light through its shadow map), and the
// blur kernel size in alpha (never 1: the cleared value marks unwritten texels for dilation).
@fragment
fn fs_light_map(input: TextureSpaceOut) -> @location(0) vec4<f32> {
    let geo_n = normalize_or(input.frame_n, vec3<f32>(0.0, 0.0, 1.0));
    let n = to_object(decode_normal(textureSampleLevel(normal_map, map_sampler, input.uv, 0.0)), input.frame_t,
        input.frame_b, geo_n);
    var e = vec3<f32>(0.0);
    let key = u32(globals.blur.w);
    let count = min(globals.counts.x, MAX_LIGHTS);
    for (var i = 0u; i < count; i++) {
        var visibility = vec3<f32>(1.0);
        if SHADOWS && i == key {
            let s = shadow_visibility(input.world, geo_n, input.frame_t, input.frame_b);
            visibility = s * translucent_transmittance(input.world, geo_n);
        }
        e += light_irradiance(i, input.world) * max(dot(n, light_direction(i, input.world)), 0.0) * visibility;
    }
    var k = 0.0;
    if globals.tsd_kernel.z == 1.0 {
        k = textureSampleLevel(kernel_map, map_sampler, input.uv, 0.0).r;
    } else {
        let inv_r = max(input.skin.x, 0.0);
        let texel_mm = max(input.skin.y, 1e-6) / globals.tsd.y;
        let radius = globals.tsd.z * (1.0 + globals.tsd.w * inv_r) / texel_mm;
        k = radius / globals.tsd_kernel.w;
    }
    return vec4<f32>(e, clamp(k, 0.0, 0.999));
}
