//! Textures as loaded from glTF, and their bilinear lookup (the CPU
//! mirror of the G-buffer's sampler).

/// An RGBA8 texture (row-major from the top).
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texels, 4 bytes each.
    pub rgba8: Vec<u8>,
}

impl Texture {
    /// Bilinear lookup with repeat wrapping (texel centres at half
    /// integers, as Vulkan samples), each byte decoded by `decode` before
    /// filtering (linear: b/255; sRGB: its transfer function).
    pub fn sample_with(&self, uv: [f64; 2], decode: impl Fn(u8) -> f64) -> [f64; 4] {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv[0] * w as f64 - 0.5;
        let y = uv[1] * h as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |xi: i64, yi: i64| -> [f64; 4] {
            let (xi, yi) = (xi.rem_euclid(w), yi.rem_euclid(h));
            let o = ((yi * w + xi) * 4) as usize;
            std::array::from_fn(|c| decode(self.rgba8[o + c]))
        };
        let (x0, y0) = (x0 as i64, y0 as i64);
        let (a, b, c, d) = (
            texel(x0, y0),
            texel(x0 + 1, y0),
            texel(x0, y0 + 1),
            texel(x0 + 1, y0 + 1),
        );
        std::array::from_fn(|i| {
            (a[i] * (1.0 - fx) + b[i] * fx) * (1.0 - fy) + (c[i] * (1.0 - fx) + d[i] * fx) * fy
        })
    }
}
