//! A path tracer over a recipe's analytic primitives: Lambertian surfaces
//! (checkerboard albedo too), homogeneous isotropic media, emitting spheres
//! and one-sided quads, and the distant environment, plus (for ground truth
//! with objects) placed triangle meshes with the simplified Disney BRDF.
//! Next-event estimation samples every emitter (spheres by cone, quads'
//! faces by area) and the environment (multiple importance sampling with
//! the BSDF); `bounces` more scattering events add
//! indirect light (0: direct light only). Objects cast shadows on the field
//! and receive its full radiance (direct plus `bounces`), but, as the
//! method assumes, there is no interreflection through them: light that
//! reaches the field by way of an object, or an object by way of itself,
//! is dropped. Both the grid bake and the reference camera images use it.

use std::f64::consts::PI;

use glam::DVec3;

use super::light_sample::sample_emitter;
use crate::brdf::{disney, SurfaceMaterial};
use crate::geometry::Ray;
use crate::geometry::{MeshScene, MeshSurface};
use crate::rng::Pcg32;
use crate::scene::{Environment, Recipe};

/// What a ray segment met first.
#[derive(Debug, Clone, Copy)]
pub enum Event {
    /// An opaque surface at `t` of primitive `prim`.
    Surface {
        /// Ray parameter.
        t: f64,
        /// Primitive index in the recipe.
        prim: usize,
    },
    /// A scattering event inside medium `prim` at `t`.
    Medium {
        /// Ray parameter.
        t: f64,
        /// Primitive index in the recipe.
        prim: usize,
    },
    /// Nothing before the segment's end.
    Escape,
}

/// How light scatters at a point.
#[derive(Debug, Clone, Copy)]
pub enum Scatter {
    /// Lambertian surface with unit normal.
    Lambert(DVec3),
    /// Isotropic phase function (inside a medium).
    Isotropic,
    /// An object's surface: simplified Disney BRDF seen from `v`.
    Disney {
        /// Unit shading normal.
        n: DVec3,
        /// Unit direction towards the viewer.
        v: DVec3,
        /// BRDF parameters.
        m: SurfaceMaterial,
    },
}

impl Scatter {
    /// BSDF/phase value times the cosine factor (per unit albedo for the
    /// field's Lambertian surfaces and media; with the colour for objects).
    fn f_cos(&self, w: DVec3) -> DVec3 {
        match self {
            Scatter::Lambert(n) => DVec3::splat(n.dot(w).max(0.0) / PI),
            Scatter::Isotropic => DVec3::splat(1.0 / (4.0 * PI)),
            Scatter::Disney { n, v, m } => disney::eval(m, *n, *v, w) * n.dot(w).max(0.0),
        }
    }

    /// Sampling density of [`Self::sample`].
    fn pdf(&self, w: DVec3) -> f64 {
        match self {
            Scatter::Lambert(n) => n.dot(w).max(0.0) / PI,
            Scatter::Isotropic => 1.0 / (4.0 * PI),
            Scatter::Disney { n, v, m } => disney::pdf(m, *n, *v, w),
        }
    }

    /// Whether this is an object's surface.
    fn is_object(&self) -> bool {
        matches!(self, Scatter::Disney { .. })
    }

    /// A direction ∝ the BSDF·cosine (cosine-weighted), uniform (phase),
    /// or by the Disney BRDF's sampler.
    fn sample(&self, u: [f64; 3]) -> DVec3 {
        let phi = 2.0 * PI * u[1];
        match self {
            Scatter::Disney { n, v, m } => disney::sample(m, *n, *v, u),
            Scatter::Lambert(n) => {
                let r = u[0].sqrt();
                let z = (1.0 - u[0]).max(0.0).sqrt();
                let (t, b) = n.any_orthonormal_pair();
                r * phi.cos() * t + r * phi.sin() * b + z * *n
            }
            Scatter::Isotropic => {
                let z = 1.0 - 2.0 * u[0];
                let r = (1.0 - z * z).max(0.0).sqrt();
                DVec3::new(r * phi.cos(), r * phi.sin(), z)
            }
        }
    }
}

/// Power-heuristic MIS weight of a strategy with density `a` against `b`.
fn mis(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 == 0.0 {
        0.0
    } else {
        a2 / (a2 + b2)
    }
}

/// The path tracer of one recipe.
pub struct PathTracer<'a> {
    recipe: &'a Recipe,
    env: &'a Environment,
    objects: Option<&'a MeshScene>,
    bounces: u32,
    /// Offset of secondary ray origins, relative to the scene's size.
    pub epsilon: f64,
}

impl<'a> PathTracer<'a> {
    /// A tracer adding `bounces` indirect scattering events to direct light.
    pub fn new(recipe: &'a Recipe, env: &'a Environment, bounces: u32) -> Self {
        Self {
            recipe,
            env,
            objects: None,
            bounces,
            epsilon: 1e-6 * recipe.bounds.diagonal(),
        }
    }

    /// The same tracer with placed objects in the scene.
    pub fn with_objects(mut self, objects: &'a MeshScene) -> Self {
        self.objects = (!objects.is_empty()).then_some(objects);
        self
    }

    /// The nearest object surface along `ray` in (`t_min`, `t_max`).
    pub fn nearest_object(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, MeshSurface)> {
        let objects = self.objects?;
        let hit = objects.intersect(ray, t_min, t_max)?;
        Some((hit.t, objects.surface(ray, &hit)))
    }

    /// Radiance leaving an object's surface towards `v` (unit, towards the
    /// viewer): direct light from the field's lights and the environment,
    /// plus the field's full radiance by BRDF sampling.
    pub fn object_radiance(&self, s: &MeshSurface, v: DVec3, rng: &mut Pcg32) -> DVec3 {
        let scatter = Scatter::Disney {
            n: s.normal,
            v,
            m: s.material,
        };
        self.scattered(s.point + s.face_normal * self.epsilon, scatter, 0, rng)
    }

    /// The first opaque surface along `ray` in (`t_min`, `t_max`); a ray that
    /// starts inside an opaque primitive is blocked at `t_min`.
    pub fn nearest_surface(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, usize)> {
        let mut best: Option<(f64, usize)> = None;
        for (i, p) in self.recipe.primitives.iter().enumerate() {
            if p.medium_density.is_some() {
                continue;
            }
            let Some((t0, t1)) = p.shape.interval(ray) else {
                continue;
            };
            let t = if t0 > t_min {
                t0
            } else if t1 > t_min {
                t_min
            } else {
                continue;
            };
            if t < t_max && best.is_none_or(|(b, _)| t < b) {
                best = Some((t, i));
            }
        }
        best
    }

    /// Transmittance of the media along `ray` over [`t_min`, `t_max`].
    pub fn media_transmittance(&self, ray: &Ray, t_min: f64, t_max: f64) -> f64 {
        let mut depth = 0.0;
        for p in &self.recipe.primitives {
            let Some(sigma) = p.medium_density else {
                continue;
            };
            if let Some((t0, t1)) = p.shape.interval(ray) {
                let len = t1.min(t_max) - t0.max(t_min);
                if len > 0.0 {
                    depth += sigma * len;
                }
            }
        }
        (-depth).exp()
    }

    /// Visibility along `ray` up to `t_max`: 0 when a surface blocks it,
    /// otherwise the media's transmittance.
    pub fn visibility(&self, ray: &Ray, t_max: f64) -> f64 {
        if self.nearest_surface(ray, 0.0, t_max).is_some()
            || self.objects.is_some_and(|o| o.occluded(ray, 0.0, t_max))
        {
            return 0.0;
        }
        self.media_transmittance(ray, 0.0, t_max)
    }

    /// Follows `ray` over (`t_min`, `t_max`): the first surface, or a
    /// scattering event sampled by free-flight sampling in the media.
    pub fn trace(&self, ray: &Ray, t_min: f64, t_max: f64, rng: &mut Pcg32) -> Event {
        let surface = self.nearest_surface(ray, t_min, t_max);
        let t_end = surface.map_or(t_max, |(t, _)| t);
        let mut first: Option<(f64, usize)> = None;
        for (i, p) in self.recipe.primitives.iter().enumerate() {
            let Some(sigma) = p.medium_density else {
                continue;
            };
            let Some((t0, t1)) = p.shape.interval(ray) else {
                continue;
            };
            let (a, b) = (t0.max(t_min), t1.min(t_end));
            if b <= a {
                continue;
            }
            // Independent exponential clocks per medium: the earliest wins,
            // which is exact for overlapping media too.
            let t = a - (1.0 - rng.next_f64()).ln() / sigma;
            if t < b && first.is_none_or(|(f, _)| t < f) {
                first = Some((t, i));
            }
        }
        match (first, surface) {
            (Some((t, prim)), _) => Event::Medium { t, prim },
            (None, Some((t, prim))) => Event::Surface { t, prim },
            (None, None) => Event::Escape,
        }
    }

    /// Radiance leaving surface point `p` of primitive `prim` (emission
    /// plus reflected light) with outward normal `n`.
    pub fn surface_radiance(&self, prim: usize, p: DVec3, n: DVec3, rng: &mut Pcg32) -> DVec3 {
        let pr = &self.recipe.primitives[prim];
        let albedo = pr.albedo_at(p);
        let reflected = if albedo.max_element() > 0.0 {
            albedo * self.scattered(p + n * self.epsilon, Scatter::Lambert(n), 0, rng)
        } else {
            DVec3::ZERO
        };
        pr.emission_at(n) + reflected
    }

    /// Irradiance at `p` on a surface facing `n`, every light and bounce
    /// the tracer takes, as the mean of `samples` paths (π × the mean of
    /// the Lambertian estimate, which is per unit albedo and so E/π).
    pub fn irradiance(&self, p: DVec3, n: DVec3, samples: u32, rng: &mut Pcg32) -> DVec3 {
        let origin = p + n * self.epsilon;
        let sum: DVec3 = (0..samples)
            .map(|_| self.scattered(origin, Scatter::Lambert(n), 0, rng))
            .sum();
        PI * sum / f64::from(samples.max(1))
    }

    /// Radiance scattered towards any direction from point `p` inside medium
    /// `prim` (albedo times the phase-weighted incident light).
    pub fn medium_radiance(&self, prim: usize, p: DVec3, rng: &mut Pcg32) -> DVec3 {
        self.recipe.primitives[prim].albedo * self.scattered(p, Scatter::Isotropic, 0, rng)
    }

    /// One-sample estimate of ∫ f·cos·L_i per unit albedo at `p`: next-event
    /// estimation for lights and environment, plus the BSDF-sampled
    /// continuation (environment by MIS; indirect light while `depth` <
    /// `bounces`).
    fn scattered(&self, p: DVec3, s: Scatter, depth: u32, rng: &mut Pcg32) -> DVec3 {
        let mut sum = DVec3::ZERO;
        // Emitters: spheres in the cone they subtend, quads by area.
        for light in &self.recipe.primitives {
            if !light.is_emitter() {
                continue;
            }
            let Some(ls) = sample_emitter(light, p, rng.next_2d()) else {
                continue;
            };
            let fc = s.f_cos(ls.dir);
            if fc.max_element() <= 0.0 {
                continue;
            }
            let ray = Ray {
                origin: p,
                dir: ls.dir,
            };
            let vis = self.visibility(&ray, ls.distance * (1.0 - 1e-9));
            sum += light.emission * fc * vis / ls.pdf;
        }
        // Environment by its own sampler (MIS against the BSDF).
        if !self.env.is_black() {
            if let Some((w, pdf_env)) =
                self.env
                    .sample([rng.next_f64(), rng.next_f64(), rng.next_f64()])
            {
                let fc = s.f_cos(w);
                if fc.max_element() > 0.0 && pdf_env > 0.0 {
                    let vis = self.visibility(&Ray { origin: p, dir: w }, f64::INFINITY);
                    if vis > 0.0 {
                        sum += self.env.eval(w) * fc * vis / pdf_env * mis(pdf_env, s.pdf(w));
                    }
                }
            }
        }
        // BSDF-sampled continuation.
        let [u0, u1] = rng.next_2d();
        let w = s.sample([u0, u1, rng.next_f64()]);
        let pdf = s.pdf(w);
        if pdf <= 0.0 {
            return sum;
        }
        let weight = s.f_cos(w) / pdf;
        let ray = Ray { origin: p, dir: w };
        // An object in the way carries no light onward (no interreflection).
        let blocked = self
            .objects
            .and_then(|o| o.intersect(&ray, 0.0, f64::INFINITY))
            .map(|h| h.t);
        match self.trace(&ray, 0.0, blocked.unwrap_or(f64::INFINITY), rng) {
            Event::Escape if blocked.is_some() => {}
            Event::Escape if !self.env.is_black() => {
                sum += self.env.eval(w) * weight * mis(pdf, self.env.pdf(w));
            }
            // An object sees the field's full radiance there.
            Event::Surface { t, prim } if s.is_object() => {
                let pr = &self.recipe.primitives[prim];
                let q = ray.at(t);
                let n = pr.shape.normal(q);
                if n.dot(w) < 0.0 {
                    // Emission is counted by next-event estimation.
                    sum += (self.surface_radiance(prim, q, n, rng) - pr.emission_at(n)) * weight;
                }
            }
            Event::Medium { t, prim } if s.is_object() => {
                sum += self.medium_radiance(prim, ray.at(t), rng) * weight;
            }
            Event::Surface { t, prim } if depth < self.bounces => {
                let pr = &self.recipe.primitives[prim];
                let q = ray.at(t);
                let n = pr.shape.normal(q);
                // Light sources are counted by next-event estimation only.
                let albedo = pr.albedo_at(q);
                if albedo.max_element() > 0.0 && n.dot(w) < 0.0 {
                    let inner =
                        self.scattered(q + n * self.epsilon, Scatter::Lambert(n), depth + 1, rng);
                    sum += albedo * inner * weight;
                }
            }
            Event::Medium { t, prim } if depth < self.bounces => {
                let pr = &self.recipe.primitives[prim];
                let inner = self.scattered(ray.at(t), Scatter::Isotropic, depth + 1, rng);
                sum += pr.albedo * inner * weight;
            }
            _ => {}
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::geometry::MeshScene;
    use crate::scene::{EquirectMap, Primitive, Shape};

    fn floor(albedo: f64) -> Primitive {
        Primitive {
            name: "floor".into(),
            shape: Shape::Plane {
                point: DVec3::ZERO,
                normal: DVec3::Y,
            },
            albedo: DVec3::splat(albedo),
            checker: None,
            emission: DVec3::ZERO,
            face: None,
            medium_density: None,
            in_field: None,
        }
    }

    /// A small bright sphere light 3 units above the origin, outside the field.
    fn bulb() -> Primitive {
        Primitive {
            name: "bulb".into(),
            shape: Shape::Sphere {
                centre: DVec3::new(0.0, 3.0, 0.0),
                radius: 0.05,
            },
            albedo: DVec3::ZERO,
            checker: None,
            emission: DVec3::splat(1e4),
            face: None,
            medium_density: None,
            in_field: Some(false),
        }
    }

    fn recipe(primitives: Vec<Primitive>) -> Recipe {
        Recipe {
            bounds: Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
            primitives,
        }
    }

    fn mean_radiance(t: &PathTracer<'_>, p: DVec3, n: DVec3, samples: u32) -> DVec3 {
        let mut rng = Pcg32::new(5, 0);
        (0..samples)
            .map(|_| t.surface_radiance(0, p, n, &mut rng))
            .sum::<DVec3>()
            / samples as f64
    }

    /// A Lambertian floor under a uniform environment L reflects a·L.
    #[test]
    fn floor_under_a_uniform_sky_reflects_albedo_times_sky() {
        let env =
            Environment::Map(EquirectMap::new(8, 4, vec![DVec3::splat(2.0); 32], 1.0).unwrap());
        let r = recipe(vec![floor(0.5)]);
        let t = PathTracer::new(&r, &env, 0);
        let l = mean_radiance(&t, DVec3::ZERO, DVec3::Y, 20_000);
        assert!((l.y - 1.0).abs() < 0.01, "{l}");
    }

    /// A one-sided square panel of radiance L facing down, at height h over
    /// a floor point: the floor's irradiance is π L · 4 F, with F the
    /// closed-form form factor from a point to a parallel rectangle seen
    /// from its corner (A = B = a/h). Turned to face up, it lights nothing.
    #[test]
    fn floor_under_a_quad_light_matches_the_form_factor() {
        let (a, h, radiance) = (0.4f64, 1.0f64, 3.0);
        let panel = |normal: DVec3| {
            let face = crate::scene::Face {
                centre: DVec3::new(0.0, h, 0.0),
                u: DVec3::X * a,
                v: DVec3::Z * a * -normal.y,
                normal,
            };
            let t = crate::scene::QUAD_THICKNESS;
            Primitive {
                name: "panel".into(),
                shape: Shape::Box {
                    centre: face.centre - normal * (0.5 * t),
                    half: DVec3::new(a, a, 0.5 * t),
                    rotation: glam::DMat3::from_cols(face.u / a, face.v / a, normal),
                },
                albedo: DVec3::ZERO,
                checker: None,
                emission: DVec3::splat(radiance),
                face: Some(face),
                medium_density: None,
                in_field: Some(false),
            }
        };
        let env = Environment::Black;
        let r = recipe(vec![floor(0.8), panel(DVec3::NEG_Y)]);
        let t = PathTracer::new(&r, &env, 0);
        let l = mean_radiance(&t, DVec3::ZERO, DVec3::Y, 20_000);
        let x = a / h;
        let s = (1.0 + x * x).sqrt();
        let corner = (2.0 * x / s * (x / s).atan()) / (2.0 * PI);
        let expected = 0.8 / PI * PI * radiance * 4.0 * corner;
        assert!((l.y / expected - 1.0).abs() < 0.01, "{} vs {expected}", l.y);
        let up = recipe(vec![floor(0.8), panel(DVec3::Y)]);
        let t = PathTracer::new(&up, &env, 0);
        assert_eq!(mean_radiance(&t, DVec3::ZERO, DVec3::Y, 1000), DVec3::ZERO);
    }

    /// The irradiance under the bulb is π L_e sin²θmax facing it, nothing
    /// facing away (no bounces, nothing else lit); under a uniform sky of
    /// radiance L over an albedo-0.5 floor with one bounce, π L facing up and
    /// π L (1 + 0.5)/2 facing sideways (half sky, half the floor's 0.5 L).
    /// The field's light alone counts in-field emitters only.
    #[test]
    fn irradiance_matches_closed_forms() {
        let env = Environment::Black;
        let r = recipe(vec![floor(0.8), bulb()]);
        let t = PathTracer::new(&r, &env, 0);
        let mut rng = Pcg32::new(9, 1);
        let up = t.irradiance(DVec3::ZERO, DVec3::Y, 4000, &mut rng);
        let expected = 1e4 * PI * (0.05f64 / 3.0).powi(2);
        assert!((up.y / expected - 1.0).abs() < 0.01, "{up} vs {expected}");
        let down = t.irradiance(DVec3::new(0.0, 0.5, 0.0), -DVec3::Y, 100, &mut rng);
        assert_eq!(down, DVec3::ZERO);
        let x = DVec3::new(0.0, 0.3, 0.0);
        let hidden = crate::envest::field_light_irradiance(&r, x, DVec3::Y, 500, 0, 3);
        assert_eq!(
            hidden,
            DVec3::ZERO,
            "a hidden bulb is not the field's light"
        );
        let mut shown = r.clone();
        shown.primitives[1].in_field = Some(true);
        let e = crate::envest::field_light_irradiance(&shown, x, DVec3::Y, 4000, 0, 3);
        let expected = 1e4 * PI * (0.05f64 / 2.7).powi(2);
        assert!((e.y / expected - 1.0).abs() < 0.01, "{e} vs {expected}");
        let sky =
            Environment::Map(EquirectMap::new(8, 4, vec![DVec3::splat(2.0); 32], 1.0).unwrap());
        let r = recipe(vec![floor(0.5)]);
        let t = PathTracer::new(&r, &sky, 1);
        let up = t.irradiance(DVec3::ZERO, DVec3::Y, 20_000, &mut rng);
        assert!((up.y / (2.0 * PI) - 1.0).abs() < 0.01, "{up}");
        let side = t.irradiance(DVec3::new(0.0, 0.5, 0.0), DVec3::X, 20_000, &mut rng);
        let expected = PI * (2.0 + 0.5 * 2.0) / 2.0;
        assert!(
            (side.y / expected - 1.0).abs() < 0.02,
            "{side} vs {expected}"
        );
    }

    /// Under a small sphere light straight above: L_o = a/π · L_e · π (r/D)².
    #[test]
    fn floor_under_a_sphere_light_matches_the_solid_angle_formula() {
        let r = recipe(vec![floor(0.8), bulb()]);
        let env = Environment::Black;
        let t = PathTracer::new(&r, &env, 0);
        let l = mean_radiance(&t, DVec3::ZERO, DVec3::Y, 4000);
        // Exact for a sphere: irradiance π L_e sin²θmax at normal incidence.
        let expected = 0.8 / PI * 1e4 * PI * (0.05f64 / 3.0).powi(2);
        assert!((l.y / expected - 1.0).abs() < 0.01, "{} vs {expected}", l.y);
        // A box between floor and bulb casts a full shadow.
        let mut r2 = r.clone();
        r2.primitives.push(Primitive {
            name: "blocker".into(),
            shape: Shape::Box {
                centre: DVec3::new(0.0, 1.0, 0.0),
                half: DVec3::splat(0.2),
                rotation: glam::DMat3::IDENTITY,
            },
            albedo: DVec3::ZERO,
            checker: None,
            emission: DVec3::ZERO,
            face: None,
            medium_density: None,
            in_field: None,
        });
        let t2 = PathTracer::new(&r2, &env, 0);
        assert_eq!(mean_radiance(&t2, DVec3::ZERO, DVec3::Y, 100), DVec3::ZERO);
        // A medium of optical depth 1 in the way transmits e^-1.
        let mut r3 = r.clone();
        r3.primitives.push(Primitive {
            name: "haze".into(),
            shape: Shape::Box {
                centre: DVec3::new(0.0, 1.0, 0.0),
                half: DVec3::new(1.0, 0.25, 1.0),
                rotation: glam::DMat3::IDENTITY,
            },
            albedo: DVec3::ZERO,
            checker: None,
            emission: DVec3::ZERO,
            face: None,
            medium_density: Some(2.0),
            in_field: None,
        });
        let t3 = PathTracer::new(&r3, &env, 0);
        let l3 = mean_radiance(&t3, DVec3::ZERO, DVec3::Y, 4000);
        assert!(
            (l3.y / (expected * (-1.0f64).exp()) - 1.0).abs() < 0.01,
            "{}",
            l3.y
        );
    }

    fn sphere_object(
        centre: DVec3,
        radius: f64,
        m: crate::object::MaterialOverride,
    ) -> crate::object::PlacedObject {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenes/objects/metal-sphere.gltf");
        crate::object::PlacedObject {
            name: "ball".into(),
            mesh: std::sync::Arc::new(crate::object::load_gltf(&path).unwrap()),
            pose: crate::object::Pose {
                position: centre,
                rotation: DVec3::ZERO,
                scale: crate::object::Scale::Uniform(radius),
            },
            material: m,
        }
    }

    /// An object between a sphere light and the floor shadows the floor;
    /// a rough white object under a uniform sky reflects about a·L (the
    /// Lambertian part) plus a few percent of specular (F0 = 0.02).
    #[test]
    fn objects_cast_shadows_and_receive_light() {
        let r = recipe(vec![floor(0.8), bulb()]);
        let env = Environment::Black;
        let white = crate::object::MaterialOverride {
            base_color: Some(DVec3::splat(0.5)),
            roughness: Some(1.0),
            metallic: Some(0.0),
        };
        let blocker = MeshScene::new(&[sphere_object(DVec3::new(0.0, 1.0, 0.0), 0.3, white)]);
        let t = PathTracer::new(&r, &env, 0).with_objects(&blocker);
        assert_eq!(mean_radiance(&t, DVec3::ZERO, DVec3::Y, 100), DVec3::ZERO);
        let lit = mean_radiance(&t, DVec3::new(1.5, 0.0, 0.0), DVec3::Y, 100);
        assert!(lit.y > 0.0);

        let sky = Environment::Map(EquirectMap::new(8, 4, vec![DVec3::ONE; 32], 1.0).unwrap());
        let empty = recipe(vec![]);
        let ball = MeshScene::new(&[sphere_object(DVec3::ZERO, 0.5, white)]);
        let t = PathTracer::new(&empty, &sky, 0).with_objects(&ball);
        let ray = Ray {
            origin: DVec3::new(0.0, 0.0, 3.0),
            dir: DVec3::NEG_Z,
        };
        let (_, surface) = t.nearest_object(&ray, 0.0, f64::INFINITY).unwrap();
        let mut rng = Pcg32::new(9, 0);
        let l = (0..20_000)
            .map(|_| t.object_radiance(&surface, DVec3::Z, &mut rng))
            .sum::<DVec3>()
            / 20_000.0;
        assert!(l.y > 0.5 && l.y < 0.56, "{l}");
    }

    /// A bright wall beside a floor under a uniform sky sends light to the
    /// floor that direct lighting alone misses: one bounce must add it.
    #[test]
    fn more_bounces_add_light() {
        let env = Environment::Map(EquirectMap::new(8, 4, vec![DVec3::ONE; 32], 1.0).unwrap());
        let mut r = recipe(vec![floor(0.5)]);
        r.primitives.push(Primitive {
            name: "wall".into(),
            shape: Shape::Box {
                centre: DVec3::new(0.0, 1.0, -0.6),
                half: DVec3::new(2.0, 1.0, 0.1),
                rotation: glam::DMat3::IDENTITY,
            },
            albedo: DVec3::splat(0.9),
            checker: None,
            emission: DVec3::ZERO,
            face: None,
            medium_density: None,
            in_field: None,
        });
        let direct = mean_radiance(
            &PathTracer::new(&r, &env, 0),
            DVec3::new(0.0, 0.0, -0.3),
            DVec3::Y,
            20_000,
        );
        let one = mean_radiance(
            &PathTracer::new(&r, &env, 1),
            DVec3::new(0.0, 0.0, -0.3),
            DVec3::Y,
            20_000,
        );
        assert!(one.y > direct.y * 1.05, "{} vs {}", one.y, direct.y);
    }
}
