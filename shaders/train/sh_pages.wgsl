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

// Further coefficient j of the node at pool index n (the accessor
// field/sh_trilinear.wgsl needs).
fn field_sh_coefficient(n: u32, j: u32) -> vec3<f32> {
    switch j {
        case 0u: {
            return sh_page_0[n].xyz;
        }
        case 1u: {
            return sh_page_1[n].xyz;
        }
        case 2u: {
            return sh_page_2[n].xyz;
        }
        case 3u: {
            return sh_page_3[n].xyz;
        }
        case 4u: {
            return sh_page_4[n].xyz;
        }
        case 5u: {
            return sh_page_5[n].xyz;
        }
        case 6u: {
            return sh_page_6[n].xyz;
        }
        default: {
            return sh_page_7[n].xyz;
        }
    }
}
