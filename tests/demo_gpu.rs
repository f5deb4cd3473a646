//! The engine demo graph run headless on the GPU (lavapipe in CI) with the
//! validation layer on: pixel values against the CPU mirror of its pattern,
//! culling, timings, transient reuse and resizing.

mod common;

use inlay::demo::pattern::{demo_quad, demo_sky};
use inlay::demo::{DemoPipelines, DemoScene};
use inlay::headless::run_headless;
use inlay_passes::shaders::embedded_library;

/// f16 storage rounds to a relative half-ulp of 2^-11 ≈ 4.9e-4; the GPU's
/// exp/sin differ from Rust's by far less. 1e-3 relative (+1e-3 absolute for
/// values near 0) covers both with room, while any real error in the
/// pattern, the sampling position or the pass order is orders larger.
fn close(gpu: f32, cpu: f32) -> bool {
    (gpu - cpu).abs() <= 1e-3 * cpu.abs().max(1.0)
}

#[test]
fn demo_pixels_match_the_cpu_pattern_and_depth_test_wins() {
    let ctx = common::gpu();
    let lib = embedded_library();
    let mut scene = DemoScene {
        pipelines: DemoPipelines::new(&ctx, &lib).unwrap(),
        keep_heatmap: false,
    };
    let (w, h) = (64u32, 48u32);
    let run = run_headless(&ctx, &mut scene, w, h, 3, 0.0).unwrap();
    common::assert_no_validation_errors(&ctx);
    let img = &run.image;
    assert_eq!(img.non_finite_count(), 0);
    // Frames 0..3 run at t = 0, 1/60, 2/60: the last is read back.
    let t = 2.0 / 60.0;
    let near = demo_quad(0, t);
    let far = demo_quad(1, t);
    let (mut sky_px, mut near_px, mut far_px, mut overlap_px) = (0, 0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let p = img.at(x, y);
            // Pixels within a pixel of a quad's edge are skipped: which
            // side they land on is up to rasterisation rules.
            let in_near = near.covers(x, y, w, h, 1.0);
            let touches_near = near.covers(x, y, w, h, -1.0);
            let in_far = far.covers(x, y, w, h, 1.0);
            let touches_far = far.covers(x, y, w, h, -1.0);
            let expected = if in_near {
                // Near quad: drawn first, the far one drawn later must fail the depth test.
                if in_far {
                    overlap_px += 1;
                }
                near_px += 1;
                near.color
            } else if in_far && !touches_near {
                far_px += 1;
                far.color
            } else if !touches_near && !touches_far {
                sky_px += 1;
                demo_sky(
                    [(x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32],
                    t,
                )
            } else {
                continue;
            };
            for c in 0..3 {
                assert!(
                    close(p[c], expected[c]),
                    "pixel ({x},{y}) channel {c}: gpu {} vs cpu {}",
                    p[c],
                    expected[c]
                );
            }
        }
    }
    assert!(
        sky_px > 1000 && near_px > 150 && far_px > 100 && overlap_px > 20,
        "coverage: sky {sky_px} near {near_px} far {far_px} overlap {overlap_px}"
    );
    // The sun makes the image HDR: values well above 1 survive the readback.
    let max = img.pixels.iter().map(|p| p[0]).fold(0.0f32, f32::max);
    assert!(max > 10.0, "max red {max}");
}

#[test]
fn demo_timings_cover_every_pass_and_the_debug_pass_is_culled_unless_consumed() {
    let ctx = common::gpu();
    let lib = embedded_library();
    let mut scene = DemoScene {
        pipelines: DemoPipelines::new(&ctx, &lib).unwrap(),
        keep_heatmap: false,
    };
    let run = run_headless(&ctx, &mut scene, 32, 32, 5, 0.0).unwrap();
    assert_eq!(run.culled, ["heatmap"]);
    assert_eq!(run.timings.len(), 5, "every frame's timings are collected");
    for (i, f) in run.timings.iter().enumerate() {
        assert_eq!(f.frame, i as u64);
        let names: Vec<&str> = f.passes.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["sky", "quads", "scene", "readback"]);
        assert!(f
            .passes
            .iter()
            .all(|p| p.gpu_ms.is_finite() && p.gpu_ms >= 0.0 && p.cpu_ms >= 0.0));
        let sum: f64 = f.passes.iter().map(|p| p.gpu_ms).sum();
        assert!(
            f.gpu_total_ms + 1e-6 >= sum * 0.999,
            "the frame spans its passes: {} < {sum}",
            f.gpu_total_ms
        );
    }
    assert!(
        run.timings.iter().any(|f| f.gpu_total_ms > 0.0),
        "timestamps advance"
    );

    scene.keep_heatmap = true;
    let run = run_headless(&ctx, &mut scene, 32, 32, 1, 0.0).unwrap();
    assert!(run.culled.is_empty());
    assert!(run.timings[0].gpu_ms("heatmap").is_some());
    common::assert_no_validation_errors(&ctx);
}

#[test]
fn transients_are_reused_across_frames_and_recreated_on_resize() {
    use inlay_engine::graph::FrameGraph;
    use inlay_engine::{vk, ImageDesc, Readback, Renderer, SubmitSync};

    let ctx = common::gpu();
    let lib = embedded_library();
    let pipelines = DemoPipelines::new(&ctx, &lib).unwrap();
    let mut renderer = Renderer::new(&ctx, 2).unwrap();
    let mut created_after = Vec::new();
    for (frame, (w, h)) in [
        (24, 16),
        (24, 16),
        (24, 16),
        (24, 16),
        (40, 20),
        (40, 20),
        (40, 20),
    ]
    .into_iter()
    .enumerate()
    {
        let readback = Readback::new(
            &ctx,
            ImageDesc {
                width: w,
                height: h,
                format: vk::Format::R16G16B16A16_SFLOAT,
            },
        )
        .unwrap();
        let mut graph = FrameGraph::new();
        let out = inlay::demo::add_demo_passes(&mut graph, &pipelines, w, h, frame as f32);
        readback.add_to_graph(&mut graph, out.hdr);
        renderer.submit(graph, &SubmitSync::none()).unwrap();
        created_after.push(renderer.transients_created());
        // The readback buffer must outlive its frame: keep it until done.
        renderer.finish().unwrap();
        let img = readback.read().unwrap();
        assert_eq!((img.width, img.height), (w, h));
        assert_eq!(img.non_finite_count(), 0);
    }
    // Two frame slots each create their transients once; frames 3-4 reuse them.
    assert_eq!(created_after[1], 2 * created_after[0]);
    assert_eq!(
        created_after[3], created_after[1],
        "no new resources at a steady size: {created_after:?}"
    );
    assert!(
        created_after[4] > created_after[3],
        "a new size creates new resources: {created_after:?}"
    );
    assert_eq!(created_after[6], created_after[5], "{created_after:?}");
    common::assert_no_validation_errors(&ctx);
}
