//! What the budget of `inlay_passes::march::loop_budget` assumes of the
//! device: where `DeviceInfo::loop_iteration_limit` is Some(L) (llvmpipe),
//! an invocation's loops stop, silently, once L iterations of all of them
//! together have run, whether one loop, loops after another or loops
//! inside loops (a short loop of constant count, with a small body, is
//! unrolled first and does not count); elsewhere every loop runs whole. If Mesa changes its
//! limit, this is the test that says so.

mod common;

use inlay_engine::{BufferReadback, Push};

/// What mode `mode` of `checks/loop_count.wgsl` counts with `n`.
fn count(mode: u32, n: u32) -> u32 {
    let ctx = common::gpu();
    let lib = common::test_library();
    let pipeline = lib
        .compute_pipeline(&ctx, "checks/loop_count.wgsl", "main", &[])
        .unwrap();
    let readback = BufferReadback::new(&ctx, "counted", 16).unwrap();
    common::run_frame(&ctx, |graph| {
        let mut counted = graph.create_buffer("counted", 16);
        graph
            .compute("loop-count", &pipeline)
            .write("counted", &mut counted)
            .push(&Push::new().u32(n).u32(mode).u32(0).u32(0))
            .groups([1, 1, 1]);
        readback.add_to_graph(graph, "loop-count-readback", counted);
    });
    readback.read_pod::<[u32; 4]>().unwrap()[0]
}

#[test]
fn an_invocations_loops_stop_together_at_the_devices_limit() {
    let limit = common::gpu().info().loop_iteration_limit;
    let Some(limit) = limit else {
        assert_eq!(count(0, 70_000), 70_000);
        assert_eq!(count(1, 40_000), 80_000);
        assert_eq!(count(2, 300), 90_000);
        assert_eq!(count(3, 10_000), 80_000);
        return;
    };
    assert_eq!(limit, inlay_engine::LLVMPIPE_LOOP_LIMIT);
    let limit = limit as u32;
    // Up to the limit, a loop runs whole; past it, it stops there.
    assert_eq!(count(0, limit), limit);
    assert_eq!(count(0, limit + 1), limit);
    assert_eq!(count(0, 70_000), limit);
    // Two loops share it: 2 × 40000 stops short of 65535 (a couple of
    // iterations go to the loops' own entries).
    let two = count(1, 40_000);
    assert!((limit - 8..=limit).contains(&two), "{two}");
    // So do nested ones, the outer loop's iterations counted too: 300 ×
    // 300 stops near 65535 − 300.
    let nested = count(2, 300);
    assert!((limit - 600..=limit - 200).contains(&nested), "{nested}");
    assert_eq!(count(2, 200), 40_000);
    // A short loop of constant count with a small body is unrolled before
    // the limit is counted: 10000 × 8 runs whole. (One with a large body
    // is not: shaders/field/sh_trilinear.wgsl.)
    assert_eq!(count(3, 10_000), 80_000);
}
