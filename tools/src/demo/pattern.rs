//! CPU mirror of shaders/demo/pattern.wgsl: the sky and quad layout the demo's
//! GPU test checks rendered pixels against.

/// HDR sky at uv in `[0,1]²` (v down) and time `t` (seconds).
pub fn demo_sky(uv: [f32; 2], t: f32) -> [f32; 3] {
    let h = 1.0 - uv[1];
    let lo = [0.9, 0.6, 0.4];
    let hi = [0.2, 0.4, 1.0];
    let base: [f32; 3] = std::array::from_fn(|i| (lo[i] + (hi[i] - lo[i]) * h) * (1.0 + 3.0 * h));
    let sun = [0.75 + 0.1 * t.sin(), 0.25];
    let d = [uv[0] - sun[0], uv[1] - sun[1]];
    let glow = 20.0 * (-(d[0] * d[0] + d[1] * d[1]) / 0.002).exp();
    [base[0] + glow, base[1] + glow * 0.9, base[2] + glow * 0.7]
}

/// One of the demo's two quads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DemoQuad {
    /// Centre in clip space (x right, y up).
    pub center: [f32; 2],
    /// Half the side in clip-space y units (x is divided by the aspect ratio).
    pub half_size: f32,
    /// Depth in [0, 1] (smaller is nearer).
    pub depth: f32,
    /// Linear HDR colour.
    pub color: [f32; 3],
}

/// Quad `i` (0: near warm, 1: far cool) at time `t`.
pub fn demo_quad(i: u32, t: f32) -> DemoQuad {
    if i == 0 {
        DemoQuad {
            center: [-0.15 + 0.3 * t.sin(), -0.1],
            half_size: 0.35,
            depth: 0.25,
            color: [4.0, 0.8, 0.2],
        }
    } else {
        DemoQuad {
            center: [0.15, 0.1],
            half_size: 0.35,
            depth: 0.75,
            color: [0.2, 0.8, 3.0],
        }
    }
}

impl DemoQuad {
    /// Whether the centre of pixel (x, y) of a `w`×`h` image lies inside the
    /// quad, with `margin` pixels to spare (so rasterisation rules don't matter).
    pub fn covers(&self, x: u32, y: u32, w: u32, h: u32, margin: f32) -> bool {
        let aspect = w as f32 / h as f32;
        let px = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
        let py = 1.0 - (y as f32 + 0.5) / h as f32 * 2.0;
        let mx = margin * 2.0 / w as f32;
        let my = margin * 2.0 / h as f32;
        (px - self.center[0]).abs() < self.half_size / aspect - mx
            && (py - self.center[1]).abs() < self.half_size - my
    }
}
