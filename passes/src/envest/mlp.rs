//! The albedo a(x; Θ_a) of the Lambertian model (METHOD.md eq. 3): a
//! 6-layer MLP, as the paper, on a Fourier encoding of the position
//! normalised to the field's box, ReLU between layers and a sigmoid on the
//! RGB output (albedo stays in (0, 1)). Forward and backward by hand; the
//! parameters are one flat vector for [`super::adam::Adam`].
//!
//! The encoding's octaves are opened coarse to fine ([`AlbedoMlp::set_band`],
//! as in BARF's annealed encoding): while only low octaves are open the
//! albedo cannot follow the sharp brightness changes of shadows, so the
//! light has to explain them first.

use glam::DVec3;

use crate::geometry::Aabb;
use crate::rng::Pcg32;

/// Linear layers of the MLP (paper: 6).
pub const ALBEDO_LAYERS: usize = 6;

/// A small fully connected network from position to albedo.
#[derive(Debug, Clone)]
pub struct AlbedoMlp {
    /// Every weight and bias, layer by layer (weights row-major out × in,
    /// then biases).
    pub params: Vec<f64>,
    sizes: Vec<usize>,
    frequencies: u32,
    bounds: Aabb,
    band: f64,
}

/// What the backward pass needs from a forward pass.
#[derive(Debug, Clone)]
pub struct MlpTrace {
    /// Inputs of each layer (after the previous activation).
    activations: Vec<Vec<f64>>,
    /// The albedo returned.
    pub albedo: DVec3,
}

impl AlbedoMlp {
    /// A network with hidden layers `width` wide on `frequencies` octaves
    /// of encoding, He-initialised from `seed`.
    pub fn new(bounds: Aabb, width: usize, frequencies: u32, seed: u64) -> Self {
        let input = 3 + 6 * frequencies as usize;
        let mut sizes = vec![input];
        sizes.extend(std::iter::repeat_n(width, ALBEDO_LAYERS - 1));
        sizes.push(3);
        let mut rng = Pcg32::new(seed, 0x00A1_BED0);
        let mut params = Vec::new();
        for l in 0..ALBEDO_LAYERS {
            let (i, o) = (sizes[l], sizes[l + 1]);
            // The last layer starts at zero: the albedo starts a uniform ½,
            // so the first steps explain shading by light, not albedo.
            let limit = if l + 1 == ALBEDO_LAYERS {
                0.0
            } else {
                (6.0 / i as f64).sqrt()
            };
            params.extend((0..i * o).map(|_| limit * (2.0 * rng.next_f64() - 1.0)));
            params.extend(std::iter::repeat_n(0.0, o));
        }
        Self {
            params,
            sizes,
            frequencies,
            bounds,
            band: frequencies as f64,
        }
    }

    /// Opens the encoding's octaves up to `band` (0: only the position;
    /// octave k is weighted (1 − cos(π·clamp(band − k, 0, 1)))/2).
    pub fn set_band(&mut self, band: f64) {
        self.band = band.clamp(0.0, self.frequencies as f64);
    }

    /// The number of encoding octaves.
    pub fn frequencies(&self) -> u32 {
        self.frequencies
    }

    /// The position encoding: x in [−1, 1]³, then sin and cos of 2^k·π·x.
    fn encode(&self, x: DVec3) -> Vec<f64> {
        let p = 2.0 * (x - self.bounds.min) / self.bounds.size() - DVec3::ONE;
        let mut e = vec![p.x, p.y, p.z];
        for k in 0..self.frequencies {
            let f = std::f64::consts::PI * (1u64 << k) as f64;
            let open = (self.band - k as f64).clamp(0.0, 1.0);
            let w = 0.5 * (1.0 - (std::f64::consts::PI * open).cos());
            for c in [p.x, p.y, p.z] {
                e.push(w * (f * c).sin());
                e.push(w * (f * c).cos());
            }
        }
        e
    }

    /// a(x), with what [`Self::backward`] needs.
    pub fn forward(&self, x: DVec3) -> MlpTrace {
        let mut a = self.encode(x);
        let mut activations = Vec::with_capacity(ALBEDO_LAYERS);
        let mut offset = 0;
        for l in 0..ALBEDO_LAYERS {
            let (i, o) = (self.sizes[l], self.sizes[l + 1]);
            let w = &self.params[offset..offset + i * o];
            let b = &self.params[offset + i * o..offset + i * o + o];
            let mut z: Vec<f64> = (0..o)
                .map(|r| {
                    b[r] + w[r * i..(r + 1) * i]
                        .iter()
                        .zip(&a)
                        .map(|(w, a)| w * a)
                        .sum::<f64>()
                })
                .collect();
            if l + 1 < ALBEDO_LAYERS {
                z.iter_mut().for_each(|v| *v = v.max(0.0));
            } else {
                z.iter_mut().for_each(|v| *v = 1.0 / (1.0 + (-*v).exp()));
            }
            activations.push(std::mem::replace(&mut a, z));
            offset += i * o + o;
        }
        MlpTrace {
            albedo: DVec3::new(a[0], a[1], a[2]),
            activations,
        }
    }

    /// Adds ∂loss/∂params to `grad` given ∂loss/∂albedo.
    pub fn backward(&self, trace: &MlpTrace, d_albedo: DVec3, grad: &mut [f64]) {
        let a = trace.albedo;
        // Through the sigmoid: σ' = σ(1 − σ).
        let mut delta: Vec<f64> = [
            d_albedo.x * a.x * (1.0 - a.x),
            d_albedo.y * a.y * (1.0 - a.y),
            d_albedo.z * a.z * (1.0 - a.z),
        ]
        .to_vec();
        let mut offsets = Vec::with_capacity(ALBEDO_LAYERS);
        let mut offset = 0;
        for l in 0..ALBEDO_LAYERS {
            offsets.push(offset);
            offset += self.sizes[l] * self.sizes[l + 1] + self.sizes[l + 1];
        }
        for l in (0..ALBEDO_LAYERS).rev() {
            let (i, o) = (self.sizes[l], self.sizes[l + 1]);
            let off = offsets[l];
            let input = &trace.activations[l];
            for r in 0..o {
                let d = delta[r];
                if d == 0.0 {
                    continue;
                }
                let row = &mut grad[off + r * i..off + (r + 1) * i];
                row.iter_mut().zip(input).for_each(|(g, x)| *g += d * x);
                grad[off + i * o + r] += d;
            }
            if l == 0 {
                break;
            }
            let w = &self.params[off..off + i * o];
            delta = (0..i)
                .map(|c| {
                    if input[c] <= 0.0 {
                        0.0
                    } else {
                        (0..o).map(|r| w[r * i + c] * delta[r]).sum()
                    }
                })
                .collect();
        }
    }
}
