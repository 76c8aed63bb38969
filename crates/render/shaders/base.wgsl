// The base pass: texture-space per-pixel bump mapping with the Lafortune BRDF
// (Haro et al. 2001, section 5). The CPU reference of every step is src/shading.rs; keep the two
// in step (tests/gpu.rs compares them pixel by pixel).
//
// The skin effects are pipeline-overridable constants: a scene that asks for none of them gets
// the plain base pass, with every skin branch folded away by the shader compiler. The same module
// holds the key light's shadow-map pass (vs_shadow) and the texture-space diffusion passes that
// draw the mesh at its UVs (vs_texture_space with fs_tsd_prepass and fs_light_map).
// skin_fit.wgsl (the closed-form LUT fits) is prepended by gpu.rs.

// 0 Lambert, 1 pre-integrated LUT, 2 the blog's closed form, 3 our fit, 4 a light map (TSD or the
// CPU reference) as the diffuse irradiance.
override DIFFUSE_MODE: u32 = 0u;
// 0 per-vertex 1/r (vertex attribute), 1 from screen-space derivatives.
override CURVATURE_MODE: u32 = 0u;
override SH_AMBIENT: bool = false;
override SHADOWS: bool = false;
override SHADOW_SCATTERING: bool = false;
override TRANSLUCENT_SHADOWS: bool = false;

const MAX_LIGHTS: u32 = 4u;
const MAX_LOBES: u32 = 4u;
const PI: f32 = 3.14159265358979;
// Same cap as brdf::LOBE_CEILING: a base above 1 with a huge exponent stays finite.
const LOBE_CEILING: f32 = 1.0e6;

struct Light {
    // xyz: direction toward the light (w = 0) or position (w = 1).
    vector: vec4<f32>,
    // rgb: colour * intensity.
    radiance: vec4<f32>,
}

struct Lobe {
    cx: vec4<f32>,
    cy: vec4<f32>,
    cz: vec4<f32>,
    n: vec4<f32>,
}

struct Globals {
    view_proj: mat4x4<f32>,
    // xyz: eye position; w: exposure.
    eye: vec4<f32>,
    // rgb: Lafortune rho_d.
    diffuse: vec4<f32>,
    // x: light count, y: lobe count, z: 1 = specular per vertex, w: 1 = green-down normal map.
    counts: vec4<u32>,
    // x: tone curve (0 none, 1 clamp, 2 Reinhard).
    options: vec4<u32>,
    lights: array<Light, 4>,
    lobes: array<Lobe, 4>,
    // x: curvature scale, y: mm per mesh unit, z, w: LUT v = inv_r * z + w.
    skin: vec4<f32>,
    // rgb: per-channel blend toward the blurred normal; w: key light index (shadows).
    blur: vec4<f32>,
    // The key light's view-projection (its shadow map).
    shadow_view_proj: mat4x4<f32>,
    // x: 1 / shadow map side, y: filter taps per side, z: one shadow-map texel in mesh units,
    // w: normal offset in texels.
    shadow: vec4<f32>,
    // x, y: shadow LUT v = width_mm * x + y; z: the sharp penumbra's share; w: unused.
    shadow_lut: vec4<f32>,
    // Environment radiance SH, 9 RGB coefficients (l = 0, 1, 2).
    sh: array<vec4<f32>, 9>,
    // x, y: zonal table u = inv_r * x + y.
    zonal: vec4<f32>,
    // x: TSD back-face bias, y: light-map side, z: kernel mm (derived), w: curvature gain (mm).
    tsd: vec4<f32>,
    // x, y: kernel radius = a * k + b texels; z: 1 = kernel from the map; w: largest radius.
    tsd_kernel: vec4<f32>,
}

@group(0) @binding(0) var<uniform> globals: Globals;
@group(0) @binding(1) var normal_map: texture_2d<f32>;
@group(0) @binding(2) var albedo_map: texture_2d<f32>;
@group(0) @binding(3) var map_sampler: sampler;
@group(0) @binding(4) var diffuse_lut: texture_2d<f32>;
@group(0) @binding(5) var shadow_lut: texture_2d<f32>;
@group(0) @binding(6) var zonal_table: texture_2d<f32>;
@group(0) @binding(7) var shadow_map: texture_depth_2d;
@group(0) @binding(8) var shadow_sampler: sampler_comparison;
@group(0) @binding(9) var light_map: texture_2d<f32>;
@group(0) @binding(10) var lut_sampler: sampler;
@group(0) @binding(11) var blurred_sampler: sampler;
@group(0) @binding(12) var kernel_map: texture_2d<f32>;
@group(0) @binding(13) var shadow_opacity: texture_2d<f32>;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) tangent: vec4<f32>,
    @location(3) uv: vec2<f32>,
    // x: 1/r in 1/mm (per vertex), y: mm per unit of UV (the light map's stretch).
    @location(4) skin: vec2<f32>,
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

fn normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let len = length(v);
    if len > 1e-12 && len < 3.0e38 {
        return v / len;
    }
    return fallback;
}

fn any_perpendicular(n: vec3<f32>) -> vec3<f32> {
    var axis = vec3<f32>(0.0, 1.0, 0.0);
    if abs(n.x) < 0.9 {
        axis = vec3<f32>(1.0, 0.0, 0.0);
    }
    return normalize_or(axis - n * dot(n, axis), vec3<f32>(0.0, 1.0, 0.0));
}

// The unit part of v perpendicular to the unit n (relative threshold, as in shading.rs).
fn perpendicular_part(v: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let p = v - n * dot(n, v);
    let len = length(p);
    if len > 1e-4 * length(v) && len < 3.0e38 {
        return p / len;
    }
    return any_perpendicular(n);
}

// Per channel max(0, base)^n capped at LOBE_CEILING; the power of a non-positive (or NaN) base is
// never used: `select` keeps the three channels in one vector op (llvmpipe runs it per SIMD lane).
fn lobe_power(base: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let value = min(pow(max(base, vec3<f32>(1e-30)), max(n, vec3<f32>(0.0))), vec3<f32>(LOBE_CEILING));
    return select(vec3<f32>(0.0), value, base > vec3<f32>(0.0));
}

fn lobes_sum(l: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let count = min(globals.counts.y, MAX_LOBES);
    for (var i = 0u; i < count; i++) {
        let lobe = globals.lobes[i];
        let base = lobe.cx.xyz * (l.x * v.x) + lobe.cy.xyz * (l.y * v.y) + lobe.cz.xyz * (l.z * v.z);
        sum += lobe_power(base, lobe.n.xyz);
    }
    return sum;
}

// Unit direction toward light i at `world` (xyz) and its irradiance (returned separately).
fn light_direction(i: u32, world: vec3<f32>) -> vec3<f32> {
    let light = globals.lights[i];
    if light.vector.w == 0.0 {
        return normalize_or(light.vector.xyz, vec3<f32>(0.0, 0.0, 1.0));
    }
    return normalize_or(light.vector.xyz - world, vec3<f32>(0.0, 0.0, 1.0));
}

fn light_irradiance(i: u32, world: vec3<f32>) -> vec3<f32> {
    let light = globals.lights[i];
    if light.vector.w == 0.0 {
        return light.radiance.rgb;
    }
    let d = light.vector.xyz - world;
    return light.radiance.rgb / max(dot(d, d), 1e-12);
}

// The vertex's texture-space frame (tangent, bitangent = cross(N, T) * handedness, normal),
// orthonormalised against the normal.
fn vertex_frame(input: VertexIn) -> mat3x3<f32> {
    let n = normalize_or(input.normal, vec3<f32>(0.0, 0.0, 1.0));
    let t = perpendicular_part(input.tangent.xyz, n);
    var sign = 1.0;
    if input.tangent.w < 0.0 {
        sign = -1.0;
    }
    return mat3x3<f32>(t, cross(n, t) * sign, n);
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
    let view_ts = to_ts * normalize_or(globals.eye.xyz - world, n);

    var lights_ts = array<vec3<f32>, 4>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var vertex_specular = vec3<f32>(0.0);
    let count = min(globals.counts.x, MAX_LIGHTS);
    for (var i = 0u; i < count; i++) {
        let l = to_ts * light_direction(i, world);
        lights_ts[i] = l;
        if globals.counts.z == 1u {
            vertex_specular += light_irradiance(i, world) * lobes_sum(l, view_ts) * max(l.z, 0.0);
        }
    }

    var out: VertexOut;
    out.clip = globals.view_proj * vec4<f32>(world, 1.0);
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

fn decode_normal(texel: vec4<f32>) -> vec3<f32> {
    var n = texel.xyz;
    if globals.counts.w == 1u {
        n.y = -n.y;
    }
    return normalize_or(n, vec3<f32>(0.0, 0.0, 1.0));
}

// Texture-space `d` in the frame whose z is the map normal `n`.
fn to_normal_frame(n: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let t = perpendicular_part(vec3<f32>(1.0, 0.0, 0.0), n);
    let b = cross(n, t);
    return vec3<f32>(dot(d, t), dot(d, b), dot(d, n));
}

fn tone_map(radiance: vec3<f32>) -> vec3<f32> {
    let c = max(radiance * globals.eye.w, vec3<f32>(0.0));
    if globals.options.x == 1u {
        return min(c, vec3<f32>(1.0));
    }
    if globals.options.x == 2u {
        return c / (vec3<f32>(1.0) + c);
    }
    return c;
}

// ---- skin helpers -------------------------------------------------------------------------

fn luminance(c: vec3<f32>) -> f32 {
    return dot(vec3<f32>(0.2125, 0.7154, 0.0721), c);
}

// 1/r in 1/mm for the LUT: the vertex attribute, or the paper's derivative form
// length(fwidth(N)) / length(fwidth(P)) with P in millimetres (constant per triangle).
fn curvature(skin: vec2<f32>, world: vec3<f32>, geo_n: vec3<f32>) -> f32 {
    var k = skin.x;
    if CURVATURE_MODE == 1u {
        let dn = length(fwidth(geo_n));
        let dp = length(fwidth(world)) * globals.skin.y;
        k = dn / max(dp, 1e-6);
    }
    let scaled = k * globals.skin.x;
    if scaled > 0.0 && scaled < 3.0e38 {
        return scaled;
    }
    return 0.0;
}

// Texture space to object space through the interpolated vertex frame.
fn to_object(d: vec3<f32>, t: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return normalize_or(t * d.x + b * d.y + n * d.z, n);
}

// The key light's shadow map coordinates of `world`: uv (row 0 at the top) and depth.
fn shadow_coords(world: vec3<f32>) -> vec3<f32> {
    let clip = globals.shadow_view_proj * vec4<f32>(world, 1.0);
    let ndc = clip.xyz / clip.w;
    return vec3<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5, ndc.z);
}

// Box-filtered shadow test (filter x filter taps, nearest compare): across a straight edge this
// is a linear ramp, the representative penumbra the shadow LUT inverts. The lookup point is pushed
// along the geometric normal by `shadow.w` texels (normal-offset bias), and each tap compares
// against the receiver's own plane at that tap (receiver-plane depth bias: the depth gradient of
// the surface in shadow-map space, from its tangent frame), so a wide filter does not shadow a
// sloped receiver with itself.
fn shadow_visibility(world: vec3<f32>, geo_n: vec3<f32>, t: vec3<f32>, b: vec3<f32>) -> f32 {
    let origin = world + geo_n * (globals.shadow.z * globals.shadow.w);
    let p = shadow_coords(origin);
    if p.z <= 0.0 || p.z >= 1.0 || p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0 {
        return 1.0;
    }
    let step = globals.shadow.z;
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
    let taps = i32(globals.shadow.y);
    let h = (taps - 1) / 2;
    let epsilon = 2.0 * globals.shadow.x * abs(pt.z) / max(length(pt.xy), 1e-12) + 1e-6;
    var sum = 0.0;
    for (var j = -h; j <= h; j++) {
        for (var i = -h; i <= h; i++) {
            let offset = vec2<f32>(f32(i), f32(j)) * globals.shadow.x;
            let depth = p.z + dot(gradient, offset) - epsilon;
            sum += textureSampleCompareLevel(shadow_map, shadow_sampler, p.xy + offset, depth);
        }
    }
    return sum / f32(taps * taps);
}

// Light let through the translucent casters in front of `world` (Gosselin et al.'s translucent
// shadows): one minus their summed opacity per channel, 1 without translucent casters.
fn translucent_transmittance(world: vec3<f32>, geo_n: vec3<f32>) -> vec3<f32> {
    if !TRANSLUCENT_SHADOWS {
        return vec3<f32>(1.0);
    }
    let p = shadow_coords(world + geo_n * (globals.shadow.z * globals.shadow.w));
    if p.z <= 0.0 || p.z >= 1.0 || p.x < 0.0 || p.x > 1.0 || p.y < 0.0 || p.y > 1.0 {
        return vec3<f32>(1.0);
    }
    let opacity = textureSampleLevel(shadow_opacity, lut_sampler, p.xy, 0.0).rgb;
    return clamp(vec3<f32>(1.0) - opacity, vec3<f32>(0.0), vec3<f32>(1.0));
}

// The filtered penumbra's width on this surface in mm: filter taps x texel, stretched by the
// slope of the surface to the light.
fn penumbra_mm(cos_light: f32) -> f32 {
    return globals.shadow.y * globals.shadow.z * globals.skin.y / max(cos_light, 0.05);
}

// The sharp penumbra P'(P^-1(s)) (a ramp `new_penumbra` as wide), for the specular.
fn sharp_shadow(s: f32) -> f32 {
    return clamp(0.5 + (s - 0.5) / globals.shadow_lut.z, 0.0, 1.0);
}

fn shadow_scattered(s: f32, width_mm: f32) -> vec3<f32> {
    let v = width_mm * globals.shadow_lut.x + globals.shadow_lut.y;
    return textureSampleLevel(shadow_lut, lut_sampler, vec2<f32>(s, v), 0.0).rgb;
}

fn lut_lookup(ndl: vec3<f32>, inv_r: f32) -> vec3<f32> {
    let v = inv_r * globals.skin.z + globals.skin.w;
    let r = textureSampleLevel(diffuse_lut, lut_sampler, vec2<f32>(ndl.x * 0.5 + 0.5, v), 0.0).r;
    let g = textureSampleLevel(diffuse_lut, lut_sampler, vec2<f32>(ndl.y * 0.5 + 0.5, v), 0.0).g;
    let b = textureSampleLevel(diffuse_lut, lut_sampler, vec2<f32>(ndl.z * 0.5 + 0.5, v), 0.0).b;
    return vec3<f32>(r, g, b);
}

// Per-channel normals: the full map blended toward its blurred (mip-clamped) sample.
fn channel_normals(n: vec3<f32>, n_blur: vec3<f32>) -> array<vec3<f32>, 3> {
    return array<vec3<f32>, 3>(
        normalize_or(mix(n, n_blur, globals.blur.x), n),
        normalize_or(mix(n, n_blur, globals.blur.y), n),
        normalize_or(mix(n, n_blur, globals.blur.z), n),
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
    let u = inv_r * globals.zonal.x + globals.zonal.y;
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
            sum += band * globals.sh[k][c] * y[k];
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
    let albedo = textureSample(albedo_map, map_sampler, input.uv).rgb;
    let geo_n = normalize_or(input.frame_n, vec3<f32>(0.0, 0.0, 1.0));
    let inv_r = curvature(input.skin, input.world, geo_n);
    let rho = globals.diffuse.rgb * albedo / PI;
    let v = to_normal_frame(n, normalize_or(input.view_ts, vec3<f32>(0.0, 0.0, 1.0)));
    var lights_ts = array<vec3<f32>, 4>(input.light0, input.light1, input.light2, input.light3);
    let normals = channel_normals(n, n_blur);
    let key = u32(globals.blur.w);

    var radiance = input.vertex_specular;
    var unshadowed = vec3<f32>(0.0);
    var key_specular = vec3<f32>(0.0);
    let count = min(globals.counts.x, MAX_LIGHTS);
    for (var i = 0u; i < count; i++) {
        let l_ts = normalize_or(lights_ts[i], vec3<f32>(0.0, 0.0, 1.0));
        let l = to_normal_frame(n, l_ts);
        let e = light_irradiance(i, input.world);
        var shadow_diffuse = vec3<f32>(1.0);
        var shadow_specular = 1.0;
        // With a light map the key light's shadow is already in it (and its specular is
        // attenuated by the light map below): no shadow-map lookups here.
        if SHADOWS && DIFFUSE_MODE != 4u && i == key {
            let s = shadow_visibility(input.world, geo_n, input.frame_t, input.frame_b);
            shadow_diffuse = vec3<f32>(s);
            shadow_specular = s;
            if SHADOW_SCATTERING {
                let cos_light = dot(geo_n, light_direction(i, input.world));
                shadow_diffuse = shadow_scattered(s, penumbra_mm(cos_light));
                shadow_specular = sharp_shadow(s);
            }
            let through = translucent_transmittance(input.world, geo_n);
            shadow_diffuse *= through;
            shadow_specular *= luminance(through);
        }
        if DIFFUSE_MODE == 4u {
            unshadowed += e * max(l.z, 0.0);
        } else {
            radiance += e * rho * diffuse_falloff(normals, l_ts, inv_r) * shadow_diffuse;
        }
        if globals.counts.z == 0u {
            let specular = e * lobes_sum(l, v) * max(l.z, 0.0);
            if DIFFUSE_MODE == 4u && SHADOWS && i == key {
                key_specular = specular;
            } else {
                radiance += specular * shadow_specular;
            }
        }
    }
    if DIFFUSE_MODE == 4u {
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

// ---- the key light's shadow map ------------------------------------------------------------

@vertex
fn vs_shadow(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return globals.shadow_view_proj * vec4<f32>(position, 1.0);
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
    out.clip = globals.shadow_view_proj * vec4<f32>(position, 1.0);
    out.opacity = opacity;
    return out;
}

@fragment
fn fs_translucent(input: TranslucentOut) -> @location(0) vec4<f32> {
    return vec4<f32>(input.opacity, 0.0);
}

// ---- texture-space diffusion (Gosselin et al. 2004) ------------------------------------------

struct TextureSpaceOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) world: vec3<f32>,
    @location(2) frame_t: vec3<f32>,
    @location(3) frame_b: vec3<f32>,
    @location(4) frame_n: vec3<f32>,
    @location(5) skin: vec2<f32>,
}

// The mesh drawn at its texture coordinates: uv (0, 0) is the light map's top-left texel.
@vertex
fn vs_texture_space(input: VertexIn) -> TextureSpaceOut {
    let frame = vertex_frame(input);
    var out: TextureSpaceOut;
    out.clip = vec4<f32>(input.uv.x * 2.0 - 1.0, 1.0 - input.uv.y * 2.0, 0.0, 1.0);
    out.uv = input.uv;
    out.world = input.position;
    out.frame_t = frame[0];
    out.frame_b = frame[1];
    out.frame_n = frame[2];
    out.skin = input.skin;
    return out;
}

// Back-face pre-pass: texels facing away from the eye by more than the bias are left out of the
// texture-space depth buffer, so the light-map pass (depth test "equal") never shades them.
@fragment
fn fs_tsd_prepass(input: TextureSpaceOut) {
    let view = normalize_or(globals.eye.xyz - input.world, input.frame_n);
    if dot(view, normalize_or(input.frame_n, view)) + globals.tsd.x < 0.0 {
        discard;
    }
}

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
