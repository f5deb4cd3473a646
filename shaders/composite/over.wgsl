// Premultiplied "over" (eq. 6), mirroring passes/src/composite/mod.rs:
// colour c + (1 − c.a)·v, coverage c.a + (1 − c.a)·v.a.
fn composite_over(front: vec4<f32>, back: vec4<f32>) -> vec4<f32> {
    return front + (1.0 - front.a) * back;
}

// The field's colour darkened by the cast-shadow factor ρ (its opacity kept).
fn composite_shade_field(field: vec4<f32>, rho: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(field.rgb * rho, field.a);
}

// The field over the object (eq. 6), or the object over the field where
// `object_front` (occlusion off).
fn composite_layer(field: vec4<f32>, object: vec4<f32>, object_front: bool) -> vec4<f32> {
    if object_front {
        return composite_over(object, field);
    }
    return composite_over(field, object);
}
