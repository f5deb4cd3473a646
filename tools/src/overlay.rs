//! The on-screen overlay: lines of text (frame rate, per-pass GPU times,
//! the viewer's settings) drawn over the presented image by one raster
//! pass (`shaders/overlay.wgsl`) with an 8×8 bitmap font (`font8x8`).

use std::sync::Arc;

use inlay_engine::graph::{
    Binding, BufferAccess, FrameGraph, ImageAccess, ImageHandle, LoadOp, PassKind,
};
use inlay_engine::shader::{compile, ShaderLibrary, ShaderStage};
use inlay_engine::{vk, Buffer, Context, GraphicsDesc, GraphicsPipeline, Push};

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

/// The overlay pipeline for one swapchain format, with the font uploaded.
pub struct OverlayPass {
    pipeline: GraphicsPipeline,
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
            pipeline: GraphicsPipeline::new(ctx, &v, &f, &desc)?,
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
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        target: ImageHandle,
        lines: &[String],
        scale: u32,
    ) -> ImageHandle {
        let Some(desc) = graph.image_desc(target) else {
            return target;
        };
        let scale = scale.max(1);
        let cell = 8 * scale;
        let cols = (desc.width.saturating_sub(8) / cell) as usize;
        let rows = lines
            .len()
            .min((desc.height.saturating_sub(8) / cell) as usize);
        if lines.is_empty() || cols == 0 || rows == 0 {
            return target;
        }
        let cols = cols
            .min(lines.iter().map(|l| l.chars().count()).max().unwrap_or(0))
            .max(1);
        let grid = text_grid(lines, cols, rows);
        let text = graph.upload_buffer(
            "overlay-text",
            grid.iter().flat_map(|c| c.to_le_bytes()).collect(),
        );
        let font = graph.import_buffer(&self.font, None);
        let mut pass = graph.add_pass("overlay", PassKind::Raster);
        pass.buffer(font, BufferAccess::StorageRead);
        pass.buffer(text, BufferAccess::StorageRead);
        let out = pass.image(target, ImageAccess::ColorAttachment(LoadOp::Load));
        let push = Push::new()
            .u32(cols as u32)
            .u32(rows as u32)
            .u32(scale)
            .u32(4)
            .u32(4);
        let pipeline = &self.pipeline;
        pass.exec(move |ctx| {
            ctx.draw(
                pipeline,
                &[Binding::StorageBuffer(font), Binding::StorageBuffer(text)],
                push.bytes(),
                3,
                1,
            )
        });
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
