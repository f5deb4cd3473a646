//! The knobs of environment-light estimation (METHOD.md "Environment light
//! estimation"): how many views and surface points, how many rays per point,
//! and how long and how the optimiser runs.

/// Every knob of `inlay estimate-env`, with the paper's values as defaults
/// where the paper gives one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvEstimateKnobs {
    /// Views kept after quality rejection (paper: 100).
    pub views: u32,
    /// Side of each view's square render, in pixels.
    pub view_size: u32,
    /// Surface points drawn per kept view (paper: 64).
    pub pixels_per_view: u32,
    /// Monte-Carlo rays per point for the near-field irradiance E_nerf
    /// (paper: 32768).
    pub rays_per_point: u32,
    /// Side of each point's cached octahedral opacity map Ô(ω; x): side² ×
    /// 4 bytes per point (105 MB at the default 6400 points). 64 rather
    /// than 16 because a coarse map blurs hard shadows: at 30 views DOG
    /// misses by 9.8–11.2 % with 64 and 9.6–12.9 % with 16, CUPS by 6.8 %
    /// and 8.0 % (docs/benchmarks.md, "Sixth pass").
    pub opacity_map: u32,
    /// Quality score above which a view is rejected (0 best, 100 worst;
    /// the paper rejects BRISQUE scores above 50).
    pub quality_threshold: f64,
    /// Views tried per view kept before giving up.
    pub max_tries_per_view: u32,
    /// SG lobes of the environment (paper: M = 32).
    pub lobes: u32,
    /// Point lights near the field fitted beside the lobes (not in the
    /// paper; [`super::near_lights`]); 0, the default, gives the paper's
    /// distant model. For a capture lit by lamps a metre or two outside
    /// it: on ROOM (bulb 1.5 m above the field; 30 views, 8192 rays) one
    /// near light takes the error at the test points from 93 % to 35 %.
    /// Not on by default: where the hidden light is distant it costs
    /// (DOG 4 → 38 %, CUPS 5 → 31 %, BOOKS 20 → 36 %), and the surface
    /// points cannot tell the two cases apart (the fit's loss is within
    /// ±8 % either way; docs/fidelity.md, "Ninth pass").
    pub near_lights: u32,
    /// Width of the albedo MLP's hidden layers (6 layers, as the paper).
    pub albedo_width: u32,
    /// Octaves of Fourier encoding on the albedo MLP's input (0: the
    /// position alone). Each octave lets the albedo follow finer detail,
    /// and with it the shading that the light should explain: at 30 views
    /// and 0 octaves CUPS, BOOKS and DOG miss the hidden light by 12–14 %,
    /// at 4 octaves by 12–30 % (docs/benchmarks.md).
    pub albedo_octaves: u32,
    /// Optimiser steps (Adam). More is not better: from 1000 to 3000
    /// steps the fit darkens the albedo and adds light that the data's
    /// inconsistencies ask for (CUPS 6.8 → 11.1 %, BOOKS 12.6 → 15.0 %,
    /// DOG 11.2 → 30 % at 30 views; docs/benchmarks.md, "Sixth pass").
    pub iterations: u32,
    /// Surface points per optimiser step.
    pub batch: u32,
    /// Directions sampled from the SG mixture per point and step for E_env.
    pub env_samples: u32,
    /// Adam step size of the SG parameters.
    pub env_rate: f64,
    /// Adam step size of the albedo MLP.
    pub albedo_rate: f64,
    /// Weight κ of the prior that keeps out of the environment light
    /// which only the model's misfit asks for: the loss gains κ·L̄² times
    /// the points' mean share of environment light in their irradiance
    /// (L̄ the points' mean radiance luminance; [`super::share_prior::SharePrior`]);
    /// 0 turns it off. The field's blur and E_nerf's noise leave some
    /// points darker than their colour asks for, and without the prior the
    /// environment fills them in: on PLANTS, whose lights are all inside
    /// the field, κ = 0 leaves 23 % of the lamp's irradiance in the
    /// environment and κ = 0.01 about 1 % (docs/benchmarks.md).
    pub share_prior: f64,
    /// The estimated light is kept only when the points' loss without it
    /// (the albedo fitted alone under the field's light) is at least this
    /// many times the loss with it; otherwise the environment is black
    /// ([`super::outside_light`]). 0 keeps it always. On the bundled
    /// fields, baked and trained, the scenes with a hidden light measured
    /// 15–195× and PLANTS, whose lights are all in the field, 0.96–1.37×
    /// (docs/fidelity.md, "Thirty-fifth pass").
    pub min_loss_gain: f64,
    /// Largest lobe sharpness the fit may reach.
    pub max_sharpness: f64,
    /// A point whose luminance exceeds this multiple of the median point's
    /// (over all the views' candidate points) is taken for a light source
    /// in the field and left out (a Lambertian reflector cannot explain it). 8, not 50: ROOM's softbox is 20–30 ×
    /// the median, and kept in the fit as a reflector it asks for twenty
    /// times the room's light (the error 829 % at 50, 151 % at 8); DOG,
    /// CUPS and PLANTS estimate the same at both, BOOKS 11.8 % → 12.5 %
    /// (30 views, 8192 rays; docs/fidelity.md).
    pub emitter_ratio: f64,
    /// How a surface point is told from a point in a medium
    /// ([`super::surface::SurfaceTest`]): by the density's gradient (for
    /// baked fields, the default) or by where the ray's weight lies (for
    /// trained fields).
    pub surface_test: super::surface::SurfaceTest,
    /// Under the `weight` surface test (trained fields), the largest bend
    /// of the surface, in degrees, within a node spacing (at least 1/128
    /// of the field's extent) of a surface point for it to be kept
    /// ([`super::surface::crease_angle`]); 180
    /// keeps every point. On an edge the field has rounded, the point's
    /// normal is a blend of two faces' and its colour mostly the brighter
    /// face's, and the fit lights it from where no light is. On DOG
    /// trained at 128 nodes, 15° took the error at the test points from
    /// 39 % to 30 % over four seeds (docs/fidelity.md, "Twenty-third
    /// pass"). The gradient test (bakes) ignores it: a bake's density is
    /// zero a node off its round surfaces, which then read as creases
    /// (DOG's bake 4.2 → 11.6 % on seed 1 with it).
    pub max_crease: f64,
    /// Under the `weight` surface test, where a point's normal is read: at
    /// the point (the default) or along the pixel's ray through the
    /// surface ([`super::surface::SurfaceNormals`]). Along the ray, ROOM's
    /// trained floor read its normals a median 20° off the recipe's
    /// against 31° at the point, and the estimate (with `max_crease` 30
    /// and a near light) placed the bulb 4.5–11.1° off over four seeds
    /// against 13.4–21.4°, though its error at the test points rose from
    /// 65 % to 77 % on average; DOG's 13.3 % over four seeds against
    /// 13.5 %; but PLANTS' all-visible
    /// estimate rose from 6–11 % of its lights to 63–162 %
    /// (docs/fidelity.md, "Thirty-fourth pass"), so it is not the
    /// default.
    pub normals: super::surface::SurfaceNormals,
    /// Where the photographs that saw a surface point are at hand
    /// (`--seen-from DATASET`), the most their readings there may
    /// disagree for it to be kept: the interquartile range of their
    /// luminance over their median plus a floor
    /// ([`super::witnesses::PhotoSpread::relative`],
    /// [`super::witnesses::PHOTO_SPREAD_FLOOR`]); 0 turns the test off.
    /// A point in a trainer's haze reads different parts of the surface
    /// behind it in each photograph. On ROOM trained from 64 views, it
    /// keeps all but one of 264 points within 8 cm of the recipe's
    /// surfaces and 11 % of 1592 further off; on the bakes, 95 % (DOG)
    /// and over 99 % (ROOM) of the points (docs/fidelity.md,
    /// "Thirty-first pass").
    pub max_photo_spread: f64,
    /// Read each surface point's radiance from the photographs that saw
    /// it (the median reading) rather than from the field.
    pub radiance_from_photos: bool,
    /// Seed of every random choice (views, pixels, rays, batches, samples).
    pub seed: u64,
}

impl Default for EnvEstimateKnobs {
    fn default() -> Self {
        Self {
            views: 100,
            view_size: 96,
            pixels_per_view: 64,
            rays_per_point: 32768,
            opacity_map: 64,
            quality_threshold: 50.0,
            max_tries_per_view: 20,
            lobes: 32,
            near_lights: 0,
            albedo_width: 64,
            albedo_octaves: 0,
            iterations: 1000,
            surface_test: super::surface::SurfaceTest::Gradient,
            batch: 512,
            env_samples: 48,
            env_rate: 0.02,
            albedo_rate: 2e-3,
            share_prior: 0.01,
            min_loss_gain: 2.0,
            max_sharpness: 2000.0,
            emitter_ratio: 8.0,
            max_crease: 15.0,
            normals: super::surface::SurfaceNormals::AtPoint,
            max_photo_spread: 0.2,
            radiance_from_photos: false,
            seed: 1,
        }
    }
}

impl EnvEstimateKnobs {
    /// The first knob out of range, with why.
    pub fn problem(&self) -> Option<(&'static str, String)> {
        let range = |name: &'static str, v: u32, lo: u32, hi: u32| {
            (!(lo..=hi).contains(&v)).then(|| (name, format!("{v} must be in {lo}..={hi}")))
        };
        range("views", self.views, 1, 10_000)
            .or_else(|| range("view_size", self.view_size, 16, 1024))
            .or_else(|| range("pixels_per_view", self.pixels_per_view, 1, 4096))
            .or_else(|| range("rays_per_point", self.rays_per_point, 16, 1 << 20))
            .or_else(|| range("opacity_map", self.opacity_map, 4, 64))
            .or_else(|| range("max_tries_per_view", self.max_tries_per_view, 1, 1000))
            .or_else(|| range("lobes", self.lobes, 1, 128))
            .or_else(|| range("near_lights", self.near_lights, 0, 16))
            .or_else(|| range("albedo_width", self.albedo_width, 4, 512))
            .or_else(|| range("albedo_octaves", self.albedo_octaves, 0, 12))
            .or_else(|| range("iterations", self.iterations, 0, 1_000_000))
            .or_else(|| range("batch", self.batch, 1, 1 << 20))
            .or_else(|| range("env_samples", self.env_samples, 1, 4096))
            .or_else(|| {
                let pos = |name: &'static str, v: f64, hi: f64| {
                    (!(v.is_finite() && v > 0.0 && v <= hi))
                        .then(|| (name, format!("{v} must be in (0, {hi}]")))
                };
                pos("quality_threshold", self.quality_threshold, 100.0)
                    .or_else(|| pos("env_rate", self.env_rate, 1.0))
                    .or_else(|| pos("albedo_rate", self.albedo_rate, 1.0))
                    .or_else(|| {
                        (!(self.share_prior.is_finite() && (0.0..=1.0).contains(&self.share_prior)))
                            .then(|| {
                                (
                                    "share_prior",
                                    format!("{} must be in [0, 1]", self.share_prior),
                                )
                            })
                    })
                    .or_else(|| {
                        (!(self.min_loss_gain.is_finite()
                            && (0.0..=1e6).contains(&self.min_loss_gain)))
                        .then(|| {
                            (
                                "min_loss_gain",
                                format!("{} must be in [0, 1e6]", self.min_loss_gain),
                            )
                        })
                    })
                    .or_else(|| pos("max_sharpness", self.max_sharpness, 1e4))
                    .or_else(|| pos("emitter_ratio", self.emitter_ratio, 1e9))
                    .or_else(|| pos("max_crease", self.max_crease, 180.0))
                    .or_else(|| {
                        (self.normals == super::surface::SurfaceNormals::AlongRay
                            && self.surface_test != super::surface::SurfaceTest::Weight)
                            .then(|| {
                                (
                                    "normals",
                                    "along-ray reads a trained field's shells: it needs the \
                                     weight surface test"
                                        .to_string(),
                                )
                            })
                    })
                    .or_else(|| {
                        (!(self.max_photo_spread.is_finite() && self.max_photo_spread >= 0.0)).then(
                            || {
                                (
                                    "max_photo_spread",
                                    format!("{} must be a number ≥ 0", self.max_photo_spread),
                                )
                            },
                        )
                    })
            })
    }

    /// Surface points asked for: views × pixels per view.
    pub fn points(&self) -> usize {
        self.views as usize * self.pixels_per_view as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envest::surface::{SurfaceNormals, SurfaceTest};

    /// Normals read along the ray need the weight test, whose shells they
    /// read; a bake's gradient test refuses them by name.
    #[test]
    fn along_ray_normals_need_the_weight_test() {
        assert!(EnvEstimateKnobs::default().problem().is_none());
        let along = EnvEstimateKnobs {
            normals: SurfaceNormals::AlongRay,
            ..EnvEstimateKnobs::default()
        };
        assert_eq!(along.problem().map(|p| p.0), Some("normals"));
        let weighed = EnvEstimateKnobs {
            surface_test: SurfaceTest::Weight,
            ..along
        };
        assert!(weighed.problem().is_none());
    }

    /// The loss-gain test's knob is a factor: negative or not a number is
    /// refused by name, 0 (off) is accepted.
    #[test]
    fn the_loss_gain_must_be_a_factor() {
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            let k = EnvEstimateKnobs {
                min_loss_gain: bad,
                ..EnvEstimateKnobs::default()
            };
            assert_eq!(k.problem().map(|p| p.0), Some("min_loss_gain"), "{bad}");
        }
        let off = EnvEstimateKnobs {
            min_loss_gain: 0.0,
            ..EnvEstimateKnobs::default()
        };
        assert!(off.problem().is_none());
    }
}
