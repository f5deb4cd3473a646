//! Baking a recipe into a grid field. Density: each opaque primitive's
//! signed distance through a smooth, compact edge profile (so σ is exactly
//! zero away from surfaces and its gradient gives normals), plus each medium's
//! density through the same profile. Colour: path-traced radiance of the
//! nearest surface point (emission + Lambertian reflection) and/or the
//! medium's in-scattered light, mixed by density.
//!
//! **Emitters keep their power**: the smooth edge makes a sphere's field
//! look larger than the sphere, so after the bake each emitting sphere's
//! nodes are scaled until the field emits the recipe's power
//! ([`super::emitter_power`]).

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{DVec3, UVec3};
use rayon::prelude::*;

use super::emitter_power::calibrate_emitters;
use super::knobs::BakeKnobs;
use super::path_tracer::PathTracer;
use crate::field::{GridField, DEFAULT_OCCUPANCY_BLOCK};
use crate::rng::Pcg32;
use crate::scene::{Environment, Recipe};

/// The edge profile: 1 for s ≤ −1, 0 for s ≥ 1, a C¹ cubic in between
/// (s is signed distance over the falloff half-width).
pub fn edge_profile(s: f64) -> f64 {
    let t = ((1.0 - s) * 0.5).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Changes whenever baking would give different nodes for the same recipe
/// and knobs (cached bakes carry it in their key).
pub const BAKE_REVISION: u32 = 4;

/// Nodes per axis for a bake at `resolution` along the longest axis.
pub fn grid_resolution(recipe: &Recipe, resolution: u32) -> UVec3 {
    let size = recipe.bounds.size();
    let longest = size.max_element();
    let n = |e: f64| ((resolution as f64 - 1.0) * e / longest).round().max(1.0) as u32 + 1;
    UVec3::new(n(size.x), n(size.y), n(size.z))
}

/// Bakes `recipe` lit by `env` into a grid field. `progress(done, total)` is
/// called as z-slices finish (from worker threads).
pub fn bake_grid(
    recipe: &Recipe,
    env: &Environment,
    knobs: &BakeKnobs,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> GridField {
    let res = grid_resolution(recipe, knobs.resolution);
    // The bounds as a field file stores them (f32), so that the field baked
    // here and the same field loaded from its file are the same field.
    let bounds = crate::geometry::Aabb::new(
        recipe.bounds.min.as_vec3().as_dvec3(),
        recipe.bounds.max.as_vec3().as_dvec3(),
    );
    let spacing = bounds.size() / (res.as_dvec3() - DVec3::ONE);
    let voxel = spacing.max_element();
    let width = knobs.falloff_voxels * voxel;
    let sigma_max = knobs.density_scale / voxel;
    // Nodes whose trilinear cells can reach non-zero density need a colour.
    let band = width + 2.0 * voxel;
    let tracer = PathTracer::new(recipe, env, knobs.bounces);
    let done = AtomicU64::new(0);
    let slices: Vec<Vec<[f32; 4]>> = (0..res.z)
        .into_par_iter()
        .map(|k| {
            let mut out = Vec::with_capacity((res.x * res.y) as usize);
            for j in 0..res.y {
                for i in 0..res.x {
                    let x = bounds.min + DVec3::new(i as f64, j as f64, k as f64) * spacing;
                    let index = (i + res.x * (j + res.y * k)) as u64;
                    let mut rng = Pcg32::new(knobs.seed, index);
                    out.push(bake_node(
                        recipe,
                        &tracer,
                        x,
                        width,
                        sigma_max,
                        band,
                        knobs.samples,
                        &mut rng,
                    ));
                }
            }
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress(d, res.z as u64);
            out
        })
        .collect();
    let nodes = slices.into_iter().flatten().collect();
    let mut field = GridField::new(res, bounds, nodes, DEFAULT_OCCUPANCY_BLOCK);
    let owner = |x: DVec3| {
        nearest_opaque(recipe, x)
            .filter(|(d, _)| d.abs() <= band)
            .map(|(_, i)| i)
    };
    calibrate_emitters(recipe, &mut field, band, &owner);
    field
}

/// The opaque primitive of `recipe` nearest to `x` (signed distance, index).
fn nearest_opaque(recipe: &Recipe, x: DVec3) -> Option<(f64, usize)> {
    recipe
        .primitives
        .iter()
        .enumerate()
        .filter(|(_, p)| p.medium_density.is_none())
        .map(|(i, p)| (p.shape.sdf(x), i))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

#[allow(clippy::too_many_arguments)]
fn bake_node(
    recipe: &Recipe,
    tracer: &PathTracer<'_>,
    x: DVec3,
    width: f64,
    sigma_max: f64,
    band: f64,
    samples: u32,
    rng: &mut Pcg32,
) -> [f32; 4] {
    // Nearest opaque primitive, and the media around x.
    let nearest = nearest_opaque(recipe, x);
    let mut sigma_media = 0.0;
    let mut medium_near: Option<(f64, usize)> = None;
    for (i, p) in recipe.primitives.iter().enumerate() {
        if let Some(sigma) = p.medium_density {
            let d = p.shape.sdf(x);
            sigma_media += sigma * edge_profile(d / width);
            if medium_near.is_none_or(|(b, _)| d < b) {
                medium_near = Some((d, i));
            }
        }
    }
    let sigma_surface = nearest.map_or(0.0, |(d, _)| sigma_max * edge_profile(d / width));
    let n = samples as f64;
    let surface_colour = nearest.filter(|(d, _)| d.abs() <= band).map(|(d, i)| {
        let shape = &recipe.primitives[i].shape;
        let normal = shape.sdf_gradient(x);
        let p = x - d * normal;
        let mut sum = DVec3::ZERO;
        for _ in 0..samples {
            sum += tracer.surface_radiance(i, p, normal, rng);
        }
        sum / n
    });
    let medium_colour = medium_near.filter(|(d, _)| *d <= band).map(|(_, i)| {
        let mut sum = DVec3::ZERO;
        for _ in 0..samples {
            sum += tracer.medium_radiance(i, x, rng);
        }
        sum / n
    });
    let total = sigma_surface + sigma_media;
    let colour = match (surface_colour, medium_colour) {
        (Some(s), Some(m)) if total > 0.0 => (s * sigma_surface + m * sigma_media) / total,
        (Some(s), _) => s,
        (None, Some(m)) => m,
        (None, None) => DVec3::ZERO,
    };
    [
        colour.x as f32,
        colour.y as f32,
        colour.z as f32,
        total as f32,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_profile_is_compact_monotone_and_smooth() {
        assert_eq!(edge_profile(-1.0), 1.0);
        assert_eq!(edge_profile(1.0), 0.0);
        assert_eq!(edge_profile(5.0), 0.0);
        assert!((edge_profile(0.0) - 0.5).abs() < 1e-12);
        let mut prev = 1.0;
        for i in -120..=120 {
            let v = edge_profile(i as f64 / 100.0);
            assert!(v <= prev);
            prev = v;
        }
        // C¹ at the ends: zero slope.
        let h = 1e-6;
        assert!((edge_profile(1.0 - h) - edge_profile(1.0)).abs() < 1e-10);
        assert!((edge_profile(-1.0 + h) - edge_profile(-1.0)).abs() < 1e-10);
    }
}
