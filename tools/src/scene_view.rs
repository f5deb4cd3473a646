//! Opening a scene file as an [`InsertionView`]: its field (file, cached
//! bake or fresh bake), the march with the given knobs, its objects and
//! the chosen camera. Shared by `render`, `profile`, `sweep` and `view`.

use std::path::Path;
use std::sync::Arc;

use inlay_engine::shader::ShaderLibrary;
use inlay_engine::Context;
use inlay_passes::camera::CameraSpec;
use inlay_passes::field::{GpuGridField, GridField};
use inlay_passes::march::{MarchKnobs, MarchPass};
use inlay_passes::scene::Scene;

use crate::field_source::{light_with_sky, scene_field, scene_seen_lights, scene_sky};
use crate::insertion_view::InsertionView;

/// `scene` seen from its camera `camera` (index or name), the field from
/// `field_file` when given (with the sky learnt with it behind, where
/// there is one, lighting the objects where the scene gives them no
/// distant light: [`light_with_sky`]), the march with `knobs` (checked),
/// bakes cached when `use_cache`.
pub fn open_view(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    scene: &Scene,
    knobs: MarchKnobs,
    field_file: Option<&Path>,
    camera: &str,
    use_cache: bool,
) -> anyhow::Result<InsertionView> {
    let camera = scene.camera(camera)?.clone();
    knobs
        .check()
        .map_err(|(k, m)| anyhow::anyhow!("march knob `{k}`: {m}"))?;
    let field = scene_field(scene, field_file, use_cache, Some(ctx.info()))?;
    let sky = scene_sky(scene, field_file)?;
    let seen = scene_seen_lights(scene, field_file)?;
    let mut lit = scene.clone();
    light_with_sky(&mut lit, sky.as_ref())?;
    lit.seen_lights = seen.clone();
    let gpu = GpuGridField::upload(ctx, &field)?
        .with_sky(sky.map(Arc::new))
        .with_seen_lights(seen);
    view_over_gpu_field(ctx, lib, &lit, knobs, gpu, camera, use_cache)
}

/// `scene`'s objects inserted into `field` (already loaded), seen from
/// `camera`, the march with `knobs` (checked).
pub fn view_over_field(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    scene: &Scene,
    knobs: MarchKnobs,
    field: &GridField,
    camera: CameraSpec,
    use_cache: bool,
) -> anyhow::Result<InsertionView> {
    let gpu = GpuGridField::upload(ctx, field)?;
    view_over_gpu_field(ctx, lib, scene, knobs, gpu, camera, use_cache)
}

/// As [`view_over_field`] over a field already on the GPU (a clone of one
/// upload shared by several views: a sweep's configurations, the
/// viewer's presets).
pub fn view_over_gpu_field(
    ctx: &Arc<Context>,
    lib: &ShaderLibrary,
    scene: &Scene,
    knobs: MarchKnobs,
    field: GpuGridField,
    camera: CameraSpec,
    use_cache: bool,
) -> anyhow::Result<InsertionView> {
    knobs
        .check()
        .map_err(|(k, m)| anyhow::anyhow!("march knob `{k}`: {m}"))?;
    let lib = &field.library(lib);
    InsertionView::new(
        ctx,
        lib,
        scene,
        MarchPass::new(ctx, lib, knobs)?,
        field,
        camera,
        use_cache,
    )
}
