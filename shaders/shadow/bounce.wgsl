// The light an inserted object sends back onto the field in place of what
// it blocks (mirrors passes/src/shadow/bounce.rs bounce_parts): its
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

// The bounce at x in two parts (bounce.rs Bounce): `fixed`, the lobes'
// light from above x's plane, and `scaled`, from below it, which counts at
// x's own shadow ratio (the field around x, shadowed by the object too).
struct CastBounce {
    fixed: vec3<f32>,
    scaled: vec3<f32>,
}

fn cast_bounce_parts(x: vec3<f32>, n: vec3<f32>) -> CastBounce {
    var b = CastBounce(vec3<f32>(0.0), vec3<f32>(0.0));
    let to = ssdf_world_sphere().xyz - x;
    let dist = length(to);
    let r = ssdf_world_sphere().w;
    if dist <= 0.0 {
        return b;
    }
    let u = to / dist;
    let s = min(r / dist, 1.0);
    // The cap's projected solid angle over π, clipped at x's horizon.
    let projected = cone_projected_solid_angle(dot(n, u), s) / SG_PI;
    if projected <= 0.0 {
        return b;
    }
    let facing = sg_clamped_cosine(-u);
    for (var k = 0u; k < pc.light_count; k++) {
        let p = sg_product(sg_unpack(light_lobes[2u * k], light_lobes[2u * k + 1u]), facing);
        let light = sg_integral(p);
        let share = bounce_below_share(p, n);
        b.fixed += light * (1.0 - share);
        b.scaled += light * share;
    }
    let scale = projected * ssdf.reflectance.rgb;
    return CastBounce(scale * b.fixed, scale * b.scaled);
}

// The bounce at shadow ratio `below` (bounce.rs Bounce::at).
fn cast_bounce_at(b: CastBounce, below: vec3<f32>) -> vec3<f32> {
    return b.fixed + b.scaled * below;
}

// The least the bounce can be at any ratio from `lowest` to 1, never below
// zero (bounce.rs Bounce::least).
fn cast_bounce_least(b: CastBounce, lowest: vec3<f32>) -> vec3<f32> {
    return max(b.fixed + min(b.scaled * lowest, b.scaled), vec3<f32>(0.0));
}

// What the object can block at most, `most`, of a point's light `total`,
// less the least it sends back there (the ratio is at least 1 − most /
// total; bounce.rs Bounce::net).
fn cast_bounce_net(b: CastBounce, most: vec3<f32>, total: vec3<f32>) -> vec3<f32> {
    let lowest = clamp(vec3<f32>(1.0) - most / max(total, vec3<f32>(1e-30)), vec3<f32>(0.0), vec3<f32>(1.0));
    return max(most - cast_bounce_least(b, lowest), vec3<f32>(0.0));
}
