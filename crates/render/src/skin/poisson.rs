//! The Poisson disc of texture-space diffusion's blur (Gosselin et al.): its 13 taps and their
//! moments, which size the blur radius so a number of passes adds a profile's variance. CPU
//! physics: the blur pass (`crate::pass::blur`) and the TSD schedule (`super::tsd`) read it.

/// The largest derived Poisson radius, in light-map texels (alpha = radius / this).
pub const MAX_KERNEL_TEXELS: f32 = 64.0;

/// The 12 Poisson taps of Gosselin et al. (the centre is the 13th).
pub const POISSON: [[f32; 2]; 12] = [
    [-0.326212, -0.40581],
    [-0.840144, -0.07358],
    [-0.695914, 0.457137],
    [-0.203345, 0.620716],
    [0.96234, -0.194983],
    [0.473434, -0.480026],
    [0.519456, 0.767022],
    [0.185461, -0.893124],
    [0.507431, 0.064425],
    [0.89642, 0.412458],
    [-0.32194, -0.932615],
    [-0.791559, -0.59771],
];

/// The mean of the 13 taps (centre included), in radii: the disc is off centre by about 0.1 of its
/// radius along v, so the blur moves its taps back by this to keep the map in place.
pub fn poisson_mean() -> [f32; 2] {
    let sum = POISSON.iter().fold([0.0f32; 2], |s, p| [s[0] + p[0], s[1] + p[1]]);
    sum.map(|v| v / 13.0)
}

/// The mean squared distance of the 13 taps (centre included) from their mean
/// ([`poisson_mean`]), in radii^2: one blur pass of radius rho adds `rho^2 * this / 2` of
/// variance per axis.
pub fn poisson_second_moment() -> f32 {
    let [mx, my] = poisson_mean();
    let raw = POISSON.iter().map(|[x, y]| x * x + y * y).sum::<f32>() / 13.0;
    raw - (mx * mx + my * my)
}

/// The 13 taps' variance along u and along v about their mean ([`poisson_mean`]), in radii^2:
/// the disc is not isotropic (0.352 along u, 0.285 along v), so a blur that should add the same
/// variance along both axes sizes its radius per axis.
pub fn poisson_axis_variance() -> [f32; 2] {
    std::array::from_fn(|axis| centred_taps(axis).map(|o| o * o).sum::<f32>() / 13.0)
}

/// The 13 taps' coordinates along `axis` (0: u, 1: v), centre first, moved by minus their mean
/// ([`poisson_mean`]) as the blur places them, in radii.
pub(crate) fn centred_taps(axis: usize) -> impl Iterator<Item = f32> {
    let mean = poisson_mean()[axis];
    std::iter::once(0.0).chain(POISSON.iter().map(move |p| p[axis])).map(move |p| p - mean)
}

/// The derived kernel radius (mm) for `passes` blur passes so that their combined variance per
/// axis equals `variance_mm2` (the profile's luminance-weighted variance).
pub(crate) fn kernel_mm_for(variance_mm2: f32, passes: u32) -> f32 {
    let per_pass = poisson_second_moment() / 2.0;
    (variance_mm2 / (passes.max(1) as f32 * per_pass)).sqrt()
}
