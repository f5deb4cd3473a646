//! The view-dependent coefficients a trainer trains, one storage binding a
//! coefficient (a page): page j holds coefficient j of every trained node
//! as (r, g, b, 0), f32, with its gradient and Adam's two moments in pages
//! of their own. In one binding, a 256-node sparse grid's degree-1
//! coefficients (ROOM and DOG keep 4.7–5.3 million nodes) would take
//! 230–255 MiB, past lavapipe's 128 MiB; a page takes 16 bytes a node, as
//! the nodes' own (r, g, b, σ) do. `shaders/train/sh_pages.wgsl` reads
//! them; the scatter kernels (`train/ray_grad*.wgsl`) add into the
//! gradient's pages. Pages past the field's degree are bound to a small
//! unused buffer (a shader's bindings are fixed).

use std::sync::Arc;

use inlay_engine::graph::{BoundPass, BufferAccess, BufferHandle, FrameGraph};
use inlay_engine::{vk, Buffer, Context};

/// Pages the shaders declare: the most further coefficients a field has
/// (degree 2).
pub const SH_PAGES: usize = 8;

/// The pages of one trainer.
pub struct ShPages {
    values: Vec<Arc<Buffer>>,
    grad: Vec<Arc<Buffer>>,
    first: Vec<Arc<Buffer>>,
    second: Vec<Arc<Buffer>>,
    /// The unused pages' buffers (values and gradient), one each.
    spare: Vec<[Arc<Buffer>; 2]>,
}

/// The pages as imported into one frame's graph.
pub struct ShPageHandles {
    /// Values, gradient, first and second moments of each trained page.
    pub trained: Vec<[BufferHandle; 4]>,
    /// Values and gradient of each unused page.
    pub spare: Vec<[BufferHandle; 2]>,
}

impl ShPages {
    /// Pages holding `coefficients` (`count` a node, node-major, as
    /// `crate::field::GridField::sh` or a pool's), their gradient and
    /// moments zero.
    pub fn new(
        ctx: &Arc<Context>,
        coefficients: &[[f32; 3]],
        count: usize,
    ) -> anyhow::Result<Self> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        let nodes = coefficients.len().checked_div(count).unwrap_or(0).max(1);
        let buffer = |name: String, data: &[u8]| -> anyhow::Result<Arc<Buffer>> {
            Ok(Arc::new(Buffer::with_data(ctx, &name, data, usage)?))
        };
        let zeros = vec![0u8; 16 * nodes];
        let mut pages = Self {
            values: Vec::new(),
            grad: Vec::new(),
            first: Vec::new(),
            second: Vec::new(),
            spare: Vec::new(),
        };
        for j in 0..count {
            let mut page: Vec<u8> = coefficients
                .iter()
                .skip(j)
                .step_by(count)
                .flat_map(|c| [c[0], c[1], c[2], 0.0])
                .flat_map(f32::to_le_bytes)
                .collect();
            page.resize(16 * nodes, 0); // no node kept: a buffer is never empty
            pages.values.push(buffer(format!("train-sh-{j}"), &page)?);
            pages
                .grad
                .push(buffer(format!("train-sh-grad-{j}"), &zeros)?);
            pages
                .first
                .push(buffer(format!("train-sh-first-{j}"), &zeros)?);
            pages
                .second
                .push(buffer(format!("train-sh-second-{j}"), &zeros)?);
        }
        for j in count..SH_PAGES {
            pages.spare.push([
                buffer(format!("train-sh-{j} (unused)"), &[0; 16])?,
                buffer(format!("train-sh-grad-{j} (unused)"), &[0; 16])?,
            ]);
        }
        Ok(pages)
    }

    /// Pages trained (the field's further coefficients a node).
    pub fn count(&self) -> usize {
        self.values.len()
    }

    /// Imports every page into `graph`.
    pub fn import(&self, graph: &mut FrameGraph) -> ShPageHandles {
        let trained = (0..self.count())
            .map(|j| {
                [
                    &self.values[j],
                    &self.grad[j],
                    &self.first[j],
                    &self.second[j],
                ]
                .map(|b| graph.import_buffer(b, None))
            })
            .collect();
        let spare = self
            .spare
            .iter()
            .map(|s| s.clone().map(|b| graph.import_buffer(&b, None)))
            .collect();
        ShPageHandles { trained, spare }
    }

    /// The values of page `j` (for reading back).
    pub fn values(&self, j: usize) -> &Arc<Buffer> {
        &self.values[j]
    }

    /// The gradient of page `j` (for reading back).
    pub fn gradient(&self, j: usize) -> &Arc<Buffer> {
        &self.grad[j]
    }
}

impl ShPageHandles {
    /// Binds every page's values (`sh_page_j`, read) and gradient
    /// (`sh_grad_j`, scattered into) on the batch pass.
    pub fn bind_to_batch(&mut self, pass: &mut BoundPass<'_>) {
        for (j, [values, grad, ..]) in self.trained.iter_mut().enumerate() {
            pass.buffer_at(&*format!("sh_page_{j}"), *values, BufferAccess::StorageRead);
            *grad = pass.buffer_at(
                &*format!("sh_grad_{j}"),
                *grad,
                BufferAccess::StorageReadWrite,
            );
        }
        let first_spare = self.trained.len();
        for (i, [values, grad]) in self.spare.iter_mut().enumerate() {
            let j = first_spare + i;
            pass.buffer_at(&*format!("sh_page_{j}"), *values, BufferAccess::StorageRead);
            *grad = pass.buffer_at(
                &*format!("sh_grad_{j}"),
                *grad,
                BufferAccess::StorageReadWrite,
            );
        }
    }
}

/// Interleaves pages read back (each 4 floats a node) into the trainer's
/// value order after `base` (`crate::field::device_values`: each node's
/// coefficients together, (r, g, b, 0) each).
pub fn interleave(base: Vec<f32>, pages: &[Vec<f32>]) -> Vec<f32> {
    let count = pages.len();
    if count == 0 {
        return base;
    }
    let nodes = base.len() / 4;
    let mut out = base;
    out.reserve(4 * nodes * count);
    for n in 0..nodes {
        for page in pages {
            out.extend_from_slice(&page[4 * n..4 * n + 4]);
        }
    }
    out
}
