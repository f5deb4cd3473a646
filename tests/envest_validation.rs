//! Issue 7 item 5: the environment estimated from each bundled field,
//! checked against the recipe's known lights (`envest::truth`). PLANTS,
//! whose lights are all inside the field, must yield an environment that
//! carries under 2 % of the irradiance its lamp delivers at the test
//! points; DOG must recover its hidden light within 15 % (measured 4.2 %),
//! CUPS within 10 % (5.2 %) and BOOKS within 22 % (20.2 %). Light sources
//! are judged against the median surface over all views (it was each
//! view's own): CUPS 14.3 → 5.2 %, DOG 3.7 → 4.2 %, BOOKS 19.0 → 20.2 %,
//! ROOM 288 → 94 %. BOOKS measured 13.3 % until the bake moved each
//! surface's density inside it so that rays end on the surface (its field
//! came closer to Cycles, 3.5 → 1.6 % on 8 × 8 blocks, and its estimate
//! moved away from the truth); why is not yet understood
//! (docs/fidelity.md).
//!
//! PLANTS' estimate comes out black since the estimate asks whether the
//! points need light from outside the field at all (their loss without
//! it 1.13× the loss with it, under `min_loss_gain`; the scenes with a
//! hidden light 15–195×: docs/fidelity.md, "Thirty-fifth pass"); before,
//! the lobes the fit left carried 1.7 %.
//!
//! Each runs the whole estimate on the bundled field (128 nodes, as
//! shipped) with 30 views, 8192 rays per point and 1000 steps, fewer than
//! the defaults so that CI stays fast (about 40 s each on 2 cores). PLANTS
//! takes 16384 rays: its only light is a small lamp inside the field, which
//! few of a point's rays hit, and the noise of that near field is what an
//! estimate mistakes for environment light (docs/benchmarks.md, "Sixth
//! pass": 2.3 % at 8192 rays, 1.7 % at 16384 on seed 1).

mod common;

use inlay_passes::envest::{estimate_environment, EnvEstimateKnobs, Validation};
use inlay_passes::field::{perturb, Perturbation};

/// Estimates `name`'s environment and checks it against the recipe.
fn validate(name: &str, rays_per_point: u32) -> Validation {
    validate_with(name, rays_per_point, 0)
}

/// As [`validate`], with `near_lights` near lights beside the lobes.
fn validate_with(name: &str, rays_per_point: u32, near_lights: u32) -> Validation {
    validate_field(name, rays_per_point, near_lights, &Perturbation::default())
}

/// As [`validate_with`], on the bundled field perturbed by `perturbation`.
fn validate_field(
    name: &str,
    rays_per_point: u32,
    near_lights: u32,
    perturbation: &Perturbation,
) -> Validation {
    let scene = common::bundled_scene(name);
    let ctx = common::gpu();
    let lib = inlay_passes::shaders::embedded_library();
    let field = inlay::field_source::scene_field(&scene, None, false, None).unwrap();
    let field = if perturbation.is_none() {
        field
    } else {
        perturb(&field, perturbation)
    };
    let knobs = EnvEstimateKnobs {
        views: 30,
        rays_per_point,
        iterations: 1000,
        near_lights,
        ..EnvEstimateKnobs::default()
    };
    let est = estimate_environment(
        &ctx,
        &lib,
        &field,
        scene.march,
        &knobs,
        &Default::default(),
        None,
        &[],
        &|_, _, _, _| {},
    )
    .unwrap();
    common::assert_no_validation_errors(&ctx);
    let v = Validation::with_lights(
        &scene,
        scene.recipe().unwrap(),
        &est.fit.lobes,
        &est.fit.lights,
        2048,
        1,
    );
    eprintln!(
        "{name}: {} points, final loss {:.4e}, {} lobes kept, loss without outside light {:.3}× (kept: {})",
        est.surface.points.len(),
        est.fit.final_loss,
        est.fit.lobes.len(),
        est.outside.gain().unwrap_or(f64::NAN),
        est.outside.kept
    );
    eprintln!(
        "{name}: hidden-light error {:.2} %, share of all lights {:.2} %",
        100.0 * v.hidden_error(),
        100.0 * v.fraction_of_lights()
    );
    v
}

#[test]
fn plants_whose_lights_are_all_in_the_field_yields_a_nearly_black_environment() {
    let v = validate("plants.toml", 16384);
    let share = v.fraction_of_lights();
    assert!(
        share < 0.02,
        "the environment carries {:.2} % of the lamp's irradiance",
        100.0 * share
    );
}

/// Item 6: PLANTS' field perturbed as a trainer leaves a field (log-normal
/// noise of 0.2 on every node, 60 floaters, 30 % of the density removed
/// everywhere) still yields a black environment: its points do not need
/// light from outside the field (measured: their loss without it 1.24×
/// the loss with it; each perturbation alone 0.88–1.49×). Before the
/// estimate asked, its lobes carried 44 % of the lamp's irradiance over
/// the test points on this field (the floaters alone 48 %, 2.3 × the
/// field's light at the toy; docs/fidelity.md, "Thirty-fifth pass").
#[test]
fn plants_perturbed_as_a_trainer_leaves_it_stays_black() {
    let trained_like = Perturbation {
        noise: 0.2,
        floaters: 60,
        see_through: 0.3,
        ..Perturbation::default()
    };
    let share = validate_field("plants.toml", 8192, 0, &trained_like).fraction_of_lights();
    assert!(
        share < 0.005,
        "the environment carries {:.2} % of the lamp's irradiance",
        100.0 * share
    );
}

#[test]
fn cups_hidden_light_is_recovered_within_10_percent() {
    let e = validate("cups.toml", 8192).hidden_error();
    assert!(e < 0.10, "error {:.1} %", 100.0 * e);
}

#[test]
fn books_hidden_light_is_recovered_within_22_percent() {
    let e = validate("books.toml", 8192).hidden_error();
    assert!(e < 0.22, "error {:.1} %", 100.0 * e);
}

#[test]
fn dog_hidden_light_is_recovered_within_15_percent() {
    let e = validate("dog.toml", 8192).hidden_error();
    assert!(e < 0.15, "error {:.1} %", 100.0 * e);
}

/// ROOM's estimate with its softbox inside the field and a bulb 1.5 m above
/// it (docs/fidelity.md, "The environment estimate on ROOM"): far from the
/// 15 % target, but held below 150 % (measured 94 %; 288 % with each
/// view's own median, whose views of the walls' dark outside took the lit
/// room for a light source); with the old light-source threshold (50 × the
/// median) the softbox's pixels stayed in the fit and the error was 829 %. Ignored (a 128-node bake and an estimate,
/// minutes): `cargo test --release --test envest_validation -- --ignored room`.
#[test]
#[ignore]
fn room_with_an_in_field_softbox_stays_within_bounds() {
    let e = validate("room.toml", 8192).hidden_error();
    assert!(e < 1.5, "error {:.1} %", 100.0 * e);
}

/// ROOM with one near light beside the lobes (docs/fidelity.md, "Ninth
/// pass"): the bulb 1.5 m above the field is placed 1.8–2.0 m up and the
/// error falls to 35–50 % over seeds 1–3 (measured 34.8 % on seed 1; 59 %
/// with two lights before they started with half the light and with the
/// irradiance at the centre as their parameter). Held below 45 %. Ignored
/// with the other ROOM test (same command).
#[test]
#[ignore]
fn room_with_a_near_light_beside_the_lobes_halves_the_error() {
    let e = validate_with("room.toml", 8192, 1).hidden_error();
    assert!(e < 0.45, "error {:.1} %", 100.0 * e);
}
