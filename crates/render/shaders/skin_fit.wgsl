// Closed forms of the pre-integrated skin falloff D(N.L, 1/r) (Penner and Borshukov 2011, eq. 1.1).
// A snippet: no bindings, no entry points; concatenate it in front of the shader that calls it.
// Each function takes N.L per channel (red, green, blue: the renderer blurs normals per channel)
// and 1/r in 1/mm. Twins of `skinkit_render::skin::fit::{blog_direct, own_direct}`, written in
// the same order of operations (a driver may still fuse multiply-adds).

// The blog's curves ("Pre-integrated skin shading: curve approximation"), minus signs restored.
const BLOG_INV_R_MIN: f32 = 0.0625;
const BLOG_INV_R_MAX: f32 = 0.5;
const BLOG_RANGE_MIN = vec3<f32>(0.0, 0.3, 0.3);
const BLOG_RANGE_MAX = vec3<f32>(1.0, 0.7, 0.7);
const BLOG_OFFSET = vec3<f32>(0.0, 0.06, 0.06);
const BLOG_LOWER_SCALE = vec3<f32>(0.65, 0.5, 0.9);
const BLOG_LOWER_ADD = vec3<f32>(0.045, 0.0, 0.0);
const BLOG_SLOPE0 = vec3<f32>(1.75, 2.0, 1.97);
const BLOG_TOP0 = vec3<f32>(0.99, 0.99, 0.99);
const BLOG_LERP_MIN = vec3<f32>(0.0, 0.35, 0.35);
const BLOG_LERP_MAX = vec3<f32>(1.0, 0.7, 0.6);
const BLOG_SLOPE1 = vec3<f32>(1.95, 2.0, 2.0);
const BLOG_TOP1 = vec3<f32>(0.99, 0.99, 1.0);

// The blog's `curvature` in [0, 1]: 0 at r = 16 mm, 1 at r = 2 mm, clamped outside.
fn blog_curvature(inv_r: f32) -> f32 {
    return saturate((inv_r - BLOG_INV_R_MIN) / (BLOG_INV_R_MAX - BLOG_INV_R_MIN));
}

fn blog_curve0(ndl01: vec3<f32>) -> vec3<f32> {
    let lo = BLOG_RANGE_MIN;
    let hi = BLOG_RANGE_MAX;
    let t = saturate(ndl01 * (1.0 / (hi - lo)) + (BLOG_OFFSET + lo) / (lo - hi));
    var lower = t * t * BLOG_LOWER_SCALE + BLOG_LOWER_ADD;
    lower.z = lower.z * t.z;
    let upper = saturate(ndl01 * BLOG_SLOPE0 + (BLOG_TOP0 - BLOG_SLOPE0));
    let lerp_lo = BLOG_LERP_MIN;
    let lerp_hi = BLOG_LERP_MAX;
    let lerp_t = saturate(ndl01 * (1.0 / (lerp_hi - lerp_lo)) + lerp_lo / (lerp_lo - lerp_hi));
    return lower + (upper - lower) * (lerp_t * lerp_t);
}

fn blog_curve1(ndl01: vec3<f32>) -> vec3<f32> {
    return saturate(ndl01 * BLOG_SLOPE1 + (BLOG_TOP1 - BLOG_SLOPE1));
}

fn blog_direct(ndl: vec3<f32>, inv_r: f32) -> vec3<f32> {
    let ndl01 = clamp(ndl, vec3<f32>(-1.0), vec3<f32>(1.0)) * 0.5 + 0.5;
    let curvature = blog_curvature(inv_r);
    let curva = (1.0 / (curvature * (0.5 - 0.0625) + 0.0625) - 2.0) / (16.0 - 2.0);
    let one_minus = 1.0 - curva;
    let one_minus2 = one_minus * one_minus;
    let blend = one_minus2 * -one_minus2 + 1.0;
    let c0 = blog_curve0(ndl01);
    let c1 = blog_curve1(ndl01);
    return c0 + (c1 - c0) * blend;
}

// Our fit: gain(k) * mix of two box-smoothed ramps of widths a k / (1 + |b| k), k = clamp(1/r, 0, 1).
// Coefficients per channel from `skin::fit::OWN_FIT` (least squares on 101 N.L x 33 1/r).
const OWN_A1 = vec3<f32>(1.119658, 0.19147016, 0.13902761);
const OWN_B1 = vec3<f32>(3.4801114, 0.0030810947, -2.3454774e-8);
const OWN_A2 = vec3<f32>(4.6450677, 0.85098916, 0.51528525);
const OWN_B2 = vec3<f32>(0.48916852, 0.0025143863, 0.004884143);
const OWN_MIX = vec3<f32>(0.27000952, 0.22228076, 0.20613755);
const OWN_GAIN_C = vec3<f32>(1.7764238, 0.06646401, 0.024659198);
const OWN_GAIN_D = vec3<f32>(3.7490337, 0.10559194, 0.048895348);
const OWN_MIN_WIDTH: f32 = 1e-6;

// max(x, 0) convolved with a box of half-width w > 0.
fn own_ramp(x: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    let t = clamp(x, -w, w) + w;
    return t * t * (0.25 / w) + max(x - w, vec3<f32>(0.0));
}

fn own_direct(ndl: vec3<f32>, inv_r: f32) -> vec3<f32> {
    let x = clamp(ndl, vec3<f32>(-1.0), vec3<f32>(1.0));
    let k = clamp(inv_r, 0.0, 1.0);
    let w1 = max(OWN_A1 * k / (1.0 + abs(OWN_B1) * k), vec3<f32>(OWN_MIN_WIDTH));
    let w2 = max(OWN_A2 * k / (1.0 + abs(OWN_B2) * k), vec3<f32>(OWN_MIN_WIDTH));
    let gain = 1.0 - OWN_GAIN_C * k * k / (1.0 + abs(OWN_GAIN_D) * k * k);
    let r1 = own_ramp(x, w1);
    let r2 = own_ramp(x, w2);
    return gain * (r1 + (r2 - r1) * OWN_MIX);
}
