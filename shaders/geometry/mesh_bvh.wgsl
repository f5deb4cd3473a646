// Any-hit ray casts against a triangle mesh in a bounding-volume hierarchy,
// the f32 mirror of MeshScene::occluded (passes/src/geometry/mesh_bvh.rs), in
// the layout of MeshScene::packed: nodes as two vec4s (min, first as bits),
// (max, count as bits), count 0 for inner nodes whose children are first
// and first + 1; triangles as three vec4s (corners).
// Needs: storage buffers `bvh_nodes` and `bvh_triangles` (array<vec4<f32>>).

const BVH_STACK: u32 = 48u;

fn bvh_hits_triangle(o: vec3<f32>, d: vec3<f32>, t: u32) -> bool {
    let p0 = bvh_triangles[3u * t].xyz;
    let e1 = bvh_triangles[3u * t + 1u].xyz - p0;
    let e2 = bvh_triangles[3u * t + 2u].xyz - p0;
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if abs(det) < 1e-30 {
        return false;
    }
    let inv = 1.0 / det;
    let tv = o - p0;
    let u = dot(tv, pv) * inv;
    if u < 0.0 || u > 1.0 {
        return false;
    }
    let qv = cross(tv, e1);
    let v = dot(d, qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    return dot(e2, qv) * inv > 0.0;
}

// The ray's entry distance into node i's box, or -1 where it misses.
fn bvh_enter(i: u32, o: vec3<f32>, inv: vec3<f32>) -> f32 {
    let t0 = (bvh_nodes[2u * i].xyz - o) * inv;
    let t1 = (bvh_nodes[2u * i + 1u].xyz - o) * inv;
    let near = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), min(t0.z, t1.z));
    let far = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z));
    return select(-1.0, max(near, 0.0), far >= max(near, 0.0));
}

// Whether the ray from `o` along unit `d` hits any triangle (t > 0). The
// children of a node are visited nearer first: the walk goes straight on
// into the nearer child the ray enters and keeps the farther one on the
// stack, so a step down touches the stack only where the ray enters both
// (on llvmpipe each lane's stack entry is a scattered store and load).
fn bvh_occluded(o: vec3<f32>, d: vec3<f32>) -> bool {
    if arrayLength(&bvh_triangles) < 3u {
        return false;
    }
    let safe = select(d, vec3<f32>(1e-30), abs(d) < vec3<f32>(1e-30));
    let inv = 1.0 / safe;
    if bvh_enter(0u, o, inv) < 0.0 {
        return false;
    }
    var stack: array<u32, BVH_STACK>;
    var sp = 0u;
    var i = 0u;
    loop {
        let first = bitcast<u32>(bvh_nodes[2u * i].w);
        let count = bitcast<u32>(bvh_nodes[2u * i + 1u].w);
        if count == 0u {
            let tl = bvh_enter(first, o, inv);
            let tr = bvh_enter(first + 1u, o, inv);
            let left_nearer = tl >= 0.0 && (tr < 0.0 || tl <= tr);
            if tl >= 0.0 || tr >= 0.0 {
                // The farther child waits on the stack where the ray enters
                // both (and the stack has room: past it, that child is
                // skipped, as a full stack always did).
                if tl >= 0.0 && tr >= 0.0 && sp < BVH_STACK {
                    stack[sp] = select(first, first + 1u, left_nearer);
                    sp += 1u;
                }
                i = select(first + 1u, first, left_nearer);
                continue;
            }
        } else {
            for (var k = first; k < first + count; k++) {
                if bvh_hits_triangle(o, d, k) {
                    return true;
                }
            }
        }
        if sp == 0u {
            break;
        }
        sp -= 1u;
        i = stack[sp];
    }
    return false;
}
