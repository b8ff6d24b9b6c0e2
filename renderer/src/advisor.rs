//! Which estimator a scene needs, and why ("model only what a scene requires"), from a survey
//! of its light transport (`survey.rs`).
//!
//! From that follow hard limits and a recommendation. A caustic from a delta light seen
//! through a specular surface (L S+ D S+ E, a point light's caustic seen through water) has no
//! edge between two non-specular vertices: no unbiased technique (pt, bdpt, mmlt) can sample
//! it, and only the photon mappers render it. A caustic from a delta light seen directly
//! (L S+ D E) is out of the path tracer's reach (its next-event estimate cannot cross the
//! specular surface, its BSDF samples cannot hit the light) but bidirectional methods reach
//! it by light tracing. Where caustics carry much of the light, photon mapping wins however
//! the light is shaped; where the camera sees little direct light, photons from Metropolis
//! chains do (amcppm); otherwise the path tracer, simplest and unbiased, is hard to beat.
//! A scene between those cases, which no bundled scene's measurement covers, gets amcppm too:
//! the default measured closest to the best on every bundled scene.

use crate::camera::CameraDesc;
use crate::integrators::ParamValues;
use crate::integrators::ppm::{photons_per_pass, pixel_footprint_radius};
use crate::scene::Scene;
use crate::survey::{TransportSurvey, survey_at};

/// An integrator a scene needs, with its parameters and the reasons.
#[derive(Clone, Debug, PartialEq)]
pub struct Recommendation {
    pub integrator: &'static str,
    /// Parameters beyond the defaults, chosen for this scene and resolution.
    pub params: ParamValues,
    pub reasons: Vec<String>,
    /// Integrators that cannot converge to the right image here, and why.
    pub cannot_converge: Vec<(&'static str, String)>,
}

/// The survey at an output size (4096 camera paths, 8192 light paths) and what follows from it.
pub fn analyse(scene: &Scene, width: u32, height: u32) -> (TransportSurvey, Recommendation) {
    let s = survey_at(scene, width, height);
    let r = s.recommend(width, height, &scene.camera);
    (s, r)
}

/// The share above which a kind of transport counts as present.
const PRESENT: f64 = 0.01;
/// The share above which it decides the choice of estimator.
const DOMINANT: f64 = 0.05;
/// Below this share of the view with a light in direct view, the light comes through
/// openings: measured with `caustica converge` at 30 s, 128 wide, three seeds, on the door
/// (0 % directly lit), amcppm had half the relMSE of mmlt and bdpt (1.95e-2 against 3.96e-2
/// and 3.86e-2).
const HIDDEN_LIGHTS: f64 = 0.05;
/// Above this share of the view with a light in direct view, and without strong caustics, the
/// path tracer wins (Cornell box 69 %, material spheres 87 %). Between `HIDDEN_LIGHTS`
/// and this no bundled scene lies: the advisor cannot classify such a scene and recommends
/// the default measured closest to the best across the bundled scenes (amcppm).
const MOSTLY_LIT: f64 = 0.5;
/// Below this share of the photons landing where the camera sees, uniform photons are mostly
/// wasted and photon paths from Metropolis chains (amcppm) pay: measured with `caustica
/// converge` at 30 s on gap-glass (0.8 % seen), amcppm had 0.78 times sppm's relMSE at the
/// same photons a pass (4.8e-3 against 6.1e-3, medians of three seeds); the caustic pool and
/// Cornell glass, where sppm wins, see 72 % and 86 %.
const FEW_PHOTONS_SEEN: f64 = 0.1;

impl TransportSurvey {
    /// The integrator this scene needs at `width` x `height`, its parameters and the reasons.
    pub fn recommend(&self, width: u32, height: u32, camera: &CameraDesc) -> Recommendation {
        let mut reasons = Vec::new();
        let mut cannot = Vec::new();
        let pct = |x: f64| format!("{:.0} %", 100.0 * x);
        if self.delta_caustic_flux > PRESENT && self.seen_through_specular > PRESENT {
            let why = format!(
                "a caustic lit by a point, spot or directional light ({} of the light reaching surfaces) is seen through specular surfaces ({} of the view): no unbiased technique can sample such paths",
                pct(self.delta_caustic_flux),
                pct(self.seen_through_specular)
            );
            for name in ["pt", "bdpt", "mmlt"] {
                cannot.push((name, why.clone()));
            }
        } else if self.delta_caustic_flux > PRESENT {
            cannot.push((
                "pt",
                format!(
                    "caustics lit by a point, spot or directional light ({} of the light reaching surfaces): the path tracer cannot reach them (bdpt and mmlt do, by light tracing)",
                    pct(self.delta_caustic_flux)
                ),
            ));
        }
        // The caustic share of the light that lands where the camera sees: light in a closet
        // the camera does not see decides nothing, a caustic under the glass it looks
        // through is the image (gap-glass, `caustica info`: 0.2 % of all the light is
        // caustic, 20 % of the light landing where the camera sees).
        let caustics_matter = self.seen_caustic_flux > DOMINANT
            || (self.delta_caustic_flux > PRESENT && self.seen_through_specular > PRESENT);
        let integrator = if caustics_matter {
            reasons.push(format!(
                "{} of the light reaching the surfaces the camera sees has passed specular ones (caustics){}: photon density estimation gathers it where paths from the camera rarely find it",
                pct(self.seen_caustic_flux),
                if self.seen_through_specular > PRESENT {
                    format!(", and {} of the view is seen through specular surfaces", pct(self.seen_through_specular))
                } else {
                    String::new()
                }
            ));
            if self.seen_flux < FEW_PHOTONS_SEEN {
                reasons.push(format!(
                    "only {} of the photons land where the camera sees: Metropolis chains over the photon paths, whose target is reaching the camera's hit points, keep them there",
                    pct(self.seen_flux)
                ));
                "amcppm"
            } else {
                "sppm"
            }
        } else if self.directly_lit < HIDDEN_LIGHTS {
            reasons.push(format!(
                "only {} of what the camera sees has a light in direct view: the light arrives through small openings, on a narrow set of paths that independent samples mostly miss; Metropolis chains over the photon paths (amcppm) keep the photons on the few that reach what the camera sees",
                pct(self.directly_lit)
            ));
            "amcppm"
        } else if self.directly_lit < MOSTLY_LIT {
            reasons.push(format!(
                "{} of what the camera sees has a light in direct view, between the scenes lit through openings (under {}) and those lit mostly directly (over {}), and no strong caustics: no bundled scene has measured which estimator wins here, so the default closest to the best on all of them (amcppm: photons from Metropolis chains merged at the camera's hit points, their count and the chains' large steps chosen as the run goes)",
                pct(self.directly_lit),
                pct(HIDDEN_LIGHTS),
                pct(MOSTLY_LIT)
            ));
            "amcppm"
        } else {
            reasons.push(format!(
                "{} of the view is lit directly and there are no strong caustics ({}): the path tracer, with next-event estimation, is the simplest unbiased choice",
                pct(self.directly_lit),
                pct(self.caustic_flux)
            ));
            "pt"
        };
        let photon_mapper = matches!(integrator, "sppm" | "amcppm");
        if self.glossy > DOMINANT && photon_mapper {
            reasons.push(format!(
                "{} of the view is glossy, which photon mapping blurs until its radius is small",
                pct(self.glossy)
            ));
        }
        let mut params = ParamValues::new();
        if photon_mapper {
            params.insert(
                "radius".into(),
                pixel_footprint_radius(self.median_hit_distance, height, camera),
            );
            // amcppm chooses its own count as the run goes (photons = 0); sppm takes one
            // photon per pixel, measured ahead of its default (README, "Choosing an
            // estimator").
            if integrator == "sppm" {
                params.insert("photons".into(), photons_per_pass(width, height) as f64);
            }
        }
        Recommendation {
            integrator,
            params,
            reasons,
            cannot_converge: cannot,
        }
    }
}

impl TransportSurvey {
    /// The integrator for a reference image, which others will be measured against: an
    /// unbiased one wherever one converges, so that a photon mapper compared with the
    /// reference does not find its own kernel bias in it, unless caustics carry so much of the
    /// light (over 20 %) that an unbiased estimator's noise after a long run would still
    /// exceed the photon mapper's bias.
    pub fn reference(&self, width: u32, height: u32, camera: &CameraDesc) -> Recommendation {
        let mut r = self.recommend(width, height, camera);
        let unbiased_possible = r.cannot_converge.iter().all(|(name, _)| *name == "pt");
        if matches!(r.integrator, "sppm" | "amcppm")
            && unbiased_possible
            && self.caustic_flux <= 0.2
        {
            r.integrator = "bdpt";
            r.params.clear();
            r.reasons.push(
                "for a reference, bdpt: unbiased (a photon mapper measured against it does not find its own kernel bias there), and it reaches what light tracing reaches, caustics included"
                    .into(),
            );
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::procedural::{caustic_pool, cornell_box, door, gap_glass};
    use crate::survey::survey;
    use glam::Vec3;

    fn lens() -> CameraDesc {
        CameraDesc::perspective(glam::Affine3A::IDENTITY, 0.7)
    }

    fn survey_of(desc: crate::scene::SceneDescription) -> TransportSurvey {
        let scene = Scene::build(desc).unwrap();
        let camera = Camera::new(&scene.camera, 64, 64);
        survey(&scene, &camera, 4096, 8192, 1)
    }

    #[test]
    fn the_bundled_scenes_get_the_estimators_their_transport_needs() {
        let glass = survey_of(cornell_box(true));
        assert!(
            glass.caustic_flux > 0.0 && glass.seen_through_specular > 0.01,
            "{glass:?}"
        );
        let plain = survey_of(cornell_box(false));
        assert_eq!(plain.caustic_flux, 0.0, "{plain:?}");
        assert_eq!(plain.seen_through_specular, 0.0);
        assert!(plain.directly_lit > 0.5, "{plain:?}");
        assert_eq!(plain.recommend(64, 64, &lens()).integrator, "pt");
        let pool = survey_of(caustic_pool());
        assert!(pool.caustic_flux > 0.3, "{pool:?}");
        assert_eq!(pool.recommend(64, 64, &lens()).integrator, "sppm");
        assert_eq!(pool.reference(64, 64, &lens()).integrator, "sppm");
        assert_eq!(glass.recommend(64, 64, &lens()).integrator, "sppm");
        assert_eq!(glass.reference(64, 64, &lens()).integrator, "bdpt");
        let gap_glass = survey_of(gap_glass());
        // Its caustic is a fifth of the light landing where the camera sees, though 0.2 % of
        // all (the rest lights the closet), and few photons land there.
        assert!(gap_glass.caustic_flux < DOMINANT, "{gap_glass:?}");
        assert!(gap_glass.seen_caustic_flux > DOMINANT, "{gap_glass:?}");
        assert!(gap_glass.seen_flux < FEW_PHOTONS_SEEN, "{gap_glass:?}");
        assert!(pool.seen_flux > FEW_PHOTONS_SEEN, "{pool:?}");
        assert!(glass.seen_flux > FEW_PHOTONS_SEEN, "{glass:?}");
        assert_eq!(gap_glass.recommend(64, 64, &lens()).integrator, "amcppm");
        assert_eq!(gap_glass.reference(64, 64, &lens()).integrator, "bdpt");
        let door = survey_of(door());
        assert!(door.directly_lit < 0.2, "{door:?}");
        assert!(door.directly_lit < HIDDEN_LIGHTS, "{door:?}");
        assert_eq!(door.recommend(64, 64, &lens()).integrator, "amcppm");
        assert_eq!(door.reference(64, 64, &lens()).integrator, "bdpt");
    }

    #[test]
    fn a_point_lights_caustic_seen_through_glass_rules_out_the_unbiased_estimators() {
        // The caustic pool with its area light replaced by a point light at its centre.
        let mut desc = caustic_pool();
        let light = desc
            .meshes
            .iter()
            .position(|m| desc.materials[m.material as usize].emission.max_element() > 0.0)
            .expect("the pool has an emitter");
        let centre = desc.meshes[light].positions.iter().sum::<Vec3>()
            / desc.meshes[light].positions.len() as f32;
        desc.meshes.remove(light);
        desc.lights.push(crate::scene::PunctualLightDesc::Point {
            position: centre,
            intensity: Vec3::splat(10.0),
        });
        let s = survey_of(desc);
        assert!(
            s.delta_light_power > 0.99 && s.delta_caustic_flux > 0.3,
            "{s:?}"
        );
        let r = s.recommend(64, 64, &lens());
        assert_eq!(r.integrator, "sppm");
        let ruled_out: Vec<&str> = r.cannot_converge.iter().map(|c| c.0).collect();
        assert_eq!(ruled_out, ["pt", "bdpt", "mmlt"]);
        assert!(r.params["radius"] > 0.0 && r.params["photons"] >= 10_000.0);
    }

    /// A view lit directly in part (between the door's hidden lights and the Cornell box's
    /// mostly direct light) without caustics matches no measured case: amcppm, which chooses
    /// its own photon count (none is given). Either side of the band keeps its rule.
    #[test]
    fn a_scene_no_rule_covers_gets_the_default_that_chooses_its_photons() {
        let partly_lit = TransportSurvey {
            directly_lit: 0.3,
            seen_flux: 0.5,
            median_hit_distance: 2.0,
            ..Default::default()
        };
        let r = partly_lit.recommend(64, 64, &lens());
        assert_eq!(r.integrator, "amcppm");
        assert!(r.params["radius"] > 0.0);
        assert!(!r.params.contains_key("photons"), "{:?}", r.params);
        assert!(r.reasons[0].contains("no bundled scene"), "{:?}", r.reasons);
        for (lit, expected) in [(0.01, "amcppm"), (0.7, "pt")] {
            let s = TransportSurvey {
                directly_lit: lit,
                ..partly_lit.clone()
            };
            assert_eq!(s.recommend(64, 64, &lens()).integrator, expected, "{lit}");
        }
        // Its reference is unbiased.
        assert_eq!(partly_lit.reference(64, 64, &lens()).integrator, "bdpt");
    }
}
