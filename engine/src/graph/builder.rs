//! Declaring a frame: resources (transient or imported) and passes with the
//! accesses they make.

use std::sync::Arc;

use ash::vk;

use super::access::{BufferAccess, ImageAccess, PassKind, SyncState};
use super::context::PassContext;
use super::decl::{BufferHandle, BufferUse, ImageHandle, ImageUse};
use super::GraphError;
use crate::error::Result;
use crate::memory::{Buffer, Image, ImageDesc};

/// Where an imported image's memory comes from.
pub(crate) enum ImageBacking {
    Owned(Arc<Image>),
    External {
        image: vk::Image,
        view: vk::ImageView,
    },
}

/// Where an imported buffer's memory comes from.
pub(crate) enum BufferBacking {
    Owned(Arc<Buffer>),
    #[cfg_attr(not(test), allow(dead_code))]
    External(vk::Buffer),
}

pub(crate) struct Import<B> {
    pub backing: B,
    pub initial: SyncState,
    pub export: Option<SyncState>,
}

pub(crate) struct ImageDecl {
    pub name: String,
    pub desc: ImageDesc,
    pub import: Option<Import<ImageBacking>>,
    pub versions: Vec<VersionInfo>,
    pub output_version: Option<u32>,
}

pub(crate) struct BufferDecl {
    pub name: String,
    pub size: u64,
    pub import: Option<Import<BufferBacking>>,
    pub versions: Vec<VersionInfo>,
    pub output_version: Option<u32>,
}

/// Who wrote one version of a resource and who read it.
#[derive(Default, Clone)]
pub(crate) struct VersionInfo {
    pub writer: Option<usize>,
    pub readers: Vec<usize>,
}

/// A pass's recording callback.
pub(crate) type PassFn = Box<dyn FnOnce(&mut PassContext<'_>) -> Result<()>>;

pub(crate) struct PassDecl {
    pub name: String,
    pub kind: PassKind,
    pub images: Vec<ImageUse>,
    pub buffers: Vec<BufferUse>,
    pub keep: bool,
    pub exec: Option<PassFn>,
}

/// One frame's graph: declare resources and passes, then hand it to the
/// [`Renderer`](crate::Renderer) (or [`Plan::new`](super::Plan::new) to inspect the plan).
/// Rebuilt every frame; declaration is cheap.
#[derive(Default)]
pub struct FrameGraph {
    pub(crate) images: Vec<ImageDecl>,
    pub(crate) buffers: Vec<BufferDecl>,
    pub(crate) passes: Vec<PassDecl>,
    pub(crate) skipped: Vec<SkippedPass>,
    pub(crate) error: Option<GraphError>,
}

/// A pass the frame's builder chose not to add because its result is not
/// needed this frame (as opposed to a culled pass, which was added but
/// whose output nothing consumed). Recorded so profilers can show it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SkippedPass {
    /// The pass's name, as it would have been added.
    pub name: String,
    /// Why it was not needed (for tables and traces).
    pub reason: String,
}

impl FrameGraph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// A transient image: created (or reused from earlier frames) by the graph,
    /// valid only within this frame, aliased with others whose lifetimes do
    /// not overlap.
    pub fn create_image(&mut self, name: &str, desc: ImageDesc) -> ImageHandle {
        self.images.push(ImageDecl {
            name: name.into(),
            desc,
            import: None,
            versions: vec![VersionInfo::default()],
            output_version: None,
        });
        ImageHandle {
            id: self.images.len() as u32 - 1,
            version: 0,
        }
    }

    /// A transient buffer of `size` bytes.
    pub fn create_buffer(&mut self, name: &str, size: u64) -> BufferHandle {
        self.buffers.push(BufferDecl {
            name: name.into(),
            size,
            import: None,
            versions: vec![VersionInfo::default()],
            output_version: None,
        });
        BufferHandle {
            id: self.buffers.len() as u32 - 1,
            version: 0,
        }
    }

    /// A transient buffer holding `bytes` (at most 65536, a multiple of 4),
    /// written by a transfer pass `upload {name}` from the command buffer:
    /// the way to hand a frame small data that changes every frame (camera,
    /// object poses, materials) without host writes racing frames in flight.
    pub fn upload_buffer(&mut self, name: &str, bytes: Vec<u8>) -> BufferHandle {
        let buffer = self.create_buffer(name, bytes.len().max(4) as u64);
        let mut pass = self.add_pass(&format!("upload {name}"), PassKind::Transfer);
        let written = pass.buffer(buffer, BufferAccess::TransferDst);
        pass.exec(move |ctx| ctx.update_buffer(written, &bytes));
        written
    }

    /// Imports an image that lives across frames. Its state from the previous
    /// frame is picked up automatically; `export`, when given, is the state
    /// it is left in at the end of the frame. Passes writing it are never culled.
    /// Importing an image already imported into this graph returns its
    /// latest version (one resource, one state track), adopting `export`
    /// if the first import gave none.
    pub fn import_image(
        &mut self,
        image: &Arc<Image>,
        name: &str,
        export: Option<SyncState>,
    ) -> ImageHandle {
        let found = self.images.iter_mut().enumerate().find(|(_, d)| {
            matches!(&d.import, Some(Import { backing: ImageBacking::Owned(i), .. }) if Arc::ptr_eq(i, image))
        });
        if let Some((id, decl)) = found {
            if let Some(import) = decl.import.as_mut() {
                import.export = import.export.or(export);
            }
            return ImageHandle {
                id: id as u32,
                version: decl.versions.len() as u32 - 1,
            };
        }
        let initial = image.sync_state();
        self.push_imported_image(
            name,
            image.desc(),
            ImageBacking::Owned(image.clone()),
            initial,
            export,
        )
    }

    /// Imports an image the engine does not own (e.g. a swapchain image).
    pub(crate) fn import_external_image(
        &mut self,
        name: &str,
        desc: ImageDesc,
        image: vk::Image,
        view: vk::ImageView,
        initial: SyncState,
        export: Option<SyncState>,
    ) -> ImageHandle {
        self.push_imported_image(
            name,
            desc,
            ImageBacking::External { image, view },
            initial,
            export,
        )
    }

    fn push_imported_image(
        &mut self,
        name: &str,
        desc: ImageDesc,
        backing: ImageBacking,
        initial: SyncState,
        export: Option<SyncState>,
    ) -> ImageHandle {
        self.images.push(ImageDecl {
            name: name.into(),
            desc,
            import: Some(Import {
                backing,
                initial,
                export,
            }),
            versions: vec![VersionInfo::default()],
            output_version: None,
        });
        ImageHandle {
            id: self.images.len() as u32 - 1,
            version: 0,
        }
    }

    /// Imports a buffer that lives across frames (see [`Self::import_image`];
    /// a second import of the same buffer likewise returns its latest version).
    pub fn import_buffer(
        &mut self,
        buffer: &Arc<Buffer>,
        export: Option<SyncState>,
    ) -> BufferHandle {
        let found = self.buffers.iter_mut().enumerate().find(|(_, d)| {
            matches!(&d.import, Some(Import { backing: BufferBacking::Owned(b), .. }) if Arc::ptr_eq(b, buffer))
        });
        if let Some((id, decl)) = found {
            if let Some(import) = decl.import.as_mut() {
                import.export = import.export.or(export);
            }
            return BufferHandle {
                id: id as u32,
                version: decl.versions.len() as u32 - 1,
            };
        }
        let initial = buffer.sync_state();
        self.push_imported_buffer(
            buffer.name(),
            buffer.size(),
            BufferBacking::Owned(buffer.clone()),
            initial,
            export,
        )
    }

    #[cfg(test)]
    pub(crate) fn import_external_buffer(
        &mut self,
        name: &str,
        size: u64,
        initial: SyncState,
        export: Option<SyncState>,
    ) -> BufferHandle {
        self.push_imported_buffer(
            name,
            size,
            BufferBacking::External(vk::Buffer::null()),
            initial,
            export,
        )
    }

    fn push_imported_buffer(
        &mut self,
        name: &str,
        size: u64,
        backing: BufferBacking,
        initial: SyncState,
        export: Option<SyncState>,
    ) -> BufferHandle {
        self.buffers.push(BufferDecl {
            name: name.into(),
            size,
            import: Some(Import {
                backing,
                initial,
                export,
            }),
            versions: vec![VersionInfo::default()],
            output_version: None,
        });
        BufferHandle {
            id: self.buffers.len() as u32 - 1,
            version: 0,
        }
    }

    /// Adds a transfer pass `name` copying the whole of `src` into `dst`
    /// (same size and format); returns the new version of `dst`.
    pub fn copy_image(&mut self, name: &str, src: ImageHandle, dst: ImageHandle) -> ImageHandle {
        let mut pass = self.add_pass(name, PassKind::Transfer);
        let read = pass.image(src, ImageAccess::TransferSrc);
        let written = pass.image(dst, ImageAccess::TransferDst);
        pass.exec(move |ctx| ctx.copy_image(read, written));
        written
    }

    /// Marks this version of an image as a result of the frame: the passes
    /// producing it are not culled.
    pub fn mark_output_image(&mut self, image: ImageHandle) {
        if let Some(d) = self.images.get_mut(image.id as usize) {
            d.output_version = Some(image.version);
        }
    }

    /// Marks this version of a buffer as a result of the frame.
    pub fn mark_output_buffer(&mut self, buffer: BufferHandle) {
        if let Some(d) = self.buffers.get_mut(buffer.id as usize) {
            d.output_version = Some(buffer.version);
        }
    }

    /// Records that the pass `name` was not added this frame and why (a
    /// skip decided by the builder, reported with the frame's timings).
    /// Repeated names are kept once.
    pub fn note_skipped(&mut self, name: &str, reason: &str) {
        if !self.skipped.iter().any(|s| s.name == name) {
            self.skipped.push(SkippedPass {
                name: name.into(),
                reason: reason.into(),
            });
        }
    }

    /// The passes noted as skipped so far.
    pub fn skipped(&self) -> &[SkippedPass] {
        &self.skipped
    }

    /// Starts declaring a pass. Declare its accesses on the returned builder,
    /// then give it its recording callback with [`PassBuilder::exec`].
    pub fn add_pass(&mut self, name: &str, kind: PassKind) -> PassBuilder<'_> {
        self.passes.push(PassDecl {
            name: name.into(),
            kind,
            images: Vec::new(),
            buffers: Vec::new(),
            keep: false,
            exec: None,
        });
        let index = self.passes.len() - 1;
        PassBuilder { graph: self, index }
    }

    /// The number of declared passes.
    pub fn pass_count(&self) -> usize {
        self.passes.len()
    }

    /// The name of a declared pass.
    pub fn pass_name(&self, index: usize) -> &str {
        &self.passes[index].name
    }

    /// The name of an image.
    pub fn image_name(&self, image: ImageHandle) -> &str {
        self.images
            .get(image.id as usize)
            .map(|d| d.name.as_str())
            .unwrap_or("?")
    }

    /// The description of an image.
    pub fn image_desc(&self, image: ImageHandle) -> Option<ImageDesc> {
        self.images.get(image.id as usize).map(|d| d.desc)
    }

    fn fail(&mut self, e: GraphError) {
        if self.error.is_none() {
            self.error = Some(e);
        }
    }
}

/// Declares one pass's accesses. Errors are recorded and reported when the
/// graph is planned, so declarations read as a plain list.
pub struct PassBuilder<'g> {
    graph: &'g mut FrameGraph,
    index: usize,
}

impl PassBuilder<'_> {
    fn pass_name(&self) -> String {
        self.graph.passes[self.index].name.clone()
    }

    /// Declares a use of an image. For a writing access, returns the new
    /// version that later readers must use; for a read, returns `image`.
    pub fn image(&mut self, image: ImageHandle, access: ImageAccess) -> ImageHandle {
        let kind = self.graph.passes[self.index].kind;
        let already = self.graph.passes[self.index]
            .images
            .iter()
            .any(|u| u.id == image.id);
        let checked = self.graph.images.get(image.id as usize).map(|d| Resource {
            name: &d.name,
            versions: d.versions.len(),
            imported: d.import.is_some(),
        });
        let use_ = Use {
            version: image.version,
            already,
            allowed: access.allowed_in(kind),
            writes: access.writes(),
            reads_previous: access.reads_previous(),
            access: format!("{access:?}"),
        };
        if let Err(e) = self.check(checked, &use_) {
            self.graph.fail(e);
            return image;
        }
        self.graph.passes[self.index].images.push(ImageUse {
            id: image.id,
            version: image.version,
            access,
        });
        let version = record_version(
            &mut self.graph.images[image.id as usize].versions,
            self.index,
            image.version,
            access.writes(),
        );
        ImageHandle {
            id: image.id,
            version,
        }
    }

    /// Declares a use of a buffer; like [`Self::image`].
    pub fn buffer(&mut self, buffer: BufferHandle, access: BufferAccess) -> BufferHandle {
        let kind = self.graph.passes[self.index].kind;
        let already = self.graph.passes[self.index]
            .buffers
            .iter()
            .any(|u| u.id == buffer.id);
        let checked = self
            .graph
            .buffers
            .get(buffer.id as usize)
            .map(|d| Resource {
                name: &d.name,
                versions: d.versions.len(),
                imported: d.import.is_some(),
            });
        let use_ = Use {
            version: buffer.version,
            already,
            allowed: access.allowed_in(kind),
            writes: access.writes(),
            reads_previous: access.reads_previous(),
            access: format!("{access:?}"),
        };
        if let Err(e) = self.check(checked, &use_) {
            self.graph.fail(e);
            return buffer;
        }
        self.graph.passes[self.index].buffers.push(BufferUse {
            id: buffer.id,
            version: buffer.version,
            access,
        });
        let version = record_version(
            &mut self.graph.buffers[buffer.id as usize].versions,
            self.index,
            buffer.version,
            access.writes(),
        );
        BufferHandle {
            id: buffer.id,
            version,
        }
    }

    /// The declaration rules shared by images and buffers.
    fn check(
        &self,
        resource: Option<Resource<'_>>,
        u: &Use,
    ) -> std::result::Result<(), GraphError> {
        let pass = self.pass_name();
        let kind = self.graph.passes[self.index].kind;
        let Some(r) = resource else {
            return Err(GraphError::UnknownHandle { pass });
        };
        let latest = r.versions as u32 - 1;
        let resource = r.name.to_owned();
        if u.version > latest {
            Err(GraphError::UnknownHandle { pass })
        } else if !u.allowed {
            Err(GraphError::AccessNotAllowed {
                pass,
                kind,
                resource,
                access: u.access.clone(),
            })
        } else if u.already {
            Err(GraphError::DuplicateAccess { pass, resource })
        } else if u.writes && u.version != latest {
            Err(GraphError::StaleWrite {
                pass,
                resource,
                version: u.version,
                latest,
            })
        } else if !r.imported && u.version == 0 && u.reads_previous {
            Err(GraphError::ReadBeforeWrite { pass, resource })
        } else {
            Ok(())
        }
    }

    /// Records a declaration error, reported when the graph is planned.
    pub(crate) fn fail(&mut self, e: GraphError) {
        self.graph.fail(e);
    }

    /// Marks the pass as having effects outside the graph: never culled.
    pub fn keep(&mut self) {
        self.graph.passes[self.index].keep = true;
    }

    /// Sets the callback that records the pass's commands.
    pub fn exec(self, f: impl FnOnce(&mut PassContext<'_>) -> Result<()> + 'static) {
        self.graph.passes[self.index].exec = Some(Box::new(f));
    }
}

/// What the declaration rules need to know of a resource.
struct Resource<'d> {
    name: &'d str,
    versions: usize,
    imported: bool,
}

/// What the declaration rules need to know of one use.
struct Use {
    version: u32,
    already: bool,
    allowed: bool,
    writes: bool,
    reads_previous: bool,
    access: String,
}

/// Records a use in a resource's version table; returns the handle version
/// after it (a new one for writes).
fn record_version(versions: &mut Vec<VersionInfo>, pass: usize, version: u32, writes: bool) -> u32 {
    if writes {
        versions.push(VersionInfo {
            writer: Some(pass),
            readers: Vec::new(),
        });
        version + 1
    } else {
        versions[version as usize].readers.push(pass);
        version
    }
}
