//! The effects a scene may list (`effects = ["shadows", "tsd"]`) and the rules between them,
//! checked once, when the scene is parsed ([`crate::scene::Scene::parse`]). What each effect
//! builds is decided in one place, [`crate::pass::graph::PassGraph::build`]; their settings live in
//! [`crate::skin::options`].

use serde::{Deserialize, Serialize};

/// One effect of the renderer. The file spells them in kebab case (`shadow-scattering`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Effect {
    /// The pre-integrated diffuse LUT D(N.L, 1/r) (Penner and Borshukov).
    Preintegrated,
    /// A closed form of the pre-integrated curves (the blog's or our fit).
    PreintegratedAnalytic,
    /// Order-2 spherical-harmonic ambient light from `[environment]`.
    ShAmbient,
    /// The key light's shadow map.
    Shadows,
    /// The shadow-scattering LUT on the key light's penumbra.
    ShadowScattering,
    /// Texture-space diffusion (light map, Poisson blurs).
    Tsd,
    /// A debug view of the mesh's tangent frames and UV stretch in place of the shading
    /// (`crate::pass::debug`).
    DebugFrames,
}

impl Effect {
    /// Every effect, in the order `--explain` and error messages list them.
    pub const ALL: [Effect; 7] = [
        Effect::Preintegrated,
        Effect::PreintegratedAnalytic,
        Effect::ShAmbient,
        Effect::Shadows,
        Effect::ShadowScattering,
        Effect::Tsd,
        Effect::DebugFrames,
    ];

    /// The name a scene file uses.
    pub fn name(self) -> &'static str {
        match self {
            Effect::Preintegrated => "preintegrated",
            Effect::PreintegratedAnalytic => "preintegrated-analytic",
            Effect::ShAmbient => "sh-ambient",
            Effect::Shadows => "shadows",
            Effect::ShadowScattering => "shadow-scattering",
            Effect::Tsd => "tsd",
            Effect::DebugFrames => "debug-frames",
        }
    }

    /// The effect a scene file's name stands for.
    pub(crate) fn from_name(name: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.name() == name)
    }

    /// The known names, comma separated (for messages).
    pub(crate) fn known_names() -> String {
        Effect::ALL.map(Effect::name).join(", ")
    }

    /// Whether the effect decides the base pass's diffuse term (one such effect at most).
    pub(crate) fn decides_diffuse(self) -> bool {
        matches!(self, Effect::Preintegrated | Effect::PreintegratedAnalytic | Effect::Tsd)
    }
}

impl std::fmt::Display for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Why a list of effects cannot be built: the scene field at fault and the reason.
pub(crate) type RuleError = (&'static str, String);

/// The rules between effects: at most one effect decides the diffuse term, `shadow-scattering`
/// needs `shadows`, `sh-ambient` needs an `[environment]` table.
///
/// # Errors
/// The first rule broken, as (field, reason).
pub(crate) fn check_rules(effects: &[Effect], has_environment: bool) -> Result<(), RuleError> {
    let has = |e: Effect| effects.contains(&e);
    let diffuse: Vec<&str> = effects.iter().filter(|e| e.decides_diffuse()).map(|e| e.name()).collect();
    if diffuse.len() > 1 {
        return Err(("effects", format!("`{}` each decide the diffuse term: list one", diffuse.join("` and `"))));
    }
    if has(Effect::ShadowScattering) && !has(Effect::Shadows) {
        return Err((
            "effects",
            format!("`{}` filters the shadow map: list `{}` too", Effect::ShadowScattering, Effect::Shadows),
        ));
    }
    if has(Effect::ShAmbient) && !has_environment {
        return Err(("environment", format!("`{}` needs an [environment] table", Effect::ShAmbient)));
    }
    Ok(())
}

/// Every list of effects the rules allow (with an environment), each in [`Effect::ALL`] order:
/// what the pass-graph tests walk.
pub fn allowed_combinations() -> Vec<Vec<Effect>> {
    (0u32..1 << Effect::ALL.len())
        .map(|bits| Effect::ALL.into_iter().enumerate().filter(|(i, _)| bits & (1 << i) != 0).map(|(_, e)| e).collect())
        .filter(|set: &Vec<Effect>| check_rules(set, true).is_ok())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_match_serde() {
        for e in Effect::ALL {
            assert_eq!(Effect::from_name(e.name()), Some(e));
            let json = serde_json::to_string(&e).unwrap();
            assert_eq!(json, format!("\"{}\"", e.name()));
        }
        assert_eq!(Effect::from_name("shadow"), None);
    }

    #[test]
    fn the_rules_refuse_two_diffuse_terms_and_scattering_without_shadows() {
        assert!(check_rules(&[Effect::Preintegrated, Effect::Tsd], true).is_err());
        assert!(check_rules(&[Effect::ShadowScattering], true).is_err());
        assert_eq!(check_rules(&[Effect::ShAmbient], false).unwrap_err().0, "environment");
        assert!(check_rules(&[Effect::Tsd, Effect::Shadows, Effect::ShAmbient], true).is_ok());
    }

    #[test]
    fn allowed_combinations_are_every_subset_the_rules_keep() {
        let all = allowed_combinations();
        // 4 diffuse choices x {none, shadows, shadows + scattering} x {ambient or not} x {debug view or not}.
        assert_eq!(all.len(), 4 * 3 * 2 * 2);
        assert!(all.contains(&Vec::new()));
        assert!(all.iter().all(|set| check_rules(set, true).is_ok()));
    }
}
