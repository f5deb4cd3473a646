// The view-dependent coefficients being trained, one binding a
// coefficient (a page: passes/src/train/sh_pages.rs): page j holds
// coefficient j of every trained node as (r, g, b, 0). Pages past the
// grid's degree are bound to an unused buffer. The gradient's pages are
// the scatter kernel's (train/ray_grad.wgsl, train/ray_grad_float.wgsl).

@group(0) @binding(7) var<storage, read> sh_page_0: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> sh_page_1: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> sh_page_2: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> sh_page_3: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> sh_page_4: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> sh_page_5: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read> sh_page_6: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read> sh_page_7: array<vec4<f32>>;

// Σ_j y_j·coefficient_j of the node at pool index n with `count` (3 or
// 8) further coefficients, y = `basis` (the accessor field/sh_trilinear.wgsl
// needs).
fn field_sh_node(n: u32, count: u32, basis: array<f32, 8>) -> vec3<f32> {
    var s = basis[0] * sh_page_0[n].xyz + basis[1] * sh_page_1[n].xyz + basis[2] * sh_page_2[n].xyz;
    if count > 3u {
        s += basis[3] * sh_page_3[n].xyz + basis[4] * sh_page_4[n].xyz + basis[5] * sh_page_5[n].xyz
            + basis[6] * sh_page_6[n].xyz + basis[7] * sh_page_7[n].xyz;
    }
    return s;
}
