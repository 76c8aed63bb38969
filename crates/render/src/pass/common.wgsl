// What every mesh pass shares. src/pass/mod.rs assembles one module from skin_fit.wgsl (the
// closed-form LUT fits), this file and one file per pass (shadow, translucent, tsd, tsd_prepass,
// light_map, base), so the passes share one shader module, compiled once per device.
//
// The skin effects are pipeline-overridable constants: a scene that asks for none of them gets
// the plain base pass, with every skin branch folded away by the shader compiler.
// The CPU reference of the shading is src/shading.rs (tests/render/gpu.rs compares them pixel by pixel).

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

// What every mesh pass reads (`SceneUniforms` in src/pass/uniforms.rs).
struct SceneUniforms {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    // Radiance scale before the tone curve.
    exposure: f32,
    light_count: u32,
    // 1: the normal map is green-down.
    green_down: u32,
    // The light with the shadow map (MAX_LIGHTS when there is none).
    key_light: u32,
    mm_per_unit: f32,
    lights: array<Light, 4>,
}

// The one uniform block of the mesh passes: the shared part, then each pass's own struct,
// declared in its file (`Globals` in src/pass/uniforms.rs).
struct Globals {
    scene: SceneUniforms,
    base: BaseUniforms,
    shadow: ShadowUniforms,
    prepass: PrepassUniforms,
    light_map: LightMapUniforms,
}

// A read-only storage buffer, not a uniform one: lavapipe (Mesa 22.3) inlines the values of a
// uniform buffer that control branches and loops into the shader, so every frame whose camera
// changed the buffer compiled the vertex shader again with LLVM (most of a frame's time) and kept
// each copy until the device went away (0.3 MiB a frame). Storage reads are never inlined; the
// layout of `Globals` is the same in both address spaces.
@group(0) @binding(0) var<storage, read> globals: Globals;
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

// Unit direction toward light i at `world` (xyz) and its irradiance (returned separately).
fn light_direction(i: u32, world: vec3<f32>) -> vec3<f32> {
    let light = globals.scene.lights[i];
    if light.vector.w == 0.0 {
        return normalize_or(light.vector.xyz, vec3<f32>(0.0, 0.0, 1.0));
    }
    return normalize_or(light.vector.xyz - world, vec3<f32>(0.0, 0.0, 1.0));
}

fn light_irradiance(i: u32, world: vec3<f32>) -> vec3<f32> {
    let light = globals.scene.lights[i];
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

fn decode_normal(texel: vec4<f32>) -> vec3<f32> {
    var n = texel.xyz;
    if globals.scene.green_down == 1u {
        n.y = -n.y;
    }
    return normalize_or(n, vec3<f32>(0.0, 0.0, 1.0));
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(vec3<f32>(0.2125, 0.7154, 0.0721), c);
}

// Texture space to object space through the interpolated vertex frame.
fn to_object(d: vec3<f32>, t: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return normalize_or(t * d.x + b * d.y + n * d.z, n);
}
