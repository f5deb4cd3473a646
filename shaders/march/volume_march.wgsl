// Volume rendering of the field along one ray (METHOD.md, "Volume
// rendering"): premultiplied colour Ĉ (each sample's colour seen along the
// ray, grid_view_colour), opacity Ô and opacity-weighted depth
// D̂ over [min(t_object, t_n), min(t_object, t_f)]. Segments of length `step`
// start at the entry point, each sampled at its midpoint (the last one is
// cut at the exit); with SKIP_EMPTY, samples inside empty occupancy cells
// are skipped whole (they would add exactly nothing). Stops once the
// transmittance falls below `termination`. Mirrors passes/src/march/reference.rs.
// Needs: common/ray_box.wgsl, field/grid.wgsl and the bool consts
// `SKIP_EMPTY` and `FIELD_VIEW_DEPENDENT`.

struct MarchResult {
    colour: vec3<f32>,
    opacity: f32,
    depth: f32,
    // Where the opacity first reached 1/2, or −1 (reference.rs half_depth).
    half_depth: f32,
}

fn march_ray(origin: vec3<f32>, dir: vec3<f32>, t_object: f32, step: f32, termination: f32) -> MarchResult {
    // FIELD_VIEW_DEPENDENT (a define of the pass's shader library,
    // passes/src/field/gpu_grid.rs) is false for a field without
    // view-dependent colour: the code that evaluates it is then left out
    // whole (a branch on grid_info.sh_degree in the loop cost lavapipe 28 %
    // of the march, two copies of the loop 20 % of the frame).
    if !FIELD_VIEW_DEPENDENT || grid_info.sh_degree == 0u {
        return march_ray_with(origin, dir, t_object, step, termination, false);
    }
    return march_ray_with(origin, dir, t_object, step, termination, true);
}

fn march_ray_with(origin: vec3<f32>, dir: vec3<f32>, t_object: f32, step: f32, termination: f32, view_dependent: bool) -> MarchResult {
    var r = MarchResult(vec3<f32>(0.0), 0.0, 0.0, -1.0);
    let tb = ray_box(origin, dir, grid_info.bounds_min, grid_info.bounds_max);
    let t0 = min(t_object, tb.x);
    let t1 = min(t_object, tb.y);
    if tb.x > tb.y || t1 <= t0 {
        return r;
    }
    var basis = array<f32, 8>();
    if view_dependent {
        basis = sh_basis(dir);
    }
    var transmittance = 1.0;
    var k = 0u;
    loop {
        let a = t0 + f32(k) * step;
        if a >= t1 {
            break;
        }
        let b = min(a + step, t1);
        let t = 0.5 * (a + b);
        let x = origin + t * dir;
        if SKIP_EMPTY {
            let s = grid_empty_until(x, dir);
            if s >= 0.0 {
                k = max(k + 1u, u32(ceil((t + s - t0) / step - 0.5)));
                continue;
            }
        }
        let v = grid_sample(x);
        let attenuation = exp(-v.w * (b - a));
        let w = transmittance * (1.0 - attenuation);
        if r.half_depth < 0.0 && r.opacity + w >= 0.5 {
            let s = log(2.0 * transmittance) / max(v.w, 1e-30);
            r.half_depth = a + clamp(s, 0.0, b - a);
        }
        var c = v.rgb;
        if view_dependent {
            c = grid_view_colour(x, basis, c);
        }
        r.colour += w * c;
        r.opacity += w;
        r.depth += w * t;
        transmittance *= attenuation;
        if transmittance < termination {
            break;
        }
        k += 1u;
    }
    return r;
}
