// Angles between unit vectors for the SSDF shaders, mirroring
// passes/src/ssdf/silhouette.rs (angle_between, chord2_to_arc,
// angle_of_chord2).

const SSDF_PI: f32 = 3.14159265358979;

// atan2(|u × v|, u·v): accurate near 0 and π.
fn ssdf_angle_between(u: vec3<f32>, v: vec3<f32>) -> f32 {
    return atan2(length(cross(u, v)), dot(u, v));
}

// The unit normal of the great circle through the arc a → b, or zero when
// the arc has none (a and b equal or opposite): what
// ssdf_chord2_to_arc takes, computed once per arc.
fn ssdf_arc_normal(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    let n_raw = cross(a, b);
    let len = length(n_raw);
    if len < 1e-7 || dot(a, b) < -1.0 + 1e-6 {
        return vec3<f32>(0.0);
    }
    return n_raw / len;
}

// The squared chord from unit d to the nearest point of the shorter
// great-circle arc a → b (normal n from ssdf_arc_normal): to the great
// circle where d's projection falls within the arc, else to the nearer
// end. The chord grows with the angle, is accurate near 0 and needs no
// inverse trigonometry.
fn ssdf_chord2_to_arc(d: vec3<f32>, a: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> f32 {
    let da = d - a;
    let db = d - b;
    let ends = min(dot(da, da), dot(db, db));
    if all(n == vec3<f32>(0.0)) {
        return ends;
    }
    if dot(d, cross(n, a)) >= 0.0 && dot(d, cross(b, n)) >= 0.0 {
        let s2 = dot(d, n) * dot(d, n);
        return min(ends, 2.0 * s2 / (1.0 + sqrt(max(1.0 - s2, 0.0))));
    }
    return ends;
}

// The angle whose squared chord is c (0..=4): 2 asin(√c / 2), written with
// atan2, which devices evaluate more precisely than asin.
fn ssdf_angle_of_chord2(c: f32) -> f32 {
    let h = min(0.5 * sqrt(max(c, 0.0)), 1.0);
    return 2.0 * atan2(h, sqrt(max(1.0 - h * h, 0.0)));
}
