//! The overlay's glyph pass on lavapipe against its CPU mirror
//! (`OverlayLayout::shade`): text at two magnifications over a known
//! background, every pixel of an RGBA32F target compared. The shader's
//! only arithmetic is the blend of 1.0 / 0.6 over the background, so the
//! two agree to f32 rounding (1e-6).

mod common;

use inlay::headless::{run_headless, Scene};
use inlay::overlay::{OverlayLayout, OverlayPass};
use inlay_engine::graph::{FrameGraph, ImageAccess, ImageHandle, LoadOp, PassKind};
use inlay_engine::{vk, ImageDesc};

const FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const BACKGROUND: [f32; 4] = [0.25, 0.5, 0.75, 1.0];

struct OverlayScene {
    pass: OverlayPass,
    lines: Vec<String>,
    scale: u32,
}

impl Scene for OverlayScene {
    fn build(
        &mut self,
        graph: &mut FrameGraph,
        width: u32,
        height: u32,
        _time: f32,
    ) -> anyhow::Result<ImageHandle> {
        let target = graph.create_image(
            "background",
            ImageDesc {
                width,
                height,
                format: FORMAT,
            },
        );
        // A raster pass that only clears: the known background.
        let mut clear = graph.add_pass("clear", PassKind::Raster);
        let target = clear.image(
            target,
            ImageAccess::ColorAttachment(LoadOp::Clear(BACKGROUND)),
        );
        clear.exec(|_| Ok(()));
        Ok(self.pass.add(graph, target, &self.lines, self.scale))
    }

    fn output_format(&self) -> vk::Format {
        FORMAT
    }
}

#[test]
fn overlay_glyphs_match_the_cpu_mirror() {
    let ctx = common::gpu();
    let lib = inlay_passes::shaders::library().unwrap();
    let lines: Vec<String> = vec![
        "9.6 fps  GPU 53.7 ms".into(),
        "Shadow: skipped (off)".into(),
        "~{|}@#%&*()[]<>".into(),
        "é → non-ASCII".into(),
    ];
    for (scale, (w, h)) in [(1u32, (150u32, 44u32)), (2, (120, 60))] {
        let mut scene = OverlayScene {
            pass: OverlayPass::new(&ctx, &lib, FORMAT).unwrap(),
            lines: lines.clone(),
            scale,
        };
        let image = run_headless(&ctx, &mut scene, w, h, 1, 0.0).unwrap().image;
        let layout = OverlayLayout::new(w, h, &lines, scale).unwrap();
        let (mut lit, mut worst) = (0, 0.0f32);
        for y in 0..h {
            for x in 0..w {
                let want = layout.shade(x, y, BACKGROUND);
                let got = image.pixels[(y * w + x) as usize];
                lit += (want[0] == 1.0) as u32;
                for c in 0..4 {
                    worst = worst.max((want[c] - got[c]).abs());
                }
                assert!(
                    (0..4).all(|c| (want[c] - got[c]).abs() <= 1e-6),
                    "scale {scale}, pixel ({x}, {y}): GPU {got:?}, CPU {want:?}"
                );
            }
        }
        // The text is there: lit glyph pixels, and cells cut at the edges.
        assert!(lit > 100, "scale {scale}: {lit} glyph pixels");
        assert!(
            (layout.cols as usize) < lines[0].len() || scale == 1,
            "cut at the right edge"
        );
        eprintln!("scale {scale}: {lit} glyph pixels, largest difference {worst:e}");
    }
    common::assert_no_validation_errors(&ctx);
}
