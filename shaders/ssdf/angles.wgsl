// Angles between unit vectors for the SSDF shaders, mirroring
// passes/src/ssdf/silhouette.rs (angle_between, angle_to_arc).

const SSDF_PI: f32 = 3.14159265358979;

// atan2(|u × v|, u·v): accurate near 0 and π.
fn ssdf_angle_between(u: vec3<f32>, v: vec3<f32>) -> f32 {
    return atan2(length(cross(u, v)), dot(u, v));
}

// The smallest angle from unit d to the shorter great-circle arc a → b: to
// the great circle (atan2(|d·n|, |d × n|)) where d's projection falls
// within the arc, else to the nearer end.
fn ssdf_angle_to_arc(d: vec3<f32>, a: vec3<f32>, b: vec3<f32>) -> f32 {
    let ends = min(ssdf_angle_between(d, a), ssdf_angle_between(d, b));
    let n_raw = cross(a, b);
    let len = length(n_raw);
    if len < 1e-7 || dot(a, b) < -1.0 + 1e-6 {
        return ends;
    }
    let n = n_raw / len;
    if dot(cross(a, d), n) >= 0.0 && dot(cross(d, b), n) >= 0.0 {
        return min(atan2(abs(dot(d, n)), length(cross(d, n))), ends);
    }
    return ends;
}
