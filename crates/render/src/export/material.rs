//! The glTF material of a scene: base colour, metallic 0 and a roughness close to the scene's
//! Lafortune skin lobes (Haro et al. 2001, section 5.2).
//!
//! glTF's metallic-roughness model has one GGX lobe; the Lafortune skin set has three generalised
//! cosine lobes. The mapping is deliberately simple and is meant to give other viewers a plausible
//! sheen, not to reproduce skinkit's shading (skinkit itself keeps rendering the lobes):
//!
//! 1. the *specular lobe* is the lobe that reflects about the normal (`Cx, Cy < 0 < Cz` after
//!    Rec. 709 luminance weighting, the mirror direction of Lafortune et al. 1997) with the
//!    largest luminance-weighted exponent `n`; with no such lobe, the lobe with the largest `n`;
//! 2. `n` is read as a Blinn-Phong exponent and turned into a GGX width by Walter et al.'s
//!    (2007) rule `alpha = sqrt(2 / (n + 2))`;
//! 3. glTF's `roughness` is `sqrt(alpha)` (the specification squares roughness into alpha).
//!
//! For the default skin set the specular lobe is lobe 2 (`n` = 64.2, 63.9, 43.8; luminance
//! weighted 62.5), so `alpha` = 0.176 and `roughness` = 0.42. A BRDF without lobes is fully rough
//! (1). Metallic is 0: skin is a dielectric.

use glam::Vec3;
use serde::Serialize;

use crate::brdf::{Lafortune, Lobe};

/// Rec. 709 luminance weights, to fold the per-channel lobe values into one number.
const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// The roughness chosen for a BRDF and how it was reached.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Roughness {
    /// The index of the lobe it came from (`None`: the BRDF has no lobes).
    pub lobe: Option<usize>,
    /// The lobe's luminance-weighted exponent `n` (0 without a lobe).
    pub exponent: f32,
    /// The GGX width `alpha = sqrt(2 / (n + 2))` (1 without a lobe).
    pub alpha: f32,
    /// glTF's `roughnessFactor`, `sqrt(alpha)`, in (0, 1].
    pub roughness: f32,
}

/// The glTF roughness of `brdf` (see the module docs for the rule). Always finite, in (0, 1].
pub fn roughness(brdf: &Lafortune) -> Roughness {
    let Some((index, lobe)) = specular_lobe(&brdf.lobes) else {
        return Roughness { lobe: None, exponent: 0.0, alpha: 1.0, roughness: 1.0 };
    };
    let n = LUMINANCE.dot(lobe.n);
    let alpha = blinn_phong_alpha(n);
    Roughness { lobe: Some(index), exponent: n, alpha, roughness: alpha.sqrt() }
}

/// Walter et al.'s Blinn-Phong to GGX rule `alpha = sqrt(2 / (n + 2))`; a non-finite or
/// non-positive exponent gives 1 (fully rough), so no input yields NaN.
pub(crate) fn blinn_phong_alpha(n: f32) -> f32 {
    if !(n.is_finite() && n > 0.0) {
        return 1.0;
    }
    (2.0 / (n + 2.0)).sqrt().clamp(0.0, 1.0)
}

/// The lobe that best stands for a single specular highlight: the sharpest mirror-like lobe, or
/// the sharpest lobe when none reflects about the normal.
fn specular_lobe(lobes: &[Lobe]) -> Option<(usize, &Lobe)> {
    let mirror = |l: &Lobe| LUMINANCE.dot(l.cx) < 0.0 && LUMINANCE.dot(l.cy) < 0.0 && LUMINANCE.dot(l.cz) > 0.0;
    sharpest(lobes.iter().enumerate().filter(|(_, l)| mirror(l))).or_else(|| sharpest(lobes.iter().enumerate()))
}

/// The lobe with the largest luminance-weighted exponent.
fn sharpest<'a>(candidates: impl Iterator<Item = (usize, &'a Lobe)>) -> Option<(usize, &'a Lobe)> {
    candidates.max_by(|a, b| LUMINANCE.dot(a.1.n).total_cmp(&LUMINANCE.dot(b.1.n)))
}

/// The glTF `baseColorFactor` (linear RGBA) for a scene: white under an albedo map (the map is
/// the colour), the constant itself, or the BRDF's `rho_d` when the scene gives no albedo (what
/// the renderer shades with in each case).
pub(crate) fn base_color_factor(albedo: Option<&crate::scene::Albedo>, brdf: &Lafortune) -> [f32; 4] {
    let rgb = match albedo {
        Some(crate::scene::Albedo::Map(_)) => Vec3::ONE,
        Some(crate::scene::Albedo::Constant(c)) => *c,
        None => brdf.diffuse,
    };
    let rgb = rgb.clamp(Vec3::ZERO, Vec3::ONE);
    [rgb.x, rgb.y, rgb.z, 1.0]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule computed independently, in f64 and as one power: `(2 / (n + 2))^(1/4)`.
    fn oracle(n: f64) -> f64 {
        (2.0 / (n + 2.0)).powf(0.25)
    }

    #[test]
    fn the_skin_set_maps_through_its_sharp_mirror_lobe() {
        let r = roughness(&Lafortune::skin());
        assert_eq!(r.lobe, Some(2));
        let n = 0.2126 * 64.208486 + 0.7152 * 63.919687 + 0.0722 * 43.809866;
        assert!((r.exponent as f64 - n).abs() < 1e-3, "{r:?}");
        assert!((r.roughness as f64 - oracle(n)).abs() < 1e-5, "{r:?} against {}", oracle(n));
        assert!((r.roughness - 0.42).abs() < 0.005, "{r:?}");
        assert!((r.alpha - r.roughness * r.roughness).abs() < 1e-6);
    }

    #[test]
    fn roughness_follows_the_rule_over_a_range_of_exponents() {
        for n in [0.5f32, 1.0, 4.0, 10.0, 64.0, 500.0, 10000.0] {
            let lobe = Lobe::isotropic(Vec3::splat(-1.0), Vec3::splat(1.0), Vec3::splat(n));
            let r = roughness(&Lafortune { diffuse: Vec3::splat(0.5), lobes: vec![lobe] });
            assert!((r.roughness as f64 - oracle(n as f64)).abs() < 1e-5, "n = {n}: {r:?}");
            assert!(r.roughness > 0.0 && r.roughness <= 1.0);
        }
    }

    #[test]
    fn no_lobes_or_degenerate_exponents_are_fully_rough_and_finite() {
        assert_eq!(roughness(&Lafortune::lambert(Vec3::splat(0.5))).roughness, 1.0);
        for n in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert_eq!(blinn_phong_alpha(n), 1.0, "{n}");
        }
        // A retro-reflective lobe alone still gives a roughness (its own exponent).
        let retro = Lobe::isotropic(Vec3::splat(1.0), Vec3::splat(1.0), Vec3::splat(8.0));
        let r = roughness(&Lafortune { diffuse: Vec3::ONE, lobes: vec![retro] });
        assert_eq!(r.lobe, Some(0));
        assert!((r.roughness as f64 - oracle(8.0)).abs() < 1e-5);
    }

    #[test]
    fn base_colour_is_what_the_renderer_shades_with() {
        let skin = Lafortune::skin();
        assert_eq!(base_color_factor(Some(&crate::scene::Albedo::Map("a.png".into())), &skin), [1.0; 4]);
        let c = crate::scene::Albedo::Constant(Vec3::new(0.2, 0.3, 0.4));
        assert_eq!(base_color_factor(Some(&c), &skin), [0.2, 0.3, 0.4, 1.0]);
        assert_eq!(base_color_factor(None, &skin)[..3], skin.diffuse.to_array());
    }
}
