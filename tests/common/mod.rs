//! Shared test setup: a Vulkan context with the validation layer on (tests
//! fail on any validation error), on lavapipe in CI.
#![allow(dead_code)]

use std::process::Output;
use std::sync::Arc;

use inlay_engine::{Context, ContextOptions};

/// A validating context. Panics with the engine's message (which says what to
/// install) when Vulkan or the validation layer is missing.
pub fn gpu() -> Arc<Context> {
    let _ = env_logger::builder().is_test(true).try_init();
    match Context::new(&ContextOptions { validate: true, device: None }, None) {
        Ok(c) => c,
        Err(e) => panic!("GPU tests need Vulkan with the validation layer (run tools/test.sh, which installs them): {e}"),
    }
}

/// Fails the test if the validation layer reported any error.
pub fn assert_no_validation_errors(ctx: &Context) {
    if let Err(e) = ctx.check_validation() {
        panic!("{e}");
    }
}

/// A finished process's stdout and stderr as one text, for assertions.
pub fn output_text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Runs the `inlay` program with `args`, its bake cache in `cache`.
pub fn inlay_cached(args: &[&str], cache: &std::path::Path) -> Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_inlay"))
        .args(args)
        .env("INLAY_CACHE_DIR", cache)
        .output()
        .expect("the inlay binary runs")
}

/// The path of bundled scene file `name` (e.g. `dog.toml`), as text.
pub fn scene_path(name: &str) -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .display()
        .to_string()
}

/// A path as text (test paths are UTF-8).
pub fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

/// The bundled objects' directory, `scenes/objects/`.
pub fn objects_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/objects")
}

/// A bundled object from `scenes/objects/`, loaded.
pub fn bundled_object(file: &str) -> std::sync::Arc<inlay_passes::object::ObjectMesh> {
    std::sync::Arc::new(inlay_passes::object::load_gltf(&objects_dir().join(file)).unwrap())
}

/// A bundled scene from `scenes/`.
pub fn bundled_scene(name: &str) -> inlay_passes::scene::Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    inlay_passes::scene::load_scene(&path).unwrap()
}

/// A scene's recipe baked at test size.
pub fn bake_small(
    scene: &inlay_passes::scene::Scene,
    resolution: u32,
    samples: u32,
    bounces: u32,
) -> inlay_passes::field::GridField {
    let knobs = inlay_passes::bake::BakeKnobs {
        resolution,
        samples,
        bounces,
        ..scene.bake
    };
    inlay_passes::bake::bake_grid(
        scene.recipe().unwrap(),
        &scene.environment,
        &knobs,
        &|_, _| {},
    )
}

/// Builds one frame with `build`, runs it to completion and checks the
/// validation layer.
pub fn run_frame(
    ctx: &std::sync::Arc<Context>,
    build: impl FnOnce(&mut inlay_engine::graph::FrameGraph),
) -> inlay_engine::FrameReport {
    let mut renderer = inlay_engine::Renderer::new(ctx, 1).unwrap();
    renderer.begin_frame().unwrap();
    let mut graph = inlay_engine::graph::FrameGraph::new();
    build(&mut graph);
    let report = renderer
        .submit(graph, &inlay_engine::SubmitSync::none())
        .unwrap();
    renderer.finish().unwrap();
    assert_no_validation_errors(ctx);
    report
}

/// The shipped shaders plus the test-only kernels of tests/shaders/, as
/// `checks/NAME` (they are not shipped in the binary).
pub fn test_library() -> inlay_engine::shader::ShaderLibrary {
    let mut lib = inlay_passes::shaders::embedded_library();
    for (name, source) in [
        (
            "checks/object_depth_pattern.wgsl",
            include_str!("../shaders/object_depth_pattern.wgsl"),
        ),
        ("checks/sg_ops.wgsl", include_str!("../shaders/sg_ops.wgsl")),
        (
            "checks/tonemap_probe.wgsl",
            include_str!("../shaders/tonemap_probe.wgsl"),
        ),
        (
            "checks/loop_count.wgsl",
            include_str!("../shaders/loop_count.wgsl"),
        ),
    ] {
        lib.insert(name, source);
    }
    lib
}

/// A field with nothing in it, on the GPU (for passes that bind a field but,
/// in a test, need none of it: the shading reads it only for local lights).
pub fn empty_field(ctx: &Arc<Context>) -> inlay_passes::field::GpuGridField {
    let field = inlay_passes::field::GridField::new(
        glam::UVec3::splat(2),
        inlay_passes::geometry::Aabb {
            min: glam::DVec3::splat(-1.0),
            max: glam::DVec3::splat(1.0),
        },
        vec![[0.0; 4]; 8],
        1,
    );
    inlay_passes::field::GpuGridField::upload(ctx, &field).unwrap()
}

/// A readback of a probe image on `map`.
pub fn probe_readback(
    ctx: &Arc<Context>,
    map: &inlay_passes::probe::DirectionMap,
) -> inlay_engine::Readback {
    inlay_engine::Readback::new(
        ctx,
        inlay_engine::ImageDesc {
            width: map.width,
            height: map.height,
            format: inlay_passes::probe::PROBE_FORMAT,
        },
    )
    .unwrap()
}

/// The SSDF of a bundled scene's first object at the scene's bake knobs,
/// from the cache (baked on first use) on `field`'s shader library.
pub fn first_object_ssdf(
    ctx: &Arc<Context>,
    field: &inlay_passes::field::GpuGridField,
    scene: &inlay_passes::scene::Scene,
) -> inlay_passes::ssdf::SsdfField {
    let lib = field.library(&inlay_passes::shaders::library().unwrap());
    inlay::ssdf_source::object_ssdf(
        ctx,
        &lib,
        &scene.objects[0].mesh,
        &scene.object_sources[0].file,
        None,
        &scene.shadows.bake,
        true,
    )
    .unwrap()
}
