//! The fit's model, one definition mirrored by `shaders/sgfit/model.wgsl`:
//! the parameterisation, the cold-start initialisation, the cost, the
//! Jacobian rows (and the features whose Gram matrix gives the normal
//! equations) and the step.
//!
//! Lobe k has six parameters around its current value (p, λ, μ):
//! a_c = √μ_c (so μ = a² ≥ 0), s = ln λ (so λ > 0, clamped to
//! [[`MIN_SHARPNESS`], [`MAX_SHARPNESS`]]) and (u, v), the axis moved in its
//! tangent plane and renormalised (so |p| = 1). The residual of texel t,
//! channel c is √w_t (Σ_k μ_kc G_k(v_t) − L_tc), w_t its solid angle: the
//! cost approximates ∫ |fit − L|² dω. Texels with a NaN, infinite or
//! negative channel get weight 0 and are counted.

use std::f64::consts::PI;

use glam::DVec3;

use crate::probe::DirectionMap;
use crate::sg::Sg64;

/// Smallest sharpness a fitted lobe may take.
pub const MIN_SHARPNESS: f64 = 1e-4;
/// Largest sharpness a fitted lobe may take at any probe resolution.
pub const MAX_SHARPNESS: f64 = 1e4;

/// Largest sharpness a lobe fitted to a probe of `texels` texels may take:
/// the variance 1/λ of the narrowest lobe equals that of the narrowest
/// feature of the filtered probe ([`super::probe_filter`]), 7h²/12 with
/// h² = 4π/texels the mean texel's solid angle, so λ ≤ 3·texels/(7π)
/// (about 140 at 32 × 32), within [1, [`MAX_SHARPNESS`]]. Such a lobe is
/// about 1.5 texel spacings wide (σ = 0.76 h), so evaluated at texel
/// centres its energy is its integral. (The earlier cap, λ ≤ texels, let
/// a lobe half a texel wide fit a bright texel with an energy off by tens
/// of per cent.) `shaders/sgfit/fit.wgsl` gets it as a define.
pub fn max_sharpness(texels: usize) -> f64 {
    (3.0 * texels as f64 / (7.0 * PI)).clamp(1.0, MAX_SHARPNESS)
}
/// Largest tangent-plane move of an axis in one step (radians, roughly).
pub const MAX_AXIS_STEP: f64 = 1.0;
/// The brightest texel seeds a lobe only when it exceeds the mean
/// luminance by this factor (a small, bright source).
pub const SEED_CONTRAST: f64 = 4.0;
/// Parameters per lobe.
pub const PARAMS_PER_LOBE: usize = 6;

/// A probe as the fit sees it: per texel direction, solid angle, radiance.
#[derive(Debug, Clone)]
pub struct ProbeSamples {
    /// Unit direction of each texel.
    pub directions: Vec<DVec3>,
    /// Solid angle of each texel (0 for invalid texels).
    pub weights: Vec<f64>,
    /// Radiance of each texel (0 for invalid texels).
    pub radiance: Vec<DVec3>,
    /// How many texels were NaN, infinite or negative.
    pub invalid: usize,
}

impl ProbeSamples {
    /// Reads `texels` (row by row, rgb + anything) laid out by `map`,
    /// filtered as the fit sees them ([`super::probe_filter::filter_probe`]),
    /// sanitising invalid ones.
    pub fn new(map: &DirectionMap, texels: &[[f64; 4]]) -> Self {
        let n = map.texels();
        let mut texels = texels.to_vec();
        // Missing texels count as invalid.
        texels.resize(n, [f64::NAN; 4]);
        let texels = super::probe_filter::filter_probe(map, &texels);
        let mut s = Self {
            directions: Vec::with_capacity(n),
            weights: Vec::with_capacity(n),
            radiance: Vec::with_capacity(n),
            invalid: 0,
        };
        for (i, t) in texels.iter().enumerate().take(n) {
            let (x, y) = (i as u32 % map.width, i as u32 / map.width);
            s.directions.push(map.direction(x, y));
            if texel_valid(t) {
                s.weights.push(map.solid_angle(x, y));
                s.radiance.push(DVec3::new(t[0], t[1], t[2]));
            } else {
                s.weights.push(0.0);
                s.radiance.push(DVec3::ZERO);
                s.invalid += 1;
            }
        }
        s
    }

    /// Σ_t w_t |L_t|²: the cost of fitting nothing (the residual's scale).
    pub fn energy(&self) -> f64 {
        self.weights
            .iter()
            .zip(&self.radiance)
            .map(|(w, l)| w * l.length_squared())
            .sum()
    }
}

/// Whether a texel's radiance is usable: every rgb channel finite and ≥ 0.
pub fn texel_valid(t: &[f64; 4]) -> bool {
    t[..3].iter().all(|c| c.is_finite() && *c >= 0.0)
}

/// Rec. 709 luminance weights of R, G and B.
pub const LUMINANCE_WEIGHTS: DVec3 = DVec3::new(0.2126, 0.7152, 0.0722);

/// Rec. 709 luminance.
pub fn luminance(c: DVec3) -> f64 {
    LUMINANCE_WEIGHTS.dot(c)
}

/// An orthonormal tangent basis (t1, t2) of unit `p` (Duff et al. 2017),
/// the same on CPU and GPU.
pub fn tangent_basis(p: DVec3) -> (DVec3, DVec3) {
    let sign = if p.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + p.z);
    let b = p.x * p.y * a;
    (
        DVec3::new(1.0 + sign * p.x * p.x * a, sign * b, -sign * p.x),
        DVec3::new(b, sign + p.y * p.y * a, -p.y),
    )
}

/// Axis k of M points spread evenly over the sphere (Fibonacci lattice, +Y up).
pub fn fibonacci_axis(k: u32, m: u32) -> DVec3 {
    let y = 1.0 - (2.0 * k as f64 + 1.0) / m as f64;
    let r = (1.0 - y * y).max(0.0).sqrt();
    let phi = k as f64 * PI * (3.0 - 5f64.sqrt());
    DVec3::new(r * phi.cos(), y, r * phi.sin())
}

/// The cold-start sharpness of M lobes: neighbours (≈ √(4π/M) apart)
/// overlap at half their peak value, λ = 8 ln 2 · M / 4π.
pub fn initial_sharpness(m: u32) -> f64 {
    8.0 * std::f64::consts::LN_2 * m as f64 / (4.0 * PI)
}

/// The cold start: Fibonacci axes at [`initial_sharpness`]; when the
/// brightest texel exceeds [`SEED_CONTRAST`] × the mean luminance, the lobe
/// nearest to it moves onto it with a sharpness matching the texel's size;
/// then amplitudes μ_k = Σ w L G_k / Σ w G_k S with S = Σ_j G_j (each texel's
/// radiance shared among the lobes covering it).
pub fn cold_start(probe: &ProbeSamples, m: u32) -> Vec<Sg64> {
    let l0 = initial_sharpness(m);
    let mut lobes: Vec<Sg64> = (0..m)
        .map(|k| Sg64 {
            direction: fibonacci_axis(k, m),
            sharpness: l0,
            amplitude: DVec3::ZERO,
        })
        .collect();
    // Brightest texel (lowest index on ties) and the mean luminance.
    let (mut best, mut best_lum, mut sum_wl, mut sum_w) = (0usize, -1.0f64, 0.0, 0.0);
    for (t, (l, w)) in probe.radiance.iter().zip(&probe.weights).enumerate() {
        if *w <= 0.0 {
            continue;
        }
        let lum = luminance(*l);
        if lum > best_lum {
            best = t;
            best_lum = lum;
        }
        sum_wl += w * lum;
        sum_w += w;
    }
    if sum_w > 0.0 && best_lum > SEED_CONTRAST * sum_wl / sum_w {
        let d = probe.directions[best];
        // Nearest axis (lowest index on ties).
        let mut k_best = 0usize;
        let mut dot_best = -2.0;
        for (k, g) in lobes.iter().enumerate() {
            let dot = g.direction.dot(d);
            if dot > dot_best {
                k_best = k;
                dot_best = dot;
            }
        }
        // Half value at the texel's radius r (w = π r²): λ = 2 ln 2 · π / w.
        let sharp = 2.0 * std::f64::consts::LN_2 * PI / probe.weights[best];
        lobes[k_best].direction = d;
        let cap = max_sharpness(probe.directions.len());
        lobes[k_best].sharpness = sharp.clamp(l0.min(cap), cap);
    }
    let cover: Vec<f64> = probe
        .directions
        .iter()
        .map(|&v| lobes.iter().map(|g| g.weight(v)).sum())
        .collect();
    let amplitudes: Vec<DVec3> = lobes
        .iter()
        .map(|g| {
            let mut num = DVec3::ZERO;
            let mut den = 0.0;
            for (t, cover) in cover.iter().enumerate() {
                let gw = probe.weights[t] * g.weight(probe.directions[t]);
                num += gw * probe.radiance[t];
                den += gw * cover;
            }
            if den > 0.0 {
                num / den
            } else {
                DVec3::ZERO
            }
        })
        .collect();
    for (g, a) in lobes.iter_mut().zip(amplitudes) {
        g.amplitude = a;
    }
    lobes
}

/// The model's radiance in direction `v`.
pub fn model(lobes: &[Sg64], v: DVec3) -> DVec3 {
    lobes.iter().map(|g| g.eval(v)).sum()
}

/// Σ_t w_t |model(v_t) − L_t|².
pub fn cost(probe: &ProbeSamples, lobes: &[Sg64]) -> f64 {
    (0..probe.directions.len())
        .map(|t| {
            let w = probe.weights[t];
            if w <= 0.0 {
                return 0.0;
            }
            w * (model(lobes, probe.directions[t]) - probe.radiance[t]).length_squared()
        })
        .sum()
}

/// The three Jacobian rows of texel t (channels r, g, b), each with
/// 6M derivative columns followed by the residual: the explicit form
/// the fit's normal equations ([`normal_from_gram`]) are checked against.
pub fn jacobian_rows(probe: &ProbeSamples, lobes: &[Sg64], t: usize, rows: &mut [Vec<f64>; 3]) {
    let p = PARAMS_PER_LOBE * lobes.len();
    for row in rows.iter_mut() {
        row.clear();
        row.resize(p + 1, 0.0);
    }
    let w = probe.weights[t];
    if w <= 0.0 {
        return;
    }
    let sw = w.sqrt();
    let v = probe.directions[t];
    let m = model(lobes, v);
    for (k, g) in lobes.iter().enumerate() {
        let e = g.weight(v);
        let (t1, t2) = tangent_basis(g.direction);
        let ds = -0.5 * g.sharpness * (v - g.direction).length_squared();
        let (du, dv) = (g.sharpness * v.dot(t1), g.sharpness * v.dot(t2));
        for (c, row) in rows.iter_mut().enumerate() {
            let mu = g.amplitude[c];
            let base = PARAMS_PER_LOBE * k;
            row[base + c] = sw * 2.0 * mu.sqrt() * e;
            row[base + 3] = sw * mu * e * ds;
            row[base + 4] = sw * mu * e * du;
            row[base + 5] = sw * mu * e * dv;
        }
    }
    for (c, row) in rows.iter_mut().enumerate() {
        row[p] = sw * (m[c] - probe.radiance[t][c]);
    }
}

/// Features per lobe in [`texel_features`].
pub const FEATURES_PER_LOBE: usize = 4;

/// Texel t's features: √w_t × (G_k, G_k ∂s, G_k ∂u, G_k ∂v) for each lobe
/// k (∂ the derivative of G_k's exponent along ln λ and the two tangent
/// moves of its axis), then √w_t (model − L) per channel: 4M + 3 numbers.
/// Every entry of the texel's three Jacobian rows ([`jacobian_rows`]) is
/// one of them times an amplitude term (2a_kc or μ_kc), so the normal
/// equations follow from the features' Gram matrix Σ_t f_t f_tᵀ
/// ([`normal_from_gram`]): (4M + 3)² products a texel where the rows take
/// 3 (6M + 1)², and no Jacobian is stored. Mirrored by `texel_features` in
/// `shaders/sgfit/fit.wgsl`.
pub fn texel_features(probe: &ProbeSamples, lobes: &[Sg64], t: usize, out: &mut Vec<f64>) {
    let f = FEATURES_PER_LOBE * lobes.len();
    out.clear();
    out.resize(f + 3, 0.0);
    let w = probe.weights[t];
    if w <= 0.0 {
        return;
    }
    let sw = w.sqrt();
    let v = probe.directions[t];
    let mut m = DVec3::ZERO;
    for (k, g) in lobes.iter().enumerate() {
        let e = g.weight(v);
        m += g.amplitude * e;
        let (t1, t2) = tangent_basis(g.direction);
        let ds = -0.5 * g.sharpness * (v - g.direction).length_squared();
        let (du, dv) = (g.sharpness * v.dot(t1), g.sharpness * v.dot(t2));
        let se = sw * e;
        out[FEATURES_PER_LOBE * k..FEATURES_PER_LOBE * (k + 1)].copy_from_slice(&[
            se,
            se * ds,
            se * du,
            se * dv,
        ]);
    }
    let r = sw * (m - probe.radiance[t]);
    out[f..].copy_from_slice(&r.to_array());
}

/// The normal matrix JᵀJ (6M × 6M, row-major) and the gradient Jᵀr at
/// `lobes` from the features' Gram matrix `gram` (F × F, F = 4M + 3,
/// row-major, symmetric; [`texel_features`]). With a_kc = √μ_kc, feature
/// e_k = 4k and d_k^i = 4k + 1 + i, for parameters (a_kc, s_k, u_k, v_k):
/// (a_kc, a_lc') = δ_cc' 4 a_kc a_lc G[e_k, e_l]; (a_kc, ·_l^i) =
/// 2 a_kc μ_lc G[e_k, d_l^i]; (·_k^i, ·_l^j) = (μ_k · μ_l) G[d_k^i, d_l^j];
/// the gradient: 2 a_kc G[e_k, r_c] and Σ_c μ_kc G[d_k^i, r_c]. Mirrored
/// by `assemble` in `shaders/sgfit/fit.wgsl`.
pub fn normal_from_gram(gram: &[f64], lobes: &[Sg64]) -> (Vec<f64>, Vec<f64>) {
    let m = lobes.len();
    let f = FEATURES_PER_LOBE * m + 3;
    let p = PARAMS_PER_LOBE * m;
    let g = |i: usize, j: usize| gram[i * f + j];
    let root = |k: usize, c: usize| lobes[k].amplitude[c].sqrt();
    let mu = |k: usize, c: usize| lobes[k].amplitude[c];
    // The feature of parameter i of lobe k (0–2 amplitudes share e_k).
    let feature = |k: usize, i: usize| FEATURES_PER_LOBE * k + i.saturating_sub(2);
    let mut a = vec![0.0; p * p];
    let mut b = vec![0.0; p];
    for k in 0..m {
        for i in 0..PARAMS_PER_LOBE {
            let row = PARAMS_PER_LOBE * k + i;
            let fi = feature(k, i);
            for l in 0..m {
                for j in 0..PARAMS_PER_LOBE {
                    let fj = feature(l, j);
                    let value = match (i < 3, j < 3) {
                        (true, true) if i == j => 4.0 * root(k, i) * root(l, i) * g(fi, fj),
                        (true, true) => 0.0,
                        (true, false) => 2.0 * root(k, i) * mu(l, i) * g(fi, fj),
                        (false, true) => 2.0 * root(l, j) * mu(k, j) * g(fi, fj),
                        (false, false) => lobes[k].amplitude.dot(lobes[l].amplitude) * g(fi, fj),
                    };
                    a[row * p + PARAMS_PER_LOBE * l + j] = value;
                }
            }
            let r = |c: usize| g(fi, f - 3 + c);
            b[row] = if i < 3 {
                2.0 * root(k, i) * r(i)
            } else {
                (0..3).map(|c| mu(k, c) * r(c)).sum()
            };
        }
    }
    (a, b)
}

/// Lobes moved by the parameter step `delta` (6 per lobe), sharpness kept
/// in [[`MIN_SHARPNESS`], `max_sharp`].
pub fn apply_step(lobes: &[Sg64], delta: &[f64], max_sharp: f64) -> Vec<Sg64> {
    lobes
        .iter()
        .enumerate()
        .map(|(k, g)| {
            let d = &delta[PARAMS_PER_LOBE * k..PARAMS_PER_LOBE * (k + 1)];
            let a = DVec3::new(
                g.amplitude.x.sqrt() + d[0],
                g.amplitude.y.sqrt() + d[1],
                g.amplitude.z.sqrt() + d[2],
            );
            let s = (g.sharpness.max(MIN_SHARPNESS).ln() + d[3])
                .clamp(MIN_SHARPNESS.ln(), max_sharp.ln());
            let (mut u, mut v) = (d[4], d[5]);
            let len = (u * u + v * v).sqrt();
            if len > MAX_AXIS_STEP {
                u *= MAX_AXIS_STEP / len;
                v *= MAX_AXIS_STEP / len;
            }
            let (t1, t2) = tangent_basis(g.direction);
            Sg64 {
                direction: (g.direction + u * t1 + v * t2).normalize(),
                sharpness: s.exp(),
                amplitude: a * a,
            }
        })
        .collect()
}
