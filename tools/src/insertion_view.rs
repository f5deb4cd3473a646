//! A radiance field with virtual objects inserted, seen from one camera:
//! the per-frame passes of METHOD.md §4.4 in one frame graph — per object
//! the probe trace and SG fit (only when the object moved), the object
//! G-buffer, the march clipped at the object, SG shading and compositing.
//! Without objects it is the bare march: no pass runs whose result the
//! frame does not need.

use std::sync::{Arc, Mutex};

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Context};
use inlay_passes::camera::{CameraFrame, CameraSpec};
use inlay_passes::composite::{CompositePass, COMPOSITE_FORMAT};
use inlay_passes::field::GpuGridField;
use inlay_passes::gbuffer::{GBufferPass, ObjectDraw};
use inlay_passes::lighting::{environment_lobes, IncidentLight};
use inlay_passes::march::MarchPass;
use inlay_passes::object::{GpuObject, PlacedObject};
use inlay_passes::scene::Scene as SceneFile;
use inlay_passes::shade::ShadePass;

/// One object of the view: its placement (changeable between frames), its
/// uploaded mesh and its incident light.
pub struct ViewObject {
    /// Pose and material override; edit between frames to move it.
    pub placed: Mutex<PlacedObject>,
    /// Mesh and textures on the GPU.
    pub gpu: GpuObject,
    /// Probe and SG fit at the object's centre.
    pub light: IncidentLight,
}

/// The field, its objects and the passes that insert them.
pub struct InsertionView {
    /// The march.
    pub march: MarchPass,
    /// The field on the GPU.
    pub field: GpuGridField,
    /// The camera.
    pub camera: CameraSpec,
    /// The objects (may be empty).
    pub objects: Vec<ViewObject>,
    gbuffer: GBufferPass,
    shade: ShadePass,
    composite: CompositePass,
}

impl InsertionView {
    /// Builds the passes for `scene`'s objects (knobs from the scene file)
    /// over `field`, seen from `camera`.
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        scene: &SceneFile,
        march: MarchPass,
        field: GpuGridField,
        camera: CameraSpec,
    ) -> anyhow::Result<Self> {
        let env = environment_lobes(&scene.environment);
        let mut objects = Vec::with_capacity(scene.objects.len());
        anyhow::ensure!(
            scene.objects.len() <= 64,
            "{}: {} objects; at most 64 are inserted at once",
            scene.path.display(),
            scene.objects.len()
        );
        for placed in &scene.objects {
            let (centre, _) = placed.sphere();
            if !field.bounds.contains(centre) {
                log::warn!(
                    "object `{}` is centred at {centre}, outside the field's bounds: it is lit by what the field shows from there",
                    placed.name
                );
            }
            objects.push(ViewObject {
                placed: Mutex::new(placed.clone()),
                gpu: GpuObject::upload(ctx, &placed.mesh)?,
                light: IncidentLight::new(
                    ctx,
                    lib,
                    scene.lighting.probe,
                    scene.lighting.fit,
                    *march.knobs(),
                    &env,
                )?,
            });
        }
        Ok(Self {
            gbuffer: GBufferPass::new(ctx, lib)?,
            shade: ShadePass::new(ctx, lib, scene.shading.ndf_lobes)?,
            composite: CompositePass::new(ctx, lib)?,
            march,
            field,
            camera,
            objects,
        })
    }
}

impl crate::headless::Scene for InsertionView {
    fn build<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        width: u32,
        height: u32,
        _time: f32,
    ) -> anyhow::Result<ImageHandle> {
        let frame = CameraFrame::new(&self.camera, width, height);
        if self.objects.is_empty() {
            return Ok(self
                .march
                .add(graph, &self.field, &frame, None)
                .colour_opacity);
        }
        // This frame's placements (copied out of the locks).
        let placed: Vec<PlacedObject> = self
            .objects
            .iter()
            .map(|o| o.placed.lock().unwrap_or_else(|e| e.into_inner()).clone())
            .collect();
        let mut lobes = Vec::with_capacity(self.objects.len());
        for (o, p) in self.objects.iter().zip(&placed) {
            let (centre, _) = p.sphere();
            let work = o.light.plan(centre, 0);
            lobes.push(o.light.add(graph, &self.field, centre, work)?);
        }
        let draws: Vec<ObjectDraw<'_>> = self
            .objects
            .iter()
            .zip(&placed)
            .map(|(o, p)| ObjectDraw {
                placed: p,
                gpu: &o.gpu,
            })
            .collect();
        let g = self.gbuffer.add(graph, &frame, &draws)?;
        let field = self
            .march
            .add(graph, &self.field, &frame, Some(g.distance_id));
        let object = self.shade.add(graph, &frame, &g, &lobes);
        Ok(self.composite.add(graph, field.colour_opacity, object))
    }

    fn output_format(&self) -> vk::Format {
        COMPOSITE_FORMAT
    }
}
