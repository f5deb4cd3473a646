//! The light an inserted object sends back onto the field, in place of the
//! light it blocks (beyond the paper; mirrored by `shaders/shadow/bounce.wgsl`).
//!
//! The paper's cast shadow removes the light the object blocks and adds
//! nothing: an object of albedo 0. Against Blender Cycles that darkened
//! every surface facing the object, a few bounding radii away, by the
//! share of its sky the object covers (ROOM: 2.4 % over the far field,
//! where Cycles measures −0.3 %; −0.3 to +0.2 % over the bundled scenes):
//! a real object reflects back about as much as it hides. Here the object seen from a field point `x` is its
//! bounding sphere's cap, filled to the share of the sphere's silhouette
//! the mesh covers (its [`ObjectReflectance::fill`], mean over directions),
//! showing the radiance of a Lambertian surface of the mesh's mean albedo
//! facing `x`, lit by the object's own lobes (their irradiance on the
//! normal towards `x`, through the clamped-cosine SG: a uniform sky L
//! gives πL). A face of normals spread over the hemisphere towards `x`
//! would average in more light from the side; one SG for that average
//! (half the cosine's sharpness) weighted a bulb straight above eight times
//! too much on the faces turned below it, and changed ROOM's shadow
//! figures by less than their noise, so the plain cosine stays. Its
//! irradiance at `x` is the cap's projected solid angle, clipped at `x`'s
//! horizon ([`super::cone::projected_solid_angle`]: π sin²β cos θ while
//! the cap is above it; sin β = 1 inside the sphere) times that radiance.
//! (Unclipped, an object standing on the surface, its cap across the
//! horizon, sent back too little: CUPS' side view's shadow correlation
//! 0.873 → 0.884, ROOM's area 1.29 → 1.26 of Cycles' with the clip.) The lobes' light reaching that face from
//! below `x`'s plane is the field around `x`, which the probe saw
//! unshadowed but the object shadows about as deeply as `x`: it counts at
//! `x`'s own shadow ratio before the bounce (each lobe's share from below
//! the plane read off its axis and sharpness, [`below_share`]). Without
//! that, the umbra under DOG's ball kept 0.24 of the bare field's light
//! where Cycles keeps 0.13 (now 0.15). The cast shadow subtracts it
//! from the blocked light, never below zero: the object does not brighten
//! the field (its own shadow on the object, the view-dependence of its
//! reflection and light it sends past its bounding sphere are left out).

use std::sync::Arc;

use glam::DVec3;

use crate::geometry::Ray;
use crate::object::{ObjectMesh, PlacedObject};
use crate::sg::Sg64;

/// Directions the silhouette is measured from.
const FILL_DIRECTIONS: u32 = 64;
/// Parallel rays per side of the square around the bounding sphere's disc.
const FILL_RAYS: u32 = 32;

/// How much of its bounding sphere's silhouette a mesh covers, and with
/// what albedo, averaged over the directions it is seen from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectReflectance {
    /// The mean share of the bounding sphere's disc the mesh covers.
    pub fill: f64,
    /// The mean albedo of the mesh's surface where it covers the disc
    /// (its own materials, textures included).
    pub albedo: DVec3,
}

impl ObjectReflectance {
    /// Measures `mesh` by casting parallel rays across its bounding
    /// sphere's disc from 64 directions (`FILL_DIRECTIONS`).
    pub fn measure(mesh: &Arc<ObjectMesh>) -> Self {
        let scene = crate::ssdf::object_scene(mesh);
        let (c, r) = mesh.bounding_sphere();
        let (mut disc, mut hits, mut albedo) = (0u64, 0u64, DVec3::ZERO);
        for k in 0..FILL_DIRECTIONS {
            let d = crate::sgfit::fibonacci_axis(k, FILL_DIRECTIONS);
            let (t, b) = d.any_orthonormal_pair();
            for i in 0..FILL_RAYS {
                for j in 0..FILL_RAYS {
                    let s = (i as f64 + 0.5) / FILL_RAYS as f64 * 2.0 - 1.0;
                    let v = (j as f64 + 0.5) / FILL_RAYS as f64 * 2.0 - 1.0;
                    if s * s + v * v > 1.0 {
                        continue;
                    }
                    disc += 1;
                    let ray = Ray {
                        origin: c - d * (2.0 * r) + (t * s + b * v) * r,
                        dir: d,
                    };
                    if let Some(hit) = scene.intersect(&ray, 0.0, 4.0 * r) {
                        hits += 1;
                        albedo += scene.surface(&ray, &hit).material.albedo;
                    }
                }
            }
        }
        Self {
            fill: hits as f64 / disc.max(1) as f64,
            albedo: if hits > 0 {
                albedo / hits as f64
            } else {
                DVec3::ZERO
            },
        }
    }

    /// fill × albedo for `placed`, whose material override (if any)
    /// replaces the mesh's colours.
    pub fn of(&self, placed: &PlacedObject) -> DVec3 {
        self.fill * placed.material.base_color.unwrap_or(self.albedo)
    }
}

/// The share of an SG's energy (axis `p`, sharpness `λ`) that comes from
/// below the plane of normal `n`: Φ(−(p·n)√λ), the lobe read as a Gaussian
/// of angular spread 1/√λ around its axis (its distance to the plane
/// ≈ p·n), with Φ by the logistic 1 / (1 + e^{1.702 z}); a half for a
/// uniform lobe. Mirrored by `bounce_below_share` in
/// `shaders/shadow/bounce.wgsl`.
pub fn below_share(p: &Sg64, n: DVec3) -> f64 {
    1.0 / (1.0
        + (1.702 * p.direction.dot(n) * p.sharpness.sqrt())
            .clamp(-80.0, 80.0)
            .exp())
}

/// The light the object sends back to a field point, split by how it
/// depends on the point's own shadow ratio `below`: `fixed` + `scaled` ×
/// `below` ([`bounce_parts`]). The lobes' light from above the
/// point's plane is `fixed`; from below it, `scaled`, since the field
/// around the point that sends it is shadowed about as deeply.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Bounce {
    /// The part that does not depend on the point's ratio.
    pub fixed: DVec3,
    /// The part counted at the point's ratio.
    pub scaled: DVec3,
}

impl Bounce {
    /// The bounce at shadow ratio `below`.
    pub fn at(&self, below: DVec3) -> DVec3 {
        self.fixed + self.scaled * below
    }

    /// The least the bounce can be at any ratio from `lowest` to 1 (per
    /// channel), and never below zero: what the blocked light is surely
    /// offset by before the ratio is known (a negative part counts in
    /// full). A point that loses at most a share s of its light has a
    /// ratio of at least 1 − s.
    pub fn least(&self, lowest: DVec3) -> DVec3 {
        (self.fixed + (self.scaled * lowest).min(self.scaled)).max(DVec3::ZERO)
    }

    /// What the object can block at most, `most`, of a point's light
    /// `total`, less the least it sends back there: the point's ratio is
    /// at least 1 − `most` / `total`. Mirrored by `cast_bounce_net` in
    /// `shaders/shadow/bounce.wgsl`.
    pub fn net(&self, most: DVec3, total: DVec3) -> DVec3 {
        let lowest =
            (DVec3::ONE - most / total.max(DVec3::splat(1e-300))).clamp(DVec3::ZERO, DVec3::ONE);
        (most - self.least(lowest)).max(DVec3::ZERO)
    }
}

/// The irradiance at field point `x` (unit normal `n`) from the object in
/// bounding sphere (`c`, `r`) under `lobes` (the light at the object), for
/// an object of silhouette reflectance `reflectance` ([`ObjectReflectance::of`]),
/// in its two parts ([`Bounce`]; [`Bounce::at`] gives it at a ratio).
/// The lobes' light from below `x`'s plane is the field around `x`, which
/// the object shadows too: it counts at x's own shadow ratio (one where
/// nothing is blocked) and the rest in full. Zero at the sphere's centre
/// and where the object lies below `x`'s horizon.
pub fn bounce_parts(
    lobes: &[Sg64],
    x: DVec3,
    n: DVec3,
    c: DVec3,
    r: f64,
    reflectance: DVec3,
) -> Bounce {
    let to = c - x;
    let dist = to.length();
    if dist <= 0.0 {
        return Bounce::default();
    }
    let u = to / dist;
    // The cap's projected solid angle over π, clipped at x's horizon.
    let projected =
        super::cone::projected_solid_angle(n.dot(u), (r / dist).min(1.0)) / std::f64::consts::PI;
    if projected <= 0.0 {
        return Bounce::default();
    }
    let facing = Sg64::clamped_cosine(-u);
    let (mut fixed, mut scaled) = (DVec3::ZERO, DVec3::ZERO);
    for g in lobes {
        let p = g.product(&facing);
        let (light, share) = (p.integral(), below_share(&p, n));
        fixed += light * (1.0 - share);
        scaled += light * share;
    }
    // (projected solid angle) × albedo × E / π.
    let scale = projected * reflectance;
    Bounce {
        fixed: scale * fixed,
        scaled: scale * scaled,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::object::{MaterialOverride, Pose};

    /// A sphere fills its own silhouette; its albedo is its material's; an
    /// override replaces it.
    #[test]
    fn a_sphere_fills_its_bounding_disc() {
        let mesh = crate::ssdf::tests::bundled_mesh("metal-sphere.gltf");
        let m = ObjectReflectance::measure(&mesh);
        // The tessellation's silhouette is inscribed in the circle.
        assert!((0.97..=1.0).contains(&m.fill), "fill {}", m.fill);
        let own = mesh.materials[0].base_colour.truncate();
        assert!(
            (m.albedo - own).abs().max_element() < 1e-9,
            "{} vs {own}",
            m.albedo
        );
        let placed = PlacedObject {
            name: "ball".into(),
            mesh: mesh.clone(),
            pose: Pose::default(),
            material: MaterialOverride {
                base_color: Some(DVec3::new(0.2, 0.4, 0.6)),
                ..Default::default()
            },
        };
        let rgb = m.of(&placed);
        assert!(
            (rgb - m.fill * DVec3::new(0.2, 0.4, 0.6))
                .abs()
                .max_element()
                < 1e-12
        );
    }

    /// Light reaching the object from below x's plane (the field around x)
    /// counts at x's own ratio; light from above in full; a uniform lobe
    /// is split in halves.
    #[test]
    fn light_from_below_the_plane_counts_at_the_ratio() {
        let n = DVec3::Y;
        let lobe = |d: DVec3, sharpness: f64| Sg64 {
            direction: d,
            sharpness,
            amplitude: DVec3::ONE,
        };
        assert!(below_share(&lobe(-n, 1e4), n) > 1.0 - 1e-12);
        assert!(below_share(&lobe(n, 1e4), n) < 1e-12);
        assert!((below_share(&lobe(n, 0.0), n) - 0.5).abs() < 1e-12);
        assert!((below_share(&lobe(DVec3::X, 50.0), n) - 0.5).abs() < 1e-12);
        // The object above x and to its side; its face towards x sees a
        // lobe from straight below (the floor) and one from above.
        let (c, r) = (DVec3::new(1.0, 0.5, 0.0), 0.3);
        let x = DVec3::ZERO;
        let below = DVec3::splat(0.25);
        for (d, expected) in [(-n, 0.25), (n, 1.0)] {
            let g = [lobe(d, 40.0)];
            let full = bounce_parts(&g, x, n, c, r, DVec3::ONE).at(DVec3::ONE);
            let shaded = bounce_parts(&g, x, n, c, r, DVec3::ONE).at(below);
            assert!(full.x > 0.0);
            assert!(
                (shaded.x / full.x - expected).abs() < 2e-3,
                "{d}: {} of the unshadowed bounce",
                shaded.x / full.x
            );
        }
    }

    /// A white sphere under a (nearly) uniform sky seen from far away
    /// sends back the light it blocks: π sin²β cos θ × L, the cap's
    /// projected solid angle times the sky's radiance (closed form).
    #[test]
    fn a_white_object_under_a_uniform_sky_returns_what_it_blocks() {
        // λ = 1e-4: within 2e-4 of uniform over the sphere.
        let sky = Sg64 {
            direction: DVec3::Y,
            sharpness: 1e-4,
            amplitude: DVec3::splat(2.0),
        };
        let (c, r) = (DVec3::new(0.0, 1.0, 0.0), 0.5);
        let x = DVec3::new(3.0, 0.0, 0.0);
        let n = DVec3::Y;
        let u = (c - x).normalize();
        let sin2 = (r / (c - x).length()).powi(2);
        let expected = std::f64::consts::PI * sin2 * n.dot(u) * 2.0;
        let got = bounce_parts(&[sky], x, n, c, r, DVec3::ONE).at(DVec3::ONE);
        assert!(
            (got.x / expected - 1.0).abs() < 1e-3,
            "{} vs {}",
            got.x,
            expected
        );
        // Below the horizon: nothing; inside the sphere, the whole
        // hemisphere's projected solid angle π at most.
        assert_eq!(
            bounce_parts(&[sky], x, -n, c, r, DVec3::ONE).at(DVec3::ONE),
            DVec3::ZERO
        );
        let inside = bounce_parts(&[sky], c - DVec3::Y * 0.1, n, c, r, DVec3::ONE).at(DVec3::ONE);
        assert!((inside.x / (std::f64::consts::PI * 2.0) - 1.0).abs() < 1e-3);
        assert!(bounce_parts(&[sky], c, n, c, r, DVec3::ONE)
            .at(DVec3::ONE)
            .is_finite());
    }
}
