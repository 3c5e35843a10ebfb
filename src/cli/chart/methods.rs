//! The methods on the chart: the integrators as they are, then SPPM's variations, each the
//! scene with a few settings changed; how each is drawn; and their validation, which runs
//! before any of them renders.

use sppm_lang::Diagnostic;
use sppm_lang::internals::chart::Dash;
use sppm_lang::internals::render::{RenderOptions, prepare};
use sppm_lang::internals::scene::{DEFAULT_PHOTONS, Integrator, Scene};

/// A method on the chart: an integrator and its parameter changes, and how it is drawn.
pub struct Method {
    pub label: String,
    integrator: Integrator,
    alpha: Option<f64>,
    radius_factor: f64,
    photon_factor: f64,
    /// Index in the chart's palette.
    pub colour: usize,
    pub dash: Dash,
    /// The earlier default radius: one pixel footprint at the look-at distance for every pixel.
    look_at_radius: bool,
}

/// The methods: the integrators as they are (solid lines, one colour each), then SPPM's
/// variations (one line style per parameter; the colour says lower, middle or higher).
pub fn methods() -> Vec<Method> {
    let m = |label: &str, integrator, alpha, radius_factor, photon_factor, colour, dash| Method {
        label: label.into(),
        integrator,
        alpha,
        radius_factor,
        photon_factor,
        colour,
        dash,
        look_at_radius: false,
    };
    use Dash::{Dashed, Dotted, Solid};
    use Integrator::{Bpt, Lt, Path, PhotonMap, Ppm, Sppm, Vcm, Whitted};
    // Palette: 0 blue, 1 orange, 2 red, 3 green, 4 teal, 5 purple, 6 brown, 7 gold, 8 pink.
    vec![
        m("sppm", Sppm, None, 1.0, 1.0, 0, Solid),
        Method {
            look_at_radius: true,
            ..m("sppm-lookat", Sppm, None, 1.0, 1.0, 0, Dashed)
        },
        m("ppm", Ppm, None, 1.0, 1.0, 1, Solid),
        m("photon_map", PhotonMap, None, 1.0, 1.0, 2, Solid),
        m("path", Path, None, 1.0, 1.0, 3, Solid),
        m("whitted", Whitted, None, 1.0, 1.0, 6, Solid),
        m("vcm", Vcm, None, 1.0, 1.0, 5, Solid),
        m("bpt", Bpt, None, 1.0, 1.0, 8, Solid),
        m("lt", Lt, None, 1.0, 1.0, 7, Solid),
        m("sppm-alpha0.5", Sppm, Some(0.5), 1.0, 1.0, 4, Dashed),
        m("sppm-alpha0.7", Sppm, Some(0.7), 1.0, 1.0, 5, Dashed),
        m("sppm-alpha0.9", Sppm, Some(0.9), 1.0, 1.0, 8, Dashed),
        m("sppm-radius0.5x", Sppm, None, 0.5, 1.0, 4, Dotted),
        m("sppm-radius2x", Sppm, None, 2.0, 1.0, 5, Dotted),
        m("sppm-radius4x", Sppm, None, 4.0, 1.0, 8, Dotted),
        m("sppm-photons0.25x", Sppm, None, 1.0, 0.25, 7, Dashed),
        m("sppm-photons4x", Sppm, None, 1.0, 4.0, 7, Dotted),
    ]
}

impl Method {
    /// The scene as this method renders it. `look_at_radius` is the earlier default initial
    /// radius (one pixel footprint at the look-at distance), for `sppm-lookat`.
    pub fn scene(&self, scene: &Scene, look_at_radius: f64) -> Scene {
        let mut s = scene.clone();
        s.settings.integrator = Some(self.integrator);
        if let Some(a) = self.alpha {
            s.settings.alpha = a;
        }
        if self.look_at_radius {
            s.settings.radius = Some(look_at_radius);
        }
        s.settings.radius_scale = self.radius_factor;
        // The photon variants scale the scene's count, or the fixed default where the scene
        // leaves the count to SPPM.
        if self.photon_factor != 1.0 {
            let n = s.settings.photons.unwrap_or(DEFAULT_PHOTONS) as f64 * self.photon_factor;
            s.settings.photons = Some((n as u64).max(1));
        }
        s
    }

    /// What this method changes in the scene, for messages.
    fn describe(&self) -> String {
        let mut changes = vec![format!("the `{}` integrator", self.integrator.name())];
        if let Some(a) = self.alpha {
            changes.push(format!("alpha {a}"));
        }
        if self.look_at_radius {
            changes.push("an initial radius of one pixel footprint at the look-at distance".into());
        }
        if self.radius_factor != 1.0 {
            changes.push(format!("{}x the initial radius", self.radius_factor));
        }
        if self.photon_factor != 1.0 {
            changes.push(format!(
                "{}x the scene's photons per iteration",
                self.photon_factor
            ));
        }
        changes.join(", ")
    }
}

/// Prepares every chosen method's scene as its render will prepare it (the settings, the
/// memory estimate, the scene's validation: what `check` runs), before any is rendered, so
/// that a method the render would refuse stops the chart before it spends the budgets of the
/// others. One error per refused method, naming it, with the span kept (the scene's
/// `settings`); the help names the methods that pass.
pub fn validate(chosen: &[(Method, Scene)], options: &RenderOptions) -> Vec<Diagnostic> {
    let results: Vec<Result<(), Diagnostic>> = chosen
        .iter()
        .map(|(_, scene)| prepare(scene, options).map(|_| ()))
        .collect();
    let passing: Vec<&str> = chosen
        .iter()
        .zip(&results)
        .filter(|(_, r)| r.is_ok())
        .map(|((m, _), _)| m.label.as_str())
        .collect();
    let leave_out = if passing.is_empty() {
        String::new()
    } else {
        format!(
            "leave the method out with `--methods` (e.g. `--methods {}`)",
            passing.join(",")
        )
    };
    chosen
        .iter()
        .zip(results)
        .filter_map(|((m, _), r)| r.err().map(|e| (m, e)))
        .map(|(m, e)| {
            let help = match (e.help.clone(), leave_out.is_empty()) {
                (Some(h), false) => Some(format!("{h}; or {leave_out}")),
                (Some(h), true) => Some(h),
                (None, false) => Some(leave_out.clone()),
                (None, true) => None,
            };
            Diagnostic {
                message: format!(
                    "the chart's method `{}` ({}) cannot render this scene: {}",
                    m.label,
                    m.describe(),
                    e.message
                ),
                help,
                ..e
            }
        })
        .collect()
}

/// Where the method labelled `label` comes in [`methods`] (others after them).
pub fn rank_of(label: &str) -> usize {
    methods()
        .iter()
        .position(|m| m.label == label)
        .unwrap_or(usize::MAX)
}

/// The colour and line style of the method labelled `label` (`None`: not one of ours).
pub fn style_of(label: &str) -> Option<(usize, Dash)> {
    methods()
        .into_iter()
        .find(|m| m.label == label)
        .map(|m| (m.colour, m.dash))
}

/// The methods `--methods` names (comma-separated labels); an unknown label is an error
/// naming the known ones (it would otherwise be skipped, and the chart end up empty).
pub fn parse_methods(text: &str) -> Result<Vec<String>, String> {
    let known: Vec<String> = methods().into_iter().map(|m| m.label).collect();
    let wanted: Vec<String> = text.split(',').map(|s| s.trim().to_string()).collect();
    for w in &wanted {
        if !known.contains(w) {
            return Err(format!(
                "--methods: unknown method `{w}`; the methods are {}",
                known.join(", ")
            ));
        }
    }
    Ok(wanted)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_has_its_own_colour_and_style() {
        let all = methods();
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert!(
                    (a.colour, a.dash) != (b.colour, b.dash),
                    "{} and {} look the same",
                    a.label,
                    b.label
                );
            }
        }
    }

    /// A scene at the photon limit: the 4x variant is refused by its label, with the scene's
    /// settings span kept, and without it every method passes.
    #[test]
    fn a_variant_past_the_photon_limit_is_refused_by_name() {
        let src = "settings { resolution <4, 4> photons 100000000000 }\n\
                   camera { location <0, 0, -5> look_at <0, 0, 0> }\n\
                   light { <0, 5, -5> intensity 10 }\nsphere { <0, 0, 0>, 1 }\n";
        let loaded = sppm_lang::internals::eval::load_source("t.scn", src, &Default::default());
        let scene = loaded.scene.expect("the scene loads");
        let chosen = |labels: &[&str]| -> Vec<(Method, Scene)> {
            methods()
                .into_iter()
                .filter(|m| labels.contains(&m.label.as_str()))
                .map(|m| {
                    let s = m.scene(&scene, 0.01);
                    (m, s)
                })
                .collect()
        };
        let options = RenderOptions::default();
        let errors = validate(&chosen(&["sppm", "sppm-photons4x"]), &options);
        assert_eq!(errors.len(), 1);
        let e = &errors[0];
        assert!(e.message.contains("`sppm-photons4x`"), "{}", e.message);
        assert!(
            e.message.contains("4x the scene's photons"),
            "{}",
            e.message
        );
        assert!(e.message.contains("at most 100000000000"), "{}", e.message);
        assert!(e.is_placed(), "the settings block is where it points");
        let help = e.help.as_deref().unwrap();
        assert!(help.contains("--methods sppm`"), "{help}");
        // Every method is checked: photon mapping stores its photons, too many for memory.
        let labels = ["sppm", "photon_map", "sppm-photons4x", "path"];
        let errors = validate(&chosen(&labels), &options);
        let named: Vec<bool> = ["`photon_map`", "`sppm-photons4x`"]
            .iter()
            .zip(&errors)
            .map(|(l, e)| e.message.contains(l))
            .collect();
        assert_eq!(named, [true, true], "{} errors", errors.len());
        let help = errors[0].help.as_deref().unwrap();
        assert!(help.contains("--methods sppm,path`"), "{help}");
        let fine = validate(&chosen(&["sppm", "sppm-photons0.25x", "path"]), &options);
        assert!(fine.is_empty());
    }
}
