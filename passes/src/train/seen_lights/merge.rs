//! One image per pose for the search: a photograph of linear radiance as
//! it is, and a pose's exposure brackets merged into one. A bulb is white
//! in every bracket but the shortest, where it may be the only thing
//! recorded; merged, each pixel is the longest exposure that did not
//! saturate there over that exposure (the least noisy reading, as
//! [`crate::train::pixels::merged_luminance`] reads it), and where every
//! bracket saturated, the shortest's reading over its exposure, a lower
//! bound.

use std::borrow::Cow;

use crate::dataset::{Dataset, Frame, PixelState};
use crate::train::pixels::{bracket_sets, is_bracket, recorded_exposure};

/// The frame a pose's brackets `set` (longest exposure first,
/// [`bracket_sets`]) record together, in radiance: not a bracket itself.
pub fn merged_brackets(dataset: &Dataset, set: &[u32]) -> Frame {
    let frames: Vec<&Frame> = set.iter().map(|&f| &dataset.frames[f as usize]).collect();
    let mut out = frames[0].clone();
    out.exposure_time = None;
    out.exif_exposure = None;
    for i in 0..out.image.state.len() {
        // The longest exposure that recorded a value, else the shortest
        // that saw the pixel at all.
        let pick = frames
            .iter()
            .find(|f| f.image.state[i] == PixelState::Value)
            .or_else(|| {
                frames
                    .iter()
                    .rev()
                    .find(|f| f.image.state[i] != PixelState::Masked)
            });
        let (state, radiance) = match pick {
            Some(f) => {
                let t = recorded_exposure(f) as f32;
                (f.image.state[i], f.image.radiance[i].map(|c| c / t))
            }
            None => (PixelState::Masked, [0.0; 3]),
        };
        out.image.state[i] = state;
        out.image.radiance[i] = radiance;
    }
    out
}

/// The frames of `frames` the search reads, one per pose: each photograph
/// of radiance as it is, each pose's brackets merged
/// ([`merged_brackets`]).
pub fn search_frames<'a>(dataset: &'a Dataset, frames: &[u32]) -> Vec<Cow<'a, Frame>> {
    let sets = bracket_sets(dataset, frames);
    frames
        .iter()
        .filter(|&&f| sets[f as usize][0] == f)
        .map(|&f| {
            let frame = &dataset.frames[f as usize];
            if is_bracket(frame) {
                Cow::Owned(merged_brackets(dataset, &sets[f as usize]))
            } else {
                Cow::Borrowed(frame)
            }
        })
        .collect()
}
