//! Physical resources behind the graph's transient slots, kept across frames
//! (one pool per frame slot) and freed when a shape goes unused, e.g. after a
//! resize.

use std::collections::HashMap;
use std::sync::Arc;

use crate::context::Context;
use crate::error::Result;
use crate::graph::SlotDesc;
use crate::memory::{Buffer, BufferLocation, Image};

/// Frames a pooled resource may go unused before it is freed.
const KEEP_UNUSED_FRAMES: u64 = 3;

enum Pooled {
    Image(Arc<Image>),
    Buffer(Arc<Buffer>),
}

struct Entry {
    resource: Pooled,
    last_used: u64,
}

/// Transient images and buffers of one frame slot, by shape.
pub(crate) struct TransientPool {
    ctx: Arc<Context>,
    entries: HashMap<SlotDesc, Vec<Entry>>,
    created: u64,
}

/// A transient slot's physical resource for this frame.
pub(crate) enum SlotResource {
    Image(Arc<Image>),
    Buffer(Arc<Buffer>),
}

impl TransientPool {
    pub(crate) fn new(ctx: &Arc<Context>) -> Self {
        Self {
            ctx: ctx.clone(),
            entries: HashMap::new(),
            created: 0,
        }
    }

    /// Number of resources created since the pool was made (for tests of reuse).
    pub(crate) fn created(&self) -> u64 {
        self.created
    }

    /// Provides one resource per slot, reusing pooled ones of the same shape
    /// and freeing shapes unused for a few frames. Call only when the frame
    /// slot's previous work has completed.
    pub(crate) fn acquire(&mut self, slots: &[SlotDesc], frame: u64) -> Result<Vec<SlotResource>> {
        let mut taken: HashMap<SlotDesc, usize> = HashMap::new();
        let mut out = Vec::with_capacity(slots.len());
        for (i, desc) in slots.iter().enumerate() {
            let k = taken.entry(*desc).or_insert(0);
            let list = self.entries.entry(*desc).or_default();
            if *k == list.len() {
                let resource = match desc {
                    SlotDesc::Image(d, usage) => Pooled::Image(Arc::new(Image::new(
                        &self.ctx,
                        &format!("transient image slot {i}"),
                        *d,
                        *usage,
                    )?)),
                    SlotDesc::Buffer(size, usage) => Pooled::Buffer(Arc::new(Buffer::new(
                        &self.ctx,
                        &format!("transient buffer slot {i}"),
                        *size,
                        *usage,
                        BufferLocation::Gpu,
                    )?)),
                };
                self.created += 1;
                list.push(Entry {
                    resource,
                    last_used: frame,
                });
            }
            let entry = &mut list[*k];
            entry.last_used = frame;
            *k += 1;
            out.push(match &entry.resource {
                Pooled::Image(i) => SlotResource::Image(i.clone()),
                Pooled::Buffer(b) => SlotResource::Buffer(b.clone()),
            });
        }
        for list in self.entries.values_mut() {
            list.retain(|e| frame.saturating_sub(e.last_used) < KEEP_UNUSED_FRAMES);
        }
        self.entries.retain(|_, l| !l.is_empty());
        Ok(out)
    }
}
