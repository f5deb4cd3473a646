// A text overlay drawn over the presented image: a grid of `cols`×`rows`
// character cells (8×8 glyphs magnified `scale` times) from `origin`, each
// glyph white over a translucent dark cell (premultiplied "over" blend).
// `font` holds 128 ASCII glyphs as two u32 words each (rows 0-3, 4-7; bit
// c of a row's byte is column c); `text` one character code per cell.
#include "common/fullscreen_vertex.wgsl"

struct OverlayPush {
    cols: u32,
    rows: u32,
    scale: u32,
    origin_x: u32,
    origin_y: u32,
}
var<immediate> pc: OverlayPush;
@group(0) @binding(0) var<storage, read> font: array<u32>;
@group(0) @binding(1) var<storage, read> text: array<u32>;

@fragment
fn fs_main(in: FullscreenOut) -> @location(0) vec4<f32> {
    let p = vec2<i32>(in.position.xy) - vec2<i32>(i32(pc.origin_x), i32(pc.origin_y));
    let cell_size = i32(8u * pc.scale);
    if p.x < 0 || p.y < 0 || p.x >= cell_size * i32(pc.cols) || p.y >= cell_size * i32(pc.rows) {
        discard;
    }
    let cell = vec2<u32>(p / cell_size);
    let ch = min(text[cell.y * pc.cols + cell.x], 127u);
    if ch == 0u {
        discard;
    }
    let texel = vec2<u32>((p % cell_size) / i32(pc.scale));
    let word = font[2u * ch + texel.y / 4u];
    let bits = (word >> (8u * (texel.y % 4u))) & 0xffu;
    if ((bits >> texel.x) & 1u) != 0u {
        return vec4<f32>(1.0, 1.0, 1.0, 1.0);
    }
    return vec4<f32>(0.0, 0.0, 0.0, 0.6);
}
