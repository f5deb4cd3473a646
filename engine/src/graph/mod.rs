//! The frame graph. Passes declare the images and buffers they use and how;
//! the graph orders them by dependency, culls what nothing consumes, assigns
//! (and aliases) transient resources, derives every barrier and layout
//! transition (synchronization2), then records the passes.
//!
//! Resources are versioned: a write returns a new handle, so dependencies are
//! explicit in the handles passes exchange, and a pass that reads an older
//! version is ordered before the pass that overwrote it.
//!
//! Declaration ([`FrameGraph`]) and planning ([`Plan`]) need no device and are
//! unit-tested alone; execution lives in [`execute`](crate::graph) and
//! [`Renderer`](crate::Renderer).

mod access;
mod bind;
mod builder;
mod context;
mod decl;
mod execute;
mod plan;
#[cfg(test)]
mod tests;

pub use access::{BufferAccess, ImageAccess, LoadOp, PassKind, SyncState};
#[doc(hidden)]
pub use bind::Resource;
pub use bind::{find_binding, BoundPass, BoundPipeline, Call, Dispatch, Draw, GraphResource, Slot};
pub(crate) use builder::{BufferBacking, ImageBacking};
pub use builder::{FrameGraph, PassBuilder, SkippedPass};
pub(crate) use context::texel_bytes;
pub use context::{Binding, PassContext, SamplerKind};
pub(crate) use context::{Resolved, ResolvedBuffer, ResolvedImage};
pub use decl::{BufferHandle, ImageHandle};
pub(crate) use execute::{record_graph, RecordEnv};
pub use plan::{Barrier, BarrierResource, Plan, SlotDesc, Target};

/// A frame graph declared inconsistently. Each variant names the pass and
/// resource involved.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GraphError {
    /// A pass wrote an old version of a resource another pass already wrote.
    #[error("pass `{pass}` writes `{resource}` through a stale handle (version {version}; the latest is {latest}); use the handle the last writer returned")]
    StaleWrite {
        /// The pass.
        pass: String,
        /// The resource.
        resource: String,
        /// Version the pass used.
        version: u32,
        /// Latest version.
        latest: u32,
    },
    /// A transient resource was read before any pass wrote it.
    #[error("pass `{pass}` reads `{resource}` before any pass writes it")]
    ReadBeforeWrite {
        /// The pass.
        pass: String,
        /// The resource.
        resource: String,
    },
    /// An access that a pass of this kind cannot make.
    #[error("pass `{pass}` ({kind:?}) cannot use `{resource}` as {access}")]
    AccessNotAllowed {
        /// The pass.
        pass: String,
        /// Its kind.
        kind: PassKind,
        /// The resource.
        resource: String,
        /// The access, in words.
        access: String,
    },
    /// A pass named one resource twice (declare one combined access instead).
    #[error("pass `{pass}` declares `{resource}` more than once; declare one access (e.g. StorageReadWrite)")]
    DuplicateAccess {
        /// The pass.
        pass: String,
        /// The resource.
        resource: String,
    },
    /// Handles from another graph, or from before a reset.
    #[error("pass `{pass}` uses a handle that does not belong to this graph")]
    UnknownHandle {
        /// The pass.
        pass: String,
    },
    /// A dispatch bound a resource its shader cannot take there, or left a
    /// binding its shader uses unbound.
    #[error("pass `{pass}`: {message}")]
    Binding {
        /// The pass.
        pass: String,
        /// What is wrong.
        message: String,
    },
    /// Passes depend on each other in a circle (through stale handles).
    #[error("passes depend on each other in a cycle: {0:?}")]
    Cycle(Vec<String>),
    /// A raster pass without attachments, or with attachments of different sizes.
    #[error("raster pass `{pass}`: {message}")]
    Attachments {
        /// The pass.
        pass: String,
        /// What is wrong.
        message: String,
    },
}
