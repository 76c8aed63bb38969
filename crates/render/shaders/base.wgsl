// The base pass: texture-space per-pixel bump mapping with the Lafortune BRDF
// (Haro et al. 2001, section 5). The CPU reference of every step is src/shading.rs; keep the two
// in step (tests/gpu.rs compares them pixel by pixel).

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
}

@group(0) @binding(0) var<uniform> globals: Globals;
@group(0) @binding(1) var normal_map: texture_2d<f32>;
@group(0) @binding(2) var albedo_map: texture_2d<f32>;
@group(0) @binding(3) var map_sampler: sampler;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) tangent: vec4<f32>,
    @location(3) uv: vec2<f32>,
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

@vertex
fn vs_main(input: VertexIn) -> VertexOut {
    let n = normalize_or(input.normal, vec3<f32>(0.0, 0.0, 1.0));
    let t = perpendicular_part(input.tangent.xyz, n);
    var sign = 1.0;
    if input.tangent.w < 0.0 {
        sign = -1.0;
    }
    let b = cross(n, t) * sign;
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

@fragment
fn fs_main(input: VertexOut) -> @location(0) vec4<f32> {
    let n = decode_normal(textureSample(normal_map, map_sampler, input.uv));
    let albedo = textureSample(albedo_map, map_sampler, input.uv).rgb;
    let rho = globals.diffuse.rgb * albedo / PI;
    let v = to_normal_frame(n, normalize_or(input.view_ts, vec3<f32>(0.0, 0.0, 1.0)));
    var lights_ts = array<vec3<f32>, 4>(input.light0, input.light1, input.light2, input.light3);

    var radiance = input.vertex_specular;
    let count = min(globals.counts.x, MAX_LIGHTS);
    for (var i = 0u; i < count; i++) {
        let l = to_normal_frame(n, normalize_or(lights_ts[i], vec3<f32>(0.0, 0.0, 1.0)));
        var f = rho;
        if globals.counts.z == 0u {
            f += lobes_sum(l, v);
        }
        radiance += light_irradiance(i, input.world) * f * max(l.z, 0.0);
    }
    return vec4<f32>(tone_map(radiance), 1.0);
}
