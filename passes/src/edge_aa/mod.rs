//! Edge anti-aliasing of the inserted objects (`object-edge-aa`, compute;
//! beyond the paper). The G-buffer is rasterised at one sample per pixel,
//! so an object's outline is stair-stepped where a multisampled or
//! supersampled render would show partial coverage. At the pixels where the
//! object index changes between 4-neighbours, the composited colour is
//! blended towards its 3 × 3 neighbourhood (edges weight 2, corners 1) by
//! FXAA's sub-pixel measure: how far the pixel's luma stands from the
//! neighbourhood's, over the neighbourhood's contrast, smoothstepped (FXAA
//! squares it as well; unsquared, the error on outline pixels against a
//! 4 × 4 supersampled render fell further: DOG 0.77 → 0.70, ROOM 0.83 →
//! 0.73 of the single-sampled error). Contrast below the thresholds is
//! left alone, and every other pixel is copied, so the field and the
//! objects' interiors stay sharp.
//! [`edge_aa_reference`] is the f64 CPU mirror of
//! `shaders/edge_aa/edge_aa.wgsl`.

use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{ComputePipeline, Context, ImageDesc};

use crate::composite::COMPOSITE_FORMAT;
use crate::frame::meta::{Effect, EffectSwitch, PassInfo, Table1Module};

inlay_engine::gpu_struct! {
    /// `EdgeAaPush` of `shaders/edge_aa/edge_aa.wgsl`.
    pub struct EdgeAaPush = "edge_aa/edge_aa.wgsl" : "EdgeAaPush" {
        /// Image width.
        pub width: u32,
        /// Image height.
        pub height: u32,
        /// The first pixel the dispatch covers (x).
        pub origin_x: u32,
        /// The first pixel the dispatch covers (y).
        pub origin_y: u32,
        /// [`EdgeAaKnobs::subpixel`].
        pub subpixel: f32,
        /// [`EdgeAaKnobs::threshold`].
        pub threshold: f32,
        /// [`EdgeAaKnobs::threshold_min`].
        pub threshold_min: f32,
    }
}

/// The edge anti-aliasing pass: its name, Table 1 module and switch.
pub const OBJECT_EDGE_AA_INFO: PassInfo = PassInfo {
    name: "object-edge-aa",
    module: Table1Module::Compositing,
    switch: Some(EDGE_AA_SWITCH),
};

/// The pass's name in the frame graph (and in timings).
pub const OBJECT_EDGE_AA: &str = OBJECT_EDGE_AA_INFO.name;

/// The switch that leaves the objects' outlines single-sampled.
pub const EDGE_AA_SWITCH: EffectSwitch = EffectSwitch {
    effect: Effect::EdgeAa,
    name: "edge-aa",
    key: "F6",
};

/// The blend's knobs (FXAA 3.11's defaults for its quality preset).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeAaKnobs {
    /// Sub-pixel strength: 0 leaves every pixel, 1 blends fully.
    pub subpixel: f64,
    /// Contrast below this share of the brightest luma is left alone.
    pub threshold: f64,
    /// Contrast below this luma is left alone.
    pub threshold_min: f64,
}

impl Default for EdgeAaKnobs {
    fn default() -> Self {
        Self {
            subpixel: 0.75,
            threshold: 0.125,
            threshold_min: 0.0312,
        }
    }
}

/// Luma of a linear colour as it would look: each channel compressed to
/// x / (1 + x), then weighted (Rec. 601, as FXAA).
pub fn display_luma(c: [f64; 4]) -> f64 {
    let w = [0.299, 0.587, 0.114];
    (0..3)
        .map(|i| w[i] * c[i].max(0.0) / (1.0 + c[i].max(0.0)))
        .sum()
}

/// The f64 mirror of the shader: `colour` and `object` (the G-buffer's
/// object index per pixel, −1 where none) are `width × height`, row-major.
pub fn edge_aa_reference(
    colour: &[[f64; 4]],
    object: &[f64],
    width: usize,
    height: usize,
    knobs: &EdgeAaKnobs,
) -> Vec<[f64; 4]> {
    let at = |x: i64, y: i64| -> usize {
        let x = x.clamp(0, width as i64 - 1) as usize;
        let y = y.clamp(0, height as i64 - 1) as usize;
        y * width + x
    };
    let mut out = colour.to_vec();
    for y in 0..height as i64 {
        for x in 0..width as i64 {
            let i = at(x, y);
            let here = object[i];
            let outline = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|&(dx, dy)| object[at(x + dx, y + dy)] != here);
            if !outline {
                continue;
            }
            let centre = colour[i];
            let (mut sum, mut luma_sum, mut weight) = ([0.0; 4], 0.0, 0.0);
            let (mut lo, mut hi) = (display_luma(centre), display_luma(centre));
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if dx == 0 && dy == 0 {
                        continue;
                    }
                    let c = colour[at(x + dx, y + dy)];
                    let w = if dx == 0 || dy == 0 { 2.0 } else { 1.0 };
                    let l = display_luma(c);
                    for k in 0..4 {
                        sum[k] += w * c[k];
                    }
                    luma_sum += w * l;
                    weight += w;
                    lo = f64::min(lo, l);
                    hi = f64::max(hi, l);
                }
            }
            let range = hi - lo;
            if range < f64::max(knobs.threshold_min, knobs.threshold * hi) {
                continue;
            }
            let b = ((luma_sum / weight - display_luma(centre)).abs() / range).clamp(0.0, 1.0);
            let s = (3.0 - 2.0 * b) * b * b;
            let blend = s * knobs.subpixel;
            out[i] = std::array::from_fn(|k| centre[k] + blend * (sum[k] / weight - centre[k]));
        }
    }
    out
}

/// The edge anti-aliasing pipeline with its knobs.
pub struct EdgeAaPass {
    pipeline: Arc<ComputePipeline>,
    knobs: EdgeAaKnobs,
}

impl EdgeAaPass {
    /// Compiles the pass.
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        knobs: EdgeAaKnobs,
    ) -> anyhow::Result<Self> {
        Ok(Self {
            pipeline: lib.compute_pipeline(ctx, "edge_aa/edge_aa.wgsl", "main", &[])?,
            knobs,
        })
    }

    /// Adds `object-edge-aa`: `colour` (the composited frame) with the
    /// outlines of the objects in `distance_id` (the G-buffer's distance
    /// and object index) blended; returns the new image. With `region`
    /// (x0, y0, x1, y1, ends exclusive: the pixels the objects can cover,
    /// widened by a pixel, as [`crate::camera::CameraFrame::sphere_pixels`]
    /// gives them), the frame is copied and only the region's pixels are
    /// taken: an outline lies on an object or beside one, and every other
    /// pixel is a copy either way.
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        colour: ImageHandle,
        distance_id: ImageHandle,
        region: Option<[u32; 4]>,
    ) -> ImageHandle {
        let (width, height) = graph
            .image_desc(colour)
            .map_or((1, 1), |d| (d.width, d.height));
        let desc = ImageDesc {
            width,
            height,
            format: COMPOSITE_FORMAT,
        };
        let mut out = graph.create_image("edge-aa", desc);
        let whole = [0, 0, width, height];
        let r = region.map_or(whole, |r| {
            [
                r[0].min(width),
                r[1].min(height),
                r[2].min(width),
                r[3].min(height),
            ]
        });
        if r != whole {
            out = graph.copy_image(OBJECT_EDGE_AA, colour, out);
        }
        let k = &self.knobs;
        let push = EdgeAaPush {
            width,
            height,
            origin_x: r[0],
            origin_y: r[1],
            subpixel: k.subpixel as f32,
            threshold: k.threshold as f32,
            threshold_min: k.threshold_min as f32,
        };
        if r[2] <= r[0] || r[3] <= r[1] {
            return out;
        }
        let pass = graph
            .compute(OBJECT_EDGE_AA, &self.pipeline)
            .read("colour", colour)
            .read("distance_id", distance_id);
        let pass = if r == whole {
            pass.write("out_colour", &mut out)
        } else {
            pass.read_write("out_colour", &mut out)
        };
        pass.push(&push).threads([r[2] - r[0], r[3] - r[1], 1]);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A diagonal step between a bright object and a dark field.
    fn staircase(w: usize, h: usize) -> (Vec<[f64; 4]>, Vec<f64>) {
        let mut colour = vec![[0.05, 0.05, 0.05, 1.0]; w * h];
        let mut object = vec![-1.0; w * h];
        for y in 0..h {
            for x in 0..w {
                if x > y {
                    colour[y * w + x] = [2.0, 1.5, 1.0, 1.0];
                    object[y * w + x] = 0.0;
                }
            }
        }
        (colour, object)
    }

    #[test]
    fn only_outline_pixels_change_and_they_move_towards_their_neighbours() {
        let (w, h) = (8, 8);
        let (colour, object) = staircase(w, h);
        let out = edge_aa_reference(&colour, &object, w, h, &EdgeAaKnobs::default());
        let mut changed = 0;
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let on_outline = (x as i64 - y as i64).abs() <= 1;
                if !on_outline {
                    assert_eq!(out[i], colour[i], "({x}, {y}) is inside a region");
                } else if out[i] != colour[i] {
                    changed += 1;
                    // A blend of the pixel and its neighbours stays within them.
                    assert!(out[i][0] > 0.05 && out[i][0] < 2.0, "{:?}", out[i]);
                }
            }
        }
        assert!(changed >= w, "{changed} outline pixels changed");
    }

    #[test]
    fn flat_or_faint_outlines_are_left_alone() {
        let (w, h) = (6, 6);
        let (mut colour, object) = staircase(w, h);
        // The object as dark as the field: no contrast to blend.
        for c in colour.iter_mut() {
            *c = [0.05, 0.05, 0.05, 1.0];
        }
        let out = edge_aa_reference(&colour, &object, w, h, &EdgeAaKnobs::default());
        assert_eq!(out, colour);
        let (colour, object) = staircase(w, h);
        let off = EdgeAaKnobs {
            subpixel: 0.0,
            ..Default::default()
        };
        assert_eq!(edge_aa_reference(&colour, &object, w, h, &off), colour);
    }

    #[test]
    fn huge_values_stay_finite() {
        let (w, h) = (5, 5);
        let (mut colour, object) = staircase(w, h);
        for c in colour.iter_mut().filter(|c| c[0] > 1.0) {
            *c = [1e30, 1e30, 1e30, 1.0];
        }
        let out = edge_aa_reference(&colour, &object, w, h, &EdgeAaKnobs::default());
        assert!(out.iter().flatten().all(|v| v.is_finite()));
    }
}
