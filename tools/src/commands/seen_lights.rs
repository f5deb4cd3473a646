//! `inlay train`'s lights past the bounds: found from the training views,
//! reported (and, with `--scene`, set against the recipe's emitters past
//! its bounds), and their pixels left out of training.

use inlay_passes::dataset::Dataset;
use inlay_passes::geometry::Aabb;
use inlay_passes::scene::{Recipe, Shape};
use inlay_passes::train::pixels::training_frames;
use inlay_passes::train::seen_lights::{
    find_seen_lights, mask_seen_lights, SeenLight, LIGHT_RATIO,
};
use inlay_passes::train::trainer::radiance_scale;

/// Finds the lights the training frames of `dataset` (all but `hold_out`)
/// show past `bounds`, reports them (against `recipe`'s emitters past its
/// bounds where given), and leaves their pixels out of the training
/// frames. `scale` is the knobs' scale where set (else the photographs').
pub fn find_and_mask(
    dataset: &mut Dataset,
    hold_out: u32,
    bounds: &Aabb,
    scale: Option<f64>,
    recipe: Option<&Recipe>,
) -> Vec<SeenLight> {
    let training = training_frames(dataset, hold_out);
    let scale = scale.unwrap_or_else(|| radiance_scale(dataset, &training, bounds));
    let found = find_seen_lights(dataset, &training, bounds, scale);
    if !found.inside.is_empty() {
        eprintln!(
            "{} light{} inside the bounds, left to the field: {}",
            found.inside.len(),
            if found.inside.len() == 1 { "" } else { "s" },
            found
                .inside
                .iter()
                .map(|c| format!("({:.3}, {:.3}, {:.3})", c.x, c.y, c.z))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let masked = mask_seen_lights(dataset, &found.lights, &training);
    for (l, &saturated) in found.lights.iter().zip(&found.saturated) {
        for line in light_lines(l, saturated, "training views", scale) {
            eprintln!("{line}");
        }
        if let Some(r) = recipe {
            against_recipe(l, r);
        }
    }
    if masked > 0 {
        eprintln!(
            "{masked} pixels of the training views are the lights' and are left out of training; \
             the held-out views draw the lights (--seen-lights off keeps every pixel)"
        );
    }
    found.lights
}

/// What `inlay train` and `inlay dataset` say of a light found past the
/// bounds: where, how large and how bright, in how many `views` (what the
/// frames read are called), the spots' threshold over `scale`, and where
/// `saturated` of its pixels were lower bounds, that its radiance is one.
pub fn light_lines(light: &SeenLight, saturated: usize, views: &str, scale: f64) -> Vec<String> {
    let (c, e) = (light.centre, light.radiance);
    let mut lines = vec![format!(
        "light past the bounds: a sphere at ({:.3}, {:.3}, {:.3}), radius {:.4}, radiance \
         ({:.4e}, {:.4e}, {:.4e}) (seen in {} {views}, spots over {:.0}x the knobs' scale {:.3e}; \
         {:.1} % of its spots' light unexplained)",
        c.x,
        c.y,
        c.z,
        light.radius,
        e.x,
        e.y,
        e.z,
        light.views,
        LIGHT_RATIO,
        scale,
        100.0 * light.residual
    )];
    if saturated > 0 {
        lines.push(format!(
            "  warning: {saturated} of its pixels saturated in every exposure: its radiance is a \
             lower bound (what its recorded pixels and those say it is at least); a shorter \
             bracket would record it"
        ));
    }
    lines
}

/// Prints how far `light` is from the nearest of `recipe`'s spheres that
/// emit past its bounds, and how its intensity compares.
fn against_recipe(light: &SeenLight, recipe: &Recipe) {
    let (_, outside) = recipe.lights();
    let nearest = outside
        .iter()
        .filter_map(|p| match p.shape {
            Shape::Sphere { centre, radius } => Some((p, centre, radius)),
            _ => None,
        })
        .min_by(|a, b| {
            let d = |c: glam::DVec3| (c - light.centre).length();
            d(a.1).total_cmp(&d(b.1))
        });
    if let Some((p, centre, radius)) = nearest {
        let truth = std::f64::consts::PI * radius * radius * p.emission;
        let ratio = light.intensity() / truth;
        eprintln!(
            "  against the recipe's `{}`: centre {:.4} off, radius {:.2}x, radiance {:.2}x, \
             intensity (pi r^2 L) {:.3}x {:.3}x {:.3}x",
            p.name,
            (light.centre - centre).length(),
            light.radius / radius,
            light.radiance.x / p.emission.x,
            ratio.x,
            ratio.y,
            ratio.z
        );
    }
}
