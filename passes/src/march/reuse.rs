//! The field's march kept across frames while the camera holds still.
//!
//! The march depends on the camera and the field alone, except where an
//! object clips it, and the field does not change while a user drags an
//! object in front of a still camera. So [`MarchReuse`] keeps the
//! unclipped march of the last still camera in two images of its own;
//! a frame from that camera copies them and marches again only the
//! rectangle its objects can cover (clipped at them). The result is the
//! same, pixel for pixel, as marching the whole image: outside the
//! objects the clipped march reads no object depth and runs the unclipped
//! march's arithmetic.
//!
//! The cache is filled on the second frame in a row from one camera, so
//! a moving camera pays nothing for it; the frame that fills it marches
//! the whole image unclipped and the objects' rectangle again.

use std::sync::Arc;

use inlay_engine::graph::{FrameGraph, ImageHandle};
use inlay_engine::{vk, Context, Image, ImageDesc};

use super::pass::{MarchOutputs, MarchPass, MARCH_COLOUR_FORMAT, MARCH_DEPTH_FORMAT, NERF_MARCH};
use crate::camera::CameraFrame;
use crate::field::{FieldIdentity, GpuGridField};

/// What a march is a function of: the camera's rays and the field.
#[derive(Debug, Clone, PartialEq)]
struct MarchKey {
    camera: Vec<u8>,
    field: FieldIdentity,
}

impl MarchKey {
    fn new(camera: &CameraFrame, field: &GpuGridField) -> Self {
        Self {
            camera: bytemuck::bytes_of(&camera.rays()).to_vec(),
            field: field.identity(),
        }
    }
}

/// The unclipped march of one camera, on images that outlive the frame.
struct KeptMarch {
    key: MarchKey,
    colour: Arc<Image>,
    depth: Arc<Image>,
}

/// Where the march may be clipped this frame.
#[derive(Debug, Clone, Copy)]
pub enum MarchClip {
    /// Nowhere: the field alone.
    None,
    /// At the objects' depths (an R32F image of distances along each
    /// pixel's ray), which only the pixels `region` (x0, y0, x1, y1,
    /// ends exclusive) can hold; `region` None when they may be anywhere.
    Objects {
        /// The objects' depth image.
        depth: ImageHandle,
        /// The pixels they can cover.
        region: Option<[u32; 4]>,
    },
}

/// The march of the last still camera and what the frames before asked.
pub struct MarchReuse {
    ctx: Arc<Context>,
    last: Option<MarchKey>,
    kept: Option<KeptMarch>,
}

impl MarchReuse {
    /// Nothing kept yet.
    pub fn new(ctx: &Arc<Context>) -> Self {
        Self {
            ctx: ctx.clone(),
            last: None,
            kept: None,
        }
    }

    /// Adds the frame's march to `graph` (passes named `nerf-march`), kept
    /// or marched afresh as the module says.
    pub fn add(
        &mut self,
        march: &MarchPass,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        clip: MarchClip,
    ) -> anyhow::Result<MarchOutputs> {
        let key = MarchKey::new(camera, field);
        let still = self.last.as_ref() == Some(&key);
        self.last = Some(key.clone());
        let (depth, region) = match clip {
            MarchClip::None => (None, None),
            MarchClip::Objects { depth, region } => (Some(depth), region),
        };
        let kept_now = self.kept.as_ref().is_some_and(|k| k.key == key);
        let whole_clip = depth.is_some() && region.is_none();
        if whole_clip || !(kept_now || still) {
            return Ok(march.add(graph, field, camera, depth));
        }
        if !kept_now {
            self.keep(march, graph, field, camera, key)?;
        }
        let kept = self.kept.as_ref().expect("kept above");
        let cached_colour = graph.import_image(&kept.colour, "nerf-colour-kept", None);
        let cached_depth = graph.import_image(&kept.depth, "nerf-depth-kept", None);
        let mut out = MarchOutputs::create(graph, camera.width, camera.height);
        out.colour_opacity = graph.copy_image(NERF_MARCH, cached_colour, out.colour_opacity);
        out.depth = graph.copy_image(NERF_MARCH, cached_depth, out.depth);
        if let (Some(depth), Some(r)) = (depth, region) {
            if r[2] > r[0] && r[3] > r[1] {
                march.record(graph, field, camera, Some(depth), r, &mut out, true);
            }
        }
        Ok(out)
    }

    /// Marches the whole image unclipped into images that outlive the
    /// frame (made anew only when the image's size changes).
    fn keep(
        &mut self,
        march: &MarchPass,
        graph: &mut FrameGraph,
        field: &GpuGridField,
        camera: &CameraFrame,
        key: MarchKey,
    ) -> anyhow::Result<()> {
        let (width, height) = (camera.width, camera.height);
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let make = |name: &str, format| -> anyhow::Result<Arc<Image>> {
            let desc = ImageDesc {
                width,
                height,
                format,
            };
            Ok(Arc::new(Image::new(&self.ctx, name, desc, usage)?))
        };
        let (colour, depth) = match self.kept.take() {
            Some(k) if k.colour.desc().width == width && k.colour.desc().height == height => {
                (k.colour, k.depth)
            }
            _ => (
                make("nerf-colour-kept", MARCH_COLOUR_FORMAT)?,
                make("nerf-depth-kept", MARCH_DEPTH_FORMAT)?,
            ),
        };
        let mut out = MarchOutputs {
            colour_opacity: graph.import_image(&colour, "nerf-colour-kept", None),
            depth: graph.import_image(&depth, "nerf-depth-kept", None),
        };
        march.record(
            graph,
            field,
            camera,
            None,
            [0, 0, width, height],
            &mut out,
            false,
        );
        self.kept = Some(KeptMarch { key, colour, depth });
        Ok(())
    }
}
