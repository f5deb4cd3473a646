//! Unit tests of the frame graph alone (no device): ordering, culling,
//! transient aliasing, and the barriers and layouts it derives.

use ash::vk;
use vk::AccessFlags2 as A;
use vk::ImageLayout as L;
use vk::PipelineStageFlags2 as S;

use super::*;
use crate::memory::ImageDesc;

fn desc(w: u32) -> ImageDesc {
    ImageDesc {
        width: w,
        height: w,
        format: vk::Format::R16G16B16A16_SFLOAT,
    }
}

fn names(g: &FrameGraph, list: &[usize]) -> Vec<String> {
    list.iter().map(|&p| g.pass_name(p).to_string()).collect()
}

fn image_barrier(plan: &Plan, g: &FrameGraph, pass: &str, image: u32) -> Option<Barrier> {
    let pos = plan.order.iter().position(|&p| g.pass_name(p) == pass)?;
    plan.barriers[pos]
        .iter()
        .find(|b| b.resource == BarrierResource::Image(image))
        .copied()
}

fn buffer_barrier(plan: &Plan, g: &FrameGraph, pass: &str, buffer: u32) -> Option<Barrier> {
    let pos = plan.order.iter().position(|&p| g.pass_name(p) == pass)?;
    plan.barriers[pos]
        .iter()
        .find(|b| b.resource == BarrierResource::Buffer(buffer))
        .copied()
}

#[test]
fn a_late_declared_reader_of_an_old_version_runs_before_the_overwrite() {
    let mut g = FrameGraph::new();
    let x = g.create_image("x", desc(8));
    let mut a = g.add_pass("a", PassKind::Compute);
    let x1 = a.image(x, ImageAccess::StorageWrite);
    let mut b = g.add_pass("b", PassKind::Compute);
    let x2 = b.image(x1, ImageAccess::StorageReadWrite);
    let mut c = g.add_pass("c", PassKind::Compute);
    c.image(x1, ImageAccess::Sampled);
    c.keep();
    g.mark_output_image(x2);
    let plan = Plan::new(&g).unwrap();
    assert_eq!(
        names(&g, &plan.order),
        ["a", "c", "b"],
        "c reads version 1, which b overwrites"
    );
    // c samples (layout change from GENERAL); b must wait for c's read and
    // change the layout back.
    let bc = image_barrier(&plan, &g, "c", 0).unwrap();
    assert_eq!(
        (bc.old_layout, bc.new_layout),
        (L::GENERAL, L::SHADER_READ_ONLY_OPTIMAL)
    );
    assert_eq!(
        (bc.src_stage, bc.src_access),
        (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE)
    );
    let bb = image_barrier(&plan, &g, "b", 0).unwrap();
    assert_eq!(
        (bb.old_layout, bb.new_layout),
        (L::SHADER_READ_ONLY_OPTIMAL, L::GENERAL)
    );
    assert!(bb.src_stage.contains(S::COMPUTE_SHADER));
    assert_eq!(
        bb.dst_access,
        A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE
    );
}

#[test]
fn order_follows_dependencies_not_declaration_when_they_differ() {
    // A chain declared producer-first still yields producer-first, and
    // independent passes keep declaration order.
    let mut g = FrameGraph::new();
    let x = g.create_buffer("x", 64);
    let y = g.create_buffer("y", 64);
    let mut p1 = g.add_pass("make-x", PassKind::Compute);
    let x1 = p1.buffer(x, BufferAccess::StorageWrite);
    let mut p2 = g.add_pass("make-y", PassKind::Compute);
    let y1 = p2.buffer(y, BufferAccess::StorageWrite);
    let mut p3 = g.add_pass("use-both", PassKind::Compute);
    p3.buffer(x1, BufferAccess::StorageRead);
    p3.buffer(y1, BufferAccess::StorageRead);
    p3.keep();
    let plan = Plan::new(&g).unwrap();
    assert_eq!(names(&g, &plan.order), ["make-x", "make-y", "use-both"]);
    let b = buffer_barrier(&plan, &g, "use-both", 0).unwrap();
    assert_eq!(
        (b.src_stage, b.src_access, b.dst_stage, b.dst_access),
        (
            S::COMPUTE_SHADER,
            A::SHADER_STORAGE_WRITE,
            S::COMPUTE_SHADER,
            A::SHADER_STORAGE_READ
        )
    );
    assert!(
        buffer_barrier(&plan, &g, "make-x", 0).is_none(),
        "a first write to a fresh buffer needs no barrier"
    );
}

#[test]
fn passes_whose_results_nothing_consumes_are_culled_transitively() {
    let mut g = FrameGraph::new();
    let used = g.create_image("used", desc(4));
    let unused = g.create_image("unused", desc(4));
    let scratch = g.create_buffer("scratch", 16);
    let mut p = g.add_pass("scratch-producer", PassKind::Compute);
    let s1 = p.buffer(scratch, BufferAccess::StorageWrite);
    let mut p = g.add_pass("debug-view", PassKind::Compute);
    p.buffer(s1, BufferAccess::StorageRead);
    p.image(unused, ImageAccess::StorageWrite);
    let mut p = g.add_pass("main", PassKind::Compute);
    let used1 = p.image(used, ImageAccess::StorageWrite);
    g.mark_output_image(used1);
    let plan = Plan::new(&g).unwrap();
    assert_eq!(names(&g, &plan.order), ["main"]);
    assert_eq!(names(&g, &plan.culled), ["scratch-producer", "debug-view"]);
    assert_eq!(
        plan.image_targets[1], None,
        "culled resources get no memory"
    );
    assert_eq!(plan.slots.len(), 1);
}

#[test]
fn writes_to_imported_resources_and_kept_passes_are_never_culled() {
    let mut g = FrameGraph::new();
    let persistent = g.import_external_buffer("lobes", 256, SyncState::FRESH, None);
    let mut p = g.add_pass("fit", PassKind::Compute);
    p.buffer(persistent, BufferAccess::StorageReadWrite);
    let mut p = g.add_pass("stats", PassKind::Compute);
    p.keep();
    let plan = Plan::new(&g).unwrap();
    assert_eq!(names(&g, &plan.order), ["fit", "stats"]);
}

#[test]
fn a_clear_discards_the_previous_writer_which_is_culled() {
    let mut g = FrameGraph::new();
    let x = g.create_image("x", desc(4));
    let mut p = g.add_pass("overwritten", PassKind::Compute);
    let x1 = p.image(x, ImageAccess::StorageWrite);
    let mut p = g.add_pass("clear-and-draw", PassKind::Raster);
    let x2 = p.image(x1, ImageAccess::ColorAttachment(LoadOp::Clear([0.0; 4])));
    g.mark_output_image(x2);
    let plan = Plan::new(&g).unwrap();
    assert_eq!(names(&g, &plan.order), ["clear-and-draw"]);
    let b = image_barrier(&plan, &g, "clear-and-draw", 0).unwrap();
    assert_eq!(
        (b.old_layout, b.new_layout),
        (L::UNDEFINED, L::COLOR_ATTACHMENT_OPTIMAL)
    );
}

#[test]
fn compute_to_raster_to_transfer_barriers_and_layouts() {
    let mut g = FrameGraph::new();
    let sky = g.create_image("sky", desc(16));
    let color = g.create_image("color", desc(16));
    let depth = g.create_image(
        "depth",
        ImageDesc {
            format: vk::Format::D32_SFLOAT,
            ..desc(16)
        },
    );
    let verts = g.create_buffer("verts", 1024);
    let readback = g.import_external_buffer(
        "readback",
        16 * 16 * 8,
        SyncState::FRESH,
        Some(SyncState {
            stage: S::HOST,
            access: A::HOST_READ,
            layout: L::UNDEFINED,
        }),
    );
    let mut p = g.add_pass("sky", PassKind::Compute);
    let sky1 = p.image(sky, ImageAccess::StorageWrite);
    let mut p = g.add_pass("quads", PassKind::Compute);
    let verts1 = p.buffer(verts, BufferAccess::StorageWrite);
    let mut p = g.add_pass("scene", PassKind::Raster);
    p.image(sky1, ImageAccess::Sampled);
    p.buffer(verts1, BufferAccess::StorageRead);
    let color1 = p.image(color, ImageAccess::ColorAttachment(LoadOp::Clear([0.0; 4])));
    p.image(depth, ImageAccess::DepthAttachment(LoadOp::Clear(1.0)));
    let mut p = g.add_pass("readback", PassKind::Transfer);
    p.image(color1, ImageAccess::TransferSrc);
    p.buffer(readback, BufferAccess::TransferDst);
    let plan = Plan::new(&g).unwrap();
    assert_eq!(
        names(&g, &plan.order),
        ["sky", "quads", "scene", "readback"]
    );

    let first = image_barrier(&plan, &g, "sky", 0).unwrap();
    assert_eq!(
        (first.src_stage, first.old_layout, first.new_layout),
        (S::NONE, L::UNDEFINED, L::GENERAL)
    );
    let sampled = image_barrier(&plan, &g, "scene", 0).unwrap();
    assert_eq!(
        (sampled.src_stage, sampled.src_access),
        (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE)
    );
    assert_eq!(
        (sampled.dst_stage, sampled.dst_access),
        (
            S::VERTEX_SHADER | S::FRAGMENT_SHADER,
            A::SHADER_SAMPLED_READ
        )
    );
    assert_eq!(
        (sampled.old_layout, sampled.new_layout),
        (L::GENERAL, L::SHADER_READ_ONLY_OPTIMAL)
    );
    let vb = buffer_barrier(&plan, &g, "scene", 0).unwrap();
    assert_eq!(
        (vb.src_access, vb.dst_access),
        (A::SHADER_STORAGE_WRITE, A::SHADER_STORAGE_READ)
    );
    let db = image_barrier(&plan, &g, "scene", 2).unwrap();
    assert_eq!(
        (db.old_layout, db.new_layout),
        (L::UNDEFINED, L::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
    );
    assert_eq!(
        db.dst_stage,
        S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS
    );
    let copy = image_barrier(&plan, &g, "readback", 1).unwrap();
    assert_eq!(
        (copy.src_stage, copy.src_access),
        (S::COLOR_ATTACHMENT_OUTPUT, A::COLOR_ATTACHMENT_WRITE)
    );
    assert_eq!(
        (copy.old_layout, copy.new_layout, copy.dst_access),
        (
            L::COLOR_ATTACHMENT_OPTIMAL,
            L::TRANSFER_SRC_OPTIMAL,
            A::TRANSFER_READ
        )
    );
    // The export makes the copy visible to the host.
    assert_eq!(plan.final_barriers.len(), 1);
    let fin = plan.final_barriers[0];
    assert_eq!(
        (fin.src_stage, fin.src_access, fin.dst_stage, fin.dst_access),
        (S::ALL_TRANSFER, A::TRANSFER_WRITE, S::HOST, A::HOST_READ)
    );
}

#[test]
fn repeated_reads_need_no_barrier_but_a_new_stage_does_and_war_waits_for_readers() {
    let mut g = FrameGraph::new();
    let b = g.create_buffer("b", 64);
    let mut p = g.add_pass("write", PassKind::Compute);
    let b1 = p.buffer(b, BufferAccess::StorageWrite);
    let mut p = g.add_pass("read-1", PassKind::Compute);
    p.buffer(b1, BufferAccess::StorageRead);
    p.keep();
    let mut p = g.add_pass("read-2", PassKind::Compute);
    p.buffer(b1, BufferAccess::StorageRead);
    p.keep();
    let target = g.create_image("t", desc(4));
    let mut p = g.add_pass("draw", PassKind::Raster);
    p.buffer(b1, BufferAccess::Vertex);
    p.image(
        target,
        ImageAccess::ColorAttachment(LoadOp::Clear([0.0; 4])),
    );
    p.keep();
    let mut p = g.add_pass("rewrite", PassKind::Compute);
    p.buffer(b1, BufferAccess::StorageWrite);
    p.keep();
    let plan = Plan::new(&g).unwrap();
    let order = names(&g, &plan.order);
    assert_eq!(order, ["write", "read-1", "read-2", "draw", "rewrite"]);
    assert!(buffer_barrier(&plan, &g, "read-1", 0).is_some());
    assert!(
        buffer_barrier(&plan, &g, "read-2", 0).is_none(),
        "same stage and access already visible"
    );
    let vertex = plan.barriers[3]
        .iter()
        .find(|x| x.resource == BarrierResource::Buffer(0))
        .unwrap();
    assert_eq!(
        (vertex.dst_stage, vertex.dst_access),
        (S::VERTEX_ATTRIBUTE_INPUT, A::VERTEX_ATTRIBUTE_READ)
    );
    let war = buffer_barrier(&plan, &g, "rewrite", 0).unwrap();
    assert!(
        war.src_stage
            .contains(S::COMPUTE_SHADER | S::VERTEX_ATTRIBUTE_INPUT),
        "waits for every reader: {:?}",
        war.src_stage
    );
}

#[test]
fn transients_with_disjoint_lifetimes_share_memory() {
    let mut g = FrameGraph::new();
    let a = g.create_image("a", desc(8));
    let b = g.create_image("b", desc(8));
    let c = g.create_image("c", desc(8));
    let other = g.create_image("other-size", desc(16));
    let out = g.create_image("out", desc(8));
    let mut p = g.add_pass("p1", PassKind::Compute);
    let a1 = p.image(a, ImageAccess::StorageWrite);
    let mut p = g.add_pass("p2", PassKind::Compute);
    p.image(a1, ImageAccess::StorageRead);
    let b1 = p.image(b, ImageAccess::StorageWrite);
    let mut p = g.add_pass("p3", PassKind::Compute);
    p.image(b1, ImageAccess::StorageRead);
    let c1 = p.image(c, ImageAccess::StorageWrite);
    let o1 = p.image(other, ImageAccess::StorageWrite);
    let mut p = g.add_pass("p4", PassKind::Compute);
    p.image(c1, ImageAccess::StorageRead);
    p.image(o1, ImageAccess::StorageRead);
    let out1 = p.image(out, ImageAccess::StorageWrite);
    g.mark_output_image(out1);
    let plan = Plan::new(&g).unwrap();
    let t = |i: usize| plan.image_targets[i].unwrap();
    assert_ne!(t(0), t(1), "a and b are alive together in p2");
    assert_eq!(t(0), t(2), "c reuses a's memory: a died after p2");
    assert_ne!(t(3), t(0));
    assert_eq!(t(4), t(1), "out reuses b's memory");
    assert_eq!(plan.slots.len(), 3);
    // c's first write on a's memory waits for a's last read and discards.
    let alias = image_barrier(&plan, &g, "p3", 2).unwrap();
    assert_eq!(
        (alias.old_layout, alias.src_stage),
        (L::UNDEFINED, S::COMPUTE_SHADER)
    );
}

#[test]
fn imported_swapchain_image_is_transitioned_for_present_and_end_states_carry_over() {
    let mut g = FrameGraph::new();
    let sc_desc = ImageDesc {
        width: 4,
        height: 4,
        format: vk::Format::B8G8R8A8_SRGB,
    };
    let initial = SyncState {
        stage: S::COLOR_ATTACHMENT_OUTPUT,
        access: A::NONE,
        layout: L::UNDEFINED,
    };
    let export = SyncState {
        stage: S::NONE,
        access: A::NONE,
        layout: L::PRESENT_SRC_KHR,
    };
    let sc = g.import_external_image(
        "swapchain",
        sc_desc,
        vk::Image::null(),
        vk::ImageView::null(),
        initial,
        Some(export),
    );
    let history = g.import_external_buffer(
        "history",
        64,
        SyncState {
            stage: S::COMPUTE_SHADER,
            access: A::SHADER_STORAGE_WRITE,
            layout: L::UNDEFINED,
        },
        None,
    );
    let mut p = g.add_pass("present", PassKind::Raster);
    p.image(sc, ImageAccess::ColorAttachment(LoadOp::Clear([0.0; 4])));
    p.buffer(history, BufferAccess::StorageRead);
    let plan = Plan::new(&g).unwrap();
    let b = image_barrier(&plan, &g, "present", 0).unwrap();
    assert_eq!(
        (b.src_stage, b.old_layout, b.new_layout),
        (
            S::COLOR_ATTACHMENT_OUTPUT,
            L::UNDEFINED,
            L::COLOR_ATTACHMENT_OPTIMAL
        )
    );
    let h = buffer_barrier(&plan, &g, "present", 0).unwrap();
    assert_eq!(
        (h.src_stage, h.src_access),
        (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE),
        "last frame's write is waited for"
    );
    let fin = plan
        .final_barriers
        .iter()
        .find(|x| x.resource == BarrierResource::Image(0))
        .unwrap();
    assert_eq!(
        (fin.old_layout, fin.new_layout, fin.src_access),
        (
            L::COLOR_ATTACHMENT_OPTIMAL,
            L::PRESENT_SRC_KHR,
            A::COLOR_ATTACHMENT_WRITE
        )
    );
    let (_, end) = plan.buffer_end_states[0];
    assert!(
        end.stage.contains(S::VERTEX_SHADER | S::FRAGMENT_SHADER),
        "the next frame's writer waits for this frame's readers"
    );
}

#[test]
fn declaration_errors_name_the_pass_and_resource() {
    let mut g = FrameGraph::new();
    let x = g.create_image("x", desc(4));
    let mut p = g.add_pass("reader", PassKind::Compute);
    p.image(x, ImageAccess::Sampled);
    assert_eq!(
        Plan::new(&g).unwrap_err(),
        GraphError::ReadBeforeWrite {
            pass: "reader".into(),
            resource: "x".into()
        }
    );

    let mut g = FrameGraph::new();
    let b = g.create_buffer("counters", 16);
    let mut p = g.add_pass("accumulate", PassKind::Compute);
    p.buffer(b, BufferAccess::StorageReadWrite);
    assert_eq!(
        Plan::new(&g).unwrap_err(),
        GraphError::ReadBeforeWrite {
            pass: "accumulate".into(),
            resource: "counters".into()
        },
        "read-modify-write of a never-written transient reads garbage"
    );

    let mut g = FrameGraph::new();
    let x = g.create_image("x", desc(4));
    let mut p = g.add_pass("w1", PassKind::Compute);
    p.image(x, ImageAccess::StorageWrite);
    let mut p = g.add_pass("w2", PassKind::Compute);
    p.image(x, ImageAccess::StorageWrite);
    assert!(
        matches!(Plan::new(&g).unwrap_err(), GraphError::StaleWrite { pass, version: 0, latest: 1, .. } if pass == "w2")
    );

    let mut g = FrameGraph::new();
    let x = g.create_image("x", desc(4));
    let mut p = g.add_pass("copy", PassKind::Transfer);
    p.image(x, ImageAccess::StorageWrite);
    assert!(matches!(
        Plan::new(&g).unwrap_err(),
        GraphError::AccessNotAllowed { .. }
    ));

    let mut g = FrameGraph::new();
    let x = g.create_image("x", desc(4));
    let mut p = g.add_pass("twice", PassKind::Compute);
    let x1 = p.image(x, ImageAccess::StorageWrite);
    p.image(x1, ImageAccess::StorageRead);
    assert!(matches!(
        Plan::new(&g).unwrap_err(),
        GraphError::DuplicateAccess { .. }
    ));

    let mut g = FrameGraph::new();
    let mut p = g.add_pass("empty-raster", PassKind::Raster);
    p.keep();
    assert!(matches!(
        Plan::new(&g).unwrap_err(),
        GraphError::Attachments { .. }
    ));

    let mut g = FrameGraph::new();
    let a = g.create_image("a", desc(4));
    let b = g.create_image("b", desc(8));
    let mut p = g.add_pass("mismatch", PassKind::Raster);
    p.image(a, ImageAccess::ColorAttachment(LoadOp::Clear([0.0; 4])));
    p.image(b, ImageAccess::ColorAttachment(LoadOp::Clear([0.0; 4])));
    assert!(Plan::new(&g)
        .unwrap_err()
        .to_string()
        .contains("differ in size"));
}

#[test]
fn cycles_through_stale_handles_are_reported() {
    let mut g = FrameGraph::new();
    let x = g.create_buffer("x", 4);
    let z = g.create_buffer("z", 4);
    let mut p = g.add_pass("w-x", PassKind::Compute);
    let x1 = p.buffer(x, BufferAccess::StorageWrite);
    let mut p = g.add_pass("p2", PassKind::Compute);
    p.buffer(x1, BufferAccess::StorageWrite);
    let z1 = p.buffer(z, BufferAccess::StorageWrite);
    let mut p = g.add_pass("p3", PassKind::Compute);
    p.buffer(x1, BufferAccess::StorageRead);
    p.buffer(z1, BufferAccess::StorageRead);
    p.keep();
    let e = Plan::new(&g).unwrap_err();
    assert!(
        matches!(&e, GraphError::Cycle(p) if p.contains(&"p2".to_string()) && p.contains(&"p3".to_string())),
        "{e}"
    );
}

/// Arguments a compute pass writes and a later dispatch reads indirectly:
/// the reader waits at the indirect-command stage.
#[test]
fn indirect_arguments_wait_for_their_writer_at_the_indirect_stage() {
    let mut g = FrameGraph::new();
    let args = g.create_buffer("args", 12);
    let mut p = g.add_pass("count", PassKind::Compute);
    let written = p.buffer(args, BufferAccess::StorageWrite);
    let mut p = g.add_pass("refine", PassKind::Compute);
    p.buffer(written, BufferAccess::Indirect);
    p.keep();
    let plan = Plan::new(&g).unwrap();
    assert_eq!(names(&g, &plan.order), ["count", "refine"]);
    let b = buffer_barrier(&plan, &g, "refine", 0).unwrap();
    assert_eq!(
        (b.src_stage, b.dst_stage, b.dst_access),
        (
            S::COMPUTE_SHADER,
            S::DRAW_INDIRECT,
            A::INDIRECT_COMMAND_READ
        )
    );
    assert!(b.src_access.contains(A::SHADER_STORAGE_WRITE));
}
