// The debug view of a mesh's texture-space frames and UV layout (`effects = ["debug-frames"]`,
// src/pass/debug): the surface coloured by its UV stretch over a UV checker, mirrored UV islands
// hatched, and each vertex's tangent (red), bitangent (green) and normal (blue) drawn as lines.
// A module of its own: it reads only the shared part of the mesh passes' uniform block.

// The first fields of `SceneUniforms` (common.wgsl, src/pass/uniforms.rs): a prefix of the same
// storage buffer, so the block's other parts need not be declared here.
struct DebugScene {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    exposure: f32,
    light_count: u32,
    green_down: u32,
    key_light: u32,
    mm_per_unit: f32,
}

// `DebugUniforms` in src/pass/debug/mod.rs.
struct DebugUniforms {
    // The mesh's median millimetres per UV unit: the stretch drawn white.
    median_mm_per_uv: f32,
    // Length of the drawn frame axes, mesh units.
    axis_length: f32,
    // Checker cells per UV unit.
    checker: f32,
    pad0: f32,
}

@group(0) @binding(0) var<storage, read> scene: DebugScene;
@group(0) @binding(1) var<uniform> debug: DebugUniforms;

struct DebugVertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) tangent: vec4<f32>,
    @location(3) uv: vec2<f32>,
}

struct SurfaceOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) normal: vec3<f32>,
    // The tangent frame's handedness: negative on a mirrored UV island.
    @location(3) handedness: f32,
}

@vertex
fn vs_debug_surface(input: DebugVertexIn) -> SurfaceOut {
    var out: SurfaceOut;
    out.clip = scene.view_proj * vec4<f32>(input.position, 1.0);
    out.world = input.position;
    out.uv = input.uv;
    out.normal = input.normal;
    out.handedness = input.tangent.w;
    return out;
}

// White at the median stretch, toward red where a UV unit covers more skin (texels larger on the
// face, pores blurred), toward blue where less; saturated at a factor of 4 either way.
fn stretch_colour(stops: f32) -> vec3<f32> {
    let t = clamp(stops / 2.0, -1.0, 1.0);
    if t >= 0.0 {
        return mix(vec3<f32>(1.0), vec3<f32>(1.0, 0.2, 0.1), t);
    }
    return mix(vec3<f32>(1.0), vec3<f32>(0.1, 0.3, 1.0), -t);
}

@fragment
fn fs_debug_surface(input: SurfaceOut) -> @location(0) vec4<f32> {
    // Within a triangle position and UV are linear, so the screen-space derivatives give the
    // triangle's own ratio of surface area to UV area, exactly.
    let world_area = length(cross(dpdx(input.world), dpdy(input.world)));
    let du = dpdx(input.uv);
    let dv = dpdy(input.uv);
    let uv_area = abs(du.x * dv.y - du.y * dv.x);
    // A triangle with no UV area (or no surface) has no stretch: magenta.
    var colour = vec3<f32>(0.8, 0.0, 0.8);
    if uv_area > 1e-30 && world_area > 0.0 && debug.median_mm_per_uv > 0.0 {
        let mm_per_uv = sqrt(world_area / uv_area) * scene.mm_per_unit;
        colour = stretch_colour(log2(mm_per_uv / debug.median_mm_per_uv));
    }
    let cell = floor(input.uv * debug.checker);
    if (i32(cell.x) + i32(cell.y)) % 2 != 0 {
        colour *= 0.75;
    }
    // Mirrored islands: diagonal hatching in screen space.
    if input.handedness < 0.0 && (i32(floor((input.clip.x + input.clip.y) / 6.0)) % 2) == 0 {
        colour *= 0.45;
    }
    let n = normalize(input.normal);
    let to_eye = normalize(scene.eye - input.world);
    let facing = abs(dot(n, to_eye));
    // Not finite (a degenerate normal) shades flat rather than black.
    let shade = select(1.0, 0.35 + 0.65 * facing, facing == facing);
    return vec4<f32>(colour * shade, 1.0);
}

struct AxisOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) colour: vec3<f32>,
}

// One line-list vertex per call: `index` 0-1 the tangent, 2-3 the bitangent, 4-5 the normal of
// the vertex given per instance (the mesh's own vertex buffer, stepped per instance).
@vertex
fn vs_debug_axes(@builtin(vertex_index) index: u32, input: DebugVertexIn) -> AxisOut {
    let axis = index / 2u;
    let n = input.normal;
    // The frame as the passes read it: bitangent = cross(N, T) * handedness (common.wgsl).
    var direction = input.tangent.xyz;
    var colour = vec3<f32>(1.0, 0.15, 0.1);
    if axis == 1u {
        direction = cross(n, input.tangent.xyz) * select(1.0, -1.0, input.tangent.w < 0.0);
        colour = vec3<f32>(0.1, 0.9, 0.1);
    } else if axis == 2u {
        direction = n;
        colour = vec3<f32>(0.2, 0.4, 1.0);
    }
    let lift = n * (0.05 * debug.axis_length);
    let world = input.position + lift + direction * (f32(index % 2u) * debug.axis_length);
    var out: AxisOut;
    out.clip = scene.view_proj * vec4<f32>(world, 1.0);
    out.colour = colour;
    return out;
}

@fragment
fn fs_debug_axes(input: AxisOut) -> @location(0) vec4<f32> {
    return vec4<f32>(input.colour, 1.0);
}
