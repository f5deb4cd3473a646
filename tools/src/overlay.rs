//! The on-screen overlay: lines of text (frame rate, per-pass GPU times,
//! the viewer's settings) drawn over the presented image by one raster
//! pass (`shaders/overlay.wgsl`) with an 8×8 bitmap font (`font8x8`).

use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle, LoadOp};
use inlay_engine::shader::{compile, ShaderLibrary, ShaderStage};
use inlay_engine::{vk, Buffer, Context, GraphicsDesc, GraphicsPipeline};

inlay_engine::gpu_struct! {
    /// `OverlayPush` of `shaders/overlay.wgsl`.
    pub struct OverlayPush = "overlay.wgsl" : "OverlayPush" {
        /// Text columns.
        pub cols: u32,
        /// Text rows.
        pub rows: u32,
        /// Glyph magnification.
        pub scale: u32,
        /// Left edge of the text (pixels).
        pub origin_x: u32,
        /// Top edge of the text (pixels).
        pub origin_y: u32,
    }
}

/// The glyphs as the shader reads them: two little-endian words per glyph.
pub fn font_words() -> Vec<u32> {
    font8x8::legacy::BASIC_LEGACY
        .iter()
        .flat_map(|g| {
            [
                u32::from_le_bytes([g[0], g[1], g[2], g[3]]),
                u32::from_le_bytes([g[4], g[5], g[6], g[7]]),
            ]
        })
        .collect()
}

/// `lines` laid out in a `cols`×`rows` grid of character codes (0: empty
/// cell, drawn transparent); characters outside ASCII become `?`, lines
/// and rows beyond the grid are cut.
pub fn text_grid(lines: &[String], cols: usize, rows: usize) -> Vec<u32> {
    let mut grid = vec![0u32; cols * rows];
    for (r, line) in lines.iter().take(rows).enumerate() {
        for (c, ch) in line.chars().take(cols).enumerate() {
            grid[r * cols + c] = if ch.is_ascii() { ch as u32 } else { '?' as u32 };
        }
    }
    grid
}

/// Pixels from the image's top-left corner to the text's.
pub const ORIGIN: u32 = 4;

/// Where the text goes on a `width`×`height` image: a `cols`×`rows` grid
/// of cells `8·scale` pixels square from [`ORIGIN`], as many columns as
/// the longest line needs and fit, as many rows as lines fit.
pub struct OverlayLayout {
    /// Columns of cells.
    pub cols: u32,
    /// Rows of cells.
    pub rows: u32,
    /// Glyph magnification (at least 1).
    pub scale: u32,
    /// The character codes, row-major ([`text_grid`]).
    pub grid: Vec<u32>,
}

impl OverlayLayout {
    /// The layout of `lines` at `scale`; None when nothing fits or there
    /// is nothing to draw.
    pub fn new(width: u32, height: u32, lines: &[String], scale: u32) -> Option<Self> {
        let scale = scale.max(1);
        let cell = 8 * scale;
        let cols = (width.saturating_sub(2 * ORIGIN) / cell) as usize;
        let rows = lines
            .len()
            .min((height.saturating_sub(2 * ORIGIN) / cell) as usize);
        if lines.is_empty() || cols == 0 || rows == 0 {
            return None;
        }
        let cols = cols
            .min(lines.iter().map(|l| l.chars().count()).max().unwrap_or(0))
            .max(1);
        Some(Self {
            cols: cols as u32,
            rows: rows as u32,
            scale,
            grid: text_grid(lines, cols, rows),
        })
    }

    /// The CPU mirror of `shaders/overlay.wgsl` with its blend (premultiplied
    /// "over": src + (1 − src.a)·dst): pixel (x, y) of an image holding
    /// `background` everywhere after the overlay is drawn.
    pub fn shade(&self, x: u32, y: u32, background: [f32; 4]) -> [f32; 4] {
        let cell = (8 * self.scale) as i64;
        let (px, py) = (x as i64 - ORIGIN as i64, y as i64 - ORIGIN as i64);
        if px < 0 || py < 0 || px >= cell * self.cols as i64 || py >= cell * self.rows as i64 {
            return background;
        }
        let (cx, cy) = ((px / cell) as usize, (py / cell) as usize);
        let ch = self.grid[cy * self.cols as usize + cx].min(127) as usize;
        if ch == 0 {
            return background;
        }
        let (tx, ty) = (
            ((px % cell) / self.scale as i64) as usize,
            ((py % cell) / self.scale as i64) as usize,
        );
        let glyph = font8x8::legacy::BASIC_LEGACY[ch];
        let src = if (glyph[ty] >> tx) & 1 != 0 {
            [1.0, 1.0, 1.0, 1.0]
        } else {
            [0.0, 0.0, 0.0, 0.6]
        };
        std::array::from_fn(|c| src[c] + (1.0 - src[3]) * background[c])
    }
}

/// The overlay pipeline for one swapchain format, with the font uploaded.
pub struct OverlayPass {
    pipeline: Arc<GraphicsPipeline>,
    font: Arc<Buffer>,
    format: vk::Format,
}

impl OverlayPass {
    /// Builds the pipeline for `format` and uploads the font.
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        format: vk::Format,
    ) -> anyhow::Result<Self> {
        let v = compile(lib, "overlay.wgsl", "vs_main", ShaderStage::Vertex, &[])?;
        let f = compile(lib, "overlay.wgsl", "fs_main", ShaderStage::Fragment, &[])?;
        let desc = GraphicsDesc {
            color_formats: vec![format],
            depth_format: None,
            depth_test: false,
            depth_write: false,
            blend: true,
            cull_back: false,
        };
        let bytes: Vec<u8> = font_words().iter().flat_map(|w| w.to_le_bytes()).collect();
        Ok(Self {
            pipeline: Arc::new(GraphicsPipeline::new(ctx, &v, &f, &desc)?),
            font: Arc::new(Buffer::with_data(
                ctx,
                "overlay-font",
                &bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?),
            format,
        })
    }

    /// The format it draws to.
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// Adds the `overlay` pass drawing `lines` over `target` (kept) at
    /// glyph magnification `scale`, from 4 pixels in; nothing when
    /// `lines` is empty.
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        target: ImageHandle,
        lines: &[String],
        scale: u32,
    ) -> ImageHandle {
        let Some(desc) = graph.image_desc(target) else {
            return target;
        };
        let Some(layout) = OverlayLayout::new(desc.width, desc.height, lines, scale) else {
            return target;
        };
        let (cols, rows, scale) = (layout.cols, layout.rows, layout.scale);
        let grid = layout.grid;
        let text = graph.upload_buffer(
            "overlay-text",
            grid.iter().flat_map(|c| c.to_le_bytes()).collect(),
        );
        let font = graph.import_buffer(&self.font, None);
        let push = OverlayPush {
            cols,
            rows,
            scale,
            origin_x: ORIGIN,
            origin_y: ORIGIN,
        };
        let mut out = target;
        let mut pass = graph.raster_pass("overlay");
        pass.color(&mut out, LoadOp::Load);
        pass.draw(&self.pipeline)
            .read("font", font)
            .read("text", text)
            .push(&push)
            .vertices(3, 1);
        pass.finish();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_pack_row_by_row_and_text_fills_the_grid() {
        let words = font_words();
        assert_eq!(words.len(), 256);
        let a = font8x8::legacy::BASIC_LEGACY['A' as usize];
        assert_eq!(words[2 * 65] & 0xff, a[0] as u32);
        assert_eq!(words[2 * 65 + 1] >> 24, a[7] as u32);
        let g = text_grid(&["ab".into(), "é".into(), "cut".into()], 2, 2);
        assert_eq!(g, vec!['a' as u32, 'b' as u32, '?' as u32, 0]);
    }
}
