// Points spread evenly over the unit sphere (a Fibonacci lattice, +Y up),
// mirroring passes/src/sgfit/model.rs fibonacci_axis.

// Axis k of m Fibonacci-lattice points.
fn fibonacci_axis(k: u32, m: u32) -> vec3<f32> {
    let y = 1.0 - (2.0 * f32(k) + 1.0) / f32(m);
    let r = sqrt(max(1.0 - y * y, 0.0));
    // Golden angle π(3 − √5); the product is reduced mod 2π first to keep
    // f32 accuracy for large k.
    let phi = (f32(k) * 2.39996322972865332) % 6.28318530717958648;
    return vec3<f32>(r * cos(phi), y, r * sin(phi));
}
