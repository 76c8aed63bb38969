// PLACEHOLDER until the fit module lands: Lambert.
fn blog_direct(ndl: vec3<f32>, inv_r: f32) -> vec3<f32> {
    return max(ndl, vec3<f32>(0.0));
}
fn own_direct(ndl: vec3<f32>, inv_r: f32) -> vec3<f32> {
    return max(ndl, vec3<f32>(0.0));
}
