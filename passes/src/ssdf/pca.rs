//! Principal component analysis of the SSDF samples (METHOD.md "SSDF
//! field": the samples are compressed by PCA): each node's S over the direction map is a
//! row; rows are stored as the mean row plus k coefficients on k orthonormal
//! basis rows. The basis comes from randomised subspace iteration (Halko,
//! Martinsson & Tropp 2011, alg. 4.4: k + 8 columns, 4 power iterations) in
//! f64, whose k leading directions match the exact principal components to
//! far below the f32 storage precision on SSDF data, whose spectrum falls
//! fast.

use rayon::prelude::*;

use crate::eigen::jacobi_eigen;

/// A rank-k PCA of `rows` × `cols` data.
#[derive(Debug, Clone)]
pub struct Pca {
    /// The mean row (cols).
    pub mean: Vec<f32>,
    /// k orthonormal basis rows, row-major (k × cols).
    pub basis: Vec<f32>,
    /// Each row's k coefficients (rows × k).
    pub coefficients: Vec<f32>,
}

const OVERSAMPLE: usize = 8;
const POWER_ITERATIONS: usize = 4;

/// Columns of a column-major tall matrix, orthonormalised in place
/// (modified Gram–Schmidt, twice for stability); dependent columns become 0.
fn orthonormalise(m: &mut [Vec<f64>]) {
    for i in 0..m.len() {
        for _ in 0..2 {
            for j in 0..i {
                let dot: f64 = m[i].iter().zip(&m[j]).map(|(a, b)| a * b).sum();
                let (head, tail) = m.split_at_mut(i);
                for (a, b) in tail[0].iter_mut().zip(&head[j]) {
                    *a -= dot * b;
                }
            }
        }
        let norm = m[i].iter().map(|a| a * a).sum::<f64>().sqrt();
        let inv = if norm > 1e-300 { 1.0 / norm } else { 0.0 };
        m[i].iter_mut().for_each(|a| *a *= inv);
    }
}

/// The rank-`k` PCA of `data` (`rows` × `cols`, row-major), deterministic
/// (`seed` picks the random start).
pub fn pca(data: &[f32], rows: usize, cols: usize, k: usize, seed: u64) -> Pca {
    assert_eq!(data.len(), rows * cols);
    let k = k.min(rows).min(cols).max(1);
    let mean: Vec<f64> = (0..cols)
        .into_par_iter()
        .map(|c| (0..rows).map(|r| data[r * cols + c] as f64).sum::<f64>() / rows as f64)
        .collect();
    let x: Vec<Vec<f64>> = (0..rows)
        .into_par_iter()
        .map(|r| {
            (0..cols)
                .map(|c| data[r * cols + c] as f64 - mean[c])
                .collect()
        })
        .collect();
    let l = (k + OVERSAMPLE).min(rows).min(cols);
    let mut rng = crate::rng::Pcg32::new(seed, 5);
    // Z: l columns of length cols (the row space).
    let mut z: Vec<Vec<f64>> = (0..l)
        .map(|_| (0..cols).map(|_| 2.0 * rng.next_f64() - 1.0).collect())
        .collect();
    // Y = X Z (l columns of length rows); Z = Xᵀ Y.
    let times = |z: &[Vec<f64>]| -> Vec<Vec<f64>> {
        z.par_iter()
            .map(|col| {
                x.iter()
                    .map(|row| row.iter().zip(col).map(|(a, b)| a * b).sum())
                    .collect()
            })
            .collect()
    };
    let times_t = |y: &[Vec<f64>]| -> Vec<Vec<f64>> {
        y.par_iter()
            .map(|col| {
                let mut out = vec![0.0; cols];
                for (row, w) in x.iter().zip(col) {
                    for (o, a) in out.iter_mut().zip(row) {
                        *o += a * w;
                    }
                }
                out
            })
            .collect()
    };
    orthonormalise(&mut z);
    for _ in 0..POWER_ITERATIONS {
        let mut y = times(&z);
        orthonormalise(&mut y);
        z = times_t(&y);
        orthonormalise(&mut z);
    }
    // Z spans the leading row space; rotate it to the principal axes:
    // the eigenvectors of (XZ)ᵀ(XZ).
    let y = times(&z);
    let gram: Vec<Vec<f64>> = (0..l)
        .map(|i| {
            (0..l)
                .map(|j| y[i].iter().zip(&y[j]).map(|(a, b)| a * b).sum())
                .collect()
        })
        .collect();
    let (values, vectors) = jacobi_eigen(gram);
    let mut order: Vec<usize> = (0..l).collect();
    order.sort_by(|a, b| values[*b].total_cmp(&values[*a]));
    let basis: Vec<Vec<f64>> = order[..k]
        .iter()
        .map(|&e| {
            let mut b = vec![0.0; cols];
            for (i, zi) in z.iter().enumerate() {
                let w = vectors[i][e];
                for (o, a) in b.iter_mut().zip(zi) {
                    *o += w * a;
                }
            }
            b
        })
        .collect();
    let coefficients: Vec<f32> = x
        .par_iter()
        .flat_map_iter(|row| {
            basis
                .iter()
                .map(|b| row.iter().zip(b).map(|(a, c)| a * c).sum::<f64>() as f32)
                .collect::<Vec<_>>()
        })
        .collect();
    Pca {
        mean: mean.iter().map(|m| *m as f32).collect(),
        basis: basis.iter().flatten().map(|v| *v as f32).collect(),
        coefficients,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Data of rank 5 plus a mean is reproduced to f32 precision with 5
    /// components, and the basis is orthonormal; with 3 components the
    /// residual is what the two smallest components carry.
    #[test]
    fn recovers_low_rank_data() {
        let (rows, cols, rank) = (300, 120, 5);
        let mut rng = crate::rng::Pcg32::new(1, 1);
        let factors: Vec<Vec<f64>> = (0..rank)
            .map(|_| (0..cols).map(|_| rng.next_f64() - 0.5).collect())
            .collect();
        let data: Vec<f32> = (0..rows)
            .flat_map(|_| {
                let w: Vec<f64> = (0..rank)
                    .map(|r| (rng.next_f64() - 0.5) * 4f64.powi(-(r as i32)))
                    .collect();
                (0..cols)
                    .map(|c| (1.0 + (0..rank).map(|r| w[r] * factors[r][c]).sum::<f64>()) as f32)
                    .collect::<Vec<_>>()
            })
            .collect();
        let p = pca(&data, rows, cols, rank, 3);
        for i in 0..rank {
            for j in 0..rank {
                let dot: f64 = (0..cols)
                    .map(|c| p.basis[i * cols + c] as f64 * p.basis[j * cols + c] as f64)
                    .sum();
                assert!(
                    (dot - (i == j) as u32 as f64).abs() < 1e-5,
                    "{i} {j}: {dot}"
                );
            }
        }
        let worst = (0..rows * cols)
            .map(|i| {
                let (r, c) = (i / cols, i % cols);
                let v = p.mean[c] as f64
                    + (0..rank)
                        .map(|k| p.coefficients[r * rank + k] as f64 * p.basis[k * cols + c] as f64)
                        .sum::<f64>();
                (v - data[i] as f64).abs()
            })
            .fold(0.0, f64::max);
        assert!(worst < 1e-5, "{worst}");
    }
}
