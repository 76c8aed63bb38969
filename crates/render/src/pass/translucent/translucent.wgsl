// Translucent shadows (Gosselin et al.): the casters' summed opacity seen from the key light, and
// the transmittance the base and light-map passes read from it. Part of the module that
// src/pass/mod.rs assembles.

// Light let through the translucent casters in front of `world` (Gosselin et al.'s translucent
// shadows): one minus their summed opacity per channel, 1 without translucent casters.
fn translucent_transmittance(world: vec3<f32>, geo_n: vec3<f32>) -> vec3<f32> {
    if !TRANSLUCENT_SHADOWS {
        return vec3<f32>(1.0);
    }
    let p = shadow_coords(world + geo_n * (globals.shadow.texel * globals.shadow.normal_offset));
    if p.z <= 0.0 || p.z >= 1.0 || p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0 {
        return vec3<f32>(1.0);
    }
    let opacity = textureSampleLevel(shadow_opacity, lut_sampler, p.xy, 0.0).rgb;
    return clamp(vec3<f32>(1.0) - opacity, vec3<f32>(0.0), vec3<f32>(1.0));
}

struct TranslucentOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) opacity: vec3<f32>,
}

// Translucent casters into the shadow map's opacity channels (depth-tested against the opaque
// depth, not written; blended additively).
@vertex
fn vs_translucent(@location(0) position: vec3<f32>, @location(1) opacity: vec3<f32>) -> TranslucentOut {
    var out: TranslucentOut;
    out.clip = globals.shadow.view_proj * vec4<f32>(position, 1.0);
    out.opacity = opacity;
    return out;
}

@fragment
fn fs_translucent(input: TranslucentOut) -> @location(0) vec4<f32> {
    return vec4<f32>(input.opacity, 0.0);
}
