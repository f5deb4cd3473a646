//! The pixels a dataset offers for training: each usable pixel of the
//! training frames as a ray and what it says ([`PixelTarget`]), drawn at
//! random per batch; the hold-out frames kept apart.

use glam::DVec3;

use super::loss::PixelTarget;
use crate::dataset::pixels::{image_kind, ImageKind};
use crate::dataset::{Dataset, Frame, PixelState};
use crate::geometry::{Aabb, Ray};
use crate::rng::Pcg32;
use crate::sgfit::model::luminance;

/// One usable pixel: its frame (index into the dataset's frames) and pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelRef {
    /// Frame index in [`Dataset::frames`].
    pub frame: u32,
    /// Pixel index, row-major.
    pub pixel: u32,
}

/// sRGB encoding (the inverse of the loader's decoding).
fn encode(v: f32) -> f64 {
    crate::dataset::pixels::srgb_encode(v as f64)
}

/// Whether `frame` is a bracket: an LDR image with an exposure time.
pub fn is_bracket(frame: &Frame) -> bool {
    frame.exposure_time.is_some() && image_kind(&frame.image_path) == Some(ImageKind::Srgb)
}

/// The exposure `frame`'s values were recorded at: a bracket's exposure
/// time, 1 for any other frame (its values are radiance).
pub fn recorded_exposure(frame: &Frame) -> f64 {
    if is_bracket(frame) {
        frame.exposure_time.unwrap_or(1.0)
    } else {
        1.0
    }
}

/// The ray through pixel `pixel` of `frame` (through its centre), or None
/// where the lens model cannot be inverted.
pub fn pixel_ray(frame: &Frame, pixel: u32) -> Option<Ray> {
    pixel_ray_at(frame, pixel, (0.5, 0.5))
}

/// The ray through the point `offset` of pixel `pixel` of `frame`, in
/// pixels from its top-left corner (each in [0, 1]; (0.5, 0.5) its
/// centre), or None where the lens model cannot be inverted. A pixel of a
/// photograph (or of a Cycles or `render-views` image) records the light
/// over its whole area, not along the ray through its centre.
pub fn pixel_ray_at(frame: &Frame, pixel: u32, offset: (f64, f64)) -> Option<Ray> {
    let w = frame.intrinsics.width;
    let (u, v) = ((pixel % w) as f64 + offset.0, (pixel / w) as f64 + offset.1);
    let d = frame.intrinsics.direction(u, v)?;
    Some(Ray {
        origin: frame.pose.origin(),
        dir: frame.pose.to_world(d).normalize(),
    })
}

/// The n × n points, in pixels from a pixel's top-left corner, at the
/// centres of an even n × n split of the pixel: row by row (n = 1: its
/// centre).
pub fn area_offsets(n: u32) -> Vec<(f64, f64)> {
    let n = n.max(1);
    let at = |k: u32| (k as f64 + 0.5) / n as f64;
    (0..n * n).map(|i| (at(i % n), at(i / n))).collect()
}

/// How a training pixel's rays are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelRays {
    /// n: the pixel's n × n rays pass through the centres of an even split
    /// of its area ([`area_offsets`]; 1: its centre).
    pub area: u32,
    /// Each ray through a point drawn uniformly over its part of the
    /// pixel instead of its centre.
    pub jitter: bool,
}

/// What pixel `pixel` of `frame` says, with `shift` added behind it: a
/// transparent pixel (alpha a) read over one background and trained over
/// another says its radiance plus (1 − a)·`shift`, `shift` the second
/// background less the first. A bracket takes no shift (its recorded code
/// cannot be moved; the trainer refuses another background behind a
/// transparent one).
pub fn pixel_target(frame: &Frame, pixel: u32, shift: DVec3) -> Option<PixelTarget> {
    let i = pixel as usize;
    let c = frame.image.radiance[i];
    let value = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)
        + (1.0 - frame.image.alpha_at(i) as f64) * shift;
    match frame.image.state[i] {
        PixelState::Masked => None,
        _ if is_bracket(frame) => Some(PixelTarget::Bracket {
            encoded: DVec3::new(encode(c[0]), encode(c[1]), encode(c[2])),
            exposure: recorded_exposure(frame),
        }),
        PixelState::LowerBound => Some(PixelTarget::AtLeast(value)),
        PixelState::Value => Some(PixelTarget::Value(value)),
    }
}

/// The frames each frame's pixels merge with to read the scene's
/// radiance: for a bracket, every bracket of the same pose (to the bit)
/// and image size among `frames` (itself included), the longest exposure
/// first; for any other frame, itself alone. Frames outside `frames`
/// (held out) stand alone and merge with none.
pub fn bracket_sets(dataset: &Dataset, frames: &[u32]) -> Vec<Vec<u32>> {
    type Key = ([u64; 16], u32, u32);
    let key = |f: &Frame| -> Key {
        (
            f.pose.matrix.to_cols_array().map(f64::to_bits),
            f.image.width,
            f.image.height,
        )
    };
    let exposure = |i: &u32| recorded_exposure(&dataset.frames[*i as usize]);
    let mut groups: std::collections::HashMap<Key, Vec<u32>> = Default::default();
    for &i in frames {
        let f = &dataset.frames[i as usize];
        if is_bracket(f) {
            groups.entry(key(f)).or_default().push(i);
        }
    }
    for g in groups.values_mut() {
        g.sort_by(|a, b| exposure(b).total_cmp(&exposure(a)));
    }
    (0..dataset.frames.len() as u32)
        .map(|i| {
            let f = &dataset.frames[i as usize];
            match groups.get(&key(f)) {
                Some(g) if is_bracket(f) && g.contains(&i) => g.clone(),
                _ => vec![i],
            }
        })
        .collect()
}

/// The frame of `set` ([`bracket_sets`]) whose reading of `pixel` tells
/// its radiance best: the longest exposure that recorded a value there
/// (the least noisy), else the shortest that saw it at all (where every
/// bracket saturated, a lower bound). None where every frame masks it.
pub fn recording<'a>(dataset: &'a Dataset, set: &[u32], pixel: u32) -> Option<&'a Frame> {
    let i = pixel as usize;
    let frames = || set.iter().map(|&f| &dataset.frames[f as usize]);
    frames()
        .find(|f| f.image.state[i] == PixelState::Value)
        .or_else(|| {
            frames()
                .rev()
                .find(|f| f.image.state[i] != PixelState::Masked)
        })
}

/// The scene's luminance at `pixel` as the frames `set` ([`bracket_sets`])
/// record it: a frame that is not a bracket, its value; brackets, the
/// longest exposure that did not saturate there over its exposure (the
/// least noisy reading), or where all saturated the shortest's, a lower
/// bound ([`recording`]). None where every frame masks the pixel.
pub fn merged_luminance(dataset: &Dataset, set: &[u32], pixel: u32) -> Option<f64> {
    let f = recording(dataset, set, pixel)?;
    let c = f.image.radiance[pixel as usize];
    Some(luminance(DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)) / recorded_exposure(f))
}

/// The frame a pose's brackets `set` (longest exposure first,
/// [`bracket_sets`]) record together, in radiance, not a bracket itself:
/// each pixel [`recording`]'s reading over its exposure, as
/// [`merged_luminance`] reads it.
pub fn merged_brackets(dataset: &Dataset, set: &[u32]) -> Frame {
    let mut out = dataset.frames[set[0] as usize].clone();
    out.exposure_time = None;
    out.exif_exposure = None;
    for i in 0..out.image.state.len() {
        let (state, radiance) = match recording(dataset, set, i as u32) {
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

/// What a dataset's brackets cannot tell: pixels that every bracket of
/// their pose recorded white (in some channel), where the photographs say
/// only that the radiance is at least white over the shortest exposure.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SaturatedInEveryBracket {
    /// Such pixels, counted once per pose.
    pub pixels: usize,
    /// The poses with at least one.
    pub poses: usize,
    /// The poses taken as brackets.
    pub bracketed_poses: usize,
    /// The shortest exposure among the poses with such pixels.
    pub shortest: f64,
}

impl SaturatedInEveryBracket {
    /// What to tell the user, where there are such pixels.
    pub fn warning(&self) -> Option<String> {
        (self.pixels > 0).then(|| {
            format!(
                "{} pixels of {} of its {} bracketed poses are white in every bracket (the \
                 shortest exposure there {:.4}): the photographs say only that their radiance is \
                 at least {:.1} there, so a light there is as bright as the rest of the loss \
                 makes it; a shorter bracket would record it",
                self.pixels,
                self.poses,
                self.bracketed_poses,
                self.shortest,
                1.0 / self.shortest
            )
        })
    }
}

/// The pixels of `dataset` that every bracket of their pose
/// ([`bracket_sets`], over every frame) recorded white, where it saw them
/// at all.
pub fn saturated_in_every_bracket(dataset: &Dataset) -> SaturatedInEveryBracket {
    let frames: Vec<u32> = (0..dataset.frames.len() as u32).collect();
    let sets = bracket_sets(dataset, &frames);
    let mut out = SaturatedInEveryBracket {
        shortest: f64::INFINITY,
        ..Default::default()
    };
    for &f in &frames {
        let set = &sets[f as usize];
        // Each pose once: at its longest exposure's frame.
        if set[0] != f || !is_bracket(&dataset.frames[f as usize]) {
            continue;
        }
        out.bracketed_poses += 1;
        let members: Vec<&Frame> = set.iter().map(|&i| &dataset.frames[i as usize]).collect();
        let pixels = members[0].image.state.len();
        let white = (0..pixels)
            .filter(|&p| {
                let mut seen = members
                    .iter()
                    .filter(|m| m.image.state[p] != PixelState::Masked)
                    .peekable();
                seen.peek().is_some() && seen.all(|m| m.image.state[p] == PixelState::LowerBound)
            })
            .count();
        if white > 0 {
            out.pixels += white;
            out.poses += 1;
            let last = members.last().expect("a pose has its own frame");
            out.shortest = out.shortest.min(recorded_exposure(last));
        }
    }
    if out.poses == 0 {
        out.shortest = 0.0;
    }
    out
}

/// The frames of `frames` that `hold_out` asks to hold out, spread evenly
/// over the list: never all of them (one always trains).
pub fn held_out_frames(frames: u32, hold_out: u32) -> Vec<u32> {
    let k = hold_out.min(frames.saturating_sub(1));
    (0..k).map(|i| (2 * i + 1) * frames / (2 * k)).collect()
}

/// The poses of `dataset`, each its frames ([`bracket_sets`]: a pose's
/// brackets, the longest exposure first; any other frame alone), in the
/// order of their first frames.
pub fn poses(dataset: &Dataset) -> Vec<Vec<u32>> {
    let all: Vec<u32> = (0..dataset.frames.len() as u32).collect();
    let sets = bracket_sets(dataset, &all);
    all.iter()
        .filter(|&&f| sets[f as usize].iter().min() == Some(&f))
        .map(|&f| sets[f as usize].clone())
        .collect()
}

/// The frames of `dataset` held out for `hold_out` poses spread evenly
/// over its [`poses`] ([`held_out_frames`] over them; never all): a pose's
/// exposure brackets together, since one bracket held out alone would be
/// scored against a pose its other brackets trained on. Where no frame is
/// a bracket, the same frames as [`held_out_frames`]. Sorted.
pub fn held_out_poses(dataset: &Dataset, hold_out: u32) -> Vec<u32> {
    let poses = poses(dataset);
    let mut out: Vec<u32> = held_out_frames(poses.len() as u32, hold_out)
        .into_iter()
        .flat_map(|k| poses[k as usize].iter().copied())
        .collect();
    out.sort_unstable();
    out
}

/// The frames of `dataset` that train when `hold_out` poses are held out
/// ([`held_out_poses`]): every choice a run makes from its photographs
/// reads these alone, so that a held-out view never shapes the field it
/// scores. Sorted.
pub fn training_frames(dataset: &Dataset, hold_out: u32) -> Vec<u32> {
    let held = held_out_poses(dataset, hold_out);
    (0..dataset.frames.len() as u32)
        .filter(|f| held.binary_search(f).is_err())
        .collect()
}

/// How wide a pixel of `dataset`'s frames `frames` is at the centre of
/// `bounds`, in node spacings of a grid of `nodes` along the bounds'
/// longest axis: the median over the frames of the camera's distance to
/// the centre over its focal length in pixels (0 where no frame). A pixel
/// wider than a few spacings averages detail the grid holds, and one ray
/// through its centre asks a point for that average
/// ([`super::knobs::TrainKnobs::auto_area_rays`]).
pub fn pixel_footprint(dataset: &Dataset, frames: &[u32], bounds: &Aabb, nodes: u32) -> f64 {
    let spacing = bounds.size().max_element() / (nodes.max(2) - 1) as f64;
    let mut widths: Vec<f64> = frames
        .iter()
        .map(|&f| {
            let frame = &dataset.frames[f as usize];
            let focal = 0.5 * (frame.intrinsics.fx + frame.intrinsics.fy);
            (frame.pose.origin() - bounds.center()).length() / focal / spacing
        })
        .filter(|w| w.is_finite())
        .collect();
    if widths.is_empty() {
        return 0.0;
    }
    widths.sort_by(f64::total_cmp);
    widths[widths.len() / 2]
}

/// The training pixels: every usable pixel of the frames not held out.
#[derive(Debug, Clone)]
pub struct PixelPool {
    /// The usable pixels.
    pub pixels: Vec<PixelRef>,
    /// The frames held out (indices into the dataset's frames; every
    /// bracket of a held-out pose).
    pub held_out: Vec<u32>,
}

impl PixelPool {
    /// The pool of `dataset`, holding out `hold_out` poses spread evenly
    /// over its poses (never all of them), each with all its brackets
    /// ([`held_out_poses`]).
    pub fn new(dataset: &Dataset, hold_out: u32) -> Self {
        let held_out = held_out_poses(dataset, hold_out);
        let mut pixels = Vec::new();
        for (f, frame) in dataset.frames.iter().enumerate() {
            if held_out.contains(&(f as u32)) {
                continue;
            }
            for (p, s) in frame.image.state.iter().enumerate() {
                if *s != PixelState::Masked {
                    pixels.push(PixelRef {
                        frame: f as u32,
                        pixel: p as u32,
                    });
                }
            }
        }
        Self { pixels, held_out }
    }

    /// `count` pixels drawn at random (with replacement) for step `step`:
    /// each one's rays drawn as `rays` says (n × n through the centres of
    /// an even split of its area: [`area_offsets`]), what it
    /// says (with `shift` behind its transparent part: [`pixel_target`]),
    /// its frame, and the length along each ray to the surface the
    /// frame's depth map records at the pixel (`depth`'s map for the frame
    /// where it is given and not empty, else the frame's own; None where
    /// it records none: [`super::depth::ray_depth`]), in the order of their frames and pixels
    /// (neighbouring rays of a view then march side by side on the device,
    /// over the same nodes and about as far). A pixel whose rays the lens model
    /// cannot all invert is not drawn.
    #[allow(clippy::too_many_arguments)]
    pub fn batch(
        &self,
        dataset: &Dataset,
        depth: &[Vec<f32>],
        count: usize,
        seed: u64,
        step: u64,
        shift: DVec3,
        rays: PixelRays,
    ) -> Vec<BatchPixel> {
        let (area, jitter) = (rays.area.max(1), rays.jitter);
        let centres = area_offsets(area);
        let mut rng = Pcg32::new(seed, 0x7EA1_0000_0000 ^ step);
        let mut out = Vec::with_capacity(count);
        let mut tries = 0;
        while out.len() < count && tries < 4 * count && !self.pixels.is_empty() {
            tries += 1;
            let r = self.pixels[rng.next_u32() as usize % self.pixels.len()];
            let frame = &dataset.frames[r.frame as usize];
            let rays: Option<Vec<Ray>> = centres
                .iter()
                .map(|&(u, v)| {
                    let offset = if jitter {
                        let half = 0.5 / area as f64;
                        (
                            u + half * (2.0 * rng.next_f64() - 1.0),
                            v + half * (2.0 * rng.next_f64() - 1.0),
                        )
                    } else {
                        (u, v)
                    };
                    pixel_ray_at(frame, r.pixel, offset)
                })
                .collect();
            if let (Some(rays), Some(t)) = (rays, pixel_target(frame, r.pixel, shift)) {
                out.push((r, rays, t));
            }
        }
        out.sort_by_key(|(r, _, _)| (r.frame, r.pixel));
        out.into_iter()
            .map(|(r, rays, t)| {
                let frame = &dataset.frames[r.frame as usize];
                let map = match depth.get(r.frame as usize) {
                    Some(d) if !d.is_empty() => d,
                    _ => &frame.depth,
                };
                let z = map.get(r.pixel as usize).copied();
                let forward = frame.pose.forward();
                let depths = rays
                    .iter()
                    .map(|ray| z.and_then(|z| super::depth::ray_depth(z, ray.dir, forward)))
                    .collect();
                (rays, t, r.frame, depths)
            })
            .collect()
    }
}

/// A pixel of a batch ([`PixelPool::batch`]): its rays, what it says, its
/// frame, and each ray's length to the surface its depth map records.
pub type BatchPixel = (Vec<Ray>, PixelTarget, u32, Vec<Option<f64>>);

#[cfg(test)]
mod tests {
    use super::{held_out_frames, pixel_footprint};
    use crate::dataset::pixels::{FrameImage, PixelCounts};
    use crate::dataset::{BoundsSource, Dataset, Dialect, Frame, Intrinsics, Pose};
    use crate::geometry::Aabb;
    use crate::train::TrainKnobs;
    use glam::DVec3;

    /// A pixel 5 units from a box of side 2, 60° over 16 pixels, spans
    /// 5 / 13.86 of a unit: 1.44 spacings of a 9-node grid, 2.89 of a
    /// 17-node one; only the wide pixel takes area rays by default, and
    /// only behind a fixed background.
    #[test]
    fn a_pixel_wider_than_the_nodes_takes_area_rays_behind_a_fixed_background() {
        let frame = Frame {
            index: 0,
            image_path: "view.exr".into(),
            pose: Pose::looking_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y),
            intrinsics: Intrinsics::centred(16, 16, 60.0),
            exposure_time: None,
            exif_exposure: None,
            image: FrameImage {
                width: 16,
                height: 16,
                radiance: vec![[0.2; 3]; 256],
                state: vec![crate::dataset::PixelState::Value; 256],
                alpha: Vec::new(),
                counts: PixelCounts::default(),
            },
            depth: Vec::new(),
        };
        let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let d = Dataset {
            file: "shots/transforms.json".into(),
            dialect: Dialect::InstantNgp,
            frames: vec![frame],
            bounds,
            bounds_source: BoundsSource::AabbKey,
            counts: PixelCounts::default(),
            skipped: Vec::new(),
        };
        let focal = 8.0 / 30f64.to_radians().tan();
        let (coarse, fine) = (
            pixel_footprint(&d, &[0], &bounds, 9),
            pixel_footprint(&d, &[0], &bounds, 17),
        );
        assert!((coarse - 5.0 / focal / 0.25).abs() < 1e-9, "{coarse}");
        assert!((fine - 2.0 * coarse).abs() < 1e-9, "{fine}");
        assert_eq!(pixel_footprint(&d, &[], &bounds, 9), 0.0);
        let fixed = TrainKnobs::default();
        let random = TrainKnobs {
            random_background: true,
            ..fixed
        };
        assert_eq!(fixed.auto_area_rays(coarse), 1);
        assert_eq!(fixed.auto_area_rays(fine), 2);
        assert_eq!(random.auto_area_rays(fine), 1);
    }

    /// Held-out frames are spread evenly over the list, and one frame is
    /// always left to train.
    #[test]
    fn held_out_frames_spread_evenly_and_leave_one_to_train() {
        assert_eq!(held_out_frames(48, 4), vec![6, 18, 30, 42]);
        assert_eq!(held_out_frames(3, 5), vec![0, 2]);
        assert_eq!(held_out_frames(1, 2), Vec::<u32>::new());
        assert_eq!(held_out_frames(0, 2), Vec::<u32>::new());
        assert_eq!(held_out_frames(10, 0), Vec::<u32>::new());
    }
}
