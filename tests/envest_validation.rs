//! Issue 7 item 5: the environment estimated from each bundled field,
//! checked against the recipe's known lights (`envest::truth`). PLANTS,
//! whose lights are all inside the field, must yield an environment that
//! carries under 2 % of the irradiance its lamp delivers at the test
//! points; DOG must recover its hidden light within 15 % (measured 3.7 %),
//! CUPS within 18 % (14.3 %) and BOOKS within 20 % (19.0 %). CUPS and BOOKS
//! measured 7.5 % and 13.3 % until the bake moved each surface's density
//! inside it so that rays end on the surface: the fields came closer to
//! Cycles (BOOKS' 8 × 8-block error against it 3.5 → 1.6 %, CUPS' 3.7 →
//! 3.1 %) and these two estimates moved away from the truth; why is not
//! yet understood (docs/fidelity.md).
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

/// Estimates `name`'s environment and checks it against the recipe.
fn validate(name: &str, rays_per_point: u32) -> Validation {
    let scene = common::bundled_scene(name);
    let ctx = common::gpu();
    let lib = inlay::shaders::embedded_library();
    let field = inlay::field_source::scene_field(&scene, None, false).unwrap();
    let knobs = EnvEstimateKnobs {
        views: 30,
        rays_per_point,
        iterations: 1000,
        ..EnvEstimateKnobs::default()
    };
    let est =
        estimate_environment(&ctx, &lib, &field, scene.march, &knobs, &|_, _, _, _| {}).unwrap();
    common::assert_no_validation_errors(&ctx);
    let v = Validation::new(&scene, scene.recipe().unwrap(), &est.fit.lobes, 2048, 1);
    eprintln!(
        "{name}: {} points, final loss {:.4e}, {} lobes kept",
        est.surface.points.len(),
        est.fit.final_loss,
        est.fit.lobes.len()
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

#[test]
fn cups_hidden_light_is_recovered_within_18_percent() {
    let e = validate("cups.toml", 8192).hidden_error();
    assert!(e < 0.18, "error {:.1} %", 100.0 * e);
}

#[test]
fn books_hidden_light_is_recovered_within_20_percent() {
    let e = validate("books.toml", 8192).hidden_error();
    assert!(e < 0.20, "error {:.1} %", 100.0 * e);
}

#[test]
fn dog_hidden_light_is_recovered_within_15_percent() {
    let e = validate("dog.toml", 8192).hidden_error();
    assert!(e < 0.15, "error {:.1} %", 100.0 * e);
}

/// ROOM's estimate with its softbox inside the field and a bulb 1.5 m above
/// it (docs/fidelity.md, "The environment estimate on ROOM"): far from the
/// 15 % target, but held below 250 % (measured 151 %); with the old light-
/// source threshold (50 × the median) the softbox's pixels stayed in the
/// fit and the error was 829 %. Ignored (a 128-node bake and an estimate,
/// minutes): `cargo test --release --test envest_validation -- --ignored room`.
#[test]
#[ignore]
fn room_with_an_in_field_softbox_stays_within_bounds() {
    let e = validate("room.toml", 8192).hidden_error();
    assert!(e < 2.5, "error {:.1} %", 100.0 * e);
}
