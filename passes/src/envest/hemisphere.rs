//! The ray set of the near-field irradiance estimate, one definition
//! mirrored by `shaders/envest/hemisphere.wgsl`: ray i of N from a point is
//! the Hammersley point ((i + ½)/N, radical inverse of i) shifted by the
//! point's own random offset (Cranley–Patterson rotation, from a hash of
//! the point's index and the seed), mapped to a cosine-distributed
//! direction about the normal in Duff et al.'s orthonormal frame.

use glam::DVec3;

use crate::sgfit::model::tangent_basis;

/// PCG's 32-bit output hash (the shader's `hs_hash`).
pub fn hash_u32(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The random offset in [0, 1)² of point `point` for `seed`.
pub fn point_rotation(point: u32, seed: u32) -> [f64; 2] {
    let a = hash_u32(point.wrapping_mul(2) ^ seed);
    let b = hash_u32(point.wrapping_mul(2).wrapping_add(1) ^ seed);
    [a as f64 / 4_294_967_296.0, b as f64 / 4_294_967_296.0]
}

/// The rotated Hammersley point i of n.
pub fn hammersley(i: u32, n: u32, rotation: [f64; 2]) -> [f64; 2] {
    let u = (i as f64 + 0.5) / n as f64 + rotation[0];
    let v = i.reverse_bits() as f64 / 4_294_967_296.0 + rotation[1];
    [u.fract(), v.fract()]
}

/// The cosine-distributed direction about unit `n` for `u` ∈ [0, 1)²
/// (density cos θ/π).
pub fn cosine_direction(n: DVec3, u: [f64; 2]) -> DVec3 {
    let r = u[0].sqrt();
    let phi = 2.0 * std::f64::consts::PI * u[1];
    let (t, b) = tangent_basis(n);
    (r * phi.cos()) * t + (r * phi.sin()) * b + (1.0 - u[0]).max(0.0).sqrt() * n
}

/// Direction of ray `i` of `n` from point `point` with normal `normal`.
pub fn ray_direction(normal: DVec3, point: u32, seed: u32, i: u32, n: u32) -> DVec3 {
    cosine_direction(normal, hammersley(i, n, point_rotation(point, seed)))
}
