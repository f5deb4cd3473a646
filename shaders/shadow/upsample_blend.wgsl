// The cast shadow's upsampling at one full-resolution pixel (mirrors
// passes/src/shadow/upsample.rs upsample_level): the four nearest blocks
// of `low_shadow` (ρ at one pixel of each pc.scale × pc.scale block, the
// block's source-pixel depth in alpha) blended bilinearly, each weighted
// down as its depth departs from the pixel's (to zero at
// UPSAMPLE_DEPTH_FALLOFF relative), or the block nearest in depth where
// none lies on the pixel's surface; ρ = 1 where the field is empty. The
// pixel is flagged for shadow-refine where fewer than two of the blocks
// lie on its surface or their ρ spread by more than pc.refine_spread in
// some channel. Composed into shadow/upsample.wgsl (a level of its own)
// and composite/composite.wgsl (the last level, blended as it is
// composited); the including shader declares `field_colour`,
// `field_depth`, `low_shadow` and a push block `pc` with width, height,
// scale and refine_spread.

const UPSAMPLE_DEPTH_FALLOFF: f32 = 0.05;

// Depth along the ray of a pixel whose march gave opacity `o` and depth
// sum `depth` (D̂), or −1 where the field is empty.
fn upsample_depth_of(o: f32, depth: f32) -> f32 {
    if o <= 1e-4 {
        return -1.0;
    }
    return depth / o;
}

// Depth along the ray at full-resolution pixel p, or −1 where empty.
fn upsample_depth(p: vec2<u32>) -> f32 {
    let o = textureLoad(field_colour, vec2<i32>(p), 0).a;
    return upsample_depth_of(o, textureLoad(field_depth, vec2<i32>(p), 0).r);
}

// ρ at full-resolution pixel p, whether shadow-refine takes it again, and
// p's depth (upsample_depth).
struct Upsampled {
    rho: vec3<f32>,
    refine: bool,
    depth: f32,
}

// upsample_blend at p, its depth read from the march.
fn upsample_pixel(p: vec2<u32>) -> Upsampled {
    return upsample_blend(p, upsample_depth(p));
}

// ρ at full-resolution pixel p of depth z (upsample_depth; < 0: empty).
fn upsample_blend(p: vec2<u32>, z: f32) -> Upsampled {
    if z < 0.0 {
        return Upsampled(vec3<f32>(1.0), false, z);
    }
    let low = vec2<u32>((pc.width + pc.scale - 1u) / pc.scale, (pc.height + pc.scale - 1u) / pc.scale);
    let t = max((vec2<f32>(p) + vec2<f32>(0.5)) / f32(pc.scale) - vec2<f32>(0.5), vec2<f32>(0.0));
    let i0 = min(vec2<u32>(floor(t)), low - vec2<u32>(1u));
    let i1 = min(i0 + vec2<u32>(1u), low - vec2<u32>(1u));
    let f = clamp(t - vec2<f32>(i0), vec2<f32>(0.0), vec2<f32>(1.0));
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    var nearest = vec3<f32>(1.0);
    var nearest_gap = 3.0e38;
    var lo = vec3<f32>(1.0);
    var hi = vec3<f32>(0.0);
    var on_surface = 0u;
    for (var k = 0u; k < 4u; k++) {
        let c = vec2<u32>(select(i0.x, i1.x, (k & 1u) != 0u), select(i0.y, i1.y, (k & 2u) != 0u));
        let wx = select(1.0 - f.x, f.x, (k & 1u) != 0u);
        let wy = select(1.0 - f.y, f.y, (k & 2u) != 0u);
        // ρ, and the depth at the block's source pixel (its upsample_depth,
        // which cast-shadow keeps in alpha: cast_body.wgsl
        // cast_source_depth).
        let block = textureLoad(low_shadow, vec2<i32>(c), 0);
        let zq = block.a;
        if zq < 0.0 {
            continue;
        }
        let rho = block.rgb;
        let gap = abs(zq - z) / max(z, 1e-30);
        if gap < nearest_gap {
            nearest = rho;
            nearest_gap = gap;
        }
        if gap < UPSAMPLE_DEPTH_FALLOFF {
            on_surface += 1u;
            lo = min(lo, rho);
            hi = max(hi, rho);
        }
        let w = wx * wy * max(1.0 - gap / UPSAMPLE_DEPTH_FALLOFF, 0.0);
        sum += w * rho;
        weight += w;
    }
    var rho = nearest;
    if weight > 1e-6 {
        rho = sum / weight;
    }
    let d = hi - lo;
    let refine = pc.refine_spread < 1.0 && (on_surface < 2u || max(d.x, max(d.y, d.z)) > pc.refine_spread);
    return Upsampled(rho, refine, z);
}
