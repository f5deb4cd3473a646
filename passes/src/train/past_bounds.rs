//! Light the photographs show past the field's bounds: pixels whose ray
//! never enters the box. The field cannot hold it (only a learnt sky
//! behind it can), so it is left out of the knobs' scale
//! ([`super::trainer::radiance_scale`]) and reported where it is much of
//! the views' light. ROOM's Cycles set sees the ceiling bulb above the
//! bounds in some views: 119 of its 294 912 pixels held 87.5 % of the
//! views' light, and a scale read over them was 8 times the room's. Half
//! of those pixels look past the box; the rest see the bulb in front of
//! it, along rays that go on into the room, and still count: a mean
//! over the pixels left read 3 times the room's, so the scale leaves out
//! the few views that see the bulb, each far brighter than the median
//! view (`--scale` sets it outright).

use rayon::prelude::*;

use crate::dataset::{Dataset, Frame, PixelState};
use crate::geometry::{ray_box, Aabb};

use super::pixels::{bracket_sets, merged_luminance, pixel_ray};

/// The share of the views' light past the bounds from which
/// [`LightPastBounds::warning`] speaks.
pub const WARN_SHARE: f64 = 0.1;

/// The share of the views' light past the bounds from which `inlay
/// train` learns a sky behind the field unless told (`--sky auto`,
/// [`LightPastBounds::auto_sky`]). DOG's Cycles set, whose dim sky fills
/// three fifths of its pixels, holds 2.3 % there; its held-out views
/// read 30.7 and 29.8 dB with an [`AUTO_SKY_HEIGHT`] sky against 24.9 and
/// 28.3 without. The `render-views` sets, black past their bounds, hold
/// 0.2 % (the rims of pixels that graze the box) and lost 0.5–1.5 dB to
/// a 64 × 32 sky (`docs/benchmarks.md`, issue 25's twenty-second pass).
pub const AUTO_SKY_SHARE: f64 = 0.01;

/// The sky `--sky auto` learns: 2N × N texels, N this. On the Cycles sets
/// a coarser sky scored better than a finer one on every held-out view
/// that changed: at N = 32, 16 and 8, DOG read 29.1/27.9, 30.2/29.2 and
/// 30.7/29.8 dB, CUPS 26.3/26.7, 28.9/27.5 and 29.1/27.6, BOOKS
/// 35.8/32.6, 35.9/35.6 and 35.9/35.7 (ROOM within 0.2 dB). A texel of
/// a fine sky is reached by few training rays, and what the held-out
/// views see of it is off (`docs/benchmarks.md`, issue 25's
/// twenty-second pass). `--sky N` asks for a finer one where the
/// background has detail and the views to learn it.
pub const AUTO_SKY_HEIGHT: u32 = 8;

/// Whether pixel `pixel` of frame `f` of `dataset` looks into `bounds`
/// (its ray enters the box in front of the camera).
pub fn pixel_sees_bounds(dataset: &Dataset, f: u32, pixel: u32, bounds: &Aabb) -> bool {
    frame_sees_bounds(&dataset.frames[f as usize], pixel, bounds)
}

/// Whether pixel `pixel` of `frame` looks into `bounds`.
pub fn frame_sees_bounds(frame: &Frame, pixel: u32, bounds: &Aabb) -> bool {
    pixel_ray(frame, pixel)
        .and_then(|ray| ray_box(&ray, bounds))
        .is_some_and(|(_, t1)| t1 > 0.0)
}

/// The light of a dataset's pixels whose rays miss the field's bounds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LightPastBounds {
    /// Usable pixels (each pose once) whose ray misses the bounds.
    pub pixels: usize,
    /// Usable pixels in all (each pose once).
    pub of: usize,
    /// Their share of the views' light (luminance; 0 in a black set).
    pub share: f64,
    /// The brightest of them (luminance).
    pub brightest: f64,
}

impl LightPastBounds {
    /// The sky `--sky auto` learns behind the field: [`AUTO_SKY_HEIGHT`]
    /// where at least [`AUTO_SKY_SHARE`] of the views' light lies past the
    /// bounds, none otherwise (nor beside a random background, which says
    /// what is behind the field itself).
    pub fn auto_sky(&self, random_background: bool) -> u32 {
        if self.share >= AUTO_SKY_SHARE && !random_background {
            AUTO_SKY_HEIGHT
        } else {
            0
        }
    }

    /// What to tell the user, where the light past the bounds is at least
    /// [`WARN_SHARE`] of the views'.
    pub fn warning(&self) -> Option<String> {
        (self.share >= WARN_SHARE).then(|| {
            format!(
                "{:.0} % of the views' light lies past the field's bounds ({} of {} pixels, up to \
                 {:.3}): the field cannot hold it, and the knobs' scale counts it black; `inlay \
                 train` learns it as a sky behind the field (`--sky`). A light in view in front of \
                 the bounds raises the scale too: `--scale` sets it to the field's own level",
                100.0 * self.share,
                self.pixels,
                self.of,
                self.brightest
            )
        })
    }
}

/// The light of the usable pixels of `dataset`'s frames `frames` (each
/// pose's brackets among them merged, [`merged_luminance`]) whose rays
/// miss `bounds`: `inlay train` reads its training frames
/// ([`super::pixels::training_frames`]), `inlay dataset` every frame.
pub fn light_past_bounds(dataset: &Dataset, frames: &[u32], bounds: &Aabb) -> LightPastBounds {
    let sets = bracket_sets(dataset, frames);
    // Each pose once (at its longest exposure's frame), in parallel.
    let poses: Vec<PoseLight> = frames
        .par_iter()
        .filter(|&&f| sets[f as usize][0] == f)
        .map(|&f| pose_light(dataset, &sets[f as usize], bounds))
        .collect();
    let (mut past, mut all) = (0.0, 0.0);
    let mut out = LightPastBounds::default();
    for pose in poses {
        past += pose.past;
        all += pose.inside + pose.past;
        out.pixels += pose.pixels_past;
        out.of += pose.pixels;
        out.brightest = out.brightest.max(pose.brightest_past);
    }
    out.share = if all > 0.0 { past / all } else { 0.0 };
    out
}

/// One pose's light: its usable pixels' luminance (its brackets merged,
/// [`merged_luminance`]), summed apart for the pixels whose ray looks
/// into the bounds and for those whose ray misses them.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PoseLight {
    /// The light of the pixels that look into the bounds.
    pub inside: f64,
    /// The light of the pixels that look past them.
    pub past: f64,
    /// The usable pixels.
    pub pixels: usize,
    /// The usable pixels that look past the bounds.
    pub pixels_past: usize,
    /// The brightest pixel past the bounds (luminance; 0 if none).
    pub brightest_past: f64,
}

/// [`PoseLight`] of the pose whose frames are `set` (the longest exposure
/// first, [`bracket_sets`]), against `bounds`.
pub fn pose_light(dataset: &Dataset, set: &[u32], bounds: &Aabb) -> PoseLight {
    let f = set[0];
    let frame = &dataset.frames[f as usize];
    let mut out = PoseLight::default();
    for p in 0..frame.image.state.len() as u32 {
        if frame.image.state[p as usize] == PixelState::Masked {
            continue;
        }
        let Some(l) = merged_luminance(dataset, set, p) else {
            continue;
        };
        out.pixels += 1;
        if pixel_sees_bounds(dataset, f, p, bounds) {
            out.inside += l;
        } else {
            out.pixels_past += 1;
            out.past += l;
            out.brightest_past = out.brightest_past.max(l);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::dataset::pixels::{FrameImage, PixelCounts};
    use crate::dataset::{BoundsSource, Dialect, Frame, Intrinsics, Pose};
    use crate::train::trainer::radiance_scale;

    /// A 16 × 16 view from 5 units up +z of a box of side 2 at the origin,
    /// 60° across: its middle looks into the box, its rim past it. Grey
    /// 0.2 everywhere but a lamp of 1000 at pixel 0 (past the box).
    fn dataset() -> Dataset {
        let (w, h) = (16u32, 16u32);
        let mut radiance = vec![[0.2f32; 3]; (w * h) as usize];
        radiance[0] = [1000.0; 3];
        Dataset {
            file: "shots/transforms.json".into(),
            dialect: Dialect::InstantNgp,
            frames: vec![Frame {
                index: 0,
                image_path: "view.exr".into(),
                pose: Pose::looking_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y),
                intrinsics: Intrinsics::centred(w, h, 60.0),
                exposure_time: None,
                exif_exposure: None,
                image: FrameImage {
                    width: w,
                    height: h,
                    radiance,
                    state: vec![PixelState::Value; (w * h) as usize],
                    alpha: Vec::new(),
                    counts: PixelCounts::default(),
                },
                depth: Vec::new(),
            }],
            bounds: Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
            bounds_source: BoundsSource::AabbKey,
            counts: PixelCounts::default(),
            skipped: Vec::new(),
        }
    }

    /// The lamp past the box is most of the view's light and is reported;
    /// the knobs' scale reads the pixels past the box as black, so it is
    /// the grey's share of the view that looks into the box.
    #[test]
    fn light_past_the_bounds_is_reported_and_left_out_of_the_scale() {
        let d = dataset();
        let inside = (0..256u32)
            .filter(|&p| pixel_sees_bounds(&d, 0, p, &d.bounds))
            .count();
        assert!(inside > 16 && inside < 240, "{inside}");
        let past = light_past_bounds(&d, &[0], &d.bounds);
        assert_eq!((past.pixels, past.of), (256 - inside, 256));
        assert_eq!(past.brightest, 1000.0);
        let total = 1000.0 + 255.0 * 0.2;
        let expected = (1000.0 + (256 - inside - 1) as f64 * 0.2) / total;
        assert!((past.share - expected).abs() < 1e-4, "{past:?} {expected}");
        let w = past
            .warning()
            .expect("most of the light is past the bounds");
        assert!(
            w.contains(&format!("{} of 256 pixels", 256 - inside)),
            "{w}"
        );
        let scale = radiance_scale(&d, &[0], &d.bounds);
        let grey = 0.2 * inside as f64 / 256.0;
        assert!((scale / grey - 1.0).abs() < 1e-4, "{scale} {grey}");
        // Bounds that hold every pixel's ray: nothing past them, and the
        // scale is the plain mean.
        let wide = Aabb::new(DVec3::splat(-4.0), DVec3::splat(4.0));
        let none = light_past_bounds(&d, &[0], &wide);
        assert_eq!((none.pixels, none.share), (0, 0.0));
        assert_eq!(none.warning(), None);
        // A sky is learnt behind the first bounds, not the wide ones, nor
        // beside a random background.
        assert_eq!(past.auto_sky(false), AUTO_SKY_HEIGHT);
        assert_eq!(past.auto_sky(true), 0);
        assert_eq!(none.auto_sky(false), 0);
        let plain = radiance_scale(&d, &[0], &wide);
        assert!((plain / (total / 256.0) - 1.0).abs() < 1e-4, "{plain}");
    }

    /// Four views black past the bounds and one that sees the lamp there:
    /// held out, the lamp's view chooses no sky for the run that scores
    /// it; trained, it does.
    #[test]
    fn a_held_out_views_light_past_the_bounds_chooses_no_sky() {
        let lamp = dataset();
        let mut dark = lamp.frames[0].clone();
        for p in 0..256u32 {
            if !pixel_sees_bounds(&lamp, 0, p, &lamp.bounds) {
                dark.image.radiance[p as usize] = [0.0; 3];
            }
        }
        let mut d = Dataset {
            frames: vec![dark; 5],
            ..lamp.clone()
        };
        let held = crate::train::held_out_poses(&d, 1);
        assert_eq!(held.len(), 1);
        d.frames[held[0] as usize] = lamp.frames[0].clone();
        let training = crate::train::pixels::training_frames(&d, 1);
        assert_eq!(training.len(), 4);
        assert!(!training.contains(&held[0]));
        let trained = light_past_bounds(&d, &training, &d.bounds);
        assert_eq!((trained.share, trained.auto_sky(false)), (0.0, 0));
        let every = crate::train::pixels::training_frames(&d, 0);
        assert_eq!(every.len(), 5);
        let all = light_past_bounds(&d, &every, &d.bounds);
        assert!(all.share > 0.5, "{all:?}");
        assert_eq!(all.auto_sky(false), AUTO_SKY_HEIGHT);
    }
}
