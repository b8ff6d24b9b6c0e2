//! vcm whose light subpaths come from Markov chains (amcvcm: visibility chains; mvcm:
//! visibility and contribution chains with the uniform bootstrap, by their MIS), against the
//! closed forms, the path tracer, bdpt where light subpaths rarely reach what the camera
//! sees, and at the extremes of the large-step probability.

const CHAINED: [&str; 2] = ["amcvcm", "mvcm"];

use caustica_renderer::camera::Camera;
use caustica_renderer::integrators::{Integrator, RenderContext, find};
use caustica_renderer::procedural::{cornell_box, door};
use caustica_renderer::scene::{Scene, SceneDescription};
use std::sync::Arc;

use crate::common::{block_means, block_means_of, mean, render, z_scores};

fn chained(
    name: &str,
    desc: SceneDescription,
    size: u32,
    seed: u64,
    extra: &[(&str, f64)],
) -> Box<dyn Integrator> {
    let scene = Arc::new(Scene::build(desc).unwrap());
    let camera = Camera::new(&scene.camera, size, size);
    let ctx = RenderContext {
        scene,
        camera,
        seed,
    };
    // vcm's automatic radius (a quarter of the photon mappers'): its kernel bias is below
    // the noise of 1024 passes on 32 x 32 pixels (`vertex_merging`'s agreement tests).
    let params: caustica_renderer::integrators::ParamValues =
        extra.iter().map(|(k, v)| (k.to_string(), *v)).collect();
    (find(name).unwrap().create)(ctx, &params)
}

/// The closed forms (radiance 1 everywhere; every light subpath is visible, so the chains'
/// normalisation is tested at a visible fraction near 1), at the default large-step
/// probability and at both ends of its range (0.01: the chains seldom re-seed and the
/// visible fraction rests on a few uniform samples a pass; 1: independent light
/// subpaths held while invisible ones are proposed). Standard error of the image mean at 64
/// passes of 24 x 24: below 0.3 % (vcm's); the chains' correlation at 0.01 widens it, so we
/// allow 2 % there and 1 % elsewhere.
#[test]
fn chained_vcm_reproduces_the_closed_forms_at_every_large_step_probability() {
    for (name, desc) in crate::common::closed_form_scenes() {
        for (integrator, (large_step, tolerance)) in CHAINED
            .iter()
            .flat_map(|i| [(0.3, 0.01), (0.01, 0.02), (1.0, 0.01)].map(|l| (*i, l)))
        {
            let (img, dropped) = render(
                desc.clone(),
                integrator,
                &[("large_step", large_step)],
                64,
                24,
                1,
                0,
            );
            assert_eq!(dropped, 0);
            let m = mean(&img);
            assert!(
                (m - 1.0).abs() < tolerance,
                "{integrator}, {name}, large_step {large_step}: mean {m}, exact 1"
            );
        }
    }
}

/// On the Cornell boxes (visible fraction about 0.8) each agrees block by block with the
/// path tracer as vcm does (`vertex_merging::merges_and_vcm_converge_to_the_path_tracer`).
/// Each pass's chains start afresh, so passes are independent and their spread is the noise.
#[test]
fn chained_vcm_converges_to_the_path_tracer_on_the_cornell_boxes() {
    for (name, desc) in [
        ("cornell-box", cornell_box(false)),
        ("cornell-glass", cornell_box(true)),
    ] {
        let pt = block_means("pt", &desc, 1024, 32, 4, 1, &[]);
        for integrator in CHAINED {
            let mut it = chained(integrator, desc.clone(), 32, 2, &[]);
            let (z, ratio) = z_scores(&pt, &block_means_of(it.as_mut(), 1024, 32, 4));
            crate::common::assert_blocks_agree(&format!("{name}, {integrator} vs pt"), &z, ratio);
        }
    }
}

/// The door (a room lit through a slit, max depth 10): about 2 % of uniform light subpaths
/// bring anything to the image, so here the chains carry the estimate, and their
/// normalisation by the visible fraction is what a wrong one would miss by a factor. Against
/// bdpt at 2048 passes, block by block.
#[test]
fn chained_vcm_agrees_with_bdpt_where_light_subpaths_are_rarely_visible() {
    let desc = door();
    let depth = [("max_depth", 10.0)];
    let bdpt = block_means("bdpt", &desc, 2048, 32, 4, 1, &depth);
    for integrator in CHAINED {
        let mut it = chained(integrator, desc.clone(), 32, 2, &depth);
        let (z, ratio) = z_scores(&bdpt, &block_means_of(it.as_mut(), 1024, 32, 4));
        crate::common::assert_blocks_agree(&format!("door, {integrator} vs bdpt"), &z, ratio);
        let stats = it.statistics().unwrap();
        let visible = stats["visible_fraction"].as_f64().unwrap();
        assert!(visible < 0.1, "{integrator}: visible fraction {visible}");
    }
}

/// The technique shares the viewer plots carry the chains' weights: over every path length
/// and technique they add up to amcvcm's and mvcm's image luminance times the passes, as
/// vcm's do (`vertex_merging::shares_add_up_to_the_image`), and merges bring part of the
/// light on the Cornell box with glass. mvcm plots its contribution chains beside the
/// visibility chains.
#[test]
fn chained_vcm_technique_shares_add_up_to_the_image() {
    use caustica_renderer::integrators::vcm::{Vcm, VcmSettings};
    for metropolised in [false, true] {
        let scene = Arc::new(Scene::build(cornell_box(true)).unwrap());
        let camera = Camera::new(&scene.camera, 24, 24);
        let ctx = RenderContext {
            scene,
            camera,
            seed: 3,
        };
        let settings = VcmSettings::from_params(&[("max_depth".to_string(), 5.0)].into());
        let vcm = Vcm::new(ctx, settings);
        let mut it = if metropolised {
            vcm.with_metropolised_light_subpaths(0.3)
        } else {
            vcm.with_metropolis_light_subpaths(0.3)
        };
        let (_, merges, total) = crate::vertex_merging::shares_add_up_to_the_image(&mut it, 8);
        assert!(merges > 0.01 * total, "merges {merges}");
        let plots = it.plots();
        assert!(plots.iter().any(|p| p.plot == "Visibility"));
        assert_eq!(
            plots.iter().any(|p| p.name.contains("contribution chain")),
            metropolised
        );
    }
}
