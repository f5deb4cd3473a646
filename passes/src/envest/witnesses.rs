//! Which surface points a field's photographs saw.
//!
//! A trained field is right only where its photographs looked. The
//! estimate's views come from all around the field (the paper's sphere),
//! and from below DOG's floor they see its underside, which no photograph
//! did: the trainer gave it the colour of the lit top, which the fit can
//! only read as light from below (on DOG trained at 128 nodes from 64
//! views, a tenth of the points, their radiance ~400× the bake's; leaving
//! them out did not move DOG's error beyond its seeds' spread, the rest
//! outweighing them: `docs/fidelity.md`, "Thirteenth pass"). With
//! witnesses, a surface point is kept only when some photograph saw it:
//! the point faces the camera, lies inside its view, and the field between
//! them is under half opaque (marched from [`START_OFFSET`] node spacings
//! off the surface, out of its own shell).
//!
//! A witness may carry its photograph's pixels ([`Photo`]); the estimate
//! then reads each point's radiance from the photographs that saw it
//! (`inlay estimate-env --radiance-from-photos`), not from the field. A
//! trained field's colour is a fit to those photographs and carries the
//! fit's errors: DOG's floor, trained at 128 nodes, is 1.11× the bake's
//! radiance at the median (1.02–1.30× from the tenth to the ninetieth
//! percentile), its photographs 1.00× (0.98–1.01×)
//! (`docs/fidelity.md`, "Fourteenth pass").
//!
//! With their pixels the photographs also say whether a point is on a
//! surface at all ([`Witnesses::photo_spread`], [`PhotoSpread`]): a Lambertian surface
//! point reads the same in every photograph that saw it, while a point a
//! trainer left in haze in front of the surface projects onto different
//! parts of the surface in each, and on a textured surface the readings
//! disagree. This test does not rest on the density's scale, which
//! another trainer moves.

use glam::{DMat3, DVec3};

use super::surface::is_mixed;
use crate::camera::CameraSpec;
use crate::dataset::{Frame, FrameImage, Intrinsics, PixelState, Pose};
use crate::field::GridField;
use crate::geometry::Ray;
use crate::march::{march_ray, MarchKnobs};
use crate::sgfit::model::luminance;

/// How far along its normal, in node spacings, the march toward a camera
/// starts from a surface point (a trained surface's density is a shell a
/// couple of nodes deep; the point sits inside it).
pub const START_OFFSET: f64 = 2.0;

/// Opacity between a point and a camera under which the camera saw it.
pub const MAX_OCCLUSION: f64 = 0.5;

/// Fewest photographs' readings from which [`Witnesses::photo_spread`]
/// judges a point: from fewer, nothing says where along the rays the
/// surface lies.
pub const MIN_PHOTO_READINGS: usize = 3;

/// A photograph's pixels as radiance.
#[derive(Debug, Clone, PartialEq)]
pub struct Photo {
    /// The pixels as the dataset loader read them (linear).
    pub image: FrameImage,
    /// What a pixel's value is multiplied by to give radiance: 1 for
    /// linear HDR images and LDR images of unknown exposure (as the
    /// trainer reads them), 1/t for a bracket taken with exposure t.
    pub scale: f64,
}

impl Photo {
    /// The radiance at image position (u, v) in pixels (pixel centres at
    /// +0.5), bilinear over the four nearest pixels; None unless all four
    /// are measured values (not saturated, not masked).
    pub fn radiance_at(&self, u: f64, v: f64) -> Option<DVec3> {
        let (w, h) = (self.image.width as usize, self.image.height as usize);
        let x = (u - 0.5).clamp(0.0, (w - 1) as f64);
        let y = (v - 0.5).clamp(0.0, (h - 1) as f64);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let mut sum = DVec3::ZERO;
        for (i, weight) in [
            (y0 * w + x0, (1.0 - fx) * (1.0 - fy)),
            (y0 * w + x1, fx * (1.0 - fy)),
            (y1 * w + x0, (1.0 - fx) * fy),
            (y1 * w + x1, fx * fy),
        ] {
            if self.image.state[i] != PixelState::Value {
                return None;
            }
            let c = self.image.radiance[i];
            sum += weight * DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64);
        }
        Some(self.scale * sum)
    }
}

/// One photograph's camera: where it was and what it took in, and, where
/// loaded, its pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct Witness {
    /// Where the camera was.
    pub pose: Pose,
    /// Its lens and image size.
    pub intrinsics: Intrinsics,
    /// Its pixels, when the estimate reads radiance from them.
    pub photo: Option<Photo>,
}

impl Witness {
    /// The pinhole camera `spec` whose image is `width` × `height`, its
    /// pixels not known.
    pub fn new(spec: &CameraSpec, width: u32, height: u32) -> Self {
        Self {
            pose: Pose::looking_at(spec.position, spec.look_at, spec.up),
            intrinsics: Intrinsics::centred(width, height, spec.fov_y),
            photo: None,
        }
    }

    /// The camera of a dataset's `frame`, with its pixels: a bracket's
    /// values divided by its exposure time.
    pub fn photographed(frame: Frame) -> Self {
        let bracket = crate::train::pixels::is_bracket(&frame);
        let scale = match frame.exposure_time {
            Some(t) if bracket && t > 0.0 => 1.0 / t,
            _ => 1.0,
        };
        Self {
            pose: frame.pose,
            intrinsics: frame.intrinsics,
            photo: Some(Photo {
                image: frame.image,
                scale,
            }),
        }
    }

    /// Where `x` lands in the image, in pixels; None behind the camera or
    /// outside the image.
    pub fn project(&self, x: DVec3) -> Option<(f64, f64)> {
        let to_local = DMat3::from_mat4(self.pose.matrix).transpose();
        let (u, v) = self
            .intrinsics
            .project(to_local * (x - self.pose.origin()))?;
        let (w, h) = (self.intrinsics.width as f64, self.intrinsics.height as f64);
        ((0.0..=w).contains(&u) && (0.0..=h).contains(&v)).then_some((u, v))
    }

    /// Whether `x` lies inside the camera's view.
    pub fn frames(&self, x: DVec3) -> bool {
        self.project(x).is_some()
    }

    /// Where in the image the camera saw the surface point `x` of `field`
    /// whose normal is `normal` (facing it, inside its view, the field
    /// between, marched with `knobs`, under [`MAX_OCCLUSION`] opaque);
    /// None where it did not.
    pub fn saw(
        &self,
        field: &GridField,
        knobs: &MarchKnobs,
        x: DVec3,
        normal: DVec3,
    ) -> Option<(f64, f64)> {
        let start = x + START_OFFSET * field.spacing().min_element() * normal;
        let to_camera = self.pose.origin() - start;
        if normal.dot(to_camera) <= 0.0 {
            return None;
        }
        let uv = self.project(x)?;
        let distance = to_camera.length();
        let ray = Ray {
            origin: start,
            dir: to_camera / distance,
        };
        (march_ray(field, &ray, distance, knobs).opacity < MAX_OCCLUSION).then_some(uv)
    }
}

/// The cameras a field was made from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Witnesses {
    /// Every camera.
    pub cameras: Vec<Witness>,
}

impl Witnesses {
    /// Whether some camera saw the surface point `x` of `field` whose
    /// normal is `normal` ([`Witness::saw`]).
    pub fn saw(&self, field: &GridField, knobs: &MarchKnobs, x: DVec3, normal: DVec3) -> bool {
        self.cameras
            .iter()
            .any(|c| c.saw(field, knobs, x, normal).is_some())
    }

    /// Whether the cameras carry their photographs' pixels.
    pub fn have_photos(&self) -> bool {
        self.cameras.iter().any(|c| c.photo.is_some())
    }

    /// The radiance the photographs that saw the surface point `x` (normal
    /// `normal`) recorded there: of their readings ([`Photo::radiance_at`]),
    /// those not mixed (within [`super::surface::MAX_MIXED_DIFFERENCE`] of the field's
    /// own colour at `x` seen from that camera, as a view's pixel must be:
    /// a pixel that straddles an edge reads the surface behind), the one
    /// of median luminance. None where no photograph saw it, or none gave
    /// a clean reading.
    pub fn photographed_radiance(
        &self,
        field: &GridField,
        knobs: &MarchKnobs,
        x: DVec3,
        normal: DVec3,
    ) -> Option<DVec3> {
        let mut readings: Vec<DVec3> = self
            .cameras
            .iter()
            .filter_map(|c| {
                let photo = c.photo.as_ref()?;
                let (u, v) = c.saw(field, knobs, x, normal)?;
                let r = photo.radiance_at(u, v)?;
                let dir = (x - c.pose.origin()).normalize();
                (!is_mixed(field, x, dir, r)).then_some(r)
            })
            .collect();
        if readings.is_empty() {
            return None;
        }
        let mid = readings.len() / 2;
        readings.select_nth_unstable_by(mid, |a, b| luminance(*a).total_cmp(&luminance(*b)));
        Some(readings[mid])
    }

    /// How much the photographs that saw the surface point `x` (normal
    /// `normal`) disagree there ([`PhotoSpread`]). None from fewer than
    /// [`MIN_PHOTO_READINGS`] readings.
    pub fn photo_spread(
        &self,
        field: &GridField,
        knobs: &MarchKnobs,
        x: DVec3,
        normal: DVec3,
    ) -> Option<PhotoSpread> {
        let mut lum: Vec<f64> = self
            .cameras
            .iter()
            .filter_map(|c| {
                let (u, v) = c.saw(field, knobs, x, normal)?;
                c.photo.as_ref()?.radiance_at(u, v).map(luminance)
            })
            .collect();
        if lum.len() < MIN_PHOTO_READINGS {
            return None;
        }
        lum.sort_by(f64::total_cmp);
        let quantile = |q: f64| {
            let at = q * (lum.len() - 1) as f64;
            let (i, f) = (at.floor() as usize, at.fract());
            lum[i] + f * (lum[(i + 1).min(lum.len() - 1)] - lum[i])
        };
        Some(PhotoSpread {
            readings: lum.len(),
            iqr: quantile(0.75) - quantile(0.25),
            median: quantile(0.5),
        })
    }
}

/// The photographs' readings of one point's luminance: how many, and how
/// far apart the middle half of them lie (quantiles interpolated
/// linearly). A quarter of the readings on either side may straddle an
/// edge or a highlight without moving it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhotoSpread {
    /// Readings taken.
    pub readings: usize,
    /// Their interquartile range.
    pub iqr: f64,
    /// Their median.
    pub median: f64,
}

impl PhotoSpread {
    /// The interquartile range over the median plus `floor`: relative
    /// where the point is bright, but not blown up by the noise of a dark
    /// point's readings (on DOG's bake, photographed path traced at 64
    /// samples, a purely relative spread over 0.2 refused 58 % of the
    /// points darker than a quarter of the median point and none of
    /// those brighter than it).
    pub fn relative(&self, floor: f64) -> f64 {
        let scale = self.median + floor;
        if scale > 0.0 {
            self.iqr / scale
        } else {
            0.0
        }
    }
}

/// The floor under a point's median reading in [`PhotoSpread::relative`],
/// as a share of the median luminance of the view's covered pixels: a
/// quarter keeps 95 % of DOG's baked points (92 % of the dark ones) and
/// 89 % of ROOM's trained points off its surfaces still out
/// (`docs/fidelity.md`, "Thirty-first pass").
pub const PHOTO_SPREAD_FLOOR: f64 = 0.25;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use glam::UVec3;

    /// A floor slab at y ≈ 0 under a camera high above; a wall on one side.
    fn floor_and_wall() -> GridField {
        let res = UVec3::new(21, 21, 21);
        let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let h = 0.1;
        let nodes = (0..res.x * res.y * res.z)
            .map(|n| {
                let (i, j) = (n % res.x, (n / res.x) % res.y);
                let (x, y) = (-1.0 + h * i as f64, -1.0 + h * j as f64);
                let floor = y.abs() < 0.05;
                // A wall at x = 0.5 from the floor up, between the
                // camera at x = 3 and the floor's left half.
                let wall = (x - 0.5).abs() < 0.05 && y > 0.0;
                let sigma = if floor || wall { 200.0 } else { 0.0 };
                [0.5, 0.5, 0.5, sigma]
            })
            .collect();
        GridField::new(res, bounds, nodes, 4)
    }

    fn camera(position: DVec3, look_at: DVec3) -> Witness {
        Witness::new(
            &CameraSpec {
                name: None,
                position,
                look_at,
                up: DVec3::Y,
                fov_y: 60.0,
            },
            3,
            2,
        )
    }

    /// The floor's top is seen from above, its underside is not; a point
    /// behind the wall is not, nor one out of the camera's view.
    #[test]
    fn a_point_counts_as_seen_only_facing_a_camera_with_nothing_between() {
        let field = floor_and_wall();
        let knobs = MarchKnobs::default();
        let above = Witnesses {
            cameras: vec![camera(DVec3::new(0.0, 3.0, 0.1), DVec3::ZERO)],
        };
        let top = DVec3::new(0.2, 0.05, 0.0);
        assert!(above.saw(&field, &knobs, top, DVec3::Y));
        assert!(!above.saw(&field, &knobs, DVec3::new(0.2, -0.05, 0.0), -DVec3::Y));
        // From the right, low: the wall hides the floor's left half.
        let right = Witnesses {
            cameras: vec![camera(DVec3::new(3.0, 0.6, 0.0), DVec3::ZERO)],
        };
        assert!(right.saw(&field, &knobs, DVec3::new(0.8, 0.05, 0.0), DVec3::Y));
        assert!(!right.saw(&field, &knobs, DVec3::new(-0.3, 0.05, 0.0), DVec3::Y));
        // Looking away from the point.
        let away = Witnesses {
            cameras: vec![camera(DVec3::new(0.0, 3.0, 0.0), DVec3::new(0.0, 6.0, 0.5))],
        };
        assert!(!away.saw(&field, &knobs, top, DVec3::Y));
        // Any one camera suffices.
        let both = Witnesses {
            cameras: [away.cameras.clone(), above.cameras.clone()].concat(),
        };
        assert!(both.saw(&field, &knobs, top, DVec3::Y));
        assert!(!Witnesses::default().saw(&field, &knobs, top, DVec3::Y));
    }

    /// A pinhole witness projects as the scene camera's frame does.
    #[test]
    fn a_scene_camera_projects_as_its_frame_does() {
        let spec = CameraSpec {
            name: None,
            position: DVec3::new(0.3, 2.0, 1.5),
            look_at: DVec3::new(-0.2, 0.0, 0.1),
            up: DVec3::Y,
            fov_y: 40.0,
        };
        let (w, h) = (64, 36);
        let frame = crate::camera::CameraFrame::new(&spec, w, h);
        let witness = Witness::new(&spec, w, h);
        for x in [
            DVec3::new(-0.2, 0.0, 0.1),
            DVec3::new(0.1, 0.2, -0.1),
            DVec3::new(-0.5, -0.1, 0.3),
        ] {
            let (a, b) = (frame.project(x).unwrap(), witness.project(x).unwrap());
            assert!(
                (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9,
                "{a:?} {b:?}"
            );
        }
        assert!(witness.project(DVec3::new(0.3, 4.0, 3.0)).is_none());
    }

    /// A photograph above the floor (whose colour is 0.5 grey) whose pixel
    /// (i, j) holds 0.25 + (i + 10 j) / 1000 + `offset` in red and 0.25 in
    /// green and blue, taken with exposure 0.5 (its values read doubled).
    fn photo_above(offset: f64, saturated: Option<usize>) -> Witness {
        let (w, h) = (8u32, 8u32);
        let witness = Witness::new(
            &CameraSpec {
                name: None,
                position: DVec3::new(0.0, 3.0, 0.0),
                look_at: DVec3::ZERO,
                up: DVec3::Z,
                fov_y: 30.0,
            },
            w,
            h,
        );
        let radiance = (0..w * h)
            .map(|p| {
                let ramp = ((p % w) + 10 * (p / w)) as f64 / 1000.0;
                [(0.25 + ramp + offset) as f32, 0.25, 0.25]
            })
            .collect();
        let mut state = vec![PixelState::Value; (w * h) as usize];
        if let Some(i) = saturated {
            state[i] = PixelState::LowerBound;
        }
        with_photo(witness, radiance, state, 2.0)
    }

    /// `witness` holding the photograph `radiance` (its own size, row-major
    /// from the top), each pixel's `state`, its values read × `scale`.
    fn with_photo(
        mut witness: Witness,
        radiance: Vec<[f32; 3]>,
        state: Vec<PixelState>,
        scale: f64,
    ) -> Witness {
        witness.photo = Some(Photo {
            image: FrameImage {
                width: witness.intrinsics.width,
                height: witness.intrinsics.height,
                radiance,
                state,
                alpha: Vec::new(),
                counts: Default::default(),
            },
            scale,
        });
        witness
    }

    /// A point is read, bilinearly, where the photograph saw it; not where
    /// it did not, nor next to a saturated pixel, nor where the reading is
    /// over 2× from the field's colour; and of several photographs the
    /// median reading wins.
    #[test]
    fn a_point_s_radiance_is_read_from_the_photographs_that_saw_it() {
        let field = floor_and_wall();
        let knobs = MarchKnobs::default();
        let top = DVec3::new(0.05, 0.05, -0.02);
        let one = Witnesses {
            cameras: vec![photo_above(0.0, None)],
        };
        let (u, v) = one.cameras[0].project(top).unwrap();
        let expected = 2.0 * (0.25 + ((u - 0.5) + 10.0 * (v - 0.5)) / 1000.0);
        let read = one
            .photographed_radiance(&field, &knobs, top, DVec3::Y)
            .unwrap();
        assert!((read.x - expected).abs() < 1e-6, "{read} {expected}");
        assert!((read.y - 0.5).abs() < 1e-6);
        assert!(one
            .photographed_radiance(&field, &knobs, DVec3::new(0.05, -0.05, 0.0), -DVec3::Y)
            .is_none());
        let (i, j) = ((u - 0.5).floor() as usize, (v - 0.5).floor() as usize);
        let blind = Witnesses {
            cameras: vec![photo_above(0.0, Some(j * 8 + i + 1))],
        };
        assert!(blind
            .photographed_radiance(&field, &knobs, top, DVec3::Y)
            .is_none());
        assert!(blind.saw(&field, &knobs, top, DVec3::Y));
        let three = Witnesses {
            cameras: vec![
                photo_above(0.0, None),
                photo_above(0.1, None),
                photo_above(0.01, None),
            ],
        };
        let median = three
            .photographed_radiance(&field, &knobs, top, DVec3::Y)
            .unwrap();
        assert!((median.x - (expected + 0.02)).abs() < 1e-6, "{median}");
        // A reading 5× the field's colour straddles something else.
        let mixed = Witnesses {
            cameras: vec![photo_above(2.0, None)],
        };
        assert!(mixed.saw(&field, &knobs, top, DVec3::Y));
        assert!(mixed
            .photographed_radiance(&field, &knobs, top, DVec3::Y)
            .is_none());
        assert!(three.have_photos() && !Witnesses::default().have_photos());
    }

    /// A photograph from `position` of a checkered floor (squares of 0.2,
    /// radiance 0.2 and 0.6 in every channel) at y = 0.05, the top of
    /// [`floor_and_wall`]'s slab: each pixel's ray meets the plane and
    /// takes the colour there, black where it misses.
    fn photo_of_checkers(position: DVec3) -> Witness {
        let (w, h) = (96u32, 96u32);
        let spec = CameraSpec {
            name: None,
            position,
            look_at: DVec3::new(0.0, 0.05, 0.0),
            up: DVec3::Y,
            fov_y: 50.0,
        };
        let frame = crate::camera::CameraFrame::new(&spec, w, h);
        let radiance = (0..w * h)
            .map(|p| {
                let ray = frame.pixel_ray(p % w, p / w);
                let t = (0.05 - ray.origin.y) / ray.dir.y;
                let c = if t > 0.0 {
                    let hit = ray.at(t);
                    let odd = ((hit.x / 0.2).floor() + (hit.z / 0.2).floor()) as i64 % 2 != 0;
                    if odd {
                        0.6
                    } else {
                        0.2
                    }
                } else {
                    0.0
                };
                [c as f32; 3]
            })
            .collect();
        let witness = Witness::new(&spec, w, h);
        let state = vec![PixelState::Value; (w * h) as usize];
        with_photo(witness, radiance, state, 1.0)
    }

    /// Points on the checkered floor read the same in every photograph;
    /// points floating 0.3 above it, where a trainer's haze would put
    /// them, project onto different squares and disagree; and from fewer
    /// than three readings nothing is judged.
    #[test]
    fn photographs_agree_on_a_surface_and_not_in_front_of_it() {
        let field = floor_and_wall();
        let knobs = MarchKnobs::default();
        let cameras: Vec<Witness> = (0..8)
            .map(|k| {
                // On the wall's far side, so that it hides nothing.
                let a = 1.8 + k as f64 * 0.2;
                photo_of_checkers(DVec3::new(2.5 * a.cos(), 2.0, 2.5 * a.sin()))
            })
            .collect();
        let all = Witnesses {
            cameras: cameras.clone(),
        };
        let (mut on, mut off) = (Vec::new(), Vec::new());
        for i in 0..5 {
            for k in 0..5 {
                // Square centres, away from the squares' edges.
                let (x, z) = (-0.7 + 0.2 * i as f64, -0.5 + 0.2 * k as f64);
                let floor = DVec3::new(x, 0.05, z);
                let s = all.photo_spread(&field, &knobs, floor, DVec3::Y).unwrap();
                assert_eq!(s.readings, 8);
                on.push(s.relative(0.0));
                let s = all
                    .photo_spread(&field, &knobs, floor + 0.3 * DVec3::Y, DVec3::Y)
                    .unwrap();
                off.push(s.relative(0.0));
            }
        }
        assert!(on.iter().all(|&s| s < 1e-9), "{on:?}");
        let disagree = off.iter().filter(|&&s| s > 0.2).count();
        assert!(disagree >= 20, "{disagree} of 25: {off:?}");
        let two = Witnesses {
            cameras: cameras[..2].to_vec(),
        };
        let floor = DVec3::new(0.1, 0.05, 0.1);
        assert!(two.photo_spread(&field, &knobs, floor, DVec3::Y).is_none());
        assert!(Witnesses::default()
            .photo_spread(&field, &knobs, floor, DVec3::Y)
            .is_none());
        // A dark point's readings spread by their noise: relative to the
        // median alone a lot, under the floor little.
        let dark = PhotoSpread {
            readings: 8,
            iqr: 0.02,
            median: 0.05,
        };
        assert!((dark.relative(0.0) - 0.4).abs() < 1e-12);
        assert!((dark.relative(0.15) - 0.1).abs() < 1e-12);
        let black = PhotoSpread {
            readings: 3,
            iqr: 0.0,
            median: 0.0,
        };
        assert_eq!(black.relative(0.0), 0.0);
    }
}
