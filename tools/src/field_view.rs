//! A radiance field seen from one camera, as a headless/window scene: the
//! frame graph's NeRF march pass and nothing else (no object yet).

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::vk;
use inlay_passes::camera::{CameraFrame, CameraSpec};
use inlay_passes::field::GpuGridField;
use inlay_passes::march::{MarchPass, MARCH_COLOUR_FORMAT};

use crate::headless::Scene;

/// The march of one uploaded field from one camera.
pub struct FieldView {
    /// The pass.
    pub march: MarchPass,
    /// The field on the GPU.
    pub field: GpuGridField,
    /// The camera.
    pub camera: CameraSpec,
}

impl Scene for FieldView {
    fn build<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        width: u32,
        height: u32,
        _time: f32,
    ) -> anyhow::Result<ImageHandle> {
        let frame = CameraFrame::new(&self.camera, width, height);
        Ok(self
            .march
            .add(graph, &self.field, &frame, None)
            .colour_opacity)
    }

    fn output_format(&self) -> vk::Format {
        MARCH_COLOUR_FORMAT
    }
}
