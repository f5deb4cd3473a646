//! The march's quadrature along one ray and its gradient with respect to
//! the grid's nodes (f64 CPU reference).
//!
//! Samples sit at the midpoints of steps of Δ = diagonal / samples_per_ray
//! from where the ray enters the bounds, as in [`crate::march::march_ray`]
//! (without empty-space skipping: what the trainer has not yet learnt is
//! not empty); each reads (c_i, σ_i) trilinearly. With α_i = 1 − e^{−σ_iΔ_i}
//! and T_{i+1} = T_i(1 − α_i), the pixel is
//! C = Σ_i T_i α_i c_i + T_N·b (b the background behind the field, a
//! fixed colour or a learnt sky read along the ray: [`crate::field::sky`]), and
//! ∂C/∂c_i = T_i α_i, ∂C/∂b = T_N (a sky texel's share by its bilinear
//! weight),
//! ∂C/∂σ_i = Δ_i·(T_{i+1} c_i − Σ_{j>i} T_j α_j c_j − T_N b).
//! The backward pass walks the ray once more with the running sum
//! Σ_{j≤i}, so that Σ_{j>i} = C − Σ_{j≤i} (Plenoxels' scheme). The march
//! stops where T falls under the termination threshold; the gradient
//! treats that stop as fixed.
//!
//! The distortion loss (Mip-NeRF 360's), with the weights w_i = T_i α_i,
//! L_d = λ/D·(Σ_{i,j} w_i w_j |t_i − t_j| + ⅓ Σ_i w_i² Δ_i) (D the
//! field's diagonal, so λ does not depend on the scene's units), is
//! smallest when a ray's weight sits in one short stretch: it pulls a
//! surface's density into a thin shell and clears haze. As a function of
//! the weights, ∂L_d/∂w_i = λ/D·(2 Σ_j w_j |t_i − t_j| + ⅔ w_i Δ_i) =: e_i,
//! and since ∂w_k/∂σ_i is Δ_i T_{i+1} for k = i and −Δ_i w_k for k > i,
//! ∂L_d/∂σ_i = Δ_i·(T_{i+1} e_i − Σ_{k>i} w_k e_k), the colour's form with
//! e in place of c. L_d is of degree 2 in the weights, so Σ_k w_k e_k =
//! 2 L_d, and the backward walk's running sums (Σ_{j<i} w_j and
//! Σ_{j<i} w_j t_j against the forward pass's totals) give the rest.
//!
//! A depth map's term ([`super::depth`]) has the same form with
//! ρ(t_i − D) in the place of c_i and ρ(t_exit − D) in the place of b.
//!
//! With view-dependent colour, c_i = max(0, base_i + Σ_k Y_k(d)·s_{k,i})
//! (`crate::field::sh_basis`): ∂C/∂base_i = T_i α_i and ∂C/∂s_{k,i} =
//! T_i α_i Y_k(d) in each channel where the sum is positive, zero where
//! the clamp holds.

use glam::DVec3;

use crate::field::{sh_basis, sh_colour_unclamped, GridField, RadianceField};
use crate::geometry::{ray_box, Ray};
use crate::march::MarchKnobs;

use super::behind::Behind;
use super::depth::{depth_penalty, effective_target, DepthTerm};

/// One ray's pixel and the gradient of a loss with respect to the nodes it
/// read.
#[derive(Debug, Clone, PartialEq)]
pub struct RayGradient {
    /// The pixel C (background included).
    pub colour: DVec3,
    /// The distortion loss L_d (0 with λ = 0).
    pub distortion: f64,
    /// The depth loss L_z (0 without a depth term).
    pub depth: f64,
    /// Opacity 1 − T_N.
    pub opacity: f64,
    /// ∂loss/∂value for each value the ray read, indexed as the device
    /// holds the field (`crate::field::device_values`): a node n as
    /// (n, [r, g, b, σ]), its further colour coefficient k as
    /// (N + n·K + k, [r, g, b, 0]); of a pixel of several rays, each
    /// ray's entries (a value read by several appears once for each).
    pub values: Vec<(usize, [f64; 4])>,
    /// ∂loss/∂texel (r, g, b) for each texel of a learnt sky the ray read
    /// (empty behind a fixed colour).
    pub sky: Vec<(usize, [f64; 3])>,
}

/// Which share of a sample's density gradient reaches its nodes, where its
/// interpolated raw density is not above zero (the clamp at zero holds,
/// [`crate::field::density_at`]). Where it is above zero, all of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DensityGate {
    /// None: the clamp's true derivative. A node a step took below zero
    /// stays there until a neighbour above zero brings its samples back.
    #[default]
    Clamp,
    /// Where the gradient asks for more density, all of it (the slope of
    /// the loss were the density raised from zero); none where it asks for
    /// less. For a field every node of which lies below zero, where the
    /// clamp passes nothing and nothing would ever come back
    /// ([`super::trainer::train`] turns it on only there, until the field
    /// holds density again: through a whole run it brought the haze back,
    /// DOG's Cycles set's held-out views 5.6 and 2.5 dB lower and their
    /// surfaces 5.8 and 3.2 node spacings off, against 2.6 and 1.3).
    Revive,
}

impl DensityGate {
    /// The share of `d_sigma` passed at a sample whose raw interpolated
    /// density is `raw`.
    pub fn share(self, raw: f64, d_sigma: f64) -> f64 {
        if raw > 0.0 || (self == Self::Revive && d_sigma < 0.0) {
            1.0
        } else {
            0.0
        }
    }
}

/// The step midpoints (t_i, Δ_i) of `ray` through `field` (unit direction).
fn samples(field: &GridField, ray: &Ray, knobs: &MarchKnobs) -> Vec<(f64, f64)> {
    let Some((t0, t1)) = ray_box(ray, &field.bounds) else {
        return Vec::new();
    };
    let step = knobs.step(field.bounds.diagonal());
    let mut out = Vec::new();
    let mut k = 0u64;
    loop {
        let a = t0 + k as f64 * step;
        if a >= t1 {
            break;
        }
        let b = (a + step).min(t1);
        out.push((0.5 * (a + b), b - a));
        k += 1;
    }
    out
}

/// Renders `ray` through `field` over `background` (a colour or a learnt
/// sky) and, given the loss's gradient with respect to the pixel as
/// `d_colour(C)`, returns the pixel and the gradient with respect to the
/// nodes (and the sky's texels) of that loss plus the distortion loss of
/// weight `distortion` (λ; 0 leaves it out) and the depth loss of `depth`
/// (None leaves it out; nor does a ray that misses the bounds take one).
pub fn render_ray_with_gradient<'a>(
    field: &GridField,
    ray: &Ray,
    knobs: &MarchKnobs,
    background: impl Into<Behind<'a>>,
    priors: (f64, Option<DepthTerm>),
    d_colour: impl Fn(DVec3) -> DVec3,
) -> RayGradient {
    render_ray_with_gradient_gated(
        field,
        ray,
        knobs,
        background,
        priors,
        d_colour,
        DensityGate::Clamp,
    )
}

/// [`render_ray_with_gradient`] with the density gradient passed by `gate`.
pub fn render_ray_with_gradient_gated<'a>(
    field: &GridField,
    ray: &Ray,
    knobs: &MarchKnobs,
    background: impl Into<Behind<'a>>,
    (distortion, depth): (f64, Option<DepthTerm>),
    d_colour: impl Fn(DVec3) -> DVec3,
    gate: DensityGate,
) -> RayGradient {
    let behind = background.into();
    let background = behind.eval(ray.dir);
    let steps = samples(field, ray, knobs);
    let lambda = distortion / field.bounds.diagonal();
    // The depth term: its weight over the diagonal, the target and the
    // tolerance (weight 0 where none).
    // Where the ray leaves the bounds: the last step's end.
    let exit = steps.last().map(|&(t, dt)| t + 0.5 * dt);
    let (mu, target, tolerance) = match (depth, exit) {
        (Some(d), Some(exit)) => (
            d.weight / field.bounds.diagonal(),
            effective_target(d.target, exit, d.tolerance),
            d.tolerance,
        ),
        _ => (0.0, 0.0, 1.0),
    };
    let penalty = |t: f64| {
        if mu == 0.0 {
            0.0
        } else {
            depth_penalty(t - target, tolerance)
        }
    };
    // Forward, with the weights' totals the distortion loss needs.
    let mut colour = DVec3::ZERO;
    let mut transmittance = 1.0;
    let mut used = 0;
    let (mut w_all, mut wt_all, mut pairs, mut own) = (0.0, 0.0, 0.0, 0.0);
    let mut depth_sum = 0.0;
    for &(t, dt) in &steps {
        let (sigma, c) = field.sample(ray.at(t), ray.dir);
        let alpha = 1.0 - (-sigma * dt).exp();
        let w = transmittance * alpha;
        colour += w * c;
        depth_sum += w * penalty(t);
        // Σ_{j<i} w_j (t_i − t_j): each unordered pair once.
        pairs += w * (t * w_all - wt_all);
        own += w * w * dt;
        w_all += w;
        wt_all += w * t;
        transmittance *= 1.0 - alpha;
        used += 1;
        if transmittance < knobs.termination {
            break;
        }
    }
    let distortion_loss = lambda * (2.0 * pairs + own / 3.0);
    // The depth loss over μ/Diag: the weights' penalties and what passes
    // the bounds', at the exit.
    let exit_penalty = exit.map_or(0.0, penalty);
    let depth_total = depth_sum + transmittance * exit_penalty;
    let total = colour + transmittance * background;
    let g = d_colour(total);
    let sky = match behind {
        Behind::Sky(s) => s
            .corners(ray.dir)
            .iter()
            .filter(|c| c.1 != 0.0)
            .map(|&(i, w)| (i, (g * transmittance * w).to_array()))
            .collect(),
        Behind::Colour(_) => Vec::new(),
    };
    // Backward: walk again with the running sums.
    let count = field.sh_count();
    let first = field.nodes.len();
    let basis = sh_basis(ray.dir);
    let mut grads: Vec<(usize, [f64; 4])> = Vec::new();
    let mut add = |i: usize, d: [f64; 4]| match grads.iter_mut().find(|(m, _)| *m == i) {
        Some((_, acc)) => acc.iter_mut().zip(d).for_each(|(a, b)| *a += b),
        None => grads.push((i, d)),
    };
    let mut t_i = 1.0;
    let mut so_far = DVec3::ZERO;
    let (mut w_before, mut wt_before, mut e_so_far) = (0.0, 0.0, 0.0);
    let mut z_so_far = 0.0;
    for &(t, dt) in &steps[..used] {
        let x = ray.at(t);
        let Some(corners) = field.corners(x) else {
            continue;
        };
        let v = field.interpolate(x);
        let c = field.colour(x, ray.dir);
        // Channels the clamp at zero holds get no colour gradient.
        let open = if count == 0 {
            DVec3::ONE
        } else {
            let base = DVec3::new(v[0], v[1], v[2]);
            let u = sh_colour_unclamped(base, &field.interpolate_sh(x), ray.dir);
            DVec3::select(u.cmpgt(DVec3::ZERO), DVec3::ONE, DVec3::ZERO)
        };
        let sigma = crate::field::density_at(v);
        let alpha = 1.0 - (-sigma * dt).exp();
        let w = t_i * alpha;
        let t_next = t_i * (1.0 - alpha);
        so_far += w * c;
        // e_i = ∂L_d/∂w_i: Σ_j w_j |t_i − t_j| from the sums before and after.
        let w_after = w_all - w_before - w;
        let wt_after = wt_all - wt_before - w * t;
        let spread = t * w_before - wt_before + wt_after - t * w_after;
        let e = lambda * (2.0 * spread + 2.0 / 3.0 * w * dt);
        e_so_far += w * e;
        let rho = penalty(t);
        z_so_far += w * rho;
        let d_c = g * w * open;
        let d_sigma = dt
            * (g.dot(t_next * c - (colour - so_far) - transmittance * background) + t_next * e
                - (2.0 * distortion_loss - e_so_far)
                + mu * (t_next * rho - (depth_total - z_so_far)));
        let d_sigma = d_sigma * gate.share(v[3], d_sigma);
        w_before += w;
        wt_before += w * t;
        for (n, wn) in corners {
            if wn == 0.0 {
                continue;
            }
            add(n, [d_c.x * wn, d_c.y * wn, d_c.z * wn, d_sigma * wn]);
            for (k, yk) in basis.iter().take(count).enumerate() {
                let e = d_c * wn * *yk;
                add(first + n * count + k, [e.x, e.y, e.z, 0.0]);
            }
        }
        t_i = t_next;
    }
    RayGradient {
        colour: total,
        distortion: distortion_loss,
        depth: mu * depth_total,
        opacity: 1.0 - transmittance,
        values: grads,
        sky,
    }
}

/// Renders one pixel as the mean of `rays` through points of its area
/// (a photograph's pixel gathers the light over its area) over
/// `background` and, given the loss's gradient with respect to the pixel
/// as `d_colour(C)`, returns the pixel and the gradient of that loss plus
/// each ray's distortion loss at weight `distortion` / n and its depth
/// loss (`depths`: one term a ray, each at its weight / n, or empty for
/// none; the pixel's weight shared among its n rays): each ray's own
/// gradient at `d_colour(C)` / n, summed. One ray is
/// [`render_ray_with_gradient`].
pub fn render_pixel_with_gradient<'a>(
    field: &GridField,
    rays: &[Ray],
    knobs: &MarchKnobs,
    background: impl Into<Behind<'a>>,
    (distortion, depths): (f64, &[Option<DepthTerm>]),
    d_colour: impl Fn(DVec3) -> DVec3,
) -> RayGradient {
    let behind = background.into();
    let n = rays.len().max(1) as f64;
    let colour = rays
        .iter()
        .map(|r| {
            render_ray_with_gradient(field, r, knobs, behind, (0.0, None), |_| DVec3::ZERO).colour
        })
        .sum::<DVec3>()
        / n;
    let g = d_colour(colour) / n;
    let mut out = RayGradient {
        colour,
        distortion: 0.0,
        depth: 0.0,
        opacity: 0.0,
        values: Vec::new(),
        sky: Vec::new(),
    };
    for (k, ray) in rays.iter().enumerate() {
        let depth = depths.get(k).copied().flatten().map(|d| DepthTerm {
            weight: d.weight / n,
            ..d
        });
        let r = render_ray_with_gradient(field, ray, knobs, behind, (distortion / n, depth), |_| g);
        out.distortion += r.distortion;
        out.depth += r.depth;
        out.opacity += r.opacity / n;
        out.values.extend(r.values);
        out.sky.extend(r.sky);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::rng::Pcg32;
    use glam::UVec3;

    /// Where every node lies below zero the field is empty and its true
    /// gradient is zero; the trained gradient passes there only what asks
    /// for more density, and it is the slope of the loss from zero: the
    /// same whether the nodes lie at zero or far below it, and equal to a
    /// forward difference from zero. A loss that asks for less density
    /// moves no node below zero.
    #[test]
    fn a_density_below_zero_passes_only_the_gradient_that_asks_for_more() {
        let knobs = MarchKnobs {
            samples_per_ray: 24,
            termination: 1e-4,
            skip_empty: false,
        };
        let at = |sigma: f32| {
            let mut f = small_field(5);
            for n in &mut f.nodes {
                n[3] = sigma;
            }
            f
        };
        let ray = Ray {
            origin: DVec3::new(-2.0, 0.1, -1.5),
            dir: DVec3::new(1.0, 0.05, 0.8).normalize(),
        };
        let bg = DVec3::splat(0.2);
        // A loss that falls as the pixel brightens (the nodes' colours are
        // brighter than the background): it asks for more density.
        let more = DVec3::splat(-1.0);
        let trained = |f: &GridField, w: DVec3| {
            render_ray_with_gradient_gated(
                f,
                &ray,
                &knobs,
                bg,
                (0.0, None),
                |_| w,
                DensityGate::Revive,
            )
        };
        let (deep, zero) = (at(-3.0), at(0.0));
        assert!(
            render_ray_with_gradient(&deep, &ray, &knobs, bg, (0.0, None), |_| more)
                .values
                .iter()
                .all(|(_, g)| g[3] == 0.0)
        );
        let from_deep = trained(&deep, more);
        let from_zero = trained(&zero, more);
        assert_eq!(from_deep.values, from_zero.values);
        let asked: Vec<_> = from_deep
            .values
            .iter()
            .filter(|(_, g)| g[3] < 0.0)
            .collect();
        assert!(asked.len() > 10, "{}", asked.len());
        let loss = |f: &GridField| trained(f, more).colour.dot(more);
        let h = 1e-4;
        for &&(n, g) in &asked {
            let mut up = zero.clone();
            up.nodes[n][3] += h as f32;
            let forward = (loss(&up) - loss(&zero)) / h;
            assert!(
                (forward - g[3]).abs() < 2e-3 * (1.0 + g[3].abs()),
                "node {n}: {forward} vs {}",
                g[3]
            );
        }
        // The opposite loss asks for less: nothing passes.
        assert!(trained(&deep, -more)
            .values
            .iter()
            .all(|(_, g)| g[3] == 0.0));
    }

    /// A small random field with a dense blob and thin air.
    fn small_field(seed: u64) -> GridField {
        let res = UVec3::new(5, 4, 6);
        let mut rng = Pcg32::new(seed, 3);
        let nodes = (0..res.x * res.y * res.z)
            .map(|_| {
                [
                    2.0 * rng.next_f64() as f32,
                    rng.next_f64() as f32,
                    5.0 * rng.next_f64() as f32,
                    // Some below zero (the clamp after interpolation).
                    (3.0 * rng.next_f64() * rng.next_f64() - 0.4) as f32,
                ]
            })
            .collect();
        GridField::new(
            res,
            Aabb::new(DVec3::new(-1.0, -0.5, -1.0), DVec3::new(1.0, 0.7, 1.2)),
            nodes,
            2,
        )
    }

    /// `small_field` with view-dependent colour of `degree`: coefficients
    /// large enough that the clamp at zero holds in some samples.
    fn small_sh_field(seed: u64, degree: u32) -> GridField {
        let f = small_field(seed);
        let mut rng = Pcg32::new(seed, 5);
        let sh = (0..f.nodes.len() * crate::field::sh_extra_coefficients(degree))
            .map(|_| std::array::from_fn(|_| (3.0 * (rng.next_f64() - 0.5)) as f32))
            .collect();
        f.with_sh(degree, sh)
    }

    /// The depth term of `ray` through `field` whose surface lies at
    /// `share` of the way from where it enters the bounds to where it
    /// leaves (past 1: beyond them).
    fn depth_at_share(field: &GridField, ray: &Ray, share: f64, weight: f64) -> DepthTerm {
        let (t0, t1) = ray_box(ray, &field.bounds).unwrap();
        DepthTerm {
            target: t0 + share * (t1 - t0),
            weight,
            tolerance: 0.05,
        }
    }

    /// The pixel equals the march's (no skipping, black background), and
    /// the gradient of a weighted sum of the pixel (plus, for λ > 0, the
    /// distortion loss, and where given the depth loss, its surface inside
    /// the bounds or past them) matches central differences of the
    /// rendered pixel in every value it reads, density, colour and
    /// (degrees 1 and 2) the view-dependent coefficients, over a
    /// background.
    #[test]
    fn the_gradient_matches_finite_differences() {
        let knobs = MarchKnobs {
            samples_per_ray: 24,
            termination: 1e-4,
            skip_empty: false,
        };
        let weights = DVec3::new(0.7, -0.2, 0.4);
        let bg = DVec3::new(0.3, 0.6, 0.9);
        let cases = [
            (0, 0.0, None),
            (1, 0.0, None),
            (2, 0.0, None),
            (0, 0.8, None),
            (2, 0.3, None),
            (0, 0.0, Some(0.4)),
            (1, 0.5, Some(1.3)),
            (0, 0.0, Some(1e9)),
        ];
        for (degree, lambda, share) in cases {
            let field = small_sh_field(1, degree);
            let first = field.nodes.len();
            let mut checked = 0;
            for (o, d) in [
                (DVec3::new(-2.0, 0.1, -1.5), DVec3::new(1.0, 0.05, 0.8)),
                (DVec3::new(0.2, 2.0, 0.3), DVec3::new(-0.1, -1.0, 0.2)),
                (DVec3::new(1.5, -0.3, 2.0), DVec3::new(-0.6, 0.1, -1.0)),
            ] {
                let ray = Ray {
                    origin: o,
                    dir: d.normalize(),
                };
                let black = render_ray_with_gradient(
                    &field,
                    &ray,
                    &knobs,
                    DVec3::ZERO,
                    (0.0, None),
                    |_| weights,
                );
                let march = crate::march::march_ray(&field, &ray, f64::INFINITY, &knobs);
                assert!((black.colour - march.colour).length() < 1e-12);
                assert!((black.opacity - march.opacity).abs() < 1e-12);
                assert_eq!((black.distortion, black.depth), (0.0, 0.0));
                let depth = share.map(|s| depth_at_share(&field, &ray, s, 2.0));
                let priors = (lambda, depth);
                let r = render_ray_with_gradient(&field, &ray, &knobs, bg, priors, |_| weights);
                assert!(!r.values.is_empty());
                assert_eq!(r.depth > 0.0, depth.is_some());
                let loss = |f: &GridField| {
                    let r = render_ray_with_gradient(f, &ray, &knobs, bg, priors, |_| weights);
                    r.colour.dot(weights) + r.distortion + r.depth
                };
                for &(n, grad) in &r.values {
                    for (ch, &analytic) in grad.iter().enumerate() {
                        if n >= first && ch == 3 {
                            assert_eq!(analytic, 0.0);
                            continue;
                        }
                        let numeric = central_difference(&field, n, ch, &loss);
                        // f32 values: the perturbation is exact only to ~1e-7.
                        assert!(
                            (numeric - analytic).abs() < 2e-3 * (1.0 + analytic.abs()),
                            "degree {degree} λ {lambda} depth {share:?} value {n} channel {ch}: \
                             {numeric} vs {analytic}"
                        );
                        checked += 1;
                    }
                }
            }
            assert!(checked > 100 * (1 + degree as usize), "{checked}");
        }
    }

    /// The central difference of `loss` in channel `ch` of value `n`: a
    /// node's below `field.nodes.len()`, a node's SH coefficients above.
    fn central_difference(
        field: &GridField,
        n: usize,
        ch: usize,
        loss: &dyn Fn(&GridField) -> f64,
    ) -> f64 {
        let h = 1e-4;
        let first = field.nodes.len();
        let eval = |delta: f32| {
            let mut f = field.clone();
            if n < first {
                f.nodes[n][ch] += delta;
            } else {
                f.sh[n - first][ch] += delta;
            }
            loss(&f)
        };
        (eval(h as f32) - eval(-h as f32)) / (2.0 * h)
    }

    /// A pixel of three rays is their mean (its distortion and depth
    /// losses the means of theirs), and the gradient of a squared loss on
    /// that mean (not the mean of the rays' losses) plus the distortion
    /// and depth losses matches central differences in every value the
    /// rays read.
    #[test]
    fn a_pixels_gradient_over_its_rays_matches_finite_differences() {
        let knobs = MarchKnobs {
            samples_per_ray: 24,
            termination: 1e-4,
            skip_empty: false,
        };
        let (bg, lambda) = (DVec3::new(0.3, 0.6, 0.9), 0.6);
        let target = DVec3::new(0.4, 1.5, 0.2);
        let field = small_sh_field(2, 1);
        let first = field.nodes.len();
        let rays: Vec<Ray> = [0.0, 0.04, 0.09]
            .iter()
            .map(|&k| Ray {
                origin: DVec3::new(-2.0, 0.1 + k, -1.5),
                dir: DVec3::new(1.0, 0.05 - k, 0.8).normalize(),
            })
            .collect();
        let depths: Vec<Option<DepthTerm>> = rays
            .iter()
            .map(|ray| Some(depth_at_share(&field, ray, 0.5, 3.0)))
            .collect();
        let d_colour = |c: DVec3| 2.0 * (c - target);
        let priors = (lambda, depths.as_slice());
        let r = render_pixel_with_gradient(&field, &rays, &knobs, bg, priors, d_colour);
        let each: Vec<RayGradient> = rays
            .iter()
            .zip(&depths)
            .map(|(ray, d)| {
                render_ray_with_gradient(&field, ray, &knobs, bg, (lambda, *d), |_| DVec3::ZERO)
            })
            .collect();
        let mean = each.iter().map(|e| e.colour).sum::<DVec3>() / 3.0;
        assert!((r.colour - mean).length() < 1e-12);
        let distortion = each.iter().map(|e| e.distortion).sum::<f64>() / 3.0;
        assert!(distortion > 0.0 && (r.distortion - distortion).abs() < 1e-12);
        let depth = each.iter().map(|e| e.depth).sum::<f64>() / 3.0;
        assert!(depth > 0.0 && (r.depth - depth).abs() < 1e-12);
        assert!((each[0].colour - each[2].colour).length() > 1e-3);
        let loss = |f: &GridField| {
            let r = render_pixel_with_gradient(f, &rays, &knobs, bg, priors, |_| DVec3::ZERO);
            (r.colour - target).length_squared() + r.distortion + r.depth
        };
        let mut summed: Vec<(usize, [f64; 4])> = Vec::new();
        for (n, g) in &r.values {
            match summed.iter_mut().find(|(m, _)| m == n) {
                Some((_, acc)) => acc.iter_mut().zip(g).for_each(|(a, b)| *a += b),
                None => summed.push((*n, *g)),
            }
        }
        let mut checked = 0;
        for &(n, grad) in &summed {
            for (ch, &analytic) in grad
                .iter()
                .enumerate()
                .filter(|(ch, _)| n < first || *ch < 3)
            {
                let numeric = central_difference(&field, n, ch, &loss);
                assert!(
                    (numeric - analytic).abs() < 2e-3 * (1.0 + analytic.abs()),
                    "value {n} channel {ch}: {numeric} vs {analytic}"
                );
                checked += 1;
            }
        }
        assert!(checked > 100, "{checked}");
    }

    /// Behind a learnt sky the pixel's gradient with respect to each texel
    /// the ray reads matches central differences, and so does the
    /// density's (its −T_N·b term reads the sky along the ray); a ray that
    /// misses the box reads the sky alone.
    #[test]
    fn the_sky_gradient_matches_finite_differences() {
        use crate::field::Sky;
        let knobs = MarchKnobs {
            samples_per_ray: 24,
            termination: 1e-4,
            skip_empty: false,
        };
        let weights = DVec3::new(0.7, -0.2, 0.4);
        let field = small_field(2);
        let mut rng = Pcg32::new(9, 1);
        let sky = Sky::new(
            8,
            4,
            (0..32)
                .map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), 2.0 * rng.next_f64()))
                .collect(),
        )
        .unwrap();
        let mut checked = 0;
        for (o, d) in [
            (DVec3::new(-2.0, 0.1, -1.5), DVec3::new(1.0, 0.05, 0.8)),
            (DVec3::new(0.2, 2.0, 0.3), DVec3::new(-0.1, -1.0, 0.2)),
            (DVec3::new(5.0, 5.0, 5.0), DVec3::new(0.3, 1.0, -0.2)),
        ] {
            let ray = Ray {
                origin: o,
                dir: d.normalize(),
            };
            let r = render_ray_with_gradient(&field, &ray, &knobs, &sky, (0.0, None), |_| weights);
            let loss = |f: &GridField, s: &Sky| {
                render_ray_with_gradient(f, &ray, &knobs, s, (0.0, None), |_| weights)
                    .colour
                    .dot(weights)
            };
            assert!(!r.sky.is_empty());
            let h = 1e-5;
            for &(i, grad) in &r.sky {
                for (ch, &analytic) in grad.iter().enumerate() {
                    let eval = |delta: f64| {
                        let mut s = sky.clone();
                        s.texels[i][ch] += delta;
                        loss(&field, &s)
                    };
                    let numeric = (eval(h) - eval(-h)) / (2.0 * h);
                    assert!(
                        (numeric - analytic).abs() < 1e-8,
                        "texel {i} channel {ch}: {numeric} vs {analytic}"
                    );
                    checked += 1;
                }
            }
            for &(n, grad) in &r.values {
                let eval = |delta: f32| {
                    let mut f = field.clone();
                    f.nodes[n][3] += delta;
                    loss(&f, &sky)
                };
                let numeric = (eval(1e-4) - eval(-1e-4)) / 2e-4;
                assert!(
                    (numeric - grad[3]).abs() < 2e-3 * (1.0 + grad[3].abs()),
                    "node {n} density: {numeric} vs {}",
                    grad[3]
                );
            }
            if r.values.is_empty() {
                // Missed the box: the pixel is the sky along the ray.
                assert!((r.colour - sky.eval(ray.dir)).length() < 1e-12);
            }
        }
        assert!(checked >= 3 * 3 * 2, "{checked}");
    }

    /// The distortion loss is the double sum over the march's weights
    /// written out (O(N²), an independent form of the one-pass sums), and
    /// a ray whose weight sits in one thin shell scores far lower than one
    /// whose weight is spread through haze.
    #[test]
    fn the_distortion_loss_is_the_double_sum() {
        let knobs = MarchKnobs {
            samples_per_ray: 40,
            termination: 1e-4,
            skip_empty: false,
        };
        let field = small_field(4);
        let lambda = 0.6;
        let ray = Ray {
            origin: DVec3::new(-2.0, 0.1, -1.5),
            dir: DVec3::new(1.0, 0.05, 0.8).normalize(),
        };
        let mut s: Vec<(f64, f64, f64)> = Vec::new();
        crate::march::march_samples(&field, &ray, f64::INFINITY, &knobs, |m| {
            s.push((m.t, m.b - m.a, m.weight))
        });
        let mut expected = 0.0;
        for &(ti, di, wi) in &s {
            for &(tj, _, wj) in &s {
                expected += wi * wj * (ti - tj).abs();
            }
            expected += wi * wi * di / 3.0;
        }
        expected *= lambda / field.bounds.diagonal();
        let priors = (lambda, None);
        let r =
            render_ray_with_gradient(&field, &ray, &knobs, DVec3::ZERO, priors, |_| DVec3::ZERO);
        assert!(expected > 0.0);
        assert!(
            (r.distortion - expected).abs() < 1e-12 * (1.0 + expected),
            "{} vs {expected}",
            r.distortion
        );
        // The same opacity (1 − e^{−2}) in one node layer and spread over all.
        let slab = |thin: bool| {
            let res = UVec3::new(9, 2, 2);
            let bounds = Aabb::new(DVec3::ZERO, DVec3::new(8.0, 1.0, 1.0));
            let nodes = (0..res.x * res.y * res.z)
                .map(|n| {
                    let i = n % res.x;
                    let sigma = if !thin {
                        2.0 / 8.0
                    } else if i == 4 {
                        2.0
                    } else {
                        0.0
                    };
                    [1.0, 1.0, 1.0, sigma]
                })
                .collect();
            let f = GridField::new(res, bounds, nodes, 2);
            let ray = Ray {
                origin: DVec3::new(-1.0, 0.5, 0.5),
                dir: DVec3::X,
            };
            let priors = (1.0, None);
            let r =
                render_ray_with_gradient(&f, &ray, &knobs, DVec3::ZERO, priors, |_| DVec3::ZERO);
            (r.distortion, r.opacity)
        };
        let (thin, thin_opacity) = slab(true);
        let (haze, haze_opacity) = slab(false);
        assert!(
            (thin_opacity - haze_opacity).abs() < 0.1,
            "{thin_opacity} vs {haze_opacity}"
        );
        assert!(thin < 0.3 * haze, "shell {thin} vs haze {haze}");
    }

    /// The depth loss is μ/Diag times the march's weights' penalties plus
    /// the light past the bounds' at the exit, summed anew here from the
    /// march's own samples; and along a slab a thin shell at the recorded
    /// depth scores far lower than the same opacity in a haze, or in a
    /// shell two nodes in front.
    #[test]
    fn the_depth_loss_is_the_weights_penalties() {
        let knobs = MarchKnobs {
            samples_per_ray: 40,
            termination: 1e-4,
            skip_empty: false,
        };
        let field = small_field(4);
        let ray = Ray {
            origin: DVec3::new(-2.0, 0.1, -1.5),
            dir: DVec3::new(1.0, 0.05, 0.8).normalize(),
        };
        let term = depth_at_share(&field, &ray, 0.6, 1.5);
        let mut s: Vec<(f64, f64)> = Vec::new();
        crate::march::march_samples(&field, &ray, f64::INFINITY, &knobs, |m| {
            s.push((m.t, m.weight))
        });
        let m = crate::march::march_ray(&field, &ray, f64::INFINITY, &knobs);
        let (_, t1) = ray_box(&ray, &field.bounds).unwrap();
        let rho = |t: f64| depth_penalty(t - term.target, term.tolerance);
        let sum: f64 = s.iter().map(|&(t, w)| w * rho(t)).sum();
        let expected = term.weight / field.bounds.diagonal() * (sum + (1.0 - m.opacity) * rho(t1));
        let r =
            render_ray_with_gradient(&field, &ray, &knobs, DVec3::ZERO, (0.0, Some(term)), |_| {
                DVec3::ZERO
            });
        assert!(expected > 0.0);
        assert!(
            (r.depth - expected).abs() < 1e-12 * (1.0 + expected),
            "{} vs {expected}",
            r.depth
        );
        // Opacity 1 − e^{−4} in the layer of nodes at x = `at`, or spread
        // over all; the ray along x, the depth map's surface at `target`.
        let slab_field = |at: Option<u32>| {
            let res = UVec3::new(9, 2, 2);
            let bounds = Aabb::new(DVec3::ZERO, DVec3::new(8.0, 1.0, 1.0));
            let nodes = (0..res.x * res.y * res.z)
                .map(|n| {
                    let i = n % res.x;
                    let sigma = match at {
                        None => 4.0 / 8.0,
                        Some(k) if k == i => 4.0,
                        _ => 0.0,
                    };
                    [1.0, 1.0, 1.0, sigma]
                })
                .collect();
            GridField::new(res, bounds, nodes, 2)
        };
        let along = Ray {
            origin: DVec3::new(-1.0, 0.5, 0.5),
            dir: DVec3::X,
        };
        // Where the shell at x = 4 holds its weight on average.
        let (mut w_sum, mut wt_sum) = (0.0, 0.0);
        crate::march::march_samples(&slab_field(Some(4)), &along, f64::INFINITY, &knobs, |m| {
            w_sum += m.weight;
            wt_sum += m.weight * m.t;
        });
        let target = wt_sum / w_sum;
        assert!((target - 4.0).abs() < 1.0, "{target}");
        let slab = |at: Option<u32>| {
            let term = DepthTerm {
                target,
                weight: 1.0,
                tolerance: 0.1,
            };
            let priors = (0.0, Some(term));
            let f = slab_field(at);
            render_ray_with_gradient(&f, &along, &knobs, DVec3::ZERO, priors, |_| DVec3::ZERO).depth
        };
        let (at, ahead, haze) = (slab(Some(4)), slab(Some(2)), slab(None));
        assert!(at < 0.3 * ahead, "shell {at} vs two nodes in front {ahead}");
        assert!(at < 0.3 * haze, "shell {at} vs haze {haze}");
    }
}
