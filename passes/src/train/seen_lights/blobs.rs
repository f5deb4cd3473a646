//! Small bright spots of one photograph: 8-connected groups of pixels far
//! brighter than the views' mean, each a sighting of a light.

use glam::DVec3;

use crate::dataset::{Frame, PixelState};
use crate::sgfit::model::luminance;

/// A group larger than this share of its image is not a small light (a
/// window, a lit wall): it is left to the field and the sky.
pub const MAX_BLOB_SHARE: f64 = 0.01;

/// One bright spot of a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Blob {
    /// Its frame (index into the frames searched).
    pub frame: u32,
    /// Its pixels (row-major indices).
    pub pixels: Vec<u32>,
    /// Its luminance-weighted centre, in pixels from the image's top-left
    /// corner (a pixel's centre is at + 0.5).
    pub centre: (f64, f64),
    /// Its brightest pixel's luminance.
    pub peak: f64,
    /// Its pixels' bounding box: (x0, y0, x1, y1), inclusive.
    pub bbox: (u32, u32, u32, u32),
}

/// A pixel's radiance.
pub fn radiance_at(frame: &Frame, p: u32) -> DVec3 {
    let c = frame.image.radiance[p as usize];
    DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)
}

/// The bright spots of `frame` (frame index `f`): groups of 8-connected
/// pixels with luminance at least `threshold`, values or lower bounds (a
/// light's core that saturated every exposure is at least that bright),
/// not masked, at most [`MAX_BLOB_SHARE`] of the image each.
pub fn bright_blobs(frame: &Frame, f: u32, threshold: f64) -> Vec<Blob> {
    let (w, h) = (frame.image.width, frame.image.height);
    let bright = |p: u32| {
        frame.image.state[p as usize] != PixelState::Masked
            && luminance(radiance_at(frame, p)) >= threshold
    };
    let mut seen = vec![false; (w * h) as usize];
    let mut blobs = Vec::new();
    let largest = (MAX_BLOB_SHARE * (w * h) as f64).max(1.0) as usize;
    for start in 0..w * h {
        if seen[start as usize] || !bright(start) {
            continue;
        }
        seen[start as usize] = true;
        let mut stack = vec![start];
        let mut pixels = Vec::new();
        while let Some(p) = stack.pop() {
            pixels.push(p);
            let (x, y) = ((p % w) as i64, (p / w) as i64);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                        continue;
                    }
                    let q = (ny as u32) * w + nx as u32;
                    if !seen[q as usize] && bright(q) {
                        seen[q as usize] = true;
                        stack.push(q);
                    }
                }
            }
        }
        if pixels.len() > largest {
            continue;
        }
        pixels.sort_unstable();
        let (mut sx, mut sy, mut sl, mut peak) = (0.0, 0.0, 0.0, 0.0f64);
        let mut bbox = (u32::MAX, u32::MAX, 0, 0);
        for &p in &pixels {
            let l = luminance(radiance_at(frame, p));
            let (x, y) = (p % w, p / w);
            sx += l * (x as f64 + 0.5);
            sy += l * (y as f64 + 0.5);
            sl += l;
            peak = peak.max(l);
            bbox = (bbox.0.min(x), bbox.1.min(y), bbox.2.max(x), bbox.3.max(y));
        }
        blobs.push(Blob {
            frame: f,
            pixels,
            centre: (sx / sl, sy / sl),
            peak,
            bbox,
        });
    }
    blobs
}
