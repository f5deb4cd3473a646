// An orthonormal tangent basis of a unit vector (Duff et al. 2017,
// branchless; the sign of p.z picks the branch). Mirrors `tangent_basis` in
// passes/src/sgfit/model.rs.

struct Basis {
    t1: vec3<f32>,
    t2: vec3<f32>,
}

fn tangent_basis(p: vec3<f32>) -> Basis {
    let s = select(-1.0, 1.0, p.z >= 0.0);
    let a = -1.0 / (s + p.z);
    let b = p.x * p.y * a;
    return Basis(
        vec3<f32>(1.0 + s * p.x * p.x * a, s * b, -s * p.x),
        vec3<f32>(b, s + p.y * p.y * a, -p.y),
    );
}
