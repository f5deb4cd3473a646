//! One image per pose for the search: a photograph of linear radiance as
//! it is, and a pose's exposure brackets merged into one
//! ([`merged_brackets`]). A bulb is white in every bracket but the
//! shortest, where it may be the only thing recorded.

use std::borrow::Cow;

use crate::dataset::{Dataset, Frame};
use crate::train::pixels::{bracket_sets, is_bracket, merged_brackets};

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
