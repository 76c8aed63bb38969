// TSD's back-face pre-pass (vertex stage in tsd.wgsl). Part of the module that src/pass/mod.rs
// assembles.

// The pre-pass's uniforms (`PrepassUniforms` in src/pass/tsd_prepass/mod.rs).
struct PrepassUniforms {
    // How far past edge-on a texel may face away and still be kept.
    backface_bias: f32,
    pad0: f32,
    pad1: f32,
    pad2: f32,
}

// Back-face pre-pass: texels facing away from the eye by more than the bias are left out of the
// texture-space depth buffer, so the light-map pass (depth test "equal") never shades them.
@fragment
fn fs_tsd_prepass(input: TextureSpaceOut) {
    let view = normalize_or(globals.scene.eye - input.world, input.frame_n);
    if dot(view, normalize_or(input.frame_n, view)) + globals.prepass.backface_bias < 0.0 {
        discard;
    }
}
