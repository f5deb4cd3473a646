//! The march's quadrature along one ray and its gradient with respect to
//! the grid's nodes (f64 CPU reference).
//!
//! Samples sit at the midpoints of steps of Δ = diagonal / samples_per_ray
//! from where the ray enters the bounds, as in [`crate::march::march_ray`]
//! (without empty-space skipping: what the trainer has not yet learnt is
//! not empty); each reads (c_i, σ_i) trilinearly. With α_i = 1 − e^{−σ_iΔ_i}
//! and T_{i+1} = T_i(1 − α_i), the pixel is
//! C = Σ_i T_i α_i c_i + T_N·b (b the background behind the field), and
//! ∂C/∂c_i = T_i α_i,
//! ∂C/∂σ_i = Δ_i·(T_{i+1} c_i − Σ_{j>i} T_j α_j c_j − T_N b).
//! The backward pass walks the ray once more with the running sum
//! Σ_{j≤i}, so that Σ_{j>i} = C − Σ_{j≤i} (Plenoxels' scheme). The march
//! stops where T falls under the termination threshold; the gradient
//! treats that stop as fixed.
//!
//! With view-dependent colour, c_i = max(0, base_i + Σ_k Y_k(d)·s_{k,i})
//! (`crate::field::sh_basis`): ∂C/∂base_i = T_i α_i and ∂C/∂s_{k,i} =
//! T_i α_i Y_k(d) in each channel where the sum is positive, zero where
//! the clamp holds.

use glam::DVec3;

use crate::field::{sh_basis, sh_colour_unclamped, GridField, RadianceField};
use crate::geometry::{ray_box, Ray};
use crate::march::MarchKnobs;

/// One ray's pixel and the gradient of a loss with respect to the nodes it
/// read.
#[derive(Debug, Clone, PartialEq)]
pub struct RayGradient {
    /// The pixel C (background included).
    pub colour: DVec3,
    /// Opacity 1 − T_N.
    pub opacity: f64,
    /// ∂loss/∂value for each value the ray read, indexed as the device
    /// holds the field (`crate::field::device_values`): a node n as
    /// (n, [r, g, b, σ]), its further colour coefficient k as
    /// (N + n·K + k, [r, g, b, 0]).
    pub values: Vec<(usize, [f64; 4])>,
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

/// Renders `ray` through `field` over `background` and, given the loss's
/// gradient with respect to the pixel as `d_colour(C)`, returns the pixel
/// and the gradient with respect to the nodes.
pub fn render_ray_with_gradient(
    field: &GridField,
    ray: &Ray,
    knobs: &MarchKnobs,
    background: DVec3,
    d_colour: impl Fn(DVec3) -> DVec3,
) -> RayGradient {
    let steps = samples(field, ray, knobs);
    // Forward.
    let mut colour = DVec3::ZERO;
    let mut transmittance = 1.0;
    let mut used = 0;
    for &(t, dt) in &steps {
        let (sigma, c) = field.sample(ray.at(t), ray.dir);
        let alpha = 1.0 - (-sigma * dt).exp();
        colour += transmittance * alpha * c;
        transmittance *= 1.0 - alpha;
        used += 1;
        if transmittance < knobs.termination {
            break;
        }
    }
    let total = colour + transmittance * background;
    let g = d_colour(total);
    // Backward: walk again with the running sum.
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
        let alpha = 1.0 - (-v[3] * dt).exp();
        let w = t_i * alpha;
        let t_next = t_i * (1.0 - alpha);
        so_far += w * c;
        let d_c = g * w * open;
        let d_sigma = dt * g.dot(t_next * c - (colour - so_far) - transmittance * background);
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
        opacity: 1.0 - transmittance,
        values: grads,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::rng::Pcg32;
    use glam::UVec3;

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
                    (3.0 * rng.next_f64() * rng.next_f64()) as f32,
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

    /// The pixel equals the march's (no skipping, black background), and
    /// the gradient of a weighted sum of the pixel matches central
    /// differences of the rendered pixel in every value it reads, density,
    /// colour and (degrees 1 and 2) the view-dependent coefficients, over a
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
        for degree in 0..=crate::field::MAX_SH_DEGREE {
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
                let black =
                    render_ray_with_gradient(&field, &ray, &knobs, DVec3::ZERO, |_| weights);
                let march = crate::march::march_ray(&field, &ray, f64::INFINITY, &knobs);
                assert!((black.colour - march.colour).length() < 1e-12);
                assert!((black.opacity - march.opacity).abs() < 1e-12);
                let r = render_ray_with_gradient(&field, &ray, &knobs, bg, |_| weights);
                assert!(!r.values.is_empty());
                for &(n, grad) in &r.values {
                    for (ch, &analytic) in grad.iter().enumerate() {
                        if n >= first && ch == 3 {
                            assert_eq!(analytic, 0.0);
                            continue;
                        }
                        let h = 1e-4;
                        let eval = |delta: f32| {
                            let mut f = field.clone();
                            if n < first {
                                f.nodes[n][ch] += delta;
                            } else {
                                f.sh[n - first][ch] += delta;
                            }
                            render_ray_with_gradient(&f, &ray, &knobs, bg, |_| weights)
                                .colour
                                .dot(weights)
                        };
                        let numeric = (eval(h as f32) - eval(-h as f32)) / (2.0 * h);
                        // f32 values: the perturbation is exact only to ~1e-7.
                        assert!(
                            (numeric - analytic).abs() < 2e-3 * (1.0 + analytic.abs()),
                            "degree {degree} value {n} channel {ch}: {numeric} vs {analytic}"
                        );
                        checked += 1;
                    }
                }
            }
            assert!(checked > 100 * (1 + degree as usize), "{checked}");
        }
    }
}
