// The light an inserted object sends back onto the field in place of what
// it blocks (mirrors passes/src/shadow/bounce.rs bounce_irradiance): its
// bounding sphere's cap, filled and coloured by ssdf.reflectance, showing
// a Lambertian face turned towards x lit by the object's lobes (their
// irradiance on the normal towards x, through the clamped-cosine SG). Needs: common/sg.wgsl,
// shadow/ssdf.wgsl's `ssdf` block, the lobes `light_lobes` and `pc.light_count`.

fn cast_bounce(x: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let to = ssdf.world_sphere.xyz - x;
    let dist = length(to);
    let r = ssdf.world_sphere.w;
    if dist <= 0.0 {
        return vec3<f32>(0.0);
    }
    let u = to / dist;
    let s = min(r / dist, 1.0);
    let projected = s * s * max(dot(n, u), 0.0);
    if projected <= 0.0 {
        return vec3<f32>(0.0);
    }
    let facing = sg_clamped_cosine(-u);
    var irradiance = vec3<f32>(0.0);
    for (var k = 0u; k < pc.light_count; k++) {
        irradiance += sg_inner_product(sg_unpack(light_lobes[2u * k], light_lobes[2u * k + 1u]), facing);
    }
    return projected * ssdf.reflectance.rgb * irradiance;
}
