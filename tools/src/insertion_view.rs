//! A radiance field with virtual objects inserted, seen from one camera, as
//! a headless or window scene: the frame of `inlay_passes::frame` with the
//! state a viewer changes between frames (camera, placements, effects).

use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Context};
use inlay_passes::camera::{CameraFrame, CameraSpec};
use inlay_passes::field::GpuGridField;
use inlay_passes::frame::{InsertionFrame, FRAME_FORMAT};
use inlay_passes::march::MarchPass;
use inlay_passes::object::PlacedObject;
use inlay_passes::scene::Scene as SceneFile;

pub use inlay_passes::frame::{Effects, FrameObject, OFF_SCREEN_SHADOW_REACH};

/// The frame and what changes between frames.
pub struct InsertionView {
    /// The passes, the field and the objects' GPU state.
    pub frame: InsertionFrame,
    /// The camera (changeable between frames).
    camera: CameraSpec,
    /// Each object's pose and material override (changeable between
    /// frames), in the frame's order.
    placed: Vec<PlacedObject>,
    /// Which effects are drawn (changeable between frames; shadows need
    /// the objects' SSDF fields, loaded when the scene asked for shadows).
    effects: Effects,
}

impl InsertionView {
    /// Builds the frame for `scene`'s objects (knobs from the scene file)
    /// over `field`, seen from `camera`. With shadows on, each object's
    /// SSDF field is loaded, or baked and cached (`use_cache`); the
    /// effects start as the scene file sets them.
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
        // Every object's limits before any SSDF is baked.
        for (placed, source) in scene.objects.iter().zip(&scene.object_sources) {
            inlay_passes::object::check_mesh_fits(ctx.info(), &placed.mesh)?;
            if shadows && source.ssdf.is_none() {
                inlay_passes::ssdf::check_bake_fits(ctx.info(), &placed.mesh)?;
            }
        }
        let ssdfs = scene
            .objects
            .iter()
            .zip(&scene.object_sources)
            .map(|(placed, source)| -> anyhow::Result<_> {
                if !shadows {
                    return Ok(None);
                }
                Ok(Some(Arc::new(crate::ssdf_source::object_ssdf(
                    ctx,
                    lib,
                    &placed.mesh,
                    &source.file,
                    source.ssdf.as_deref(),
                    &scene.shadows.bake,
                    use_cache,
                )?)))
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        Ok(Self {
            frame: InsertionFrame::new(ctx, lib, scene, march, field, ssdfs)?,
            camera,
            placed: scene.objects.clone(),
            effects: Effects::of_scene(&scene.shadows),
        })
    }

    /// The objects' GPU state, in the scene's order.
    pub fn objects(&self) -> &[FrameObject] {
        &self.frame.objects
    }

    /// The objects' GPU state, to replace an SSDF between frames.
    pub fn objects_mut(&mut self) -> &mut [FrameObject] {
        &mut self.frame.objects
    }
}

impl InsertionView {
    /// This frame's camera for a `width`×`height` image.
    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        CameraFrame::new(&self.camera, width, height)
    }

    /// The camera.
    pub fn camera(&self) -> &CameraSpec {
        &self.camera
    }

    /// Moves the camera from the next frame on (a camera with a problem
    /// is ignored).
    pub fn set_camera(&mut self, camera: CameraSpec) {
        if camera.problem().is_none() {
            self.camera = camera;
        }
    }

    /// A copy of object `index`'s current placement.
    pub fn placed(&self, index: usize) -> Option<PlacedObject> {
        self.placed.get(index).cloned()
    }

    /// Replaces object `index`'s placement (pose and material).
    pub fn set_placed(&mut self, index: usize, placed: PlacedObject) {
        if let Some(p) = self.placed.get_mut(index) {
            *p = placed;
        }
    }

    /// The effects drawn now.
    pub fn effects(&self) -> Effects {
        self.effects
    }

    /// Sets the effects drawn from the next frame on.
    pub fn set_effects(&mut self, effects: Effects) {
        self.effects = effects;
    }

    /// Whether any object has an SSDF field (shadows can be drawn).
    pub fn has_shadows(&self) -> bool {
        self.frame.has_shadows()
    }
}

impl crate::headless::Scene for InsertionView {
    fn build(
        &mut self,
        graph: &mut FrameGraph,
        width: u32,
        height: u32,
        _time: f32,
    ) -> anyhow::Result<ImageHandle> {
        let camera = self.frame(width, height);
        self.frame.add(graph, &camera, &self.placed, self.effects)
    }

    fn output_format(&self) -> vk::Format {
        FRAME_FORMAT
    }
}
