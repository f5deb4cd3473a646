//! Nothing silently wrong: the device's limits are checked before work and
//! named, the validation layer fails every command run on the device, and
//! no output is replaced by a run that fails. (The command-line side of
//! these is in `cli_fields.rs`.)

mod common;

use inlay::commands::on_device;
use inlay::outputs::Outputs;
use inlay_engine::graph::{BufferAccess, FrameGraph, PassKind};
use inlay_engine::{vk, Buffer, BufferLocation, ContextOptions, DeviceInfo, Renderer, SubmitSync};
use inlay_passes::field::{check_field_fits, check_field_may_fit, NodeStorage};

const RENDER: NodeStorage = NodeStorage::Render;
use inlay_passes::object::check_mesh_fits;
use inlay_passes::ssdf::{check_bake_fits, BAKE_BYTES_PER_TRIANGLE};

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("inlay-reliability-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The device's facts with a smaller storage binding and heap, to check
/// that the limits are read from the device rather than assumed.
fn small_device(base: &DeviceInfo, binding: u32, heap: u64) -> DeviceInfo {
    let mut info = base.clone();
    info.name = "a small device".into();
    info.max_storage_buffer_range = binding;
    info.device_heap_bytes = heap;
    info
}

#[test]
fn validation_errors_fail_the_command_and_replace_no_output() {
    let dir = temp_dir("validation");
    let out = dir.join("result.txt");
    std::fs::write(&out, "previous").unwrap();
    let options = ContextOptions {
        validate: true,
        device: None,
    };
    // A command that writes its output through `Outputs` after a
    // validation error: the output is not replaced.
    let e = on_device(&options, |ctx| {
        let mut outputs = Outputs::new();
        outputs.bytes(&out, b"computed on a device that erred")?;
        ctx.provoke_validation_error();
        outputs.commit(Some(ctx))?;
        Ok(())
    })
    .unwrap_err();
    assert!(format!("{e:#}").contains("validation layer"), "{e:#}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous");
    // A command that never looks at the layer (as `bake-ssdf` and `probe`
    // did not): the run fails all the same.
    let e = on_device(&options, |ctx| {
        ctx.provoke_validation_error();
        Ok(())
    })
    .unwrap_err();
    assert!(
        format!("{e:#}").contains("VUID-VkBufferCreateInfo-size"),
        "{e:#}"
    );
    on_device(&options, |_| Ok(())).unwrap();
}

#[test]
fn storage_buffers_past_the_binding_limit_are_refused() {
    let ctx = common::gpu();
    let limit = ctx.info().max_storage_buffer_range as u64;
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let e = Buffer::new(&ctx, "too big", limit + 4, storage, BufferLocation::Gpu)
        .err()
        .expect("a storage buffer past the binding limit is refused");
    let text = e.to_string();
    assert!(
        text.contains("too big") && text.contains("largest storage binding"),
        "{text}"
    );
    // Not bound as storage, the same size is not this check's business.
    let small = Buffer::new(&ctx, "fits", 1 << 16, storage, BufferLocation::Gpu);
    assert!(small.is_ok());
    common::assert_no_validation_errors(&ctx);
}

#[test]
fn limits_come_from_the_device_and_say_what_fits() {
    let mesh = common::bundled_object("toy.glb");
    let triangles = mesh.triangles() as u64;
    let real = common::gpu().info().clone();
    check_bake_fits(&real, &mesh).unwrap();
    check_mesh_fits(&real, &mesh).unwrap();
    // A device whose binding holds one triangle fewer than the bake needs.
    let tight = (BAKE_BYTES_PER_TRIANGLE * triangles - 1) as u32;
    let e = check_bake_fits(&small_device(&real, tight, 1 << 40), &mesh).unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("toy.glb")
            && text.contains("a small device")
            && text.contains(&format!("at most {} triangles", triangles - 1)),
        "{text}"
    );
    let e = check_mesh_fits(&small_device(&real, 1024, 1 << 40), &mesh).unwrap_err();
    assert!(e.to_string().contains("simplify the mesh"), "{e}");
    // A field: the binding first, then the heap.
    let res = glam::UVec3::new(64, 64, 64);
    check_field_fits(&small_device(&real, 16 << 18, 1 << 40), res, 0, RENDER).unwrap();
    let e = check_field_fits(
        &small_device(&real, (16 << 18) - 16, 1 << 40),
        res,
        0,
        RENDER,
    )
    .unwrap_err();
    assert!(e.to_string().contains("largest storage binding"), "{e}");
    let e = check_field_fits(&small_device(&real, u32::MAX, 1 << 20), res, 0, RENDER).unwrap_err();
    assert!(e.to_string().contains("largest memory heap"), "{e}");
    // View-dependent colour of degree 2 takes 48 more bytes a node (f16),
    // split over two bindings of 24; the trainer takes 16 a node in each
    // of four bindings at degree 1, 64 in the heap.
    let e = check_field_fits(&small_device(&real, 16 << 18, 1 << 40), res, 2, RENDER).unwrap_err();
    assert!(e.to_string().contains("degree 2"), "{e}");
    check_field_fits(&small_device(&real, 24 << 18, 1 << 40), res, 2, RENDER).unwrap();
    let e = check_field_fits(&small_device(&real, 24 << 18, 63 << 18), res, 2, RENDER).unwrap_err();
    assert!(e.to_string().contains("largest memory heap"), "{e}");
    let training = NodeStorage::Training;
    check_field_fits(&small_device(&real, 16 << 18, 64 << 18), res, 1, training).unwrap();
    let e =
        check_field_fits(&small_device(&real, 16 << 18, 63 << 18), res, 1, training).unwrap_err();
    assert!(e.to_string().contains("largest memory heap"), "{e}");
    // Before the nodes are known, only the heap refuses: the sparse layout
    // may fit the binding.
    check_field_may_fit(&small_device(&real, 1024, 16 << 18), res, 0, RENDER).unwrap();
    let e = check_field_may_fit(
        &small_device(&real, u32::MAX, (16 << 18) - 16),
        res,
        0,
        RENDER,
    )
    .unwrap_err();
    assert!(e.to_string().contains("largest memory heap"), "{e}");
}

/// A frame of far more passes than the timer's first pool holds (a scene of
/// 64 objects needs over 128) runs and is timed pass by pass; before, a
/// graph over 128 passes was refused when the frame was submitted.
#[test]
fn a_frame_of_many_passes_is_timed() {
    let ctx = common::gpu();
    let passes = 300;
    let mut renderer = Renderer::new(&ctx, 2).unwrap();
    for _ in 0..3 {
        let mut graph = FrameGraph::new();
        let mut buffer = graph.create_buffer("filled", 256);
        for i in 0..passes {
            let mut p = graph.add_pass(&format!("fill {i}"), PassKind::Transfer);
            let written = p.buffer(buffer, BufferAccess::TransferDst);
            p.exec(move |c| c.fill_buffer(written, i));
            buffer = written;
        }
        graph.mark_output_buffer(buffer);
        renderer.submit(graph, &SubmitSync::none()).unwrap();
    }
    renderer.finish().unwrap();
    let timed = renderer.timings().last().unwrap();
    assert_eq!(timed.passes.len(), passes as usize);
    assert_eq!(timed.passes[299].name, "fill 299");
    assert!(timed.passes.iter().all(|p| p.gpu_ms.is_finite()));
    common::assert_no_validation_errors(&ctx);
}
