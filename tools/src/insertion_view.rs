//! A radiance field with virtual objects inserted, seen from one camera:
//! the per-frame passes of METHOD.md §4.4 in one frame graph — per object
//! the probe trace and SG fit (only when the object moved), the object
//! G-buffer, the march clipped at the object, SG shading with self-shadows,
//! the cast shadow on the field and compositing. Without objects it is the
//! bare march, without shadows no SSDF is read: no pass runs whose result
//! the frame does not need.

use std::sync::{Arc, Mutex};

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Context};
use inlay_passes::camera::{CameraFrame, CameraSpec};
use inlay_passes::composite::{CompositePass, COMPOSITE_FORMAT};
use inlay_passes::field::GpuGridField;
use inlay_passes::gbuffer::{GBufferPass, ObjectDraw};
use inlay_passes::lighting::IncidentLight;
use inlay_passes::march::MarchPass;
use inlay_passes::object::{GpuObject, PlacedObject};
use inlay_passes::scene::Scene as SceneFile;
use inlay_passes::scene::ShadowKnobs;
use inlay_passes::shade::{SelfShadow, ShadePass};
use inlay_passes::shadow::{CastShadowPass, GpuFhTable, GpuSsdf};

/// One object of the view: its placement (changeable between frames), its
/// uploaded mesh and its incident light.
pub struct ViewObject {
    /// Pose and material override; edit between frames to move it.
    pub placed: Mutex<PlacedObject>,
    /// Mesh and textures on the GPU.
    pub gpu: GpuObject,
    /// Probe and SG fit at the object's centre.
    pub light: IncidentLight,
    /// Its SSDF field on the GPU (when the scene draws shadows).
    pub ssdf: Option<GpuSsdf>,
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
    /// Which shadows are drawn (changeable between frames; objects need
    /// their SSDF fields, loaded when the scene asked for shadows).
    pub shadows: Mutex<ShadowKnobs>,
    gbuffer: GBufferPass,
    shade: ShadePass,
    composite: CompositePass,
    cast: Option<CastShadowPass>,
    fh: Option<GpuFhTable>,
}

impl InsertionView {
    /// Builds the passes for `scene`'s objects (knobs from the scene file)
    /// over `field`, seen from `camera`. With shadows on, each object's
    /// SSDF field is loaded, or baked and cached (`use_cache`).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        scene: &SceneFile,
        march: MarchPass,
        field: GpuGridField,
        camera: CameraSpec,
        use_cache: bool,
    ) -> anyhow::Result<Self> {
        let shadows = scene.shadows.any() && !scene.objects.is_empty();
        let env = scene.object_light_lobes();
        let mut objects = Vec::with_capacity(scene.objects.len());
        anyhow::ensure!(
            scene.objects.len() <= 64,
            "{}: {} objects; at most 64 are inserted at once",
            scene.path.display(),
            scene.objects.len()
        );
        for (placed, source) in scene.objects.iter().zip(&scene.object_sources) {
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
                ssdf: if shadows {
                    let f = crate::ssdf_source::object_ssdf(
                        ctx,
                        lib,
                        &placed.mesh,
                        &source.file,
                        source.ssdf.as_deref(),
                        &scene.shadows.bake,
                        use_cache,
                    )?;
                    Some(GpuSsdf::upload(ctx, Arc::new(f))?)
                } else {
                    None
                },
            });
        }
        Ok(Self {
            gbuffer: GBufferPass::new(ctx, lib)?,
            shade: ShadePass::new(ctx, lib, scene.shading.ndf_lobes)?,
            composite: CompositePass::new(ctx, lib)?,
            cast: if shadows {
                Some(CastShadowPass::new(ctx, lib)?)
            } else {
                None
            },
            fh: if shadows {
                Some(GpuFhTable::new(ctx)?)
            } else {
                None
            },
            shadows: Mutex::new(scene.shadows),
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
        let knobs = *self.shadows.lock().unwrap_or_else(|e| e.into_inner());
        let fh = self.fh.as_ref().map(|t| t.import(graph));
        // Each object's SSDF bindings this frame (None: no shadows for it).
        let ssdf: Vec<_> = self
            .objects
            .iter()
            .zip(&placed)
            .map(|(o, p)| match (&o.ssdf, fh) {
                (Some(s), Some(_)) if knobs.any() => Some(s.import(graph, p, knobs.outside)),
                _ => None,
            })
            .collect();
        let self_shadow: Vec<Option<SelfShadow>> = ssdf
            .iter()
            .map(|s| match (s, fh) {
                (Some(ssdf), Some(fh_table)) if knobs.self_shadow => Some(SelfShadow {
                    fh_table,
                    ssdf: *ssdf,
                }),
                _ => None,
            })
            .collect();
        let object = self.shade.add(graph, &frame, &g, &lobes, &self_shadow);
        let mut shadow = None;
        if let (true, Some(cast), Some(fh_table)) = (knobs.cast, &self.cast, fh) {
            for (s, l) in ssdf.iter().zip(&lobes) {
                if let Some(s) = s {
                    shadow = Some(cast.add(
                        graph,
                        &self.field,
                        &frame,
                        &field,
                        *l,
                        fh_table,
                        *s,
                        shadow,
                    ));
                }
            }
        }
        Ok(self
            .composite
            .add(graph, field.colour_opacity, object, shadow))
    }

    fn output_format(&self) -> vk::Format {
        COMPOSITE_FORMAT
    }
}
