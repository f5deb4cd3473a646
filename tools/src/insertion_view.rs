//! A radiance field with virtual objects inserted, seen from one camera, as
//! a headless or window scene: the frame of `inlay_passes::frame` with the
//! state a viewer changes between frames (camera, placements, effects).

use std::sync::{Arc, Mutex};

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
    pub camera: Mutex<CameraSpec>,
    /// Each object's pose and material override (changeable between
    /// frames), in the frame's order.
    placed: Vec<Mutex<PlacedObject>>,
    /// Which effects are drawn (changeable between frames; shadows need
    /// the objects' SSDF fields, loaded when the scene asked for shadows).
    effects: Mutex<Effects>,
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
            camera: Mutex::new(camera),
            placed: scene.objects.iter().cloned().map(Mutex::new).collect(),
            effects: Mutex::new(Effects::of_scene(&scene.shadows)),
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

/// Locks `m`, recovering the value if a panicking thread poisoned it.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl InsertionView {
    /// This frame's camera for a `width`×`height` image.
    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        CameraFrame::new(&lock(&self.camera), width, height)
    }

    /// Moves the camera from the next frame on.
    pub fn set_camera(&self, camera: CameraSpec) {
        if camera.problem().is_none() {
            *lock(&self.camera) = camera;
        }
    }

    /// A copy of object `index`'s current placement.
    pub fn placed(&self, index: usize) -> Option<PlacedObject> {
        self.placed.get(index).map(|p| lock(p).clone())
    }

    /// Replaces object `index`'s placement (pose and material).
    pub fn set_placed(&self, index: usize, placed: PlacedObject) {
        if let Some(p) = self.placed.get(index) {
            *lock(p) = placed;
        }
    }

    /// The effects drawn now.
    pub fn effects(&self) -> Effects {
        *lock(&self.effects)
    }

    /// Sets the effects drawn from the next frame on.
    pub fn set_effects(&self, effects: Effects) {
        *lock(&self.effects) = effects;
    }

    /// Whether any object has an SSDF field (shadows can be drawn).
    pub fn has_shadows(&self) -> bool {
        self.frame.has_shadows()
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
        let frame = self.frame(width, height);
        // This frame's placements (copied out of the locks).
        let placed: Vec<PlacedObject> = self.placed.iter().map(|p| lock(p).clone()).collect();
        self.frame.add(graph, &frame, &placed, self.effects())
    }

    fn output_format(&self) -> vk::Format {
        FRAME_FORMAT
    }
}
