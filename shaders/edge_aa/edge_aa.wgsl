// Edge anti-aliasing of the inserted objects (passes/src/edge_aa): the
// G-buffer is rasterised at one sample per pixel, so the objects' outlines
// are stair-stepped. At pixels whose object index differs from a
// 4-neighbour's (an object's outline, in front of the field or behind
// it), the composited colour is blended towards its 3 × 3 neighbourhood
// by FXAA's sub-pixel measure: by how far the pixel's luma stands from the
// neighbourhood's, relative to the neighbourhood's contrast, smoothstepped. Luma is taken
// on x / (1 + x), so HDR values compare as they would look. Elsewhere the
// pixel is copied. Mirrors passes/src/edge_aa/mod.rs (`edge_aa_reference`).

struct EdgeAaPush {
    width: u32,
    height: u32,
    // The dispatch covers the pixels from here on (the objects' region;
    // the pixels outside it were copied).
    origin_x: u32,
    origin_y: u32,
    // FXAA's sub-pixel strength (0: off, 1: full blend).
    subpixel: f32,
    // Contrast below max(threshold_min, threshold × brightest) is left alone.
    threshold: f32,
    threshold_min: f32,
}

var<immediate> pc: EdgeAaPush;
@group(0) @binding(0) var colour: texture_2d<f32>;
@group(0) @binding(1) var distance_id: texture_2d<f32>;
@group(0) @binding(2) var out_colour: texture_storage_2d<rgba32float, write>;

fn clamped(p: vec2<i32>) -> vec2<i32> {
    return clamp(p, vec2<i32>(0, 0), vec2<i32>(i32(pc.width) - 1, i32(pc.height) - 1));
}

fn object_at(p: vec2<i32>) -> f32 {
    return textureLoad(distance_id, clamped(p), 0).y;
}

fn luma(c: vec4<f32>) -> f32 {
    let m = max(c.rgb, vec3<f32>(0.0));
    return dot(m / (vec3<f32>(1.0) + m), vec3<f32>(0.299, 0.587, 0.114));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = id.xy + vec2<u32>(pc.origin_x, pc.origin_y);
    if pixel.x >= pc.width || pixel.y >= pc.height {
        return;
    }
    let p = vec2<i32>(pixel);
    let centre = textureLoad(colour, p, 0);
    let here = object_at(p);
    let outline = object_at(p + vec2<i32>(1, 0)) != here || object_at(p - vec2<i32>(1, 0)) != here
        || object_at(p + vec2<i32>(0, 1)) != here || object_at(p - vec2<i32>(0, 1)) != here;
    if !outline {
        textureStore(out_colour, p, centre);
        return;
    }
    // The 3 × 3 neighbourhood, edges weighted 2 and corners 1 (FXAA).
    var sum = vec4<f32>(0.0);
    var luma_sum = 0.0;
    var weight = 0.0;
    var lo = luma(centre);
    var hi = lo;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            if dx == 0 && dy == 0 {
                continue;
            }
            let c = textureLoad(colour, clamped(p + vec2<i32>(dx, dy)), 0);
            let w = select(1.0, 2.0, dx == 0 || dy == 0);
            let l = luma(c);
            sum += w * c;
            luma_sum += w * l;
            weight += w;
            lo = min(lo, l);
            hi = max(hi, l);
        }
    }
    let range = hi - lo;
    if range < max(pc.threshold_min, pc.threshold * hi) {
        textureStore(out_colour, p, centre);
        return;
    }
    let b = clamp(abs(luma_sum / weight - luma(centre)) / range, 0.0, 1.0);
    let s = (3.0 - 2.0 * b) * b * b;
    let blend = s * pc.subpixel;
    textureStore(out_colour, p, mix(centre, sum / weight, blend));
}
