//! A long run does not grow memory: frames of DOG with its object dragged,
//! lit, cast-shadowed and self-shadowed (every pass a viewer frame runs,
//! probe and fit included) are rendered in one process, and its resident memory after the warm-up must stay flat.
//! It caught Mesa 22.3's lavapipe recompiling the cast-shadow shader at
//! every bind and keeping each compile (~1.2 MB and a JIT per frame) while
//! the SSDF block was a uniform buffer (see shaders/ssdf/ssdf.wgsl).
//! In its own test binary so no other test's allocations are counted.

mod common;

use inlay::commands::profile::{profile_view, Motion};
use inlay::scene_view::open_view;
use inlay::view::presets::Preset;

/// Resident memory of this process in MiB (Linux's /proc/self/status).
fn resident_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: f64 = status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()?;
    Some(kb / 1024.0)
}

#[test]
fn rendering_frame_after_frame_keeps_memory_flat() {
    if resident_mib().is_none() {
        eprintln!("no /proc/self/status: resident memory cannot be read here");
        return;
    }
    let ctx = common::gpu();
    let lib = inlay_passes::shaders::library().unwrap();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dog.toml");
    let mut scene = Preset::Fast.apply(&inlay_passes::scene::load_scene(&path).unwrap());
    assert!(scene.shadows.cast && scene.shadows.self_shadow);
    // A small field and SSDF (cheap to bake on a cold cache): what is
    // measured is the per-frame work, not the assets' size.
    scene.bake.resolution = 24;
    scene.bake.samples = 2;
    scene.bake.bounces = 0;
    scene.shadows.bake.grid = 4;
    let mut view = open_view(&ctx, &lib, &scene, scene.march, None, "0", true).unwrap();
    let (w, h) = (64, 36);
    // Warm-up: pipelines, pools, the allocator's blocks.
    profile_view(&ctx, &mut view, w, h, 12, Motion::Drag).unwrap();
    let before = resident_mib().unwrap();
    let frames = 60;
    let run = profile_view(&ctx, &mut view, w, h, frames, Motion::Drag).unwrap();
    let after = resident_mib().unwrap();
    common::assert_no_validation_errors(&ctx);
    let ran = |name: &str| {
        run.frames
            .iter()
            .all(|f| f.passes.iter().any(|p| p.name == name))
    };
    for pass in ["probe-trace", "sg-fit", "object-shade", "cast-shadow"] {
        assert!(ran(pass), "{pass} ran in every frame");
    }
    // A leak of the size it caught adds ~70 MiB here; timings and descriptor
    // pools add well under 1 MiB.
    let grown = after - before;
    eprintln!("resident memory {before:.1} MiB -> {after:.1} MiB over {frames} frames");
    assert!(
        grown < 16.0,
        "resident memory grew {grown:.1} MiB over {frames} frames ({before:.1} -> {after:.1})"
    );
}
