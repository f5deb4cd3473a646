// The light an inserted object sends back onto the field in place of what
// it blocks (mirrors passes/src/shadow/bounce.rs bounce_irradiance): its
// bounding sphere's cap, filled and coloured by ssdf.reflectance, showing
// a Lambertian face turned towards x lit by the object's lobes (their
// irradiance on the normal towards x, through the clamped-cosine SG; the
// part from below x's plane at x's own shadow ratio), over the cap's
// projected solid angle clipped at x's horizon. Needs: common/sg.wgsl,
// shadow/cone.wgsl,
// ssdf/ssdf.wgsl's `ssdf` block, the lobes `light_lobes` and `pc.light_count`.

// The share of SG `p`'s energy from below the plane of normal `n`
// (bounce.rs below_share): Φ(−(p·n)√λ) by the logistic.
fn bounce_below_share(p: Sg, n: vec3<f32>) -> f32 {
    // The exponent is clamped where the share is 0 or 1 to f32 precision.
    return 1.0 / (1.0 + exp(clamp(1.702 * dot(p.direction, n) * sqrt(p.sharpness), -80.0, 80.0)));
}

// `below`: x's own shadow ratio, at which the lobes' light from below x's
// plane (the field around x, shadowed by the object too) counts.
fn cast_bounce(x: vec3<f32>, n: vec3<f32>, below: vec3<f32>) -> vec3<f32> {
    let to = ssdf_world_sphere().xyz - x;
    let dist = length(to);
    let r = ssdf_world_sphere().w;
    if dist <= 0.0 {
        return vec3<f32>(0.0);
    }
    let u = to / dist;
    let s = min(r / dist, 1.0);
    // The cap's projected solid angle over π, clipped at x's horizon.
    let projected = cone_projected_solid_angle(dot(n, u), s) / SG_PI;
    if projected <= 0.0 {
        return vec3<f32>(0.0);
    }
    let facing = sg_clamped_cosine(-u);
    var irradiance = vec3<f32>(0.0);
    for (var k = 0u; k < pc.light_count; k++) {
        let p = sg_product(sg_unpack(light_lobes[2u * k], light_lobes[2u * k + 1u]), facing);
        let share = bounce_below_share(p, n);
        irradiance += sg_integral(p) * (vec3<f32>(1.0 - share) + share * below);
    }
    return projected * ssdf.reflectance.rgb * irradiance;
}
