//! Unit tests of the estimate's CPU parts: gradients against finite
//! differences, the ray set, the quality score and the environment file.

use glam::DVec3;

use super::env_model::{env_term, initial_params, lobes, EnvSampler, PARAMS_PER_LOBE};
use super::mlp::AlbedoMlp;
use crate::geometry::Aabb;
use crate::rng::Pcg32;

fn unit_box() -> Aabb {
    Aabb::new(DVec3::splat(-1.0), DVec3::ONE)
}

/// Central difference of `f` along parameter `i` of `params`.
fn numeric(params: &[f64], i: usize, h: f64, f: &dyn Fn(&[f64]) -> f64) -> f64 {
    let mut p = params.to_vec();
    p[i] += h;
    let up = f(&p);
    p[i] -= 2.0 * h;
    let down = f(&p);
    (up - down) / (2.0 * h)
}

#[test]
fn albedo_mlp_gradient_matches_finite_differences() {
    let mut mlp = AlbedoMlp::new(unit_box(), 8, 2, 3);
    // Non-zero last layer so every layer's gradient is exercised.
    let mut rng = Pcg32::new(5, 5);
    mlp.params
        .iter_mut()
        .for_each(|p| *p += 0.3 * (rng.next_f64() - 0.5));
    let x = DVec3::new(0.3, -0.2, 0.5);
    let w = DVec3::new(0.7, -1.3, 0.4);
    let loss = |m: &AlbedoMlp| m.forward(x).albedo.dot(w);
    let mut grad = vec![0.0; mlp.params.len()];
    mlp.backward(&mlp.forward(x), w, &mut grad);
    let mut worst: f64 = 0.0;
    for i in (0..mlp.params.len()).step_by(7) {
        let f = |p: &[f64]| {
            let mut m = mlp.clone();
            m.params.copy_from_slice(p);
            loss(&m)
        };
        let n = numeric(&mlp.params, i, 1e-6, &f);
        worst = worst.max((n - grad[i]).abs() / (1e-6 + n.abs().max(grad[i].abs())));
    }
    assert!(worst < 1e-4, "worst relative gradient error {worst}");
}

#[test]
fn environment_gradient_matches_finite_differences() {
    let params = initial_params(4, 0.8);
    let n = DVec3::new(0.2, 0.9, 0.1).normalize();
    let w = DVec3::new(0.5, -0.8, 1.1);
    let visibility = |d: DVec3| if d.x > 0.3 { 0.25 } else { 1.0 };
    // The sampled directions are fixed by the sampler (built once, from the
    // starting lobes) and the seed; the estimate is then smooth in the
    // parameters.
    let sampler = EnvSampler::new(&lobes(&params));
    let e = |p: &[f64]| {
        let mut rng = Pcg32::new(9, 1);
        env_term(&lobes(p), &sampler, n, 64, &visibility, &mut rng)
            .irradiance
            .dot(w)
    };
    let mut rng = Pcg32::new(9, 1);
    let term = env_term(&lobes(&params), &sampler, n, 64, &visibility, &mut rng);
    let mut grad = vec![0.0; params.len()];
    term.backward(&params, w, &mut grad);
    for (i, g) in grad.iter().enumerate() {
        let n_i = numeric(&params, i, 1e-6, &e);
        assert!(
            (n_i - g).abs() <= 1e-5 * (1.0 + n_i.abs()),
            "parameter {i} (lobe {}, slot {}): numeric {n_i}, analytic {}",
            i / PARAMS_PER_LOBE,
            i % PARAMS_PER_LOBE,
            g
        );
    }
}

#[test]
fn share_prior_slope_matches_finite_differences_and_stays_finite() {
    use super::share_prior::SharePrior;
    let prior = SharePrior {
        weight: 0.02,
        floor: 1e-3,
    };
    for near in [0.0, 1e-6, 0.05, 1.0, 300.0] {
        for env in [0.0, 1e-6, 0.05, 1.0, 300.0] {
            let h = 1e-6 * (near + env + prior.floor);
            let numeric = (prior.value(near, env + h) - prior.value(near, (env - h).max(0.0)))
                / (env + h - (env - h).max(0.0));
            let slope = prior.slope(near, env);
            assert!(slope.is_finite() && slope >= 0.0, "near {near} env {env}");
            assert!(
                (slope - numeric).abs() <= 1e-4 * slope.abs() + 1e-9,
                "near {near} env {env}: {slope} vs {numeric}"
            );
            // Bounded by the floor, wherever the field leaves a point dark.
            assert!(slope <= prior.weight / prior.floor * (1.0 + 1e-12));
        }
    }
    // No floor and no light at all: zero, not NaN.
    let bare = SharePrior {
        weight: 0.02,
        floor: 0.0,
    };
    assert_eq!(bare.value(0.0, 0.0), 0.0);
    assert_eq!(bare.slope(0.0, 0.0), 0.0);
    // A point the environment lights almost alone barely feels the prior;
    // one the field lights feels it in full.
    assert!(prior.slope(0.01, 1.0) < 0.02 * prior.slope(1.0, 0.01));
    // The value is a share of the weight.
    assert!((prior.value(1.0, 1.0) - 0.02 * 1.0 / 2.001).abs() < 1e-12);
}

#[test]
fn ray_set_is_cosine_distributed_about_the_normal() {
    use super::hemisphere::ray_direction;
    let n = DVec3::new(0.3, -0.5, 0.8).normalize();
    let rays = 4096;
    let mut mean_cos = 0.0;
    for i in 0..rays {
        let d = ray_direction(n, 17, 5, i, rays);
        assert!((d.length() - 1.0).abs() < 1e-12);
        let c = d.dot(n);
        assert!(c >= -1e-12, "ray {i} below the surface");
        mean_cos += c / rays as f64;
    }
    // E[cos θ] under the density cos θ/π is 2/3.
    assert!(
        (mean_cos - 2.0 / 3.0).abs() < 1e-3,
        "mean cosine {mean_cos}"
    );
    // Tangent frames are orthonormal for normals near ±Z too.
    for n in [DVec3::Z, -DVec3::Z, DVec3::new(1e-9, 0.0, -1.0).normalize()] {
        let (t, b) = crate::sgfit::model::tangent_basis(n);
        assert!(
            t.dot(b).abs() < 1e-12 && t.dot(n).abs() < 1e-12 && (t.cross(b) - n).length() < 1e-12
        );
    }
}

fn view(
    width: u32,
    height: u32,
    pixel: impl Fn(u32, u32) -> ([f32; 4], f32),
) -> super::quality::ViewImage {
    let mut colour_opacity = Vec::new();
    let mut depth = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let (c, d) = pixel(x, y);
            colour_opacity.push(c);
            depth.push(d);
        }
    }
    super::quality::ViewImage {
        width,
        height,
        colour_opacity,
        depth,
    }
}

#[test]
fn quality_score_rejects_empty_flat_and_cluttered_views() {
    use super::quality::view_quality;
    // A checkered, fully covered view at a sane depth: good.
    let good = view(48, 48, |x, y| {
        let v = if (x / 6 + y / 6) % 2 == 0 { 0.8 } else { 0.1 };
        ([v, v, v, 1.0], 1.0)
    });
    assert!(
        view_quality(&good, 1.0).score < 10.0,
        "{:?}",
        view_quality(&good, 1.0)
    );
    // Nothing in view.
    let empty = view(48, 48, |_, _| ([0.0; 4], 0.0));
    assert!(view_quality(&empty, 1.0).empty > 50.0);
    // Uniform colour (the inside of a solid, a wall filling the view).
    let flat = view(48, 48, |_, _| ([0.5, 0.5, 0.5, 1.0], 1.0));
    assert!(view_quality(&flat, 1.0).flat > 50.0);
    // The same checker blurred into a smooth ramp.
    let blurred = view(48, 48, |x, _| {
        let v = 0.3 + 0.2 * (x as f32 / 48.0);
        ([v, v, v, 1.0], 1.0)
    });
    assert!(view_quality(&blurred, 1.0).score > 50.0);
    // Matter right at the camera (D̂ is opacity-weighted depth).
    let near = view(48, 48, |x, y| {
        let v = if (x / 6 + y / 6) % 2 == 0 { 0.8 } else { 0.1 };
        ([v, v, v, 1.0], 0.02)
    });
    assert!(view_quality(&near, 1.0).near > 50.0);
}

#[test]
fn environment_file_round_trips_and_names_bad_fields() {
    use super::file::{environment_file_text, parse_environment_file};
    use crate::sg::Sg64;
    let lobes = vec![
        Sg64 {
            direction: DVec3::new(0.5, 0.8, 0.35).normalize(),
            sharpness: 812.5,
            amplitude: DVec3::new(900.0, 840.0, 1e-30),
        },
        Sg64 {
            direction: DVec3::Y,
            sharpness: 0.05,
            amplitude: DVec3::ZERO,
        },
    ];
    let path = std::path::Path::new("books-env.toml");
    let lights = vec![super::near_lights::PointLight {
        position: DVec3::new(0.1, 2.9, -0.3),
        intensity: DVec3::new(22.0, 20.5, 1e-20),
    }];
    let seen_lights = vec![crate::field::SeenLight {
        centre: DVec3::new(0.198, 2.894, 0.298),
        radius: 0.0299,
        radiance: DVec3::new(7954.4, 7357.8, 6363.6),
        views: 13,
        residual: 0.017,
    }];
    let light = super::file::EstimatedLight {
        lobes: lobes.clone(),
        lights: lights.clone(),
        seen_lights: seen_lights.clone(),
    };
    let text = environment_file_text(&light, "books", &[("views".into(), "100".into())]);
    let back = parse_environment_file(path, &text).unwrap();
    assert_eq!(back.lights, lights);
    assert_eq!(back.seen_lights, seen_lights);
    let back = back.lobes;
    assert_eq!(back.len(), 2);
    for (a, b) in lobes.iter().zip(&back) {
        assert!((a.direction - b.direction).length() < 1e-15);
        assert_eq!(a.sharpness, b.sharpness);
        assert_eq!(a.amplitude, b.amplitude);
    }
    let bad = |t: &str, field: &str| {
        let e = parse_environment_file(path, t).unwrap_err();
        assert_eq!(e.field, field, "{e}");
        assert!(e.to_string().contains("books-env.toml"), "{e}");
    };
    bad("format = \"x\"\nversion = 1\n", "format");
    bad("format = \"inlay-environment\"\nversion = 7\n", "version");
    bad(
        "format = \"inlay-environment\"\nversion = 1\n[[lobes]]\ndirection = [0, 0, 0]\nsharpness = 1.0\namplitude = [1, 1, 1]\n",
        "lobes[0]",
    );
    bad(
        "format = \"inlay-environment\"\nversion = 1\n[[lobes]]\ndirection = [0, 1, 0]\nsharpness = nan\namplitude = [1, 1, 1]\n",
        "lobes[0]",
    );
    bad(
        "format = \"inlay-environment\"\nversion = 1\n[[lobes]]\ndirection = [0, 1, 0]\nsharpness = 1.0\namplitude = [1, -1, 1]\n",
        "lobes[0]",
    );
    bad(
        "format = \"inlay-environment\"\nversion = 1\n[[lights]]\nposition = [0, 1, 0]\nintensity = [1, -1, 1]\n",
        "lights[0]",
    );
    bad(
        "format = \"inlay-environment\"\nversion = 1\n[[seen_lights]]\ncentre = [0, 3, 0]\nradius = -0.1\nradiance = [1, 1, 1]\n",
        "seen_lights[0].radius",
    );
    assert_eq!(
        parse_environment_file(path, "format = \"inlay-environment\"\nversion = 1\n").unwrap(),
        super::file::EstimatedLight::default()
    );
}

/// Synthetic surface points lit by a known sun over an open floor and a
/// box's sides, with a uniform near field: the fit's input without a GPU.
fn synthetic_data(
    sun: &crate::sg::Sg64,
) -> (
    Vec<super::surface::SurfacePoint>,
    super::near_field::NearField,
) {
    synthetic_data_lit(&|_, normal| {
        sun.amplitude
            * (2.0 * std::f64::consts::PI / sun.sharpness)
            * sun.direction.dot(normal).max(0.0)
    })
}

/// As [`synthetic_data`], the hidden light's irradiance at a point with a
/// normal given by `hidden`.
fn synthetic_data_lit(
    hidden: &dyn Fn(DVec3, DVec3) -> DVec3,
) -> (
    Vec<super::surface::SurfacePoint>,
    super::near_field::NearField,
) {
    use super::near_field::NearField;
    use super::surface::SurfacePoint;
    let side = 8u32;
    let texels = (side * side) as usize;
    let mut rng = Pcg32::new(2, 2);
    let mut points = Vec::new();
    let mut near = NearField {
        irradiance: Vec::new(),
        covered: Vec::new(),
        map_side: side,
        opacity: Vec::new(),
    };
    for i in 0..256 {
        let normal = [DVec3::Y, DVec3::X, DVec3::Z, -DVec3::X][i % 4];
        let position = DVec3::new(
            rng.next_f64() - 0.5,
            0.3 * rng.next_f64(),
            rng.next_f64() - 0.5,
        );
        let albedo = 0.6;
        let e_nerf = DVec3::splat(0.3);
        let e_sun = hidden(position, normal);
        points.push(SurfacePoint {
            position,
            normal,
            radiance: albedo / std::f64::consts::PI * (e_nerf + e_sun),
            view: 0,
        });
        near.irradiance.push(e_nerf);
        near.covered.push(0.0);
        near.opacity.extend(std::iter::repeat_n(0.0, texels));
    }
    (points, near)
}

/// The fit's view of synthetic points (the box they lie in).
fn synthetic_fit_data<'a>(
    points: &'a [super::surface::SurfacePoint],
    near: &'a super::near_field::NearField,
) -> super::fit::FitData<'a> {
    super::fit::FitData {
        points,
        near,
        known: &[],
        bounds: Aabb::new(DVec3::new(-0.5, 0.0, -0.5), DVec3::new(0.5, 0.3, 0.5)),
    }
}

/// Knobs for a fast fit on synthetic points: `lobes` lobes, `iterations`
/// steps, a small network and batch.
fn small_fit_knobs(lobes: u32, iterations: u32) -> super::knobs::EnvEstimateKnobs {
    super::knobs::EnvEstimateKnobs {
        lobes,
        albedo_width: 8,
        iterations,
        batch: 64,
        env_samples: 16,
        env_rate: 0.05,
        near_lights: 0,
        ..Default::default()
    }
}

/// The sun the synthetic fits look for.
fn synthetic_sun() -> crate::sg::Sg64 {
    crate::sg::Sg64 {
        direction: DVec3::new(0.4, 0.8, 0.3).normalize(),
        sharpness: 60.0,
        amplitude: DVec3::splat(40.0),
    }
}

/// A hidden point light 0.5 above the field is found where it is, with its
/// intensity, by the fit with one near light beside the lobes.
#[test]
fn a_near_light_is_found_where_it_is() {
    use super::fit::fit_environment;
    use super::knobs::EnvEstimateKnobs;
    use super::near_lights::PointLight;
    let bulb = PointLight {
        position: DVec3::new(0.1, 0.8, -0.1),
        intensity: DVec3::splat(0.5),
    };
    let (points, near) = synthetic_data_lit(&|x, n| bulb.irradiance(x, n).0);
    let data = synthetic_fit_data(&points, &near);
    let knobs = EnvEstimateKnobs {
        near_lights: 1,
        ..small_fit_knobs(8, 600)
    };
    let fit = fit_environment(&data, &knobs, &|_, _, _| {});
    eprintln!("lights {:?}, loss {:.3e}", fit.lights, fit.exact_loss);
    assert_eq!(fit.lights.len(), 1);
    let off = (fit.lights[0].position - bulb.position).length();
    assert!(off < 0.1, "the near light is {off} from the bulb");
    let ratio = fit.lights[0].intensity.x / bulb.intensity.x;
    assert!((ratio - 1.0).abs() < 0.1, "intensity ratio {ratio}");
}

#[test]
fn a_seed_gives_the_same_lobes_twice_and_the_fit_lowers_the_loss() {
    use super::fit::fit_environment;
    use super::knobs::EnvEstimateKnobs;
    let sun = synthetic_sun();
    let (points, near) = synthetic_data(&sun);
    let data = synthetic_fit_data(&points, &near);
    let knobs = small_fit_knobs(8, 150);
    let a = fit_environment(&data, &knobs, &|_, _, _| {});
    let b = fit_environment(&data, &knobs, &|_, _, _| {});
    assert_eq!(a.lobes, b.lobes, "the same seed gave different lobes");
    let c = fit_environment(&data, &EnvEstimateKnobs { seed: 2, ..knobs }, &|_, _, _| {});
    assert_ne!(a.lobes, c.lobes, "the seed changes nothing");
    // Loss falls from the starting environment.
    let first = a.history.first().unwrap().1;
    assert!(
        a.final_loss < 0.5 * first,
        "loss {first} → {}",
        a.final_loss
    );
}

/// The mean share of the environment in the irradiance of `points`
/// (unoccluded), for lobes `lobes` and near-field light `near`.
fn environment_share(
    points: &[super::surface::SurfacePoint],
    near: &super::near_field::NearField,
    lobes: &[crate::sg::Sg64],
) -> f64 {
    use super::env_model::{env_term, EnvSampler};
    use crate::sgfit::model::luminance;
    let sampler = EnvSampler::new(lobes);
    let mut rng = Pcg32::new(7, 7);
    let shares: f64 = points
        .iter()
        .zip(&near.irradiance)
        .map(|(p, e)| {
            let env = env_term(lobes, &sampler, p.normal, 256, &|_| 1.0, &mut rng).irradiance;
            luminance(env) / (luminance(env) + luminance(*e))
        })
        .sum();
    shares / points.len() as f64
}

#[test]
fn the_share_prior_keeps_light_that_only_noise_asks_for_out_of_the_environment() {
    use super::fit::fit_environment;
    use super::knobs::EnvEstimateKnobs;
    // Points lit by the field alone (no environment), more under a lamp
    // at one side, whose recorded E_nerf carries ±10 % noise, as a
    // Monte-Carlo estimate does: the points whose E_nerf came out low look
    // as if some other light reached them.
    let dark = crate::sg::Sg64 {
        direction: DVec3::Y,
        sharpness: 1.0,
        amplitude: DVec3::ZERO,
    };
    let (mut points, mut near) = synthetic_data(&dark);
    let mut rng = Pcg32::new(3, 3);
    for (p, e) in points.iter_mut().zip(&mut near.irradiance) {
        let lit = 0.05 + 1.5 * (p.position.x + 0.5).powi(2);
        p.radiance *= lit / e.x;
        *e = DVec3::splat(lit * (1.0 + 0.2 * (rng.next_f64() - 0.5)));
    }
    let data = synthetic_fit_data(&points, &near);
    let knobs = small_fit_knobs(8, 1000);
    let free = fit_environment(
        &data,
        &EnvEstimateKnobs {
            share_prior: 0.0,
            ..knobs
        },
        &|_, _, _| {},
    );
    let held = fit_environment(&data, &knobs, &|_, _, _| {});
    let (free, held) = (
        environment_share(&points, &near, &free.lobes),
        environment_share(&points, &near, &held.lobes),
    );
    eprintln!("environment share: no prior {free:.4}, default prior {held:.4}");
    assert!(
        free > 0.1,
        "without the prior the noise should pull light in ({free})"
    );
    assert!(
        held < 0.5 * free,
        "the prior kept {held} of the light in (without: {free})"
    );
}

#[test]
fn lobes_that_reach_no_point_are_dropped_from_the_estimate() {
    use super::fit::fit_environment;
    use super::prune::lobe_reach;
    let sun = synthetic_sun();
    // A floor: every point faces up, and its cached opacity is full below
    // 6° above the horizon, so no light from below reaches it.
    let (mut points, mut near) = synthetic_data(&sun);
    let map = crate::probe::DirectionMap::new(crate::probe::MapKind::Octahedral, near.map_side);
    let side = near.map_side;
    for (t, o) in near.opacity.iter_mut().enumerate() {
        let t = t as u32 % (side * side);
        if map.direction(t % side, t / side).y < 0.1 {
            *o = 1.0;
        }
    }
    let e_sun = sun.amplitude * (2.0 * std::f64::consts::PI / sun.sharpness) * sun.direction.y;
    for (p, e) in points.iter_mut().zip(&near.irradiance) {
        p.normal = DVec3::Y;
        p.radiance = 0.6 / std::f64::consts::PI * (*e + e_sun);
    }
    let data = synthetic_fit_data(&points, &near);
    let down = crate::sg::Sg64 {
        direction: -DVec3::Y,
        sharpness: 20.0,
        amplitude: DVec3::ONE,
    };
    let reach = lobe_reach(&data, &[sun, down], 64, 1);
    assert!(
        reach[0] > 0.1 && reach[1] < 1e-6 * reach[0],
        "reach {reach:?}"
    );
    let knobs = small_fit_knobs(32, 150);
    let fit = fit_environment(&data, &knobs, &|_, _, _| {});
    // The starting lobes cover the sphere; those far below the horizon
    // (axis more than 53° under it) send well under 1 % of their energy to
    // the floor and must be gone.
    assert!(
        !fit.lobes.is_empty() && fit.lobes.len() < 32,
        "{} lobes",
        fit.lobes.len()
    );
    for l in &fit.lobes {
        assert!(l.direction.y > -0.8, "a lobe from below was kept: {l:?}");
    }
}

#[test]
fn rays_start_on_their_line_through_the_point_risen_off_the_surface() {
    use super::near_field::{ray_start, MIN_RISE_COSINE};
    use super::surface::SurfacePoint;
    let p = SurfacePoint {
        position: DVec3::new(0.2, 0.1, -0.3),
        normal: DVec3::Y,
        radiance: DVec3::ONE,
        view: 0,
    };
    let rise = 0.03;
    for (x, y) in [(0.0, 1.0), (0.6, 0.8), (0.9, 0.3), (1.0, 0.1)] {
        let dir = DVec3::new(x, y, 0.0).normalize();
        let offset = ray_start(&p, rise, dir) - p.position;
        // On the ray through the point, ahead of it.
        assert!(offset.cross(dir).length() < 1e-12 && offset.dot(dir) > 0.0);
        // Risen by `rise` unless the ray is nearer the horizon than the cap.
        let height = offset.dot(p.normal);
        if dir.y >= MIN_RISE_COSINE {
            assert!((height - rise).abs() < 1e-12, "{dir}: {height}");
        } else {
            assert!(height < rise && height > 0.0, "{dir}: {height}");
            assert!((offset.length() - rise / MIN_RISE_COSINE).abs() < 1e-12);
        }
    }
}

/// Under the weight test (trained fields) the rays rise the same length
/// of the scene on a 257-node grid as on a 129-node one, twice their own
/// spacings; the gradient test (bakes) keeps node spacings.
#[test]
fn a_trained_surface_s_rays_rise_over_a_length_of_the_scene() {
    use super::near_field::{ray_rise, SURFACE_OFFSET_SPACINGS};
    use super::surface::SurfaceTest;
    use crate::field::GridField;
    let line = |nodes: u32| {
        let res = glam::UVec3::new(nodes, 2, 2);
        let bounds = Aabb::new(DVec3::ZERO, DVec3::new(1.0, 0.01, 0.01));
        let count = (res.x * res.y * res.z) as usize;
        GridField::new(res, bounds, vec![[0.5, 0.5, 0.5, 0.0]; count], 4)
    };
    let (coarse, fine) = (line(129), line(257));
    let (h_coarse, h_fine) = (1.0 / 128.0, 1.0 / 256.0);
    for (field, h) in [(&coarse, h_coarse), (&fine, h_fine)] {
        let bake = ray_rise(field, SurfaceTest::Gradient);
        assert!((bake - SURFACE_OFFSET_SPACINGS * h).abs() < 1e-12, "{bake}");
        let trained = ray_rise(field, SurfaceTest::Weight);
        assert!(
            (trained - SURFACE_OFFSET_SPACINGS * h_coarse).abs() < 1e-12,
            "{trained}"
        );
    }
}

/// Points on one wall lit by a lamp in the field alone, with ±10 % noise
/// on their recorded E_nerf (as PLANTS' trained back wall, which held
/// every point of its estimate): the fit leaves some light in the
/// environment, which the test of whether the points need it removes;
/// the same points lit by a sun as well keep it.
#[test]
fn light_the_points_do_not_need_is_dropped_and_light_they_need_is_kept() {
    use super::fit::fit_environment;
    use super::knobs::EnvEstimateKnobs;
    use super::near_lights::PointLight;
    use super::outside_light::keep_if_needed;
    let lamp = PointLight {
        position: DVec3::new(0.1, 0.25, 0.4),
        intensity: DVec3::splat(0.05),
    };
    let sun = synthetic_sun();
    let wall = |with_sun: bool| {
        let (mut points, mut near) = synthetic_data_lit(&|_, _| DVec3::ZERO);
        let mut rng = Pcg32::new(5, 5);
        for (p, e) in points.iter_mut().zip(&mut near.irradiance) {
            p.normal = DVec3::Z;
            p.position.z = -0.4;
            let lit = lamp.irradiance(p.position, p.normal).0;
            let outside = if with_sun {
                sun.amplitude * (2.0 * std::f64::consts::PI / sun.sharpness) * sun.direction.z
            } else {
                DVec3::ZERO
            };
            p.radiance = 0.7 / std::f64::consts::PI * (lit + outside);
            *e = lit * (1.0 + 0.2 * (rng.next_f64() - 0.5));
        }
        (points, near)
    };
    let knobs = small_fit_knobs(8, 400);
    for (with_sun, keep) in [(false, false), (true, true)] {
        let (points, near) = wall(with_sun);
        let data = synthetic_fit_data(&points, &near);
        let fit = fit_environment(&data, &knobs, &|_, _, _| {});
        let share = environment_share(&points, &near, &fit.lobes);
        let (test, kept) = keep_if_needed(&data, &knobs, fit);
        let gain = test.gain().unwrap();
        eprintln!("sun {with_sun}: share {share:.3}, loss gain {gain:.2}");
        assert_eq!(test.kept, keep, "sun {with_sun}: gain {gain}");
        assert_eq!(kept.lobes.is_empty(), !keep);
        if !keep {
            // What the fit had left there, for the test to remove.
            assert!(share > 0.02, "the fit left only {share} in the environment");
        } else {
            assert!(gain > 10.0, "the sun lowered the loss only {gain}×");
        }
    }
    // Off: the light is kept without asking.
    let (points, near) = wall(false);
    let data = synthetic_fit_data(&points, &near);
    let off = EnvEstimateKnobs {
        min_loss_gain: 0.0,
        ..knobs
    };
    let fit = fit_environment(&data, &off, &|_, _, _| {});
    let (test, kept) = keep_if_needed(&data, &off, fit);
    assert!(test.kept && test.gain().is_none() && !kept.lobes.is_empty());
}

/// The light that lit synthetic points explains them (the albedo fitted
/// alone under it) far better than a wrong one, and a point light at a
/// lamp's place as well as the lamp: what `estimate-env` reads to tell a
/// fit that fell short from points that ask for another light.
#[test]
fn the_light_that_lit_the_points_explains_them() {
    use super::near_lights::PointLight;
    use super::outside_light::loss_under;
    let sun = synthetic_sun();
    let (points, near) = synthetic_data(&sun);
    let data = synthetic_fit_data(&points, &near);
    let knobs = small_fit_knobs(8, 400);
    let right = loss_under(&data, &knobs, &[sun], &[]);
    let wrong = crate::sg::Sg64 {
        direction: DVec3::new(-0.4, 0.8, -0.3).normalize(),
        ..sun
    };
    let wrong = loss_under(&data, &knobs, &[wrong], &[]);
    let none = loss_under(&data, &knobs, &[], &[]);
    eprintln!("sun: right {right:.3e}, wrong {wrong:.3e}, none {none:.3e}");
    assert!(right < 0.1 * wrong && right < 0.1 * none);
    let lamp = PointLight {
        position: DVec3::new(0.2, 0.6, -0.1),
        intensity: DVec3::splat(0.3),
    };
    let (points, near) = synthetic_data_lit(&|x, n| lamp.irradiance(x, n).0);
    let data = synthetic_fit_data(&points, &near);
    let right = loss_under(&data, &knobs, &[], &[lamp]);
    let moved = PointLight {
        position: DVec3::new(-0.6, 0.4, 0.5),
        ..lamp
    };
    let wrong = loss_under(&data, &knobs, &[], &[moved]);
    eprintln!("lamp: right {right:.3e}, moved {wrong:.3e}");
    assert!(right < 0.1 * wrong);
}

/// ROOM's hidden bulb in the fit's terms is one point light at its centre
/// with its radiance × πr² (it lights a point below it as the path
/// tracer's ball does, within 5 %: the ball is 3 cm across at 2.5 m), and
/// its sky one lobe.
#[test]
fn room_s_hidden_light_is_its_bulb_as_a_point_and_its_sky() {
    use super::truth::{hidden_light_model, light_irradiance, Lights};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/room.toml");
    let scene = crate::scene::load_scene(&path).unwrap();
    let recipe = scene.recipe().unwrap();
    let at = DVec3::new(0.0, 0.4, 0.0);
    let (lobes, lights) = hidden_light_model(recipe, &scene.environment, at, 2000.0);
    assert_eq!(lights.len(), 1);
    assert_eq!(lobes.len(), 1, "the sky alone");
    assert!((lights[0].position - DVec3::new(0.2, 2.9, 0.3)).length() < 1e-12);
    // The bulb's direct light at a point below it, against the path
    // tracer's (the environment left black).
    let bulb = lights[0].irradiance(at, DVec3::Y).0;
    let black = crate::scene::Environment::Black;
    let traced = light_irradiance(recipe, &black, Lights::Hidden, at, DVec3::Y, 4096, 1, true);
    let ratio = bulb.y / traced.y;
    eprintln!("point light / traced bulb: {ratio:.4}");
    assert!((ratio - 1.0).abs() < 0.05, "{ratio}");
}

/// Points lit by a bulb their photographs saw, a light known beside the
/// field: given its light, the fit finds that the points need nothing
/// more and keeps a black environment, where the same points without it
/// ask for outside light. With a sun as well, the fit given the bulb
/// reads the sun as the fit of points lit by the sun alone does, and the
/// fit not given it adds the bulb's light to the lobes.
#[test]
fn a_known_light_is_given_and_only_the_rest_is_estimated() {
    use super::env_model::{env_term, EnvSampler};
    use super::fit::{fit_environment, FitData};
    use super::known_lights::{as_point_lights, known_irradiance};
    use super::near_lights::PointLight;
    use super::outside_light::keep_if_needed;
    use crate::sgfit::model::luminance;
    let bulb = PointLight {
        position: DVec3::new(0.1, 0.8, -0.1),
        intensity: DVec3::splat(0.5),
    };
    let radius = 0.01;
    let seen = crate::field::SeenLight {
        centre: bulb.position,
        radius,
        radiance: bulb.intensity / (std::f64::consts::PI * radius * radius),
        views: 3,
        residual: 0.0,
    };
    let known_lights = as_point_lights(&[seen]);
    assert!(
        (known_lights[0].intensity - bulb.intensity)
            .abs()
            .max_element()
            < 1e-12
    );
    let sun = synthetic_sun();
    let sun_light = |n: DVec3| {
        sun.amplitude * (2.0 * std::f64::consts::PI / sun.sharpness) * sun.direction.dot(n).max(0.0)
    };
    let knobs = small_fit_knobs(8, 400);
    // The lobes' light over the points (unoccluded), over the sun's.
    let over_sun = |lobes: &[crate::sg::Sg64], points: &[super::surface::SurfacePoint]| {
        let sampler = EnvSampler::new(lobes);
        let mut rng = Pcg32::new(9, 9);
        let (mut light, mut truth) = (0.0, 0.0);
        for p in points {
            let e = env_term(lobes, &sampler, p.normal, 256, &|_| 1.0, &mut rng);
            light += luminance(e.irradiance);
            truth += luminance(sun_light(p.normal));
        }
        light / truth
    };
    let (points, near) = synthetic_data_lit(&|_, n| sun_light(n));
    let alone = fit_environment(&synthetic_fit_data(&points, &near), &knobs, &|_, _, _| {});
    let alone = over_sun(&alone.lobes, &points);
    for with_sun in [false, true] {
        let (points, near) = synthetic_data_lit(&|x, n| {
            bulb.irradiance(x, n).0 + if with_sun { sun_light(n) } else { DVec3::ZERO }
        });
        let known = known_irradiance(&points, &near, &known_lights);
        let bare = synthetic_fit_data(&points, &near);
        let given = FitData {
            known: &known,
            ..bare
        };
        let mut read = [0.0; 2];
        for (k, data) in [bare, given].iter().enumerate() {
            let fit = fit_environment(data, &knobs, &|_, _, _| {});
            let (test, kept) = keep_if_needed(data, &knobs, fit);
            let gain = test.gain().unwrap();
            read[k] = over_sun(&kept.lobes, &points);
            eprintln!(
                "sun {with_sun}, bulb given {}: loss gain {gain:.2}, {} lobes kept, estimate / sun {:.3}",
                k == 1,
                kept.lobes.len(),
                read[k]
            );
            assert_eq!(
                test.kept,
                k == 0 || with_sun,
                "sun {with_sun}, given {k}: gain {gain}"
            );
        }
        if with_sun {
            let bulb_share = points
                .iter()
                .map(|p| luminance(bulb.irradiance(p.position, p.normal).0))
                .sum::<f64>()
                / points
                    .iter()
                    .map(|p| luminance(sun_light(p.normal)))
                    .sum::<f64>();
            eprintln!(
                "the sun alone: estimate / sun {alone:.3}; the bulb / the sun {bulb_share:.3}"
            );
            // Measured: 1.230 given, 1.210 alone, 1.364 not given, the bulb 0.165.
            assert!(
                (read[1] - alone).abs() < 0.25 * bulb_share,
                "{read:?} against {alone}"
            );
            assert!(
                read[0] - read[1] > 0.5 * bulb_share,
                "{read:?}, the bulb {bulb_share}"
            );
        }
    }
}
