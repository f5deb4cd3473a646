//! Total variation over the grid: the sum over neighbouring node pairs of
//! their squared differences, per channel group weighted (colour, density).
//! It smooths what the views do not pin down, floaters above all. It is
//! applied as a plain gradient step after Adam's ([`tv_step`]): through
//! Adam, whose step is normalised per value, any weight moved the values no
//! ray reads by a full step. Mirrored by `shaders/train/tv.wgsl` (the
//! gradient) and `shaders/train/descend.wgsl` (the step).

use glam::UVec3;

/// The total variation of `nodes` (r, g, b, σ, x fastest) with weights for
/// colour and density.
pub fn tv_loss(nodes: &[[f32; 4]], res: UVec3, colour: f64, density: f64) -> f64 {
    let w = [colour, colour, colour, density];
    let idx = |i: u32, j: u32, k: u32| (i + res.x * (j + res.y * k)) as usize;
    let mut sum = 0.0;
    for k in 0..res.z {
        for j in 0..res.y {
            for i in 0..res.x {
                let v = nodes[idx(i, j, k)];
                let next = [
                    (i + 1 < res.x).then(|| idx(i + 1, j, k)),
                    (j + 1 < res.y).then(|| idx(i, j + 1, k)),
                    (k + 1 < res.z).then(|| idx(i, j, k + 1)),
                ];
                for m in next.into_iter().flatten() {
                    for c in 0..4 {
                        sum += w[c] * (v[c] as f64 - nodes[m][c] as f64).powi(2);
                    }
                }
            }
        }
    }
    sum
}

/// ∂[`tv_loss`]/∂node for every node.
pub fn tv_gradient(nodes: &[[f32; 4]], res: UVec3, colour: f64, density: f64) -> Vec<[f64; 4]> {
    let w = [colour, colour, colour, density];
    let idx = |i: u32, j: u32, k: u32| (i + res.x * (j + res.y * k)) as usize;
    let mut out = vec![[0.0; 4]; nodes.len()];
    for k in 0..res.z {
        for j in 0..res.y {
            for i in 0..res.x {
                let n = idx(i, j, k);
                let v = nodes[n];
                let c = [i, j, k];
                for a in 0..3 {
                    for d in [-1i64, 1] {
                        let mut m = c.map(|x| x as i64);
                        m[a] += d;
                        let r = [res.x, res.y, res.z][a] as i64;
                        if m[a] < 0 || m[a] >= r {
                            continue;
                        }
                        let q = nodes[idx(m[0] as u32, m[1] as u32, m[2] as u32)];
                        for ch in 0..4 {
                            out[n][ch] += 2.0 * w[ch] * (v[ch] as f64 - q[ch] as f64);
                        }
                    }
                }
            }
        }
    }
    out
}

/// Largest weight for which the step is stable: a node has six neighbours,
/// so a step of weight w moves it by up to 12·w of its difference to them.
pub const MAX_TV_WEIGHT: f64 = 1.0 / 12.0;

/// One total-variation step over `nodes`: each value minus the gradient of
/// [`tv_loss`], the colours kept non-negative (a density may be negative:
/// [`crate::field::density_at`]).
pub fn tv_step(nodes: &mut [[f32; 4]], res: UVec3, colour: f64, density: f64) {
    let g = tv_gradient(nodes, res, colour, density);
    for (n, g) in nodes.iter_mut().zip(g) {
        for c in 0..3 {
            n[c] = (n[c] - g[c] as f32).max(0.0);
        }
        n[3] -= g[3] as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn the_tv_gradient_matches_finite_differences() {
        let res = UVec3::new(4, 3, 5);
        let mut rng = Pcg32::new(2, 2);
        let nodes: Vec<[f32; 4]> = (0..60)
            .map(|_| [0; 4].map(|_: i32| rng.next_f64() as f32))
            .collect();
        let g = tv_gradient(&nodes, res, 0.7, 2.0);
        for n in [0usize, 17, 59] {
            for c in 0..4 {
                let h = 1e-3f32;
                let mut a = nodes.clone();
                let mut b = nodes.clone();
                a[n][c] += h;
                b[n][c] -= h;
                let numeric =
                    (tv_loss(&a, res, 0.7, 2.0) - tv_loss(&b, res, 0.7, 2.0)) / (2.0 * h as f64);
                assert!(
                    (numeric - g[n][c]).abs() < 1e-3,
                    "{n} {c}: {numeric} vs {}",
                    g[n][c]
                );
            }
        }
    }
}
