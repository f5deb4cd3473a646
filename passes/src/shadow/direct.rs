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

use crate::geometry::MeshScene;
use crate::geometry::Ray;
use crate::lighting::local::{Emission, LocalLight};
use crate::object::PlacedObject;

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
}

impl DirectOcclusion<'_> {
    /// The index of the first direct lobe among `count` lobes.
    pub fn first(&self, count: usize) -> usize {
        count.saturating_sub(self.rays.len() + self.local.len())
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
