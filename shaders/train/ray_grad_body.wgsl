// The body of the training kernel: one training pixel per invocation
// (pc.rays_per_pixel rays through points of its area, the pixel their
// mean), the march's quadrature over the trained grid (no empty-space skipping but
// a sparse grid's dropped bricks: past_dropped_brick), the
// pixel's loss, and the loss's gradient with respect to every value its
// rays read. The trained nodes are laid out as a field's on the device (a
// sparse grid's pool of bricks, field/bricks.wgsl), the view-dependent
// colour's coefficients in pages of their own (train/sh_pages.wgsl). A
// photograph records its frame's exposure gain
// (RGB) times the pixel (1 unless learnt); with learn_gains, the loss's
// gradient with respect to the gain of every frame but the first is
// scattered too. With pc.distortion > 0, the distortion loss of the ray's
// weights is added, and its gradient with respect to the densities.
// With pc.depth_weight > 0, a ray whose depth is recorded (ray.depth > 0)
// adds the depth loss (passes/src/train/depth.rs) and its gradient with
// respect to the densities.
// Behind the field is pc.background, or where pc.sky_width is not 0 a learnt sky
// (field/sky.wgsl) whose gradient is scattered too.
// Mirrors passes/src/train/render.rs render_pixel_with_gradient.
// Needs from the includer: the bindings `grad` (2), `gain_grad` (5),
// `sky_grad` (24) and the gradient's pages `sh_grad_j` (15..22), and
// `add_float(i, v)`, `add_gain_float(i, v)`, `add_sky_float(i, v)`,
// `add_sh_float(j, i, v)` that add v to their
// element i atomically (train/ray_grad.wgsl: a compare-and-swap loop, core WGSL;
// train/ray_grad_float.wgsl: atomicAdd on f32, VK_EXT_shader_atomic_float).

#include "common/ray_box.wgsl"
#include "field/trilinear.wgsl"
#include "field/sh.wgsl"
#include "train/loss.wgsl"
#include "field/sky.wgsl"

struct TrainPush {
    bounds_min: vec3<f32>,
    ray_count: u32,
    bounds_max: vec3<f32>,
    step: f32,
    resolution: vec3<u32>,
    termination: f32,
    background: vec3<f32>,
    epsilon: f32,
    sh_degree: u32,
    learn_gains: u32,
    // The distortion loss's weight over the field's diagonal, λ/D (0: none).
    distortion: f32,
    // A learnt sky's texels across (0: pc.background behind the field).
    sky_width: u32,
    // Bricks per axis of a sparse grid (0: dense; field/bricks.wgsl).
    brick_dims: vec3<u32>,
    // A learnt sky's texels down.
    sky_height: u32,
    // Rays a pixel (1..=MAX_RAYS_PER_PIXEL, a u32 define:
    // passes/src/train/gpu.rs MAX_RAYS_PER_PIXEL): a pixel's rays lie
    // consecutively in `rays`, ray_count of them in all.
    rays_per_pixel: u32,
    // The depth loss's weight μ over the field's diagonal (0: none).
    depth_weight: f32,
    // The depth loss's tolerance s (scene units).
    depth_tolerance: f32,
    // 1: densities below zero take the gradient that asks for more
    // (density_gate).
    revive: u32,
}

// A ray and what its pixel says: kind 0 value, 1 lower bound, 2 bracket.
struct TrainRay {
    origin: vec3<f32>,
    kind: u32,
    dir: vec3<f32>,
    exposure: f32,
    target_value: vec3<f32>,
    weight: f32,
    frame: u32,
    // The length along the ray to the surface a depth map records (0:
    // none).
    depth: f32,
    pad0: u32,
    pad1: u32,
}

var<immediate> pc: TrainPush;
@group(0) @binding(0) var<storage, read> grid_nodes: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> rays: array<TrainRay>;
@group(0) @binding(3) var<storage, read_write> ray_out: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> gains: array<vec4<f32>>;
// A sparse grid's brick table (one unused entry for a dense grid).
@group(0) @binding(6) var<storage, read> bricks: array<u32>;
// A learnt sky's texels (r, g, b, 0; one unused entry without a sky).
@group(0) @binding(23) var<storage, read> sky: array<vec4<f32>>;

#include "field/bricks.wgsl"
#include "train/sh_pages.wgsl"
#include "field/sh_trilinear.wgsl"

// Where node i's values lie (4 a node), or EMPTY_BRICK where its brick
// is not trained (the node is zero).
fn field_node_index(i: vec3<u32>) -> u32 {
    if pc.brick_dims.x != 0u {
        let slot = bricks[brick_table_index(i, pc.brick_dims)];
        if slot == EMPTY_BRICK {
            return EMPTY_BRICK;
        }
        return brick_pool_index(slot, i);
    }
    let r = pc.resolution;
    return i.x + r.x * (i.y + r.y * i.z);
}

// The share of a sample's density gradient `d_sigma` that reaches its
// nodes (train::render::DensityGate::share): all of it where the
// interpolated raw density is above zero; where the clamp at zero holds,
// none, or with pc.revive all of it if it asks for more density (the
// slope of the loss were the density raised from zero).
fn density_gate(raw: f32, d_sigma: f32) -> f32 {
    return select(select(0.0, 1.0, pc.revive != 0u && d_sigma < 0.0), 1.0, raw > 0.0);
}

// The first sample past a dropped brick, where sample `s` (its cell
// `cell`) lies inside one with all eight of its cell's corners: every
// sample until then reads only zeros, so it adds no light, dims nothing
// and takes no gradient (a density's gradient is cut where it is not
// above zero), and skipping it changes no result. Otherwise (a trained
// brick, a cell across two bricks, a dense grid) s itself. A sample is
// skipped only where its midpoint lies inside the brick's cells by a
// thousandth of a step, so rounding never skips one that reads a trained
// node. The forward and the backward skip alike.
fn past_dropped_brick(origin: vec3<f32>, dir: vec3<f32>, t0: f32, s: u32, cell: TrilinearCell) -> u32 {
    if pc.brick_dims.x == 0u || !cell.inside {
        return s;
    }
    let local = cell.base % BRICK_SIDE;
    if any(local == vec3<u32>(BRICK_SIDE - 1u)) {
        return s;
    }
    if bricks[brick_table_index(cell.base, pc.brick_dims)] != EMPTY_BRICK {
        return s;
    }
    // The cells whose corners all lie in the brick: nodes 8b to 8b + 7.
    let spacing = (pc.bounds_max - pc.bounds_min) / vec3<f32>(pc.resolution - vec3<u32>(1u));
    let first = vec3<f32>(cell.base - local);
    let lo = pc.bounds_min + first * spacing;
    let hi = pc.bounds_min + (first + vec3<f32>(f32(BRICK_SIDE - 1u))) * spacing;
    let exit = ray_box(origin, dir, lo, hi).y;
    let next = ceil((exit - t0) / pc.step - 0.5 - 1e-3);
    return max(s + 1u, u32(max(next, 0.0)));
}

// The pool indices of the cell's eight corners (EMPTY_BRICK where a
// brick was dropped): looked up once a sample, for its values, its
// view-dependent colour and its gradient's scatter (each lookup reads the
// brick table; looking them up three times a sample in the backward walk
// cost DOG's steps at 128 nodes a tenth of their rays' time).
fn cell_nodes(cell: TrilinearCell) -> CellNodes {
    return CellNodes(
        vec4<u32>(corner_node(cell, 0u), corner_node(cell, 1u), corner_node(cell, 2u), corner_node(cell, 3u)),
        vec4<u32>(corner_node(cell, 4u), corner_node(cell, 5u), corner_node(cell, 6u), corner_node(cell, 7u)),
    );
}

// The pool index of the cell's corner k.
fn corner_node(cell: TrilinearCell, k: u32) -> u32 {
    return field_node_index(cell.base + trilinear_corner(k));
}

// The trilinear (r, g, b, σ) of the cell's nodes (`nodes`, cell_nodes),
// σ before the clamp at zero.
fn sample_at(cell: TrilinearCell, nodes: CellNodes) -> vec4<f32> {
    var v = vec4<f32>(0.0);
    if !cell.inside {
        return v;
    }
    for (var k = 0u; k < 8u; k++) {
        let n = node_of(nodes, k);
        if n != EMPTY_BRICK {
            v += trilinear_weight(cell.f, k) * grid_nodes[n];
        }
    }
    return v;
}

// The colour along dir before the clamp at zero: the base, plus the
// view-dependent part where the grid has one.
fn unclamped_colour(cell: TrilinearCell, nodes: CellNodes, base: vec3<f32>, basis: array<f32, 8>) -> vec3<f32> {
    if pc.sh_degree == 0u || !cell.inside {
        return base;
    }
    return base + sh_trilinear_nodes(cell, nodes, pc.sh_degree, basis);
}

// Adds the gradient `e` of coefficient j (one per colour channel) to the
// words n, n + 1, n + 2 of its page.
fn add_sh_grad(j: u32, n: u32, e: vec3<f32>) {
    add_sh_float(j, n, e.x);
    add_sh_float(j, n + 1u, e.y);
    add_sh_float(j, n + 2u, e.z);
}

// The colour seen: clamped at zero where the grid has view-dependent
// colour, the base itself where it has not (as grid_view_colour).
fn seen_colour(u: vec3<f32>) -> vec3<f32> {
    return select(u, max(u, vec3<f32>(0.0)), pc.sh_degree > 0u);
}

// The radiance behind the field along unit direction d.
fn background_along(d: vec3<f32>) -> vec3<f32> {
    if pc.sky_width == 0u {
        return pc.background;
    }
    return sky_radiance(vec2<u32>(pc.sky_width, pc.sky_height), d);
}

// Adds `e` to sky texel t's gradient (r, g, b).
fn add_sky_texel(t: u32, e: vec3<f32>) {
    add_sky_float(4u * t, e.x);
    add_sky_float(4u * t + 1u, e.y);
    add_sky_float(4u * t + 2u, e.z);
}

// Adds the gradient g·T_N of the radiance behind the field along d to
// the sky texels it read (written out: no loop for llvmpipe to count).
fn add_sky_grad(d: vec3<f32>, e: vec3<f32>) {
    let c = sky_corners(vec2<u32>(pc.sky_width, pc.sky_height), d);
    add_sky_texel(c.index.x, e * c.weight.x);
    add_sky_texel(c.index.y, e * c.weight.y);
    add_sky_texel(c.index.z, e * c.weight.z);
    add_sky_texel(c.index.w, e * c.weight.w);
}

// What the forward march of one ray leaves for its backward walk.
struct RayForward {
    // Σ T_i α_i c_i (the background not included).
    colour: vec3<f32>,
    // T_N: the transmittance past the last sample.
    transmittance: f32,
    // The distortion loss's sums: Σw, Σw·t, the ordered pairs
    // Σ_{j<i} w_i w_j (t_i − t_j), and Σ w²Δ.
    w_all: f32,
    wt_all: f32,
    pairs: f32,
    own: f32,
    // The depth loss's sum Σ w·ρ(t − D) (the light past the bounds not
    // included).
    depth_sum: f32,
    // The samples marched (dropped bricks' skipped ones included).
    used: u32,
    // Where the ray enters and leaves the bounds.
    t0: f32,
    t1: f32,
}

// ρ(x) = √(x² + s²) − s, the depth loss's penalty for weight x away from
// the recorded surface, as x² / (√(x² + s²) + s). Mirrors
// passes/src/train/depth.rs depth_penalty.
fn depth_penalty(x: f32, s: f32) -> f32 {
    return x * x / (sqrt(x * x + s * s) + s);
}

// Whether `ray` takes the depth loss.
fn has_depth(ray: TrainRay) -> bool {
    return pc.depth_weight > 0.0 && ray.depth > 0.0;
}

// How many tolerances past the bounds a recorded surface is taken at most.
// Mirrors passes/src/train/depth.rs FAR_TOLERANCES.
const FAR_TOLERANCES: f32 = 16.0;

// The depth the loss takes for `ray`, which leaves the bounds at `exit`:
// its recorded one, or FAR_TOLERANCES tolerances past `exit` where that
// lies further. Mirrors passes/src/train/depth.rs effective_target.
fn depth_target(ray: TrainRay, exit: f32) -> f32 {
    return min(ray.depth, exit + FAR_TOLERANCES * pc.depth_tolerance);
}

// The forward march of `ray` over the trained grid, with the sums the
// distortion loss needs where pc.distortion > 0, and the depth loss's
// where the ray takes it.
fn march_forward(ray: TrainRay, y: array<f32, 8>) -> RayForward {
    let tb = ray_box(ray.origin, ray.dir, pc.bounds_min, pc.bounds_max);
    var f = RayForward(vec3<f32>(0.0), 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0u, tb.x, tb.y);
    let distort = pc.distortion > 0.0;
    let depth = has_depth(ray);
    let recorded = depth_target(ray, f.t1);
    if f.t1 <= f.t0 {
        return f;
    }
    loop {
        let a = f.t0 + f32(f.used) * pc.step;
        if a >= f.t1 {
            break;
        }
        let b = min(a + pc.step, f.t1);
        let cell = trilinear_cell(ray.origin + 0.5 * (a + b) * ray.dir, pc.bounds_min, pc.bounds_max, pc.resolution);
        let past = past_dropped_brick(ray.origin, ray.dir, f.t0, f.used, cell);
        if past != f.used {
            f.used = past;
            continue;
        }
        let nodes = cell_nodes(cell);
        let v = sample_at(cell, nodes);
        let alpha = 1.0 - exp(-density_at(v.w) * (b - a));
        let w = f.transmittance * alpha;
        f.colour += w * seen_colour(unclamped_colour(cell, nodes, v.xyz, y));
        if distort {
            let t = 0.5 * (a + b);
            f.pairs += w * (t * f.w_all - f.wt_all);
            f.own += w * w * (b - a);
            f.w_all += w;
            f.wt_all += w * t;
        }
        if depth {
            f.depth_sum += w * depth_penalty(0.5 * (a + b) - recorded, pc.depth_tolerance);
        }
        f.transmittance *= 1.0 - alpha;
        f.used += 1u;
        if f.transmittance < pc.termination {
            break;
        }
    }
    return f;
}

// The depth loss over its weight: the weights' penalties and the light
// past the bounds', at the exit (0 for a ray without one or that misses
// the bounds).
fn depth_total(ray: TrainRay, f: RayForward) -> f32 {
    if !has_depth(ray) || f.t1 <= f.t0 {
        return 0.0;
    }
    return f.depth_sum + f.transmittance * depth_penalty(f.t1 - depth_target(ray, f.t1), pc.depth_tolerance);
}

// The backward walk of `ray` (its forward march `f`, the radiance behind
// it `background`) with the running sum: scatters the gradient of a loss
// whose gradient with respect to the ray's colour is `g`, plus the
// distortion loss `distortion` of weight `lambda` (λ/D, the ray's share)
// and the depth loss of weight `mu` (μ/D, the ray's share).
fn march_backward(ray: TrainRay, y: array<f32, 8>, f: RayForward, background: vec3<f32>, g: vec3<f32>, lambda: f32, distortion: f32, mu: f32) {
    let distort = pc.distortion > 0.0;
    let depth = has_depth(ray);
    let depth_all = depth_total(ray, f);
    let recorded = depth_target(ray, f.t1);
    var z_so_far = 0.0;
    let count = select(0u, sh_count(pc.sh_degree), pc.sh_degree > 0u);
    var t_i = 1.0;
    var so_far = vec3<f32>(0.0);
    var w_before = 0.0;
    var wt_before = 0.0;
    var e_so_far = 0.0;
    var next = 0u;
    loop {
        let s = next;
        if s >= f.used {
            break;
        }
        next = s + 1u;
        let a = f.t0 + f32(s) * pc.step;
        if a >= f.t1 {
            break;
        }
        let b = min(a + pc.step, f.t1);
        let cell = trilinear_cell(ray.origin + 0.5 * (a + b) * ray.dir, pc.bounds_min, pc.bounds_max, pc.resolution);
        if !cell.inside {
            continue;
        }
        let past = past_dropped_brick(ray.origin, ray.dir, f.t0, s, cell);
        if past != s {
            next = past;
            continue;
        }
        let nodes = cell_nodes(cell);
        let v = sample_at(cell, nodes);
        let u = unclamped_colour(cell, nodes, v.xyz, y);
        let c = seen_colour(u);
        // Channels the clamp at zero holds get no colour gradient.
        let open = select(vec3<f32>(1.0), select(vec3<f32>(0.0), vec3<f32>(1.0), u > vec3<f32>(0.0)), count > 0u);
        let dt = b - a;
        let alpha = 1.0 - exp(-density_at(v.w) * dt);
        let w = t_i * alpha;
        let t_next = t_i * (1.0 - alpha);
        so_far += w * c;
        let d_c = g * w * open;
        var d_sigma = dt * dot(g, t_next * c - (f.colour - so_far) - f.transmittance * background);
        if distort {
            // e = ∂L_d/∂w of this sample, from the sums before and after it.
            let t = 0.5 * (a + b);
            let w_after = f.w_all - w_before - w;
            let wt_after = f.wt_all - wt_before - w * t;
            let spread = t * w_before - wt_before + wt_after - t * w_after;
            let e = lambda * (2.0 * spread + 2.0 / 3.0 * w * dt);
            e_so_far += w * e;
            d_sigma += dt * (t_next * e - (2.0 * distortion - e_so_far));
            w_before += w;
            wt_before += w * t;
        }
        if depth {
            let rho = depth_penalty(0.5 * (a + b) - recorded, pc.depth_tolerance);
            z_so_far += w * rho;
            d_sigma += mu * dt * (t_next * rho - (depth_all - z_so_far));
        }
        // Where the clamp at zero after interpolation holds (density_at),
        // none passes, or what asks for more density (density_gate).
        d_sigma *= density_gate(v.w, d_sigma);
        // A sample with no weight (empty space: σ = 0) moves no colour:
        // its colour and coefficient adds would add zeros, one atomic each.
        let colour_moves = any(d_c != vec3<f32>(0.0));
        if !colour_moves && d_sigma == 0.0 {
            t_i = t_next;
            continue;
        }
        for (var k = 0u; k < 8u; k++) {
            let wk = trilinear_weight(cell.f, k);
            if wk == 0.0 {
                continue;
            }
            let node = node_of(nodes, k);
            if node == EMPTY_BRICK {
                continue;
            }
            let n = 4u * node;
            add_float(n + 3u, d_sigma * wk);
            if !colour_moves {
                continue;
            }
            add_float(n, d_c.x * wk);
            add_float(n + 1u, d_c.y * wk);
            add_float(n + 2u, d_c.z * wk);
            // Written out, not looped over `count`: llvmpipe counts every
            // iteration of a loop of unknown length against its 65535 per
            // invocation (field/sh_trilinear.wgsl).
            if count > 0u {
                add_sh_grad(0u, n, d_c * (wk * y[0]));
                add_sh_grad(1u, n, d_c * (wk * y[1]));
                add_sh_grad(2u, n, d_c * (wk * y[2]));
            }
            if count > 3u {
                add_sh_grad(3u, n, d_c * (wk * y[3]));
                add_sh_grad(4u, n, d_c * (wk * y[4]));
                add_sh_grad(5u, n, d_c * (wk * y[5]));
                add_sh_grad(6u, n, d_c * (wk * y[6]));
                add_sh_grad(7u, n, d_c * (wk * y[7]));
            }
        }
        t_i = t_next;
    }
}

// The distortion loss of a ray's forward march, at weight `lambda`.
fn distortion_of(f: RayForward, lambda: f32) -> f32 {
    return lambda * (2.0 * f.pairs + f.own / 3.0);
}

// Renders pixel `index` of the batch (its pc.rays_per_pixel rays,
// consecutive in `rays`, all carrying the pixel's target, weight and
// frame), its loss on the mean of its rays' colours (the pixel's light
// over its area) and the gradient: each ray takes 1/n of the pixel's, and
// its own distortion and depth losses at 1/n of the pixel's weight.
fn train_pixel(index: u32) {
    let n = pc.rays_per_pixel;
    if index >= pc.ray_count / n {
        return;
    }
    let first = index * n;
    let ray = rays[first];
    // Forward, each ray; the pixel is their mean.
    var forward: array<RayForward, MAX_RAYS_PER_PIXEL>;
    var total = vec3<f32>(0.0);
    for (var s = 0u; s < n; s++) {
        let r = rays[first + s];
        forward[s] = march_forward(r, sh_basis(r.dir));
        total += forward[s].colour + forward[s].transmittance * background_along(r.dir);
    }
    total /= f32(n);
    let gain = gains[ray.frame].xyz;
    let l = pixel_loss(gain * total, ray.kind, ray.target_value, ray.exposure, pc.epsilon);
    // The distortion loss, weighted as the pixel's (λ/D folded in),
    // shared among its rays.
    let lambda = ray.weight * pc.distortion / f32(n);
    var distortion = 0.0;
    for (var s = 0u; s < n; s++) {
        distortion += distortion_of(forward[s], lambda);
    }
    // The depth loss, weighted as the pixel's (μ/D folded in), each ray's
    // own target, shared among its rays.
    let mu = ray.weight * pc.depth_weight / f32(n);
    var depth = 0.0;
    for (var s = 0u; s < n; s++) {
        depth += mu * depth_total(rays[first + s], forward[s]);
    }
    ray_out[index] = vec4<f32>(gain * total, ray.weight * l.loss + distortion + depth);
    if pc.learn_gains != 0u && ray.frame != 0u {
        let gg = ray.weight * l.grad * total;
        add_gain_float(4u * ray.frame, gg.x);
        add_gain_float(4u * ray.frame + 1u, gg.y);
        add_gain_float(4u * ray.frame + 2u, gg.z);
    }
    let g = ray.weight * l.grad * gain / f32(n);
    if all(g == vec3<f32>(0.0)) && distortion == 0.0 && depth == 0.0 {
        return;
    }
    // Backward, each ray with the running sum.
    for (var s = 0u; s < n; s++) {
        let r = rays[first + s];
        let f = forward[s];
        if pc.sky_width != 0u && f.transmittance > 0.0 {
            add_sky_grad(r.dir, g * f.transmittance);
        }
        march_backward(r, sh_basis(r.dir), f, background_along(r.dir), g, lambda, distortion_of(f, lambda), mu);
    }
}
