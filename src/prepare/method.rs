//! Which integrator a render runs, and why: the render's options (`--integrator`), else the
//! scene's `settings { integrator ... }`, else the default rule ([`default_method`]). The scene
//! says only what its file declared (`Settings::integrator` is `None` when it names no method);
//! the rule is applied here, where the options meet the scene's settings, and nowhere else.

use crate::scene::{Integrator, Scene, Settings};

/// The method the default rule gives a scene that sets neither an integrator nor
/// `final_gather on`. The rule's measured choice there is `vcm` (docs/integrators.md, "The
/// default"); this constant is the one line that switches it.
pub const DEFAULT_ELSEWHERE: Integrator = Integrator::Sppm;

/// Why a render runs its method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MethodSource {
    /// The render's options chose it (`RenderOptions::integrator`, `render --integrator`).
    Options,
    /// The scene's `settings { integrator ... }`.
    Scene,
    /// The default rule: the scene sets `final_gather on`, which SPPM's final gather serves.
    FinalGather,
    /// The default rule: the scene's camera is orthographic, which [`DEFAULT_ELSEWHERE`]
    /// cannot take (it connects light paths to the lens).
    Orthographic,
    /// The default rule: the scene sets no `final_gather`.
    Elsewhere,
}

impl MethodSource {
    /// Why, in words (`check` and `render` print it after the method's name).
    pub fn reason(self) -> &'static str {
        match self {
            MethodSource::Options => "set by the render options, `--integrator`",
            MethodSource::Scene => "the scene's `integrator` setting",
            MethodSource::FinalGather => "default: the scene sets final_gather on",
            MethodSource::Orthographic => {
                "default: the scene's camera is orthographic, which the default method elsewhere cannot take"
            }
            MethodSource::Elsewhere => "default: the scene does not set final_gather",
        }
    }
}

/// The method a render runs and why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MethodChoice {
    pub integrator: Integrator,
    pub source: MethodSource,
}

impl std::fmt::Display for MethodChoice {
    /// `vcm (default: the scene does not set final_gather)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({})", self.integrator.name(), self.source.reason())
    }
}

/// Whether `method` connects light paths to the lens, which an orthographic camera's parallel
/// rays cannot take.
pub fn needs_a_lens(method: Integrator) -> bool {
    matches!(method, Integrator::Vcm | Integrator::Bpt | Integrator::Lt)
}

/// The default rule, for a scene that names no integrator: `sppm` where the scene sets
/// `final_gather on` (its final gather was made for scenes lit mostly by interreflection, where
/// `vcm` lost by 2.7x), [`DEFAULT_ELSEWHERE`] elsewhere, unless the camera is orthographic and
/// that method needs a lens.
pub fn default_method(settings: &Settings, orthographic: bool) -> MethodChoice {
    let (integrator, source) = if settings.final_gather {
        (Integrator::Sppm, MethodSource::FinalGather)
    } else if orthographic && needs_a_lens(DEFAULT_ELSEWHERE) {
        (Integrator::Sppm, MethodSource::Orthographic)
    } else {
        (DEFAULT_ELSEWHERE, MethodSource::Elsewhere)
    };
    MethodChoice { integrator, source }
}

/// The method a render of `scene` runs when the options choose `option` (`None`: they leave it
/// to the scene).
pub fn method_choice(scene: &Scene, option: Option<Integrator>) -> MethodChoice {
    match (option, scene.settings.integrator) {
        (Some(integrator), _) => MethodChoice {
            integrator,
            source: MethodSource::Options,
        },
        (None, Some(integrator)) => MethodChoice {
            integrator,
            source: MethodSource::Scene,
        },
        (None, None) => default_method(&scene.settings, scene.camera.orthographic),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(integrator: Option<Integrator>, final_gather: bool, orthographic: bool) -> Scene {
        let loaded = crate::eval::load_source("m.scn", "sphere { <0,0,0> 1 }", &Default::default());
        let mut s = loaded.scene.expect("a valid scene");
        s.settings.integrator = integrator;
        s.settings.final_gather = final_gather;
        s.camera.orthographic = orthographic;
        s
    }

    /// The option wins over the scene, the scene over the rule; the rule gives `sppm` with
    /// `final_gather on` and [`DEFAULT_ELSEWHERE`] elsewhere, `sppm` for an orthographic
    /// camera when that method needs a lens.
    #[test]
    fn the_option_then_the_scene_then_the_rule_choose() {
        use Integrator::*;
        let choose = |option, integrator, gather, ortho| {
            let c = method_choice(&scene(integrator, gather, ortho), option);
            (c.integrator, c.source)
        };
        assert_eq!(
            choose(Some(Path), Some(Whitted), true, false),
            (Path, MethodSource::Options)
        );
        assert_eq!(
            choose(None, Some(Whitted), true, false),
            (Whitted, MethodSource::Scene)
        );
        // The scene's own choice stands even where the rule would choose otherwise.
        assert_eq!(
            choose(None, Some(Vcm), true, false),
            (Vcm, MethodSource::Scene)
        );
        assert_eq!(
            choose(None, None, true, false),
            (Sppm, MethodSource::FinalGather)
        );
        assert_eq!(
            choose(None, None, true, true),
            (Sppm, MethodSource::FinalGather)
        );
        assert_eq!(
            choose(None, None, false, false),
            (DEFAULT_ELSEWHERE, MethodSource::Elsewhere)
        );
        let ortho = choose(None, None, false, true);
        if needs_a_lens(DEFAULT_ELSEWHERE) {
            assert_eq!(ortho, (Sppm, MethodSource::Orthographic));
        } else {
            assert_eq!(ortho, (DEFAULT_ELSEWHERE, MethodSource::Elsewhere));
        }
        // Whatever the rule gives, an orthographic camera can render it.
        for gather in [false, true] {
            let (m, _) = choose(None, None, gather, true);
            assert!(!needs_a_lens(m), "{m:?}");
        }
        assert!(needs_a_lens(Vcm) && needs_a_lens(Bpt) && needs_a_lens(Lt));
        assert!(!needs_a_lens(Sppm) && !needs_a_lens(Path));
    }

    #[test]
    fn the_choice_reads_as_the_method_and_its_reason() {
        let c = method_choice(&scene(None, false, false), None);
        assert_eq!(
            c.to_string(),
            format!(
                "{} (default: the scene does not set final_gather)",
                DEFAULT_ELSEWHERE.name()
            )
        );
        let c = method_choice(&scene(Some(Integrator::Path), false, false), None);
        assert_eq!(c.to_string(), "path (the scene's `integrator` setting)");
    }
}
