//! The joint fit of the albedo MLP and the environment's SG lobes
//! (METHOD.md eq. 3): minimise the mean squared difference, over surface
//! points and RGB, between each point's radiance and the Lambertian
//! L_o(x) = a(x)/π · (E_nerf(x) + E_env(x)), by Adam on random batches of
//! points (E_nerf joined by the light of any lights known beside the
//! field, [`super::known_lights`]), E_env importance sampled afresh every step
//! ([`super::env_model`]). The step sizes decay exponentially to a tenth
//! over the run. Beyond the paper, the loss gains a prior on the
//! environment's share of the points' irradiance ([`super::share_prior`]),
//! and lobes the points do not support are dropped at the end
//! ([`super::prune`]). Every random choice comes from the seed and the
//! step (and the batch is split into fixed chunks whose gradients are
//! summed in order), so a seed gives the same lobes on any number of
//! threads.

use glam::DVec3;
use rayon::prelude::*;

use super::adam::Adam;
use super::env_model::{env_term, initial_params, lobes, project, EnvSampler};
use super::fit_data::mean_luminance;
pub use super::fit_data::FitData;
use super::knobs::EnvEstimateKnobs;
use super::mlp::AlbedoMlp;
use super::near_lights::{self, near_term, PointLight};
use super::prune::prune_unseen;
use super::share_prior::SharePrior;
use crate::rng::Pcg32;
use crate::sg::Sg64;
use crate::sgfit::model::{luminance, LUMINANCE_WEIGHTS};

/// Fraction of the steps over which the albedo's encoding opens from the
/// coarsest to the finest octave.
pub const ANNEAL_FRACTION: f64 = 0.5;

/// Points per chunk of a batch (the unit of parallel work).
const CHUNK: usize = 32;

/// The fitted environment and how the fit went.
#[derive(Debug, Clone)]
pub struct FitResult {
    /// The environment's lobes.
    pub lobes: Vec<Sg64>,
    /// The hidden lights near the field, as points
    /// ([`super::near_lights`]).
    pub lights: Vec<PointLight>,
    /// The albedo network.
    pub albedo: AlbedoMlp,
    /// (step, mean squared error of that step's batch), every few steps.
    pub history: Vec<(u32, f64)>,
    /// Mean squared error over every point at the end (E_env sampled, so
    /// it includes the sampling noise of E_env).
    pub final_loss: f64,
    /// The same error without the noise: the mean of r_A·r_B (see
    /// `point_loss`), whose expectation is the squared residual of the
    /// exact E_env; noise can take it slightly below zero when the fit is
    /// near exact.
    pub exact_loss: f64,
}

/// The loss of point `i` and, when `grads` is given, its gradients added.
///
/// E_env is estimated twice from independent halves of the samples, Ê_A
/// and Ê_B, giving residuals r_A and r_B. The squared residual of one
/// noisy estimate would be biased by the estimate's variance, and its
/// gradient would pull the environment towards what samples with little
/// variance (broad, dim lobes instead of a sun); the gradient of r_A·r_B,
/// whose expectation is the squared residual of the exact E_env, is not.
/// Returns ½(r_A² + r_B²) and r_A·r_B, each averaged over RGB.
#[allow(clippy::too_many_arguments)]
fn point_loss(
    data: &FitData,
    i: usize,
    mlp: &AlbedoMlp,
    env: &[f64],
    env_lobes: &[Sg64],
    sampler: &EnvSampler,
    lights: &[PointLight],
    samples: u32,
    rng: &mut Pcg32,
    prior: &SharePrior,
    grads: Option<PointGrads>,
) -> (f64, f64) {
    let p = &data.points[i];
    let trace = mlp.forward(p.position);
    let visibility = |d: DVec3| 1.0 - data.near.opacity_at(i, d);
    let half = samples.div_ceil(2);
    let term_a = env_term(env_lobes, sampler, p.normal, half, &visibility, rng);
    let term_b = env_term(env_lobes, sampler, p.normal, half, &visibility, rng);
    let near_light = near_term(lights, p.position, p.normal, &visibility);
    let given = data.given(i);
    let e_a = given + term_a.irradiance + near_light.irradiance;
    let e_b = given + term_b.irradiance + near_light.irradiance;
    let a = trace.albedo;
    let inv_pi = 1.0 / std::f64::consts::PI;
    let r_a = a * e_a * inv_pi - p.radiance;
    let r_b = a * e_b * inv_pi - p.radiance;
    let loss = 0.5 * (r_a.length_squared() + r_b.length_squared()) / 3.0;
    if let Some(PointGrads {
        mlp: g_mlp,
        env: g_env,
        lights: g_lights,
        bounds,
        scale,
    }) = grads
    {
        let k = scale / 3.0;
        mlp.backward(&trace, k * (e_a * r_b + r_a * e_b) * inv_pi, g_mlp);
        term_a.backward(env, k * r_b * a * inv_pi, g_env);
        term_b.backward(env, k * r_a * a * inv_pi, g_env);
        near_light.backward(lights, bounds, k * (r_a + r_b) * a * inv_pi, g_lights);
        if prior.weight > 0.0 {
            // Each half's gradient scaled by the slope the other half sees,
            // so the noise of the two does not multiply. The near lights
            // are hidden light too: they count in the share.
            let near = luminance(given);
            let lit = luminance(near_light.irradiance);
            let slope_a = prior.slope(near, luminance(term_a.irradiance) + lit);
            let slope_b = prior.slope(near, luminance(term_b.irradiance) + lit);
            let w = LUMINANCE_WEIGHTS * (0.5 * scale);
            term_a.backward(env, w * slope_b, g_env);
            term_b.backward(env, w * slope_a, g_env);
            near_light.backward(lights, bounds, w * (slope_a + slope_b), g_lights);
        }
    }
    (loss, r_a.dot(r_b) / 3.0)
}

/// Where one point's gradients go.
struct PointGrads<'a> {
    mlp: &'a mut [f64],
    env: &'a mut [f64],
    lights: &'a mut [f64],
    /// The field's bounds (the lights' frame).
    bounds: &'a crate::geometry::Aabb,
    /// The point's weight in the batch.
    scale: f64,
}

/// Share of the starting light the near lights take when there are any
/// (the lobes start with the rest). Started at a twentieth, they grew
/// slowly while the albedo took up the slack, and ROOM's settled on the
/// bounds' margin, 1.3 m below its bulb (docs/fidelity.md, "Ninth pass").
pub const NEAR_START_SHARE: f64 = 0.5;

/// Runs the fit from the starting environment
/// ([`super::env_model::initial_params`], its light shared with the near
/// lights when there are any); `progress(step, steps, batch
/// loss)` every few steps.
pub fn fit_environment(
    data: &FitData,
    knobs: &EnvEstimateKnobs,
    progress: &dyn Fn(u32, u32, f64),
) -> FitResult {
    let share = if knobs.near_lights > 0 {
        1.0 - NEAR_START_SHARE
    } else {
        1.0
    };
    let level = mean_luminance(data.points);
    let env = initial_params(knobs.lobes as usize, share * level);
    // Near lights start with [`NEAR_START_SHARE`] of the points' mean
    // irradiance scale at the field's centre, shared among them, and the
    // lobes with the rest.
    let k = knobs.near_lights.max(1) as f64;
    let near = near_lights::initial_params(
        knobs.near_lights as usize,
        &data.bounds,
        NEAR_START_SHARE * std::f64::consts::PI * level / k,
    );
    fit_from(data, knobs, env, near, true, progress)
}

/// The environment parameters of `lobes` (for [`fit_from`]).
pub fn params_of(lobes: &[Sg64]) -> Vec<f64> {
    lobes
        .iter()
        .flat_map(|l| {
            let d = l.direction.normalize();
            let e = (l.amplitude / super::env_model::amplitude_per_energy(l.sharpness))
                .max(DVec3::splat(1e-17));
            [
                d.x,
                d.y,
                d.z,
                l.sharpness.ln(),
                e.x.ln(),
                e.y.ln(),
                e.z.ln(),
            ]
        })
        .collect()
}

/// Runs the fit from environment parameters `env` and near-light
/// parameters `near` ([`near_lights::params`]); with `fit_env` false the
/// light stays as given and only the albedo is fitted (to ask how well a
/// known light explains the points).
pub fn fit_from(
    data: &FitData,
    knobs: &EnvEstimateKnobs,
    mut env: Vec<f64>,
    mut near: Vec<f64>,
    fit_env: bool,
    progress: &dyn Fn(u32, u32, f64),
) -> FitResult {
    let mut mlp = AlbedoMlp::new(
        data.bounds,
        knobs.albedo_width as usize,
        knobs.albedo_octaves,
        knobs.seed,
    );
    let mut adam_env = Adam::new(env.len());
    let mut adam_near = Adam::new(near.len());
    let mut adam_mlp = Adam::new(mlp.params.len());
    let mut history = Vec::new();
    let n = data.points.len();
    let steps = knobs.iterations;
    let batch = knobs.batch as usize;
    let report_every = (steps / 100).max(1);
    let prior = SharePrior::new(knobs.share_prior, data);
    for step in 0..steps {
        mlp.set_band(
            mlp.frequencies() as f64 * (step as f64 / (ANNEAL_FRACTION * steps as f64)).min(1.0),
        );
        let env_lobes = lobes(&env);
        let sampler = EnvSampler::new(&env_lobes);
        let lights = near_lights::lights(&near, &data.bounds);
        let mut rng = Pcg32::new(knobs.seed, 0xBA7C_0000_0000 | step as u64);
        let picks: Vec<usize> = (0..batch).map(|_| rng.next_u32() as usize % n).collect();
        let scale = 1.0 / batch as f64;
        type Part = (f64, Vec<f64>, Vec<f64>, Vec<f64>);
        let parts: Vec<Part> = picks
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut g_mlp = vec![0.0; mlp.params.len()];
                let mut g_env = vec![0.0; env.len()];
                let mut g_near = vec![0.0; near.len()];
                let mut rng = Pcg32::new(knobs.seed ^ 0x5A3D, ((step as u64) << 24) | c as u64);
                let mut loss = 0.0;
                for &i in chunk {
                    loss += point_loss(
                        data,
                        i,
                        &mlp,
                        &env,
                        &env_lobes,
                        &sampler,
                        &lights,
                        knobs.env_samples,
                        &mut rng,
                        &prior,
                        Some(PointGrads {
                            mlp: &mut g_mlp,
                            env: &mut g_env,
                            lights: &mut g_near,
                            bounds: &data.bounds,
                            scale,
                        }),
                    )
                    .0;
                }
                (loss, g_mlp, g_env, g_near)
            })
            .collect();
        let mut loss = 0.0;
        let mut g_mlp = vec![0.0; mlp.params.len()];
        let mut g_env = vec![0.0; env.len()];
        let mut g_near = vec![0.0; near.len()];
        for (l, gm, ge, gn) in parts {
            loss += l;
            g_mlp.iter_mut().zip(gm).for_each(|(a, b)| *a += b);
            g_env.iter_mut().zip(ge).for_each(|(a, b)| *a += b);
            g_near.iter_mut().zip(gn).for_each(|(a, b)| *a += b);
        }
        let decay = 0.1f64.powf(step as f64 / steps.max(1) as f64);
        if fit_env {
            adam_env.step(&mut env, &g_env, knobs.env_rate * decay);
            project(&mut env, knobs.max_sharpness);
            adam_near.step(&mut near, &g_near, knobs.env_rate * decay);
            near_lights::project(&mut near, &data.bounds);
        }
        adam_mlp.step(&mut mlp.params, &g_mlp, knobs.albedo_rate * decay);
        let loss = loss * scale;
        if step % report_every == 0 || step + 1 == steps {
            history.push((step, loss));
            progress(step + 1, steps, loss);
        }
    }
    mlp.set_band(mlp.frequencies() as f64);
    if fit_env {
        env = prune_unseen(data, &env, knobs.env_samples, knobs.seed);
    }
    let env_lobes = lobes(&env);
    let sampler = EnvSampler::new(&env_lobes);
    let lights = near_lights::prune_dim(data, near_lights::lights(&near, &data.bounds));
    let (final_loss, exact_loss) = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut rng = Pcg32::new(knobs.seed ^ 0xF1A1, i as u64);
            point_loss(
                data,
                i,
                &mlp,
                &env,
                &env_lobes,
                &sampler,
                &lights,
                knobs.env_samples,
                &mut rng,
                &prior,
                None,
            )
        })
        .collect::<Vec<(f64, f64)>>()
        .into_iter()
        .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    let per_point = 1.0 / n.max(1) as f64;
    FitResult {
        lobes: env_lobes,
        lights,
        albedo: mlp,
        history,
        final_loss: final_loss * per_point,
        exact_loss: exact_loss * per_point,
    }
}
