// Order-2 spherical harmonics for ambient light on pre-integrated skin. A snippet: no bindings,
// no entry points; concatenate it in front of the shader that calls it. Twins of
// `skinkit_render::skin::sh` (basis in world Cartesian form, index l (l + 1) + m).
//
// coeffs: the nine RGB radiance coefficients (xyz used, w ignored) in index order.
// zonal: the convolution factors A_l per channel for l = 0, 1, 2 (a row of the ZonalTable
// texture: width n over 1/r, row l = band l; or LAMBERT_ZONAL, or blog_zonal).

const SH_C0: f32 = 0.2820948;
const SH_C1: f32 = 0.4886025;
const SH_C2: f32 = 1.0925484;
const SH_C20: f32 = 0.31539157;
const SH_C22: f32 = 0.5462742;
const SH_PI: f32 = 3.14159265;

fn sh9_basis(d: vec3<f32>) -> array<f32, 9> {
    let x = d.x;
    let y = d.y;
    let z = d.z;
    return array<f32, 9>(
        SH_C0,
        SH_C1 * y,
        SH_C1 * z,
        SH_C1 * x,
        SH_C2 * x * y,
        SH_C2 * y * z,
        SH_C20 * (3.0 * z * z - 1.0),
        SH_C2 * x * z,
        SH_C22 * (x * x - y * y),
    );
}

// sum_l zonal[l] * sum_m coeffs[l (l + 1) + m] * Y_lm(n), per channel.
fn sh9_convolve(coeffs: array<vec4<f32>, 9>, zonal: array<vec3<f32>, 3>, n: vec3<f32>) -> vec3<f32> {
    let y = sh9_basis(n);
    var out = vec3<f32>(0.0);
    out = out + zonal[0] * coeffs[0].xyz * y[0];
    for (var i = 1; i < 4; i = i + 1) {
        out = out + zonal[1] * coeffs[i].xyz * y[i];
    }
    for (var i = 4; i < 9; i = i + 1) {
        out = out + zonal[2] * coeffs[i].xyz * y[i];
    }
    return out;
}

// sh9_convolve with a normal per channel (red, green, blue).
fn sh9_convolve_rgb(coeffs: array<vec4<f32>, 9>, zonal: array<vec3<f32>, 3>, n_r: vec3<f32>, n_g: vec3<f32>, n_b: vec3<f32>) -> vec3<f32> {
    let r = sh9_convolve(coeffs, zonal, n_r).x;
    let g = sh9_convolve(coeffs, zonal, n_g).y;
    let b = sh9_convolve(coeffs, zonal, n_b).z;
    return vec3<f32>(r, g, b);
}

fn sh9_lambert_zonal() -> array<vec3<f32>, 3> {
    return array<vec3<f32>, 3>(vec3<f32>(SH_PI), vec3<f32>(2.0 * SH_PI / 3.0), vec3<f32>(SH_PI / 4.0));
}

// The blog's zh0, zh1 (minus signs restored) as factors A_l; band 2 is Lambert's pi / 4.
// 1/r in 1/mm, clamped to the blog's [0.0625, 0.5].
fn blog_zonal(inv_r: f32) -> array<vec3<f32>, 3> {
    let curvature = saturate((inv_r - 0.0625) / (0.5 - 0.0625));
    let curva = (1.0 / (curvature * (0.5 - 0.0625) + 0.0625) - 2.0) / (16.0 - 2.0);
    let one_minus = 1.0 - curva;
    var remap = vec2<f32>(1.0) - saturate(curva * vec2<f32>(3.0, 2.7));
    remap = remap * remap;
    remap = remap * remap;
    let multiplier = vec3<f32>(1.0 / (curva * 3.2 + 0.4), remap.x, remap.y);
    let zh0 = multiplier * vec3<f32>(0.061659, 0.00991683, 0.003783) + vec3<f32>(0.868938, 0.885506, 0.8854);
    let rc = 1.0 - saturate(curva * 2.7);
    let lower = vec3<f32>(0.197573092, 0.0117447875, 0.0040980375) * (1.0 - rc * rc * rc) + vec3<f32>(0.7672169, 1.009236, 1.017741);
    let upper = vec3<f32>(1.018366, 1.022107, 1.022232);
    let zh1 = upper + (lower - upper) * (one_minus * one_minus);
    let four_pi = 4.0 * SH_PI;
    return array<vec3<f32>, 3>(sqrt(four_pi) * zh0, sqrt(four_pi / 3.0) * zh1, vec3<f32>(SH_PI / 4.0));
}
