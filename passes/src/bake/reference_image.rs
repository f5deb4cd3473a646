//! Ground-truth camera images of a recipe, path traced directly over the
//! analytic primitives (no field). Like the march, only what lies inside the
//! field's bounds is seen: each pixel holds premultiplied radiance and the
//! fraction of its samples that met a surface or scattered in a medium.
//! Where the bounds cut through a solid, the cut face shows the radiance of
//! the nearest surface point, which is what the bake stores inside solids.
//! Placed objects are seen wherever they are (inside the bounds or not),
//! cut the field's rays, cast shadows and count as covered pixels: the
//! ground truth of the full insertion.

use glam::DVec3;
use rayon::prelude::*;

use super::path_tracer::{Event, PathTracer};
use crate::camera::CameraFrame;
use crate::geometry::ray_box;
use crate::geometry::MeshScene;
use crate::object::PlacedObject;
use crate::rng::Pcg32;
use crate::scene::{Environment, Recipe};

/// Options of a reference render.
#[derive(Debug, Clone, Copy)]
pub struct ReferenceOptions {
    /// Samples per pixel.
    pub samples: u32,
    /// Indirect scattering events after direct light.
    pub bounces: u32,
    /// Seed.
    pub seed: u64,
    /// Jitter samples over the pixel (anti-aliasing); off: pixel centres,
    /// as the march samples them.
    pub antialias: bool,
    /// A camera ray that leaves the bounds sees the environment, as a
    /// photograph sees past any box (off: black there, the pixel's
    /// coverage below 1).
    pub sky_behind: bool,
}

/// Renders the camera image; pixels are (r, g, b, coverage), row-major from
/// the top. `progress(done, total)` is called as rows finish.
pub fn render_reference(
    recipe: &Recipe,
    env: &Environment,
    objects: &[PlacedObject],
    camera: &CameraFrame,
    options: &ReferenceOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Vec<[f32; 4]> {
    let meshes = MeshScene::new(objects);
    let tracer = PathTracer::new(recipe, env, options.bounces).with_objects(&meshes);
    let (w, h) = (camera.width, camera.height);
    let done = std::sync::atomic::AtomicU64::new(0);
    let rows: Vec<Vec<[f32; 4]>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let row = (0..w)
                .map(|x| {
                    let mut rng = Pcg32::new(options.seed, (y * w + x) as u64);
                    let mut sum = DVec3::ZERO;
                    let mut cover = 0.0;
                    for _ in 0..options.samples {
                        let (jx, jy) = if options.antialias {
                            (rng.next_f64(), rng.next_f64())
                        } else {
                            (0.5, 0.5)
                        };
                        let ray = camera.ray(x as f64 + jx, y as f64 + jy);
                        let object = tracer.nearest_object(&ray, 0.0, f64::INFINITY);
                        let t_object = object.map_or(f64::INFINITY, |(t, _)| t);
                        let event = match ray_box(&ray, &recipe.bounds) {
                            Some((t_near, t_far)) if t_near < t_object => {
                                tracer.trace(&ray, t_near, t_far.min(t_object), &mut rng)
                            }
                            _ => Event::Escape,
                        };
                        if let (Event::Escape, Some((_, surface))) = (&event, &object) {
                            sum += tracer.object_radiance(surface, -ray.dir, &mut rng);
                            cover += 1.0;
                            continue;
                        }
                        match event {
                            Event::Surface { t, prim } => {
                                let shape = &recipe.primitives[prim].shape;
                                let mut p = ray.at(t);
                                let d = shape.sdf(p);
                                // A ray that enters the bounds inside a solid
                                // (a floor cut by the bounds) sees what the
                                // bake stores there: the nearest surface point.
                                let n = if d < -tracer.epsilon {
                                    let g = shape.sdf_gradient(p);
                                    p -= d * g;
                                    g
                                } else {
                                    shape.normal(p)
                                };
                                sum += tracer.surface_radiance(prim, p, n, &mut rng);
                                cover += 1.0;
                            }
                            Event::Medium { t, prim } => {
                                sum += tracer.medium_radiance(prim, ray.at(t), &mut rng);
                                cover += 1.0;
                            }
                            Event::Escape if options.sky_behind => {
                                sum += env.eval(ray.dir);
                                cover += 1.0;
                            }
                            Event::Escape => {}
                        }
                    }
                    let n = options.samples.max(1) as f64;
                    let c = sum / n;
                    [c.x as f32, c.y as f32, c.z as f32, (cover / n) as f32]
                })
                .collect();
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(d, h as u64);
            row
        })
        .collect();
    rows.into_iter().flatten().collect()
}
