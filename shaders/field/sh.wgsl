// View-dependent colour: the real spherical harmonics of bands 1 and 2
// (Y_1 … Y_8) at a unit direction, in the order and normalisation of
// passes/src/field/sh.rs (which documents the colour model).

const SH_C1: f32 = 0.48860251;

fn sh_basis(d: vec3<f32>) -> array<f32, 8> {
    return array<f32, 8>(
        -SH_C1 * d.y,
        SH_C1 * d.z,
        -SH_C1 * d.x,
        1.09254843 * d.x * d.y,
        -1.09254843 * d.y * d.z,
        0.31539157 * (2.0 * d.z * d.z - d.x * d.x - d.y * d.y),
        -1.09254843 * d.x * d.z,
        0.54627422 * (d.x * d.x - d.y * d.y),
    );
}
