// Angles between unit vectors for the SSDF shaders, mirroring
// passes/src/ssdf/silhouette.rs (angle_between, chord2_to_arc,
// angle_of_chord2).

const SSDF_PI: f32 = 3.14159265358979;

// atan2(|u × v|, u·v): accurate near 0 and π.
fn ssdf_angle_between(u: vec3<f32>, v: vec3<f32>) -> f32 {
    return atan2(length(cross(u, v)), dot(u, v));
}

// An arc a → b (unit ends) prepared once for ssdf_arc_chord2, as four
// vec4s: (a, m.x), (b, m.y), (n, m.z), (q, 1), with n the unit normal of
// its great circle, m = n × a and q = b × n the normals of the planes
// that bound it; the last w is 0 (and n, m, q zero) when the arc has no
// great circle (a and b equal or opposite), and then only its ends count.
fn ssdf_prepare_arc(a: vec3<f32>, b: vec3<f32>) -> array<vec4<f32>, 4> {
    let n_raw = cross(a, b);
    let len = length(n_raw);
    if len < 1e-7 || dot(a, b) < -1.0 + 1e-6 {
        return array<vec4<f32>, 4>(vec4<f32>(a, 0.0), vec4<f32>(b, 0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    }
    let n = n_raw / len;
    let m = cross(n, a);
    return array<vec4<f32>, 4>(vec4<f32>(a, m.x), vec4<f32>(b, m.y), vec4<f32>(n, m.z), vec4<f32>(cross(b, n), 1.0));
}

// The squared chord from unit d to the nearest point of a prepared arc
// (ssdf_prepare_arc), in two parts a caller keeps the smaller of over
// many arcs: x, the squared chord to the nearer end; y, where d's
// projection falls within the arc, (d·n)², the squared sine of its angle
// to the great circle (else 2, above any sine). ssdf_chord2_of gives the
// chord from the two minima (the chord grows with the sine, so the
// minimum of one is that of the other): the per-arc work is dot products
// alone. Mirrors chord2_to_arc (passes/src/ssdf/silhouette.rs): the chord
// grows with the angle, is accurate near 0 and needs no inverse
// trigonometry.
fn ssdf_arc_chord2(d: vec3<f32>, p0: vec4<f32>, p1: vec4<f32>, p2: vec4<f32>, p3: vec4<f32>) -> vec2<f32> {
    let da = d - p0.xyz;
    let db = d - p1.xyz;
    let ends = min(dot(da, da), dot(db, db));
    let within = p3.w != 0.0 && dot(d, vec3<f32>(p0.w, p1.w, p2.w)) >= 0.0 && dot(d, p3.xyz) >= 0.0;
    let s = dot(d, p2.xyz);
    return vec2<f32>(ends, select(2.0, s * s, within));
}

// ssdf_arc_chord2 for four directions at once, their components in
// vec4s (dx, dy, dz): the two parts of each, x in .0 and y in .1.
struct SsdfChords4 {
    ends: vec4<f32>,
    sines: vec4<f32>,
}

fn ssdf_arc_chord2_4(dx: vec4<f32>, dy: vec4<f32>, dz: vec4<f32>, p0: vec4<f32>, p1: vec4<f32>, p2: vec4<f32>, p3: vec4<f32>) -> SsdfChords4 {
    let ax = dx - p0.x;
    let ay = dy - p0.y;
    let az = dz - p0.z;
    let bx = dx - p1.x;
    let by = dy - p1.y;
    let bz = dz - p1.z;
    let ends = min(ax * ax + ay * ay + az * az, bx * bx + by * by + bz * bz);
    let after_a = dx * p0.w + dy * p1.w + dz * p2.w >= vec4<f32>(0.0);
    let before_b = dx * p3.x + dy * p3.y + dz * p3.z >= vec4<f32>(0.0);
    let within = after_a & before_b & vec4<bool>(p3.w != 0.0);
    let s = dx * p2.x + dy * p2.y + dz * p2.z;
    return SsdfChords4(ends, select(vec4<f32>(2.0), s * s, within));
}

// The squared chord from the minima of ssdf_arc_chord2's two parts.
fn ssdf_chord2_of(m: vec2<f32>) -> f32 {
    if m.y > 1.0 {
        return m.x;
    }
    return min(m.x, 2.0 * m.y / (1.0 + sqrt(max(1.0 - m.y, 0.0))));
}

// The angle whose squared chord is c (0..=4): 2 asin(√c / 2), written with
// atan2, which devices evaluate more precisely than asin.
fn ssdf_angle_of_chord2(c: f32) -> f32 {
    let h = min(0.5 * sqrt(max(c, 0.0)), 1.0);
    return 2.0 * atan2(h, sqrt(max(1.0 - h * h, 0.0)));
}
