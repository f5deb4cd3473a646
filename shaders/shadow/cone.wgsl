// The light the object can block at a point, integrated over its
// bounding sphere's cone (passes/src/shadow/cone.rs ConeQuadrature, which
// explains the quadrature): CONE_POINTS directions spread evenly over the
// cone's solid angle, each weighted by the clamped cosine at the point's
// normal and the covered solid angle's share; a lobe sharper than the
// points resolve (λ Ω / N > CONE_RESOLUTION) gets no bound from it. The
// weights are scaled to sum to the cone's horizon-clipped projected solid
// angle (its closed form) times the covered share.
// Needs: CastSphere (shadow/cast_body.wgsl), common/sg.wgsl; defines
// CONE_POINTS, CONE_RESOLUTION.

struct CastCone {
    directions: array<vec3<f32>, CONE_POINTS>,
    weights: array<f32, CONE_POINTS>,
    // The whole cone's solid angle 2π(1 − cos β).
    solid: f32,
}

const CONE_GOLDEN_ANGLE: f32 = 2.39996322972865;

// The cone of `v` (not inside the sphere) for a point of unit normal `n`.
fn cast_cone(v: CastSphere, n: vec3<f32>) -> CastCone {
    var cone: CastCone;
    let u = v.u;
    var t = vec3<f32>(1.0, 0.0, 0.0);
    if abs(u.x) > 0.9 {
        t = vec3<f32>(0.0, 1.0, 0.0);
    }
    let a = normalize(cross(u, t));
    let b = cross(u, a);
    let per = v.covered_solid / f32(CONE_POINTS);
    for (var i = 0u; i < CONE_POINTS; i++) {
        let xi = (f32(i) + 0.5) / f32(CONE_POINTS);
        let c = 1.0 - xi * (1.0 - v.cos_beta);
        let s = sqrt(max(1.0 - c * c, 0.0));
        let phi = f32(i) * CONE_GOLDEN_ANGLE;
        let d = u * c + (a * cos(phi) + b * sin(phi)) * s;
        cone.directions[i] = d;
        cone.weights[i] = max(dot(d, n), 0.0) * per;
    }
    cone.solid = 2.0 * SG_PI * (1.0 - v.cos_beta);
    var sum = 0.0;
    for (var i = 0u; i < CONE_POINTS; i++) {
        sum += cone.weights[i];
    }
    if sum > 0.0 {
        let scale = v.covered_solid / cone.solid * cone_projected_solid_angle(dot(u, n), v.sin_beta) / sum;
        for (var i = 0u; i < CONE_POINTS; i++) {
            cone.weights[i] *= scale;
        }
    }
    return cone;
}

// ∫ (ω·n)₊ dω over a cone of angular radius β whose axis makes cos θ with
// n, clipped at the horizon (cone.rs projected_solid_angle).
fn cone_projected_solid_angle(cos_theta: f32, sin_beta: f32) -> f32 {
    let sin2 = sin_beta * sin_beta;
    if cos_theta * cos_theta >= sin2 {
        return SG_PI * sin2 * max(cos_theta, 0.0);
    }
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    let x = sqrt(max(1.0 / sin2 - 1.0, 0.0));
    let y = clamp(-x * cos_theta / max(sin_theta, 1e-30), -1.0, 1.0);
    let s = sin_theta * sqrt(max(1.0 - y * y, 0.0));
    let e = (cos_theta * acos(y) - x * s) * sin2 + atan(s / max(x, 1e-30));
    return max(e, 0.0);
}

// Whether the cone's points resolve lobe `g`.
fn cone_resolves(cone: ptr<function, CastCone>, g: Sg) -> bool {
    return g.sharpness * (*cone).solid / f32(CONE_POINTS) <= CONE_RESOLUTION;
}

// The cosine-weighted light of light lobe `g` over the cone's covered
// share (call where cone_resolves).
fn cone_blockable(cone: ptr<function, CastCone>, g: Sg) -> vec3<f32> {
    var sum = 0.0;
    for (var i = 0u; i < CONE_POINTS; i++) {
        sum += sg_weight(g, (*cone).directions[i]) * (*cone).weights[i];
    }
    return g.amplitude * sum;
}
