//! Every shipped shader compiles; errors name file and line; the shared
//! tonemap WGSL matches its Rust mirror on the GPU.

mod common;

use inlay::headless::Scene;
use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::{compile, Define, ShaderStage};
use inlay_engine::tonemap::{aces_filmic, srgb_encode};
use inlay_engine::Push;
use inlay_engine::{vk, ComputePipeline, ImageDesc};
use inlay_passes::shaders::embedded_library;

/// Knob constants some shaders expect from the pass that builds them
/// (unused ones are harmless).
fn knob_defines() -> Vec<Define> {
    let mut defines = vec![
        Define::Bool("SKIP_EMPTY", true),
        Define::Bool("OCTAHEDRAL", true),
        Define::F32("FIT_MAX_SHARPNESS", 1024.0),
        Define::U32("ARC_PIECES", 16),
        Define::F32("OUTSIDE_OFFSET", 2e-3),
        Define::F32("PIECE_ANGLE", 1e-2),
        Define::U32("PIECE_CAPACITY", 65536),
        Define::U32("ARC_CAPACITY", 16384),
        Define::U32("DIRECTIONS_PER_INVOCATION", 8),
        Define::U32(
            "VALUES_PER_INVOCATION",
            inlay_passes::train::gpu::VALUES_PER_INVOCATION,
        ),
        Define::Bool(inlay_passes::train::gpu::TV_COLOUR_DEFINE, false),
        Define::Bool(inlay_passes::train::gpu::DENSITIES_ONLY_DEFINE, true),
        Define::U32(
            "MAX_RAYS_PER_PIXEL",
            inlay_passes::train::gpu::MAX_RAYS_PER_PIXEL,
        ),
        Define::U32(
            "NF_RAYS_PER_INVOCATION",
            inlay_passes::envest::near_field::RAYS_PER_INVOCATION,
        ),
    ];
    defines.extend(inlay_passes::shadow::shadow_defines());
    defines
}

/// Every host struct whose bytes go to the GPU (push constants, uniform
/// blocks, per-object and per-draw records) has the size and member
/// offsets naga gives the WGSL struct it mirrors.
#[test]
fn gpu_structs_match_their_shaders() {
    let lib = embedded_library();
    let mut errors = inlay_passes::shaders::gpu_layout_errors(&lib, &knob_defines());
    errors.extend(inlay::gpu_layouts::gpu_layout_errors(&lib));
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// Every entry point of every shipped shader file compiles and validates.
#[test]
fn every_shipped_shader_compiles() {
    let lib = embedded_library();
    let mut compiled = 0;
    for path in lib.paths() {
        let source = lib.get(path).unwrap();
        let lines: Vec<&str> = source.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let stage = match line.trim() {
                l if l.starts_with("@compute") => ShaderStage::Compute,
                "@vertex" => ShaderStage::Vertex,
                "@fragment" => ShaderStage::Fragment,
                _ => continue,
            };
            let decl = lines[i..]
                .iter()
                .find(|l| l.trim_start().starts_with("fn "))
                .unwrap();
            let name = decl.trim_start()[3..].split('(').next().unwrap().trim();
            compile(&lib, path, name, stage, &knob_defines()).unwrap_or_else(|e| panic!("{e}"));
            compiled += 1;
        }
    }
    assert!(compiled >= 10, "found {compiled} entry points");
}

#[test]
fn a_broken_shader_is_reported_with_file_and_line() {
    let mut lib = embedded_library();
    let mut broken = lib.get("common/tonemap.wgsl").unwrap().to_string();
    let line = broken.lines().count() + 2;
    broken.push_str("\nfn oops() -> f32 {\n    return undefined_name;\n}\n");
    lib.insert("common/tonemap.wgsl", &broken);
    // present.wgsl includes the broken file: the error points into it.
    let e = compile(&lib, "present.wgsl", "fs_main", ShaderStage::Fragment, &[]).unwrap_err();
    assert_eq!(e.file, "common/tonemap.wgsl");
    assert_eq!(e.line as usize, line + 1, "{e}");
    assert!(
        e.to_string()
            .starts_with(&format!("common/tonemap.wgsl:{}:", line + 1)),
        "{e}"
    );
    assert!(
        e.message.contains("undefined_name") || e.message.contains("no definition"),
        "{e}"
    );
}

struct TonemapProbe {
    pipeline: std::sync::Arc<ComputePipeline>,
}

impl Scene for TonemapProbe {
    fn build(
        &mut self,
        graph: &mut FrameGraph,
        width: u32,
        height: u32,
        _time: f32,
    ) -> anyhow::Result<ImageHandle> {
        let result = graph.create_image(
            "tonemap-probe",
            ImageDesc {
                width,
                height,
                format: vk::Format::R32G32B32A32_SFLOAT,
            },
        );
        let mut out = result;
        graph
            .compute("tonemap-probe", &self.pipeline)
            .write("result", &mut out)
            .push(&Push::new().u32(width).u32(height))
            .threads([width, height, 1]);
        Ok(out)
    }
}

#[test]
fn tonemap_gpu_matches_cpu() {
    let ctx = common::gpu();
    let lib = common::test_library();
    let shader = compile(
        &lib,
        "checks/tonemap_probe.wgsl",
        "main",
        ShaderStage::Compute,
        &[],
    )
    .unwrap();
    let mut probe = TonemapProbe {
        pipeline: std::sync::Arc::new(ComputePipeline::new(&ctx, &shader).unwrap()),
    };
    // The headless runner reads RGBA16F back; this probe writes RGBA32F, so
    // read through a dedicated 32-bit readback instead.
    let run = run_headless_rgba32(&ctx, &mut probe, 16, 16);
    common::assert_no_validation_errors(&ctx);
    for p in &run {
        let v = p[0];
        let t = aces_filmic(v);
        // f32 on both sides; pow/exp on the GPU differ by a few ulp. 2e-6 on
        // values in [0, 1] is ~16 ulp near 1.
        assert!((p[1] - t).abs() < 2e-6, "aces({v}): gpu {} cpu {t}", p[1]);
        assert!(
            (p[2] - srgb_encode(t)).abs() < 2e-6,
            "srgb(aces({v})): gpu {} cpu {}",
            p[2],
            srgb_encode(t)
        );
        assert!(
            (p[3] - srgb_encode(v)).abs() < 2e-6,
            "srgb({v}): gpu {} cpu {}",
            p[3],
            srgb_encode(v)
        );
    }
}

fn run_headless_rgba32(
    ctx: &std::sync::Arc<inlay_engine::Context>,
    scene: &mut TonemapProbe,
    w: u32,
    h: u32,
) -> Vec<[f32; 4]> {
    use inlay_engine::{Readback, Renderer, SubmitSync};
    let mut renderer = Renderer::new(ctx, 1).unwrap();
    let readback = Readback::new(
        ctx,
        ImageDesc {
            width: w,
            height: h,
            format: vk::Format::R32G32B32A32_SFLOAT,
        },
    )
    .unwrap();
    let mut graph = FrameGraph::new();
    let img = scene.build(&mut graph, w, h, 0.0).unwrap();
    readback.add_to_graph(&mut graph, img);
    renderer.submit(graph, &SubmitSync::none()).unwrap();
    renderer.finish().unwrap();
    readback.read().unwrap().pixels
}

/// The library compiles a compute pipeline once per (device, file, entry
/// point, defines) and hands the same one out again while it is held;
/// other defines compile anew; a clone shares them; changing a file
/// forgets them all; a pipeline nobody holds is not kept (nor its device).
/// Objects share kernels this way: four objects' incident-light passes
/// (probe trace, SG fit) compile no more than the first one did.
#[test]
fn pipelines_are_compiled_once_per_key() {
    use std::sync::Arc;
    let ctx = common::gpu();
    let mut lib = embedded_library();
    assert_eq!(lib.compiled_pipelines(), 0);
    let on = [Define::Bool("SKIP_EMPTY", true)];
    let a = lib
        .compute_pipeline(&ctx, "march/march.wgsl", "main_unclipped", &on)
        .unwrap();
    let b = lib
        .compute_pipeline(&ctx, "march/march.wgsl", "main_unclipped", &on)
        .unwrap();
    assert!(Arc::ptr_eq(&a, &b));
    assert_eq!(lib.compiled_pipelines(), 1);
    let off = [Define::Bool("SKIP_EMPTY", false)];
    let c = lib
        .compute_pipeline(&ctx, "march/march.wgsl", "main_unclipped", &off)
        .unwrap();
    assert!(!Arc::ptr_eq(&a, &c));
    assert_eq!(lib.compiled_pipelines(), 2);
    // A clone shares the pipelines; a changed file starts afresh.
    let clone = lib.clone();
    clone
        .compute_pipeline(&ctx, "march/march.wgsl", "main_unclipped", &on)
        .unwrap();
    assert_eq!(clone.compiled_pipelines(), 2);
    let source = lib.get("march/march.wgsl").unwrap().to_owned();
    lib.insert("march/march.wgsl", &source);
    assert_eq!(lib.compiled_pipelines(), 0);
    let d = lib
        .compute_pipeline(&ctx, "march/march.wgsl", "main_unclipped", &on)
        .unwrap();
    assert!(!Arc::ptr_eq(&a, &d));

    use inlay_passes::lighting::IncidentLight;
    use inlay_passes::march::MarchKnobs;
    use inlay_passes::probe::ProbeKnobs;
    use inlay_passes::sgfit::FitKnobs;
    let lib = embedded_library();
    let object = || {
        let t = std::time::Instant::now();
        let light = IncidentLight::new(
            &ctx,
            &lib,
            ProbeKnobs::default(),
            FitKnobs::default(),
            MarchKnobs::default(),
            &[],
            &[],
            1,
        )
        .unwrap();
        (light, t.elapsed())
    };
    let (first, first_time) = object();
    let after_one = lib.compiled_pipelines();
    assert!(
        after_one >= 10,
        "the probe and the fit have {after_one} kernels?"
    );
    let mut more = Vec::new();
    let t = std::time::Instant::now();
    for _ in 0..3 {
        more.push(object().0);
    }
    assert_eq!(
        lib.compiled_pipelines(),
        after_one,
        "a second object compiled kernels again"
    );
    eprintln!(
        "first object's incident-light passes: {:.0} ms ({after_one} pipelines); three more: {:.0} ms",
        first_time.as_secs_f64() * 1e3,
        t.elapsed().as_secs_f64() * 1e3
    );
    drop((first, more));
    common::assert_no_validation_errors(&ctx);
}

/// A kernel reading two storage buffers into a third, for the binding layer.
const SUM_KERNEL: &str = "
@group(0) @binding(0) var<storage, read> first: array<f32>;
@group(0) @binding(1) var<storage, read> second: array<f32>;
@group(0) @binding(2) var<storage, read_write> sum: array<f32>;
@compute @workgroup_size(4, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    sum[id.x] = first[id.x] + 2.0 * second[id.x];
}
";

/// Passes declared by binding (`FrameGraph::compute`): one buffer read at
/// two bindings is declared once, a binding the shader does not have is
/// left out, and an unbound binding or a resource of the wrong kind is an
/// error that names the binding, before anything runs.
#[test]
fn passes_are_declared_by_binding() {
    use inlay_engine::graph::Plan;
    use inlay_engine::{Buffer, BufferReadback, Renderer, SubmitSync};
    use std::sync::Arc;
    let ctx = common::gpu();
    let mut lib = embedded_library();
    lib.insert("checks/sum.wgsl", SUM_KERNEL);
    let pipeline = lib
        .compute_pipeline(&ctx, "checks/sum.wgsl", "main", &[])
        .unwrap();
    let values = [1.0f32, 2.0, 3.0, 4.0];
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let input = Arc::new(
        Buffer::with_data(
            &ctx,
            "sum input",
            &bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )
        .unwrap(),
    );
    let readback = BufferReadback::new(&ctx, "sum readback", 16).unwrap();
    let mut renderer = Renderer::new(&ctx, 1).unwrap();
    renderer.begin_frame().unwrap();
    let mut graph = FrameGraph::new();
    let x = graph.import_buffer(&input, None);
    let mut sum = graph.create_buffer("sum", 16);
    let image = graph.create_image(
        "never bound",
        ImageDesc {
            width: 1,
            height: 1,
            format: vk::Format::R32G32B32A32_SFLOAT,
        },
    );
    graph
        .compute("sum", &pipeline)
        .read("first", x)
        .read(1, x)
        .read("not_in_the_shader", image)
        .write("sum", &mut sum)
        .push(&Push::new())
        .threads([4, 1, 1]);
    readback.add_to_graph(&mut graph, "sum readback", sum);
    renderer.submit(graph, &SubmitSync::none()).unwrap();
    renderer.finish().unwrap();
    common::assert_no_validation_errors(&ctx);
    let got = readback.read_f32().unwrap();
    let want: Vec<f32> = values.iter().map(|v| 3.0 * v).collect();
    assert_eq!(got, want);

    let mut graph = FrameGraph::new();
    let x = graph.import_buffer(&input, None);
    let mut sum = graph.create_buffer("sum", 16);
    graph
        .compute("sum", &pipeline)
        .read("first", x)
        .write("sum", &mut sum)
        .threads([4, 1, 1]);
    let e = Plan::new(&graph).expect_err("an unbound binding fails");
    assert!(e.to_string().contains("1 (`second`)"), "{e}");

    let mut graph = FrameGraph::new();
    let x = graph.import_buffer(&input, None);
    let img = graph.create_image(
        "image",
        ImageDesc {
            width: 1,
            height: 1,
            format: vk::Format::R32G32B32A32_SFLOAT,
        },
    );
    let mut sum = graph.create_buffer("sum", 16);
    graph
        .compute("sum", &pipeline)
        .read("first", x)
        .read("second", img)
        .write("sum", &mut sum)
        .threads([4, 1, 1]);
    let e = Plan::new(&graph).expect_err("an image at a buffer binding fails");
    assert!(e.to_string().contains("`second`"), "{e}");
}
