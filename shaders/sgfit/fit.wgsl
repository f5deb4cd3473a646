// Levenberg–Marquardt fit of M spherical Gaussians to the probe, mirroring
// passes/src/sgfit/{model,solve,reference}.rs. Entry points, dispatched in
// this order by passes/src/sgfit/pass.rs (one graph pass; the graph orders
// successive dispatches):
//   filter_probe (texels / 64) the probe filtered by passes/src/sgfit/probe_filter.rs's
//                              matrix, with each texel's solid angle, into `fitted`
//   a fresh fit:
//     init_cold (M groups)     cold-start lobes into the candidate slot
//     cost (candidate [, current]) partial sums of the cost of a slot's lobes
//     select (1 thread)        warm lobes (current) or the cold start, state reset
//   or a fit continued from an earlier frame: resume (1 thread)
//   per iteration: texel_features, gram_blocks, assemble (the normal equations from
//                              the features' Gram matrix), solve_channels (3 groups),
//                              solve_schur, solve_nonlinear, cost (candidate), decide.
//   conserve_energy (M groups): the current lobes with amplitudes that hold
//                              the probe's energy (energy.rs), into the shading slot.
// The lobe buffer holds three slots of M lobes (SLOT_*), two vec4 each.
// `state` holds the scalars listed below and the cost after every
// iteration.
#include "common/sg.wgsl"
#include "common/direction_map.wgsl"
#include "common/tangent_basis.wgsl"
#include "sgfit/model.wgsl"

struct FitPush {
    width: u32,
    height: u32,
    lobe_count: u32,
    // Columns of the normal matrix: 6M + 1 rounded up to 16.
    cols: u32,
    // Rows of the feature matrix: texels rounded up to 16.
    rows: u32,
    slot: u32,
    warm: u32,
    // Cost-partial workgroups (texels / 64, rounded up).
    groups: u32,
    damping: f32,
    // Columns of the feature matrix: 4M + 3 rounded up to 16.
    feature_cols: u32,
    pad1: u32,
    pad2: u32,
}

var<immediate> pc: FitPush;

@group(0) @binding(0) var probe: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> lobes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> state: FitState;
@group(0) @binding(3) var<storage, read_write> partials: array<vec4<f32>>;
// Per texel, its features (model.rs `texel_features`), `feature_cols` a row,
// lobe k's four in vec4 k, the residual in vec4 M.
@group(0) @binding(4) var<storage, read_write> features: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> normal: array<f32>;
@group(0) @binding(6) var<storage, read_write> work: array<f32>;
// Per texel: the filtered radiance (rgb) and the solid angle (w).
@group(0) @binding(7) var<storage, read_write> fitted: array<vec4<f32>>;
// The probe filter as a sparse matrix (filter_probe).
@group(0) @binding(8) var<storage, read> filter_offsets: array<u32>;
@group(0) @binding(9) var<storage, read> filter_entries: array<vec2<u32>>;
// The features' Gram matrix, row-major, its upper 4 × 4 blocks
// (gram_blocks).
@group(0) @binding(10) var<storage, read_write> gram: array<vec4<f32>>;

// The fit's scalars and its cost log, kept across frames for the warm
// start and read back by the host (`FitState` in passes/src/sgfit/pass.rs,
// checked against this layout).
struct FitState {
    cost: f32,
    damping: f32,
    // Whether the normal equations of the current lobes are still valid
    // (the last candidate was rejected), as 0 or 1.
    normal_valid: f32,
    energy: f32,
    invalid: f32,
    started_cold: f32,
    iterations: f32,
    accepted: f32,
    cold_cost: f32,
    warm_cost: f32,
    candidate_ok: f32,
    // The cost at the start and after each iteration: MAX_ITERATIONS + 1.
    log: array<f32, 257>,
}

// The lobe buffer's slots of M lobes: the shading lobes (what the frame
// reads, the iterate with its energy conserved), the fit's current iterate,
// and the candidate step.
const SLOT_SHADING: u32 = 0u;
const SLOT_CURRENT: u32 = 1u;
const SLOT_CANDIDATE: u32 = 2u;

const DAMPING_DOWN: f32 = 0.333333333;
const DAMPING_UP: f32 = 4.0;
const DAMPING_LIMIT: f32 = 1e-9;
const RELATIVE_DIAGONAL_FLOOR: f32 = 1e-12;
const ABSOLUTE_DIAGONAL_FLOOR: f32 = 1e-30;

fn texel_count() -> u32 {
    return pc.width * pc.height;
}

fn texel_xy(t: u32) -> vec2<u32> {
    return vec2<u32>(t % pc.width, t / pc.width);
}

// ---- the probe as the fit sees it --------------------------------------------

// Row t of the filter (passes/src/sgfit/probe_filter.rs, built on the CPU):
// filter_entries[filter_offsets[t] .. filter_offsets[t + 1]], each (source
// texel, weight as f32 bits).
@compute @workgroup_size(64, 1, 1)
fn filter_probe(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = id.x;
    if t >= texel_count() {
        return;
    }
    let xy = texel_xy(t);
    let own = textureLoad(probe, xy, 0).rgb;
    let omega = dm_solid_angle(xy, vec2<u32>(pc.width, pc.height));
    if !fit_texel_valid(own) {
        fitted[t] = vec4<f32>(own, omega);
        return;
    }
    var sum = vec3<f32>(0.0);
    for (var e = filter_offsets[t]; e < filter_offsets[t + 1u]; e++) {
        let entry = filter_entries[e];
        let l = textureLoad(probe, texel_xy(entry.x), 0).rgb;
        if fit_texel_valid(l) {
            sum += bitcast<f32>(entry.y) * l;
        }
    }
    fitted[t] = vec4<f32>(sum, omega);
}

// The filtered radiance of texel t.
fn fit_radiance(t: u32) -> vec3<f32> {
    return fitted[t].rgb;
}

// The solid angle of texel t.
fn fit_weight(t: u32) -> f32 {
    return fitted[t].w;
}

fn lobe(slot: u32, k: u32) -> Sg {
    let i = 2u * (slot * pc.lobe_count + k);
    return sg_unpack(lobes[i], lobes[i + 1u]);
}

fn store_lobe(slot: u32, k: u32, g: Sg) {
    let i = 2u * (slot * pc.lobe_count + k);
    lobes[i] = vec4<f32>(g.direction, g.sharpness);
    lobes[i + 1u] = vec4<f32>(g.amplitude, 0.0);
}

fn copy_candidate_to_current() {
    for (var k = 0u; k < pc.lobe_count; k++) {
        store_lobe(SLOT_CURRENT, k, lobe(SLOT_CANDIDATE, k));
    }
}

// ---- cold start -----------------------------------------------------------

var<workgroup> red_a: array<f32, 64>;
var<workgroup> red_b: array<f32, 64>;
var<workgroup> red_c: array<f32, 64>;
var<workgroup> red_i: array<u32, 64>;
var<workgroup> red_v: array<vec3<f32>, 64>;

// The cold-start axis and sharpness of lobe j, given the seeded lobe.
fn cold_lobe(j: u32, seeded: u32, seed_dir: vec3<f32>, seed_sharpness: f32) -> Sg {
    if j == seeded {
        return Sg(seed_dir, seed_sharpness, vec3<f32>(0.0));
    }
    return Sg(fit_fibonacci_axis(j, pc.lobe_count), fit_initial_sharpness(pc.lobe_count), vec3<f32>(0.0));
}

@compute @workgroup_size(64, 1, 1)
fn init_cold(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let k = wg.x;
    let n = texel_count();
    let size = vec2<u32>(pc.width, pc.height);
    // Brightest valid texel (lowest index on ties), Σ w·lum and Σ w.
    var best_lum = -1.0;
    var best = 0u;
    var sum_wl = 0.0;
    var sum_w = 0.0;
    for (var t = lid; t < n; t += 64u) {
        let l = fit_radiance(t);
        if !fit_texel_valid(l) {
            continue;
        }
        let w = fit_weight(t);
        let lum = fit_luminance(l);
        if lum > best_lum {
            best_lum = lum;
            best = t;
        }
        sum_wl += w * lum;
        sum_w += w;
    }
    red_a[lid] = best_lum;
    red_i[lid] = best;
    red_b[lid] = sum_wl;
    red_c[lid] = sum_w;
    workgroupBarrier();
    for (var s = 32u; s > 0u; s >>= 1u) {
        if lid < s {
            let o = lid + s;
            if red_a[o] > red_a[lid] || (red_a[o] == red_a[lid] && red_i[o] < red_i[lid]) {
                red_a[lid] = red_a[o];
                red_i[lid] = red_i[o];
            }
            red_b[lid] += red_b[o];
            red_c[lid] += red_c[o];
        }
        workgroupBarrier();
    }
    let m = pc.lobe_count;
    let l0 = fit_initial_sharpness(m);
    var seeded = m;
    var seed_dir = vec3<f32>(0.0, 1.0, 0.0);
    var seed_sharpness = l0;
    if red_c[0] > 0.0 && red_a[0] > FIT_SEED_CONTRAST * red_b[0] / red_c[0] {
        let bt = texel_xy(red_i[0]);
        seed_dir = dm_direction(bt, size);
        var dot_best = -2.0;
        for (var j = 0u; j < m; j++) {
            let d = dot(fit_fibonacci_axis(j, m), seed_dir);
            if d > dot_best {
                dot_best = d;
                seeded = j;
            }
        }
        let sharp = 2.0 * FIT_LN_2 * FIT_PI / fit_weight(red_i[0]);
        seed_sharpness = clamp(sharp, min(l0, FIT_MAX_SHARPNESS), FIT_MAX_SHARPNESS);
    }
    workgroupBarrier();
    // μ_k = Σ w L G_k / Σ w G_k S, S = Σ_j G_j.
    let g = cold_lobe(k, seeded, seed_dir, seed_sharpness);
    var num = vec3<f32>(0.0);
    var den = 0.0;
    for (var t = lid; t < n; t += 64u) {
        let l = fit_radiance(t);
        if !fit_texel_valid(l) {
            continue;
        }
        let v = dm_direction(texel_xy(t), size);
        var cover = 0.0;
        for (var j = 0u; j < m; j++) {
            cover += sg_weight(cold_lobe(j, seeded, seed_dir, seed_sharpness), v);
        }
        let gw = fit_weight(t) * sg_weight(g, v);
        num += gw * l;
        den += gw * cover;
    }
    red_v[lid] = num;
    red_a[lid] = den;
    workgroupBarrier();
    for (var s = 32u; s > 0u; s >>= 1u) {
        if lid < s {
            red_v[lid] += red_v[lid + s];
            red_a[lid] += red_a[lid + s];
        }
        workgroupBarrier();
    }
    if lid == 0u {
        var amplitude = vec3<f32>(0.0);
        if red_a[0] > 0.0 {
            amplitude = red_v[0] / red_a[0];
        }
        store_lobe(SLOT_CANDIDATE, k, Sg(g.direction, g.sharpness, amplitude));
    }
}

// ---- energy -----------------------------------------------------------------

// Lobe k (workgroup k) of the current lobes with its amplitude set to its
// share of the probe's energy, Σ_t Ω_t L_t G_k(v_t) / Σ_j G_j(v_t), over
// its integral, into the shading slot (mirrors passes/src/sgfit/energy.rs):
// the iterate itself stays as the fit left it, so a fit continued next
// frame goes on from where it stopped.
@compute @workgroup_size(64, 1, 1)
fn conserve_energy(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let k = wg.x;
    let n = texel_count();
    let size = vec2<u32>(pc.width, pc.height);
    let g = lobe(SLOT_CURRENT, k);
    var share = vec3<f32>(0.0);
    for (var t = lid; t < n; t += 64u) {
        let l = fit_radiance(t);
        if !fit_texel_valid(l) {
            continue;
        }
        let v = dm_direction(texel_xy(t), size);
        var sum = vec3<f32>(0.0);
        for (var j = 0u; j < pc.lobe_count; j++) {
            sum += sg_eval(lobe(SLOT_CURRENT, j), v);
        }
        let mine = sg_eval(g, v);
        share += fit_weight(t) * l * select(vec3<f32>(0.0), mine / sum, sum > vec3<f32>(0.0));
    }
    red_v[lid] = share;
    workgroupBarrier();
    for (var s = 32u; s > 0u; s >>= 1u) {
        if lid < s {
            red_v[lid] += red_v[lid + s];
        }
        workgroupBarrier();
    }
    if lid == 0u {
        store_lobe(SLOT_SHADING, k, Sg(g.direction, g.sharpness, red_v[0] / sg_sphere_factor(g.sharpness)));
    }
}

// ---- cost -------------------------------------------------------------------

// Partial sums over 64 texels of (Σ w|fit − L|², Σ w|L|², invalid texels)
// for the lobes of slot pc.slot (current or candidate), into
// partials[(slot − 1) · groups + group].
@compute @workgroup_size(64, 1, 1)
fn cost(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let t = id.x;
    var c = 0.0;
    var e = 0.0;
    var invalid = 0.0;
    if t < texel_count() {
        let xy = texel_xy(t);
        let l = fit_radiance(t);
        if fit_texel_valid(l) {
            let size = vec2<u32>(pc.width, pc.height);
            let v = dm_direction(xy, size);
            let w = fit_weight(t);
            var model = vec3<f32>(0.0);
            for (var k = 0u; k < pc.lobe_count; k++) {
                model += sg_eval(lobe(pc.slot, k), v);
            }
            let r = model - l;
            c = w * dot(r, r);
            e = w * dot(l, l);
        } else {
            invalid = 1.0;
        }
    }
    red_a[lid] = c;
    red_b[lid] = e;
    red_c[lid] = invalid;
    workgroupBarrier();
    for (var s = 32u; s > 0u; s >>= 1u) {
        if lid < s {
            red_a[lid] += red_a[lid + s];
            red_b[lid] += red_b[lid + s];
            red_c[lid] += red_c[lid + s];
        }
        workgroupBarrier();
    }
    if lid == 0u {
        partials[(pc.slot - 1u) * pc.groups + wg.x] = vec4<f32>(red_a[0], red_b[0], red_c[0], 0.0);
    }
}

fn sum_partials(slot: u32) -> vec4<f32> {
    var s = vec4<f32>(0.0);
    for (var g = 0u; g < pc.groups; g++) {
        s += partials[(slot - 1u) * pc.groups + g];
    }
    return s;
}

// ---- start --------------------------------------------------------------------

// Starts the fit from the previous iterate (the current slot) when warm and no worse
// than the cold start, else from the cold start; resets the state.
@compute @workgroup_size(1, 1, 1)
fn select_start() {
    let cold = sum_partials(SLOT_CANDIDATE);
    var warm_cost = -1.0;
    var use_warm = false;
    if pc.warm != 0u {
        warm_cost = sum_partials(SLOT_CURRENT).x;
        use_warm = fit_finite(warm_cost) && warm_cost <= cold.x;
    }
    if !use_warm {
        copy_candidate_to_current();
    }
    let c = select(cold.x, warm_cost, use_warm);
    state.cost = c;
    state.damping = pc.damping;
    state.normal_valid = 0.0;
    state.energy = cold.y;
    state.invalid = cold.z;
    state.started_cold = select(1.0, 0.0, use_warm);
    state.iterations = 0.0;
    state.accepted = 0.0;
    state.cold_cost = cold.x;
    state.warm_cost = warm_cost;
    state.candidate_ok = 0.0;
    state.log[0] = c;
}

// ---- one iteration --------------------------------------------------------

// Row t of the feature matrix: √w (G_k, G_k ∂s, G_k ∂u, G_k ∂v) per lobe,
// then √w (model − L), zero past 4M + 3 and for invalid texels (mirrors
// `texel_features` in passes/src/sgfit/model.rs). Skipped while the normal
// equations of the current lobes are still valid (after a rejected step).
@compute @workgroup_size(64, 1, 1)
fn texel_features(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = id.x;
    if t >= texel_count() || state.normal_valid != 0.0 {
        return;
    }
    let m = pc.lobe_count;
    let blocks = pc.feature_cols / 4u;
    let row0 = t * blocks;
    let l = fit_radiance(t);
    if !fit_texel_valid(l) {
        for (var j = 0u; j < blocks; j++) {
            features[row0 + j] = vec4<f32>(0.0);
        }
        return;
    }
    let v = dm_direction(texel_xy(t), vec2<u32>(pc.width, pc.height));
    let sw = sqrt(fit_weight(t));
    var model = vec3<f32>(0.0);
    for (var k = 0u; k < m; k++) {
        let g = lobe(SLOT_CURRENT, k);
        let e = sg_weight(g, v);
        model += g.amplitude * e;
        let b = tangent_basis(g.direction);
        let dv = v - g.direction;
        let d = vec3<f32>(-0.5 * dot(dv, dv), dot(v, b.t1), dot(v, b.t2)) * g.sharpness;
        features[row0 + k] = sw * e * vec4<f32>(1.0, d);
    }
    features[row0 + m] = vec4<f32>(sw * (model - l), 0.0);
    for (var j = m + 1u; j < blocks; j++) {
        features[row0 + j] = vec4<f32>(0.0);
    }
}

// One 4 × 4 block of the features' Gram matrix Σ_t f_t f_tᵀ per
// invocation, upper blocks only (rows 4i.., columns 4j.., i ≤ j): 16
// products for two vec4 loads a texel, no barriers. Skipped while the
// normal equations are still valid.
@compute @workgroup_size(64, 1, 1)
fn gram_blocks(@builtin(global_invocation_id) id: vec3<u32>) {
    let blocks = pc.feature_cols / 4u;
    let i = id.x / blocks;
    let j = id.x % blocks;
    if i >= blocks || j < i || state.normal_valid != 0.0 {
        return;
    }
    var c0 = vec4<f32>(0.0);
    var c1 = vec4<f32>(0.0);
    var c2 = vec4<f32>(0.0);
    var c3 = vec4<f32>(0.0);
    for (var t = 0u; t < texel_count(); t++) {
        let a = features[t * blocks + i];
        let b = features[t * blocks + j];
        c0 += a.x * b;
        c1 += a.y * b;
        c2 += a.z * b;
        c3 += a.w * b;
    }
    let at = 4u * i * blocks + j;
    gram[at] = c0;
    gram[at + blocks] = c1;
    gram[at + 2u * blocks] = c2;
    gram[at + 3u * blocks] = c3;
}

// Gram entry (a, b), read from the upper blocks.
fn gram_at(a: u32, b: u32) -> f32 {
    let r = min(a, b);
    let c = max(a, b);
    return gram[r * (pc.feature_cols / 4u) + c / 4u][c % 4u];
}

// The feature of parameter i (0–5) of lobe k: the three amplitudes share G_k.
fn param_feature(k: u32, i: u32) -> u32 {
    return 4u * k + max(i, 2u) - 2u;
}

// Entry (i, j ≥ i) of JᵀJ, or of Jᵀr for j = 6M, from the Gram matrix and
// the current lobes (mirrors `normal_from_gram` in passes/src/sgfit/model.rs).
@compute @workgroup_size(64, 1, 1)
fn assemble(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = 6u * pc.lobe_count;
    if id.x >= p * (p + 1u) || state.normal_valid != 0.0 {
        return;
    }
    let i = id.x / (p + 1u);
    let j = id.x % (p + 1u);
    if j < i {
        return;
    }
    let k = i / 6u;
    let ii = i % 6u;
    let gk = lobe(SLOT_CURRENT, k);
    let fi = param_feature(k, ii);
    var value = 0.0;
    if j == p {
        let f = 4u * pc.lobe_count;
        let r = vec3<f32>(gram_at(fi, f), gram_at(fi, f + 1u), gram_at(fi, f + 2u));
        if ii < 3u {
            value = 2.0 * sqrt(gk.amplitude[ii]) * r[ii];
        } else {
            value = dot(gk.amplitude, r);
        }
    } else {
        let l = j / 6u;
        let jj = j % 6u;
        let gl = lobe(SLOT_CURRENT, l);
        let g = gram_at(fi, param_feature(l, jj));
        if ii < 3u && jj < 3u {
            value = select(0.0, 4.0 * sqrt(gk.amplitude[ii]) * sqrt(gl.amplitude[ii]) * g, ii == jj);
        } else if ii < 3u {
            value = 2.0 * sqrt(gk.amplitude[ii]) * gl.amplitude[ii] * g;
        } else if jj < 3u {
            value = 2.0 * sqrt(gl.amplitude[jj]) * gk.amplitude[jj] * g;
        } else {
            value = dot(gk.amplitude, gl.amplitude) * g;
        }
    }
    normal[i * pc.cols + j] = value;
}

// Invocations of the solve's workgroups: stage 1 reduces 4M + 1 rows and
// stage 3 3M + 1 a column; lavapipe runs every invocation of a workgroup
// through each barrier, so 64 (rows taken in turns) ran an LM iteration
// 15 % faster than 256 at M = 32 (docs/benchmarks.md, issue 26's fifth pass).
const SOLVE_WORKGROUP: u32 = 64u;
var<workgroup> red_max: array<f32, 256>;
var<workgroup> wg_fail: u32;
var<workgroup> wg_bad_step: atomic<u32>;

// ---- the damped step (mirrors passes/src/sgfit/solve.rs) ------------------
// Marquardt's step from the Jacobi-scaled, damped normal equations, in the
// three stages of solve.rs's doc: each channel's amplitude block factored
// by its own workgroup (`solve_channels`), the Schur complement in the
// nonlinear block over every core (`solve_schur`), then that factored and
// both substituted back in one workgroup (`solve_nonlinear`). Layout of
// `work` (M lobes, q = 3M nonlinear parameters, R = 4M + 1 rows a channel):
//   √D (6M); per channel, R rows of M: its M × M block (lower), the q
//   nonlinear rows in its columns, its right-hand side; S with its
//   right-hand side as row q ((q + 1) × q); the step (6M); a failure flag
//   per channel (3).

fn solve_channel_at(c: u32) -> u32 {
    let m = pc.lobe_count;
    return 6u * m + c * (4u * m + 1u) * m;
}

fn solve_schur_at() -> u32 {
    return solve_channel_at(3u);
}

fn solve_step_at() -> u32 {
    let q = 3u * pc.lobe_count;
    return solve_schur_at() + (q + 1u) * q;
}

fn solve_flags_at() -> u32 {
    return solve_step_at() + 6u * pc.lobe_count;
}

// The fit's parameter index of amplitude c of lobe k, and of nonlinear
// parameter r (solve.rs amplitude_index, nonlinear_index).
fn amplitude_index(c: u32, k: u32) -> u32 {
    return 6u * k + c;
}

fn nonlinear_index(r: u32) -> u32 {
    return 6u * (r / 3u) + 3u + r % 3u;
}

// Entry (a, b) of the normal matrix, read from the upper triangle the
// assemble kernel wrote; its right-hand side −b_a / √D_a.
fn normal_sym(a: u32, b: u32) -> f32 {
    return normal[min(a, b) * pc.cols + max(a, b)];
}

fn scaled_rhs(a: u32, d: f32) -> f32 {
    return -normal[a * pc.cols + 6u * pc.lobe_count] / d;
}

// Reduces rows j + 1.. of the `count` rows of `width` at `at` by column j
// of their head block (a step of solve.rs factor_unscaled); invocations
// take rows by `lid`, SOLVE_WORKGROUP apart. Returns whether the pivot was positive.
fn factor_column(at: u32, width: u32, count: u32, j: u32, lid: u32) -> bool {
    let pivot = work[at + j * width + j];
    for (var i = j + 1u + lid; i < count; i += SOLVE_WORKGROUP) {
        let f = work[at + i * width + j] / pivot;
        let last = min(i, width - 1u);
        for (var k = j + 1u; k <= last; k++) {
            work[at + i * width + k] -= f * work[at + k * width + j];
        }
    }
    return pivot > 0.0 && fit_finite(pivot);
}

// Stage 1, one workgroup per channel: √D (the first workgroup writes it
// for the later stages; each computes what it reads), the channel's rows
// filled and factored.
@compute @workgroup_size(SOLVE_WORKGROUP, 1, 1)
fn solve_channels(@builtin(local_invocation_index) lid: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let m = pc.lobe_count;
    let n = 6u * m;
    let q = 3u * m;
    let c = wg.x;
    let at = solve_channel_at(c);
    var mx = 0.0;
    for (var i = lid; i < n; i += SOLVE_WORKGROUP) {
        mx = max(mx, normal[i * pc.cols + i]);
    }
    red_max[lid] = mx;
    if lid == 0u {
        atomicStore(&wg_bad_step, 0u);
    }
    workgroupBarrier();
    for (var s = SOLVE_WORKGROUP / 2u; s > 0u; s >>= 1u) {
        if lid < s {
            red_max[lid] = max(red_max[lid], red_max[lid + s]);
        }
        workgroupBarrier();
    }
    let diag_floor = max(RELATIVE_DIAGONAL_FLOOR * red_max[0], ABSOLUTE_DIAGONAL_FLOOR);
    if c == 0u {
        for (var i = lid; i < n; i += SOLVE_WORKGROUP) {
            work[i] = sqrt(max(normal[i * pc.cols + i], diag_floor));
        }
    }
    let eta = state.damping;
    for (var idx = lid; idx < (m + q + 1u) * m; idx += SOLVE_WORKGROUP) {
        let i = idx / m;
        let j = idx % m;
        let aj = amplitude_index(c, j);
        let dj = sqrt(max(normal[aj * pc.cols + aj], diag_floor));
        if i < m {
            if j <= i {
                let ai = amplitude_index(c, i);
                let di = sqrt(max(normal[ai * pc.cols + ai], diag_floor));
                work[at + idx] = normal_sym(ai, aj) / (di * dj) + select(0.0, eta, i == j);
            }
        } else if i < m + q {
            let r = nonlinear_index(i - m);
            let dr = sqrt(max(normal[r * pc.cols + r], diag_floor));
            work[at + idx] = normal_sym(r, aj) / (dr * dj);
        } else {
            work[at + idx] = scaled_rhs(aj, dj);
        }
    }
    storageBarrier();
    for (var j = 0u; j < m; j++) {
        if !factor_column(at, m, m + q + 1u, j, lid) {
            atomicStore(&wg_bad_step, 1u);
        }
        storageBarrier();
    }
    if lid == 0u {
        work[solve_flags_at() + c] = f32(atomicLoad(&wg_bad_step));
    }
}

// Stage 2, an entry of S (or of its right-hand side, row q) per
// invocation: Â_rt − Σ_c Σ_j C_rj C_tj / L_jj².
@compute @workgroup_size(64, 1, 1)
fn solve_schur(@builtin(global_invocation_id) id: vec3<u32>) {
    let m = pc.lobe_count;
    let q = 3u * m;
    let r = id.x / q;
    let t = id.x % q;
    if r > q || (r < q && t > r) {
        return;
    }
    let nt = nonlinear_index(t);
    var value = 0.0;
    if r < q {
        let nr = nonlinear_index(r);
        value = normal_sym(nr, nt) / (work[nr] * work[nt]) + select(0.0, state.damping, r == t);
    } else {
        value = scaled_rhs(nt, work[nt]);
    }
    for (var c = 0u; c < 3u; c++) {
        let at = solve_channel_at(c);
        let row_r = at + (m + r) * m;
        let row_t = at + (m + t) * m;
        var sum = 0.0;
        for (var j = 0u; j < m; j++) {
            sum += work[row_r + j] * work[row_t + j] / work[at + j * m + j];
        }
        value -= sum;
    }
    work[solve_schur_at() + r * q + t] = value;
}

// Stage 3, one workgroup: S factored, the nonlinear step, each channel's
// amplitudes, the step applied to the current lobes into the candidate
// slot.
@compute @workgroup_size(SOLVE_WORKGROUP, 1, 1)
fn solve_nonlinear(@builtin(local_invocation_index) lid: u32) {
    let m = pc.lobe_count;
    let n = 6u * m;
    let q = 3u * m;
    let s_at = solve_schur_at();
    let x_at = solve_step_at();
    let flags = solve_flags_at();
    if lid == 0u {
        let earlier = work[flags] + work[flags + 1u] + work[flags + 2u];
        atomicStore(&wg_bad_step, select(0u, 1u, earlier != 0.0));
    }
    workgroupBarrier();
    for (var j = 0u; j < q; j++) {
        if !factor_column(s_at, q, q + 1u, j, lid) {
            atomicStore(&wg_bad_step, 1u);
        }
        storageBarrier();
    }
    // Lᵀ x = z through S, its right-hand side (row q) in place: x_j =
    // y_j / L_jj², then y_i −= C_ji x_j (i < j).
    let y_at = s_at + q * q;
    for (var jj = 0u; jj < q; jj++) {
        let j = q - 1u - jj;
        let xj = work[y_at + j] / work[s_at + j * q + j];
        if lid == 0u {
            work[x_at + nonlinear_index(j)] = xj;
        }
        for (var i = lid; i < j; i += SOLVE_WORKGROUP) {
            work[y_at + i] -= work[s_at + j * q + i] * xj;
        }
        storageBarrier();
    }
    // Each channel's right-hand side less the nonlinear step's share.
    for (var idx = lid; idx < 3u * m; idx += SOLVE_WORKGROUP) {
        let at = solve_channel_at(idx / m);
        let j = idx % m;
        var y = work[at + (m + q) * m + j];
        for (var r = 0u; r < q; r++) {
            y -= work[at + (m + r) * m + j] * work[x_at + nonlinear_index(r)];
        }
        work[at + (m + q) * m + j] = y;
    }
    storageBarrier();
    // Back through the three channels' blocks at once.
    for (var jj = 0u; jj < m; jj++) {
        let j = m - 1u - jj;
        for (var idx = lid; idx < 3u * m; idx += SOLVE_WORKGROUP) {
            let c = idx / m;
            let i = idx % m;
            let at = solve_channel_at(c);
            let xj = work[at + (m + q) * m + j] / work[at + j * m + j];
            if i == j {
                work[x_at + amplitude_index(c, j)] = xj;
            } else if i < j {
                work[at + (m + q) * m + i] -= work[at + j * m + i] * xj;
            }
        }
        storageBarrier();
    }
    for (var i = lid; i < n; i += SOLVE_WORKGROUP) {
        let delta = work[x_at + i] / work[i];
        work[x_at + i] = delta;
        if !fit_finite(delta) {
            atomicStore(&wg_bad_step, 1u);
        }
    }
    storageBarrier();
    if lid == 0u {
        wg_fail = atomicLoad(&wg_bad_step);
    }
    let failed = workgroupUniformLoad(&wg_fail);
    if failed == 0u {
        for (var k = lid; k < pc.lobe_count; k += SOLVE_WORKGROUP) {
            let b = x_at + 6u * k;
            let d0 = vec4<f32>(work[b], work[b + 1u], work[b + 2u], work[b + 3u]);
            let d1 = vec2<f32>(work[b + 4u], work[b + 5u]);
            store_lobe(SLOT_CANDIDATE, k, fit_apply_step(lobe(SLOT_CURRENT, k), d0, d1));
        }
    }
    if lid == 0u {
        state.candidate_ok = select(1.0, 0.0, failed != 0u);
    }
}

// Goes on with the fit of an earlier frame on the same probe: its lobes,
// cost and damping stand; the normal equations, not kept across frames,
// are built again.
@compute @workgroup_size(1, 1, 1)
fn resume() {
    state.normal_valid = 0.0;
}

// Accepts the candidate if its cost is finite and lower, adapts
// the damping and logs the cost.
@compute @workgroup_size(1, 1, 1)
fn decide() {
    let c = sum_partials(SLOT_CANDIDATE).x;
    let current = state.cost;
    let eta = state.damping;
    if state.candidate_ok != 0.0 && fit_finite(c) && c < current {
        copy_candidate_to_current();
        state.cost = c;
        state.damping = max(eta * DAMPING_DOWN, DAMPING_LIMIT);
        state.normal_valid = 0.0;
        state.accepted += 1.0;
    } else {
        state.damping = min(eta * DAMPING_UP, 1.0 / DAMPING_LIMIT);
        state.normal_valid = 1.0;
    }
    let it = min(u32(state.iterations) + 1u, 256u);
    state.iterations = f32(it);
    state.log[it] = state.cost;
}
