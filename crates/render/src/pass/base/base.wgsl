// The base pass: texture-space per-pixel bump mapping with the Lafortune BRDF
// (Haro et al. 2001, section 5), and the skin effects it reads (pre-integrated diffuse, shadow
// scattering, SH ambient, a TSD light map). The CPU reference of every step is src/shading.rs;
// keep the two in step (tests/render/gpu.rs compares them pixel by pixel). Part of the module that
// src/pass/mod.rs assembles after common.wgsl.

struct Lobe {
    cx: vec4<f32>,
    cy: vec4<f32>,
    cz: vec4<f32>,
    n: vec4<f32>,
}

// The base pass's uniforms (`BaseUniforms` in src/pass/base/mod.rs).
struct BaseUniforms {
    // Lafortune rho_d.
    diffuse: vec3<f32>,
    lobe_count: u32,
    // Per-channel blend toward the blurred normal.
    normal_blur: vec3<f32>,
    // 1: the specular is evaluated per vertex.
    vertex_specular: u32,
    // 0 none, 1 clamp, 2 Reinhard.
    tone: u32,
    curvature_scale: f32,
    // Diffuse LUT v = inv_r * lut_scale + lut_offset.
    lut_scale: f32,
    lut_offset: f32,
    // Zonal table u = inv_r * zonal_scale + zonal_offset.
    zonal_scale: f32,
    zonal_offset: f32,
    // Shadow LUT v = width_mm * shadow_lut_scale + shadow_lut_offset.
    shadow_lut_scale: f32,
    shadow_lut_offset: f32,
    // The sharp penumbra's share (shadow scattering).
    new_penumbra: f32,
    pad0: f32,
    pad1: f32,
    pad2: f32,
    lobes: array<Lobe, 4>,
    // Environment radiance SH, 9 RGB coefficients (l = 0, 1, 2).
    sh: array<vec4<f32>, 9>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) view_ts: vec3<f32>,
    @location(2) world: vec3<f32>,
    @location(3) vertex_specular: vec3<f32>,
    @location(4) light0: vec3<f32>,
    @location(5) light1: vec3<f32>,
    @location(6) light2: vec3<f32>,
    @location(7) light3: vec3<f32>,
    // Object-space tangent frame (for world normals: SH ambient, curvature, shadows).
    @location(8) frame_t: vec3<f32>,
    @location(9) frame_b: vec3<f32>,
    @location(10) frame_n: vec3<f32>,
    @location(11) skin: vec2<f32>,
}

// Per channel max(0, base)^n capped at LOBE_CEILING; the power of a non-positive (or NaN) base is
// never used: `select` keeps the three channels in one vector op (llvmpipe runs it per SIMD lane).
fn lobe_power(base: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let value = min(pow(max(base, vec3<f32>(1e-30)), max(n, vec3<f32>(0.0))), vec3<f32>(LOBE_CEILING));
    return select(vec3<f32>(0.0), value, base > vec3<f32>(0.0));
}

fn lobes_sum(l: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let count = min(globals.base.lobe_count, MAX_LOBES);
    for (var i = 0u; i < count; i++) {
        let lobe = globals.base.lobes[i];
        let base = lobe.cx.xyz * (l.x * v.x) + lobe.cy.xyz * (l.y * v.y) + lobe.cz.xyz * (l.z * v.z);
        sum += lobe_power(base, lobe.n.xyz);
    }
    return sum;
}

@vertex
fn vs_main(input: VertexIn) -> VertexOut {
    let frame = vertex_frame(input);
    let t = frame[0];
    let b = frame[1];
    let n = frame[2];
    // Object space to the vertex's texture space (the paper's M_T, equation 6).
    let to_ts = transpose(mat3x3<f32>(t, b, n));
    let world = input.position;
    let view_ts = to_ts * normalize_or(globals.scene.eye - world, n);

    var lights_ts = array<vec3<f32>, 4>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var vertex_specular = vec3<f32>(0.0);
    let count = min(globals.scene.light_count, MAX_LIGHTS);
    for (var i = 0u; i < count; i++) {
        let l = to_ts * light_direction(i, world);
        lights_ts[i] = l;
        if globals.base.vertex_specular == 1u {
            vertex_specular += light_irradiance(i, world) * lobes_sum(l, view_ts) * max(l.z, 0.0);
        }
    }

    var out: VertexOut;
    out.clip = globals.scene.view_proj * vec4<f32>(world, 1.0);
    out.uv = input.uv;
    out.view_ts = view_ts;
    out.world = world;
    out.vertex_specular = vertex_specular;
    out.light0 = lights_ts[0];
    out.light1 = lights_ts[1];
    out.light2 = lights_ts[2];
    out.light3 = lights_ts[3];
    out.frame_t = t;
    out.frame_b = b;
    out.frame_n = n;
    out.skin = input.skin;
    return out;
}

// Texture-space `d` in the frame whose z is the map normal `n`.
fn to_normal_frame(n: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let t = perpendicular_part(vec3<f32>(1.0, 0.0, 0.0), n);
    let b = cross(n, t);
    return vec3<f32>(dot(d, t), dot(d, b), dot(d, n));
}

fn tone_map(radiance: vec3<f32>) -> vec3<f32> {
    let c = max(radiance * globals.scene.exposure, vec3<f32>(0.0));
    if globals.base.tone == 1u {
        return min(c, vec3<f32>(1.0));
    }
    if globals.base.tone == 2u {
        return c / (vec3<f32>(1.0) + c);
    }
    return c;
}

// 1/r in 1/mm for the LUT: the vertex attribute, or the paper's derivative form
// length(fwidth(N)) / length(fwidth(P)) with P in millimetres (constant per triangle).
fn curvature(skin: vec2<f32>, world: vec3<f32>, geo_n: vec3<f32>) -> f32 {
    var k = skin.x;
    if CURVATURE_MODE == 1u {
        let dn = length(fwidth(geo_n));
        let dp = length(fwidth(world)) * globals.scene.mm_per_unit;
        k = dn / max(dp, 1e-6);
    }
    let scaled = k * globals.base.curvature_scale;
    if scaled > 0.0 && scaled < 3.0e38 {
        return scaled;
    }
    return 0.0;
}

// The shadow table's row: the diameter of shadow scattering's disc in mm.
fn penumbra_mm() -> f32 {
    return 2.0 * globals.shadow.disc_radius * globals.scene.mm_per_unit;
}

// The sharp penumbra P'(P^-1(s)) (a ramp `new_penumbra` as wide as the disc), for the specular:
// near the edge the disc's lit share is s = 0.5 + (2 / pi) t, t the edge's distance in radii, and
// a narrow new penumbra only needs it there.
fn sharp_shadow(s: f32) -> f32 {
    return clamp(0.5 + (s - 0.5) * 0.7853982 / globals.base.new_penumbra, 0.0, 1.0);
}

fn shadow_scattered(s: f32, width_mm: f32) -> vec3<f32> {
    let v = width_mm * globals.base.shadow_lut_scale + globals.base.shadow_lut_offset;
    return textureSampleLevel(shadow_lut, lut_sampler, vec2<f32>(s, v), 0.0).rgb;
}

fn lut_lookup(ndl: vec3<f32>, inv_r: f32) -> vec3<f32> {
    let v = inv_r * globals.base.lut_scale + globals.base.lut_offset;
    let r = textureSampleLevel(diffuse_lut, lut_sampler, vec2<f32>(ndl.x * 0.5 + 0.5, v), 0.0).r;
    let g = textureSampleLevel(diffuse_lut, lut_sampler, vec2<f32>(ndl.y * 0.5 + 0.5, v), 0.0).g;
    let b = textureSampleLevel(diffuse_lut, lut_sampler, vec2<f32>(ndl.z * 0.5 + 0.5, v), 0.0).b;
    return vec3<f32>(r, g, b);
}

// Per-channel normals: the full map blended toward its blurred (mip-clamped) sample.
fn channel_normals(n: vec3<f32>, n_blur: vec3<f32>) -> array<vec3<f32>, 3> {
    return array<vec3<f32>, 3>(
        normalize_or(mix(n, n_blur, globals.base.normal_blur.x), n),
        normalize_or(mix(n, n_blur, globals.base.normal_blur.y), n),
        normalize_or(mix(n, n_blur, globals.base.normal_blur.z), n),
    );
}

// The diffuse falloff per channel for a texture-space light direction: max(0, N.L) (Lambert) or
// the pre-integrated D(N.L, 1/r) from the LUT or a closed form, with per-channel normals.
fn diffuse_falloff(normals: array<vec3<f32>, 3>, l_ts: vec3<f32>, inv_r: f32) -> vec3<f32> {
    let ndl = vec3<f32>(dot(normals[0], l_ts), dot(normals[1], l_ts), dot(normals[2], l_ts));
    if DIFFUSE_MODE == 1u {
        return lut_lookup(ndl, inv_r);
    }
    if DIFFUSE_MODE == 2u {
        return blog_direct(ndl, inv_r);
    }
    if DIFFUSE_MODE == 3u {
        return own_direct(ndl, inv_r);
    }
    return max(ndl, vec3<f32>(0.0));
}

fn sh_basis(d: vec3<f32>) -> array<f32, 9> {
    return array<f32, 9>(
        0.282095,
        0.488603 * d.y,
        0.488603 * d.z,
        0.488603 * d.x,
        1.092548 * d.x * d.y,
        1.092548 * d.y * d.z,
        0.315392 * (3.0 * d.z * d.z - 1.0),
        1.092548 * d.x * d.z,
        0.546274 * (d.x * d.x - d.y * d.y),
    );
}

// Convolution factors A_l (l = 0, 1, 2) for channel c: Lambert's, or the skin's per 1/r.
fn zonal_factors(c: u32, inv_r: f32) -> vec3<f32> {
    if DIFFUSE_MODE == 0u || DIFFUSE_MODE == 4u {
        return vec3<f32>(PI, 2.0 * PI / 3.0, PI / 4.0);
    }
    let u = inv_r * globals.base.zonal_scale + globals.base.zonal_offset;
    let a0 = textureSampleLevel(zonal_table, lut_sampler, vec2<f32>(u, 1.0 / 6.0), 0.0);
    let a1 = textureSampleLevel(zonal_table, lut_sampler, vec2<f32>(u, 0.5), 0.0);
    let a2 = textureSampleLevel(zonal_table, lut_sampler, vec2<f32>(u, 5.0 / 6.0), 0.0);
    return vec3<f32>(a0[c], a1[c], a2[c]);
}

// Ambient irradiance per channel from the order-2 SH environment, each channel with its normal
// (object space) and the skin's zonal factors.
fn ambient_irradiance(normals: array<vec3<f32>, 3>, inv_r: f32) -> vec3<f32> {
    var e = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        let y = sh_basis(normals[c]);
        let a = zonal_factors(c, inv_r);
        var sum = 0.0;
        for (var k = 0u; k < 9u; k++) {
            var band = a.x;
            if k >= 4u {
                band = a.z;
            } else if k >= 1u {
                band = a.y;
            }
            sum += band * globals.base.sh[k][c] * y[k];
        }
        e[c] = max(sum, 0.0);
    }
    return e;
}

@fragment
fn fs_main(input: VertexOut) -> @location(0) vec4<f32> {
    let n = decode_normal(textureSample(normal_map, map_sampler, input.uv));
    var n_blur = n;
    if DIFFUSE_MODE >= 1u && DIFFUSE_MODE <= 3u {
        n_blur = decode_normal(textureSample(normal_map, blurred_sampler, input.uv));
    }
    var light_map_e = vec3<f32>(0.0);
    if DIFFUSE_MODE == 4u {
        light_map_e = textureSample(light_map, lut_sampler, input.uv).rgb;
    }
    // Surfaces whose UVs leave the map's square (the sample head's eyes and pockets, moved to
    // u + 1) are not drawn into the light map: they are shaded directly, as Lambert.
    let uv_in_map = all(input.uv >= vec2<f32>(0.0)) && all(input.uv <= vec2<f32>(1.0));
    let from_map = DIFFUSE_MODE == 4u && uv_in_map;
    let albedo = textureSample(albedo_map, map_sampler, input.uv).rgb;
    let geo_n = normalize_or(input.frame_n, vec3<f32>(0.0, 0.0, 1.0));
    let inv_r = curvature(input.skin, input.world, geo_n);
    let rho = globals.base.diffuse * albedo / PI;
    let v = to_normal_frame(n, normalize_or(input.view_ts, vec3<f32>(0.0, 0.0, 1.0)));
    var lights_ts = array<vec3<f32>, 4>(input.light0, input.light1, input.light2, input.light3);
    let normals = channel_normals(n, n_blur);
    let key = globals.scene.key_light;

    var radiance = input.vertex_specular;
    var unshadowed = vec3<f32>(0.0);
    var key_specular = vec3<f32>(0.0);
    let count = min(globals.scene.light_count, MAX_LIGHTS);
    for (var i = 0u; i < count; i++) {
        let l_ts = normalize_or(lights_ts[i], vec3<f32>(0.0, 0.0, 1.0));
        let l = to_normal_frame(n, l_ts);
        let e = light_irradiance(i, input.world);
        var shadow_diffuse = vec3<f32>(1.0);
        var shadow_specular = 1.0;
        // With a light map the key light's shadow is already in it (and its specular is
        // attenuated by the light map below): no shadow-map lookups here.
        if SHADOWS && !from_map && i == key {
            if SHADOW_SCATTERING {
                let s = disc_visibility(input.world, geo_n, light_direction(i, input.world));
                shadow_diffuse = shadow_scattered(s, penumbra_mm());
                shadow_specular = sharp_shadow(s);
            } else {
                let s = shadow_visibility(input.world, geo_n, input.frame_t, input.frame_b);
                shadow_diffuse = vec3<f32>(s);
                shadow_specular = s;
            }
            let through = translucent_transmittance(input.world, geo_n);
            shadow_diffuse *= through;
            shadow_specular *= luminance(through);
        }
        if from_map {
            unshadowed += e * max(l.z, 0.0);
        } else {
            radiance += e * rho * diffuse_falloff(normals, l_ts, inv_r) * shadow_diffuse;
        }
        if globals.base.vertex_specular == 0u {
            let specular = e * lobes_sum(l, v) * max(l.z, 0.0);
            if from_map && SHADOWS && i == key {
                key_specular = specular;
            } else {
                radiance += specular * shadow_specular;
            }
        }
    }
    if from_map {
        // Gosselin et al.: diffuse = light map x albedo; the key light's specular is attenuated
        // by the light map's luminance, taken relative to the unshadowed irradiance here.
        radiance += rho * light_map_e;
        let attenuation = clamp(luminance(light_map_e) / max(luminance(unshadowed), 1e-6), 0.0, 1.0);
        radiance += key_specular * attenuation;
    }
    if SH_AMBIENT {
        let t = input.frame_t;
        let b = input.frame_b;
        let world_normals = array<vec3<f32>, 3>(
            to_object(normals[0], t, b, geo_n),
            to_object(normals[1], t, b, geo_n),
            to_object(normals[2], t, b, geo_n),
        );
        radiance += rho * ambient_irradiance(world_normals, inv_r);
    }
    return vec4<f32>(tone_map(radiance), 1.0);
}
