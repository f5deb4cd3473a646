// The near-field irradiance's ray set, mirroring
// passes/src/envest/hemisphere.rs: ray i of N from a point is the Hammersley
// point ((i + ½)/N, radical inverse of i) shifted by the point's random
// offset (a hash of its index and the seed), mapped to a cosine-distributed
// direction about the normal in Duff et al.'s orthonormal frame.
// Needs: common/tangent_basis.wgsl.

const HS_PI: f32 = 3.14159265358979;
const HS_TWO_POW_32: f32 = 4294967296.0;

fn hs_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn hs_point_rotation(point: u32, seed: u32) -> vec2<f32> {
    let a = hs_hash((point * 2u) ^ seed);
    let b = hs_hash((point * 2u + 1u) ^ seed);
    return vec2<f32>(f32(a) / HS_TWO_POW_32, f32(b) / HS_TWO_POW_32);
}

fn hs_hammersley(i: u32, n: u32, rotation: vec2<f32>) -> vec2<f32> {
    let u = (f32(i) + 0.5) / f32(n) + rotation.x;
    let v = f32(reverseBits(i)) / HS_TWO_POW_32 + rotation.y;
    return fract(vec2<f32>(u, v));
}

fn hs_cosine_direction(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let frame = tangent_basis(n);
    let r = sqrt(u.x);
    let phi = 2.0 * HS_PI * u.y;
    return (r * cos(phi)) * frame.t1 + (r * sin(phi)) * frame.t2 + sqrt(max(1.0 - u.x, 0.0)) * n;
}

fn hs_ray_direction(normal: vec3<f32>, point: u32, seed: u32, i: u32, n: u32) -> vec3<f32> {
    return hs_cosine_direction(normal, hs_hammersley(i, n, hs_point_rotation(point, seed)));
}
