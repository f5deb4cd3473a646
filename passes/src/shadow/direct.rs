//! Shadows from the direct lobes (the lobes of L_env too sharp for the
//! fit, [`crate::lighting::sharp`]) by ray casting against the object's
//! mesh: a sharp light's shadow is as sharp as the mesh, and its penumbra
//! is the share of the lobe's own rays the mesh blocks. The SSDF's
//! half-space model, read from a 16³ grid of 32² directions, blurs thin
//! parts (ROOM's monkey's ears, the crescent near a ball's contact point)
//! out of such shadows; measured against Cycles, the shadows of DOG's bulb
//! and ROOM's came out 0.6–0.8 × their area with it. Mirrors
//! `shaders/shadow/direct_rays.wgsl`; beyond the paper.

use glam::DVec3;

use crate::field::GridField;
use crate::geometry::MeshScene;
use crate::geometry::Ray;
use crate::lighting::local::{sphere_lobe, transmittance_to, Emission, LocalLight};
use crate::march::MarchKnobs;
use crate::object::PlacedObject;
use crate::sg::Sg64;

/// A self-shadow ray starts this many bounding radii off the surface,
/// along the normal, so that it does not hit the triangle it starts on
/// (`DIRECT_RAY_OFFSET` in the shader).
pub const DIRECT_RAY_OFFSET: f64 = 1e-3;

/// What the direct lobes' shadows are cast from: the object's mesh in its
/// own frame ([`crate::ssdf::object_scene`]), each direct lobe's rays, and
/// the local lights that come after those.
#[derive(Clone, Copy)]
pub struct DirectOcclusion<'a> {
    /// The object in its own frame.
    pub scene: &'a MeshScene,
    /// Each direct lobe's rays (world directions), in the order the lobes
    /// come last in the light ([`crate::lighting::lobe_rays`]).
    pub rays: &'a [Vec<DVec3>],
    /// The local lights, last of all, each with the emission the
    /// direct-light pass measured ([`crate::lighting::local`]), and the
    /// side of their rays (side² per point).
    pub local: &'a [(LocalLight, Emission)],
    /// Side of the local lights' rays.
    pub local_side: u32,
    /// The field a local light's light crosses to reach a point of the
    /// cast shadow, with the march's knobs (None: it crosses nothing).
    pub field: Option<(&'a GridField, MarchKnobs)>,
}

impl DirectOcclusion<'_> {
    /// The index of the first direct lobe among `count` lobes.
    pub fn first(&self, count: usize) -> usize {
        count.saturating_sub(self.rays.len() + self.local.len())
    }

    /// The index of the first local light among `count` lobes.
    pub fn first_local(&self, count: usize) -> usize {
        count.saturating_sub(self.local.len())
    }

    /// Local light `l` as its sphere shows world point `x`, before the
    /// field or the object take any of it: the cast shadow weighs a local
    /// light by its light at the shadowed point, not at the object's
    /// centre, whose view of the light may pass through a medium the point
    /// sees past (PLANTS' lamp reaches its toy through foliage and the
    /// floor behind it in the open: eighteenth pass of docs/fidelity.md).
    /// A black lobe while the light is inactive (its disk's radius 0).
    pub fn local_lobe(&self, l: usize, x: DVec3) -> Sg64 {
        let (light, emission) = &self.local[l];
        let to = light.centre - x;
        if emission.radius <= 0.0 || to.length() <= 0.0 {
            return Sg64 {
                direction: DVec3::Y,
                sharpness: 1.0,
                amplitude: DVec3::ZERO,
            };
        }
        sphere_lobe(
            to.normalize(),
            to.length(),
            emission.radius,
            emission.intensity,
        )
    }

    /// How much of local light `l`'s light reaches field point `x` (unit
    /// normal `n`) without the object: (the field's transmittance towards
    /// it, the share of its `local_side`² rays to its disk that leave from
    /// above the plane — a ray from below carries none of its light). The
    /// transmittance is taken along one ray, from `x` lifted two node
    /// spacings along `n` (off the surface's own density) to the centre of
    /// the light's disk, up to its sphere; 1 without a field. Mirrors
    /// `local_cast_arrival` in `shaders/shadow/local_rays.wgsl`.
    pub fn local_arrival(&self, l: usize, x: DVec3, n: DVec3) -> (f64, f64) {
        let (light, emission) = &self.local[l];
        let count = self.local_side * self.local_side;
        let above = (0..count)
            .filter(|&k| {
                let p = light.disk_point_towards(x, k, self.local_side, emission.radius);
                (p - x).dot(n) > 0.0
            })
            .count();
        let t = self.field.map_or(1.0, |(f, march)| {
            let lifted = x + n * (2.0 * f.spacing().min_element());
            transmittance_to(f, light, lifted, (0, 1, emission.radius), &march)
        });
        (t, above as f64 / count.max(1) as f64)
    }

    /// The share of local light `l`'s `local_side`² rays from field point
    /// `x` (unit normal `n`) to its disk that leave from above the plane
    /// and pass the object's mesh. Mirrors `local_cast_clear` in
    /// `shaders/shadow/local_rays.wgsl`.
    pub fn local_clear(&self, placed: &PlacedObject, l: usize, x: DVec3, n: DVec3) -> f64 {
        let (light, emission) = &self.local[l];
        let m = placed.world_to_object();
        let origin = m.transform_point3(x);
        let count = self.local_side * self.local_side;
        let clear = (0..count)
            .filter(|&k| {
                let d = (light.disk_point_towards(x, k, self.local_side, emission.radius) - x)
                    .normalize();
                let ray = Ray {
                    origin,
                    dir: m.transform_vector3(d).normalize(),
                };
                d.dot(n) > 0.0 && !self.scene.occluded(&ray, 0.0, f64::INFINITY)
            })
            .count();
        clear as f64 / count.max(1) as f64
    }

    /// The share of direct lobe `k`'s rays from world point `x` that the
    /// placed object leaves clear; with `above = Some(n)` only rays above
    /// the plane of normal `n` count (1 when none does). For a local light
    /// (k past the rays), the share of its rays to its disk the mesh leaves
    /// clear, every ray counted (its cast shadow,
    /// `shaders/shadow/local_rays.wgsl`; its self-shadow also needs the
    /// field, [`crate::lighting::local::visibility`]).
    pub fn clear_fraction(
        &self,
        placed: &PlacedObject,
        x: DVec3,
        k: usize,
        above: Option<DVec3>,
    ) -> f64 {
        if let Some((light, emission)) = k
            .checked_sub(self.rays.len())
            .and_then(|l| self.local.get(l))
        {
            return crate::lighting::local::mesh_clear_fraction(
                self.scene,
                placed.world_to_object(),
                light,
                x,
                (self.local_side, emission.radius),
            );
        }
        let m = placed.world_to_object();
        let origin = m.transform_point3(x);
        let (mut clear, mut counted) = (0u32, 0u32);
        for &d in &self.rays[k] {
            if above.is_some_and(|n| d.dot(n) <= 0.0) {
                continue;
            }
            counted += 1;
            let ray = Ray {
                origin,
                dir: m.transform_vector3(d).normalize(),
            };
            if !self.scene.occluded(&ray, 0.0, f64::INFINITY) {
                clear += 1;
            }
        }
        if counted == 0 {
            1.0
        } else {
            clear as f64 / counted as f64
        }
    }
}
