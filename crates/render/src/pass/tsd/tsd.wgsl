// Texture-space diffusion (Gosselin et al. 2004): the vertex stage its pre-pass and light-map
// pass share, drawing the mesh at its texture coordinates. Part of the module that
// src/pass/mod.rs assembles.

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
