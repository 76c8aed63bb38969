// TSD's back-face pre-pass (vertex stage in tsd.wgsl). Part of the module that src/pass/mod.rs
// assembles.

// Back-face pre-pass: texels facing away from the eye by more than the bias are left out of the
// texture-space depth buffer, so the light-map pass (depth test "equal") never shades them.
@fragment
fn fs_tsd_prepass(input: TextureSpaceOut) {
    let view = normalize_or(globals.eye.xyz - input.world, input.frame_n);
    if dot(view, normalize_or(input.frame_n, view)) + globals.tsd.x < 0.0 {
        discard;
    }
}
