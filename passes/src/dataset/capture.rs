//! Training sets from the bundled recipes: cameras spread over a cap
//! around the field as a capture would be, and the `transforms.json`
//! (instant-ngp convention) and bracketed sRGB frames that describe them.

use glam::DVec3;
use serde_json::json;

use super::intrinsics::Intrinsics;
use super::pose::Pose;
use crate::bake::PathTracer;
use crate::camera::{CameraFrame, CameraSpec};
use crate::geometry::Aabb;
use crate::scene::Recipe;

/// Lowest camera elevation above the field's centre, degrees.
pub const CAP_LOWEST: f64 = 10.0;
/// Highest camera elevation, degrees.
pub const CAP_HIGHEST: f64 = 60.0;

/// Where a photographer can stand around a recipe: the azimuths of the
/// cap, in degrees from +x towards +z (a scene's `[capture] azimuth`).
/// A room's walls are photographed from inside; a capture from behind
/// them sees each wall's dark back and lit front at once, which a field
/// with one colour per node can only fake with haze (ROOM trained at the
/// trainer's defaults from the whole cap: an optical depth of 1.6 per
/// metre of its free space; from its open side, 0.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capture {
    /// The first azimuth, degrees.
    pub azimuth_from: f64,
    /// The last azimuth, degrees (more than `azimuth_from`, at most 360
    /// beyond it).
    pub azimuth_to: f64,
}

impl Capture {
    /// The whole cap around the field.
    pub const FULL: Capture = Capture {
        azimuth_from: 0.0,
        azimuth_to: 360.0,
    };

    /// Whether the arc goes all the way round.
    pub fn is_full(&self) -> bool {
        self.azimuth_to - self.azimuth_from >= 360.0
    }

    /// What is wrong with the arc, if anything.
    pub fn problem(&self) -> Option<String> {
        let (a, b) = (self.azimuth_from, self.azimuth_to);
        if !(a.is_finite() && b.is_finite()) {
            return Some(format!("[{a}, {b}] must be two finite angles in degrees"));
        }
        if b - a < MIN_CAPTURE_ARC || b - a > 360.0 {
            return Some(format!(
                "[{a}, {b}]: the second angle must exceed the first by {MIN_CAPTURE_ARC}° to 360°"
            ));
        }
        None
    }
}

impl Default for Capture {
    fn default() -> Self {
        Capture::FULL
    }
}

/// The narrowest arc of azimuths a capture may span, degrees: narrower,
/// the cameras barely triangulate across it.
pub const MIN_CAPTURE_ARC: f64 = 20.0;

/// `views` cameras looking at the field's centre from a cap between
/// [`CAP_LOWEST`] and [`CAP_HIGHEST`] degrees of elevation and over the
/// `capture`'s azimuths, spread evenly over its area (a Fibonacci spiral;
/// over part of the circle, a Fibonacci lattice of the same golden
/// ratio), far enough that the field's bounding sphere fills 1/1.1 of the
/// narrower field of view (`fov_y` degrees, for an image `aspect` = width
/// / height).
pub fn cap_cameras(
    bounds: &Aabb,
    views: u32,
    fov_y: f64,
    aspect: f64,
    capture: &Capture,
) -> Vec<CameraSpec> {
    let centre = bounds.center();
    let radius = 0.5 * bounds.diagonal();
    let half_y = 0.5 * fov_y.to_radians();
    let half = half_y.min((half_y.tan() * aspect).atan());
    let distance = 1.1 * radius / half.sin();
    let (s0, s1) = (
        CAP_LOWEST.to_radians().sin(),
        CAP_HIGHEST.to_radians().sin(),
    );
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..views)
        .map(|i| {
            let t = (i as f64 + 0.5) / views as f64;
            let elevation = (s0 + t * (s1 - s0)).asin();
            let azimuth = if capture.is_full() {
                i as f64 * golden
            } else {
                let span = capture.azimuth_to - capture.azimuth_from;
                let turn = (i as f64 * golden / std::f64::consts::TAU).fract();
                (capture.azimuth_from + turn * span).to_radians()
            };
            let dir = DVec3::new(
                elevation.cos() * azimuth.cos(),
                elevation.sin(),
                elevation.cos() * azimuth.sin(),
            );
            CameraSpec {
                name: Some(format!("view-{i:03}")),
                position: centre + distance * dir,
                look_at: centre,
                up: DVec3::Y,
                fov_y,
            }
        })
        .collect()
}

/// One frame of a written dataset.
#[derive(Debug, Clone, PartialEq)]
pub struct WrittenFrame {
    /// File name, relative to the transforms file.
    pub file: String,
    /// The camera.
    pub camera: CameraSpec,
    /// Exposure time (relative; radiance × exposure is what the sensor
    /// records, 1 at white), for bracketed frames.
    pub exposure_time: Option<f64>,
    /// Its depth map's file name, relative to the transforms file (a
    /// 16-bit PNG in units of [`super::depth::PNG_DEPTH_UNIT`]), where one
    /// is written.
    pub depth_file: Option<String>,
}

/// The `transforms.json` of `frames` of `width` × `height` pixels taken of
/// a field of `bounds`: instant-ngp's keys (`fl_x`, `fl_y`, `cx`, `cy`,
/// `w`, `h`; `aabb_scale`, `scale` and `offset` mapping the bounds' cube
/// onto its unit cube) and the bounds themselves as `aabb`. All frames
/// share `fov_y`.
pub fn transforms_json(
    frames: &[WrittenFrame],
    width: u32,
    height: u32,
    bounds: &Aabb,
) -> serde_json::Value {
    let fov_y = frames.first().map_or(50.0, |f| f.camera.fov_y);
    let f = Intrinsics::centred(width, height, fov_y).fy;
    let extent = bounds.size().max_element();
    let scale = 1.0 / extent;
    let c = bounds.center();
    // instant-ngp holds world (x, y, z) at its (z, x, y): its offset along
    // its axis k centres the world axis it holds.
    let offset = [0.5 - c.y * scale, 0.5 - c.z * scale, 0.5 - c.x * scale];
    let frames: Vec<serde_json::Value> = frames
        .iter()
        .map(|fr| {
            let pose = Pose::looking_at(fr.camera.position, fr.camera.look_at, fr.camera.up);
            let rows: Vec<Vec<f64>> = (0..4)
                .map(|r| pose.matrix.row(r).to_array().to_vec())
                .collect();
            let mut v = json!({ "file_path": fr.file, "transform_matrix": rows });
            if let Some(t) = fr.exposure_time {
                v["exposure_time"] = t.into();
            }
            if let Some(d) = &fr.depth_file {
                v["depth_file_path"] = d.as_str().into();
            }
            v
        })
        .collect();
    let mut doc = json!({
        "fl_x": f, "fl_y": f,
        "cx": 0.5 * width as f64, "cy": 0.5 * height as f64,
        "w": width, "h": height,
        "aabb": [bounds.min.to_array(), bounds.max.to_array()],
        "aabb_scale": 1, "scale": scale, "offset": offset,
        "frames": frames,
    });
    if frames_have_depth(&doc) {
        doc["depth_unit_scale_factor"] = super::depth::PNG_DEPTH_UNIT.into();
    }
    doc
}

/// Whether some frame of the transforms document `doc` names a depth map.
fn frames_have_depth(doc: &serde_json::Value) -> bool {
    doc["frames"]
        .as_array()
        .is_some_and(|f| f.iter().any(|v| v.get("depth_file_path").is_some()))
}

/// The z-depth of each pixel of `frame` (row-major) in `recipe`, as a
/// depth sensor records it: the recipe's expected depth along the pixel's
/// centre ray ([`crate::train::known_depth`], the media up to the first
/// opaque surface included) where that ray is at least half opaque, 0
/// (nothing recorded) elsewhere. `tracer` is made from `recipe` (only its
/// nearest surface is used).
pub fn recipe_depth_map(recipe: &Recipe, tracer: &PathTracer, frame: &CameraFrame) -> Vec<f32> {
    // Far enough for any surface a camera of a scene sees.
    const FAR: f64 = 1e4;
    (0..frame.height)
        .flat_map(|y| (0..frame.width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let ray = frame.pixel_ray(x, y);
            let along = crate::train::recipe_along(recipe, tracer, &ray, 0.0, FAR);
            let k = crate::train::known_depth(&along, 0.0, FAR);
            if k.opacity >= 0.5 {
                (k.depth / k.opacity * ray.dir.dot(frame.forward)) as f32
            } else {
                0.0
            }
        })
        .collect()
}

/// Linear [0, 1] to 8-bit sRGB (values outside clip).
pub fn linear_to_srgb8(v: f32) -> u8 {
    (super::pixels::srgb_encode(v as f64) * 255.0 + 0.5) as u8
}

/// What an 8-bit sRGB bracket taken at `exposure` records of linear
/// radiance `v`, read back linear as the loader reads it, and whether it
/// saturated (a lower bound to the loader).
pub fn bracket_reading(v: f32, exposure: f32) -> (f32, bool) {
    let byte = linear_to_srgb8(v * exposure);
    (
        super::pixels::srgb_to_linear(byte as f32 / 255.0),
        byte == 255,
    )
}

/// The light a capture's brackets cannot record: pixels that saturate
/// even the shortest exposure, where every bracket says only that the
/// radiance is at least white over that exposure. A light there is as
/// bright in a trained field as the rest of the loss happens to make it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct UnrecordedLight {
    /// Pixels saturated (in any channel) in the shortest bracket.
    pub pixels: u64,
    /// Views with at least one such pixel.
    pub views: u32,
    /// The brightest channel of any of them, linear radiance.
    pub brightest: f32,
    /// Their light (the sum of their channels), linear radiance.
    pub light: f64,
    /// Every pixel's light added.
    pub total_light: f64,
}

impl UnrecordedLight {
    /// Adds one view's radiance, bracketed down to exposure `shortest`.
    pub fn add_view(&mut self, rgb: &[[f32; 3]], shortest: f32) {
        let mut seen = false;
        for p in rgb {
            let light = p.iter().map(|&c| c as f64).sum::<f64>();
            self.total_light += light;
            if p.iter().any(|&c| bracket_reading(c, shortest).1) {
                self.light += light;
                self.pixels += 1;
                self.brightest = self.brightest.max(p[0].max(p[1]).max(p[2]));
                seen = true;
            }
        }
        self.views += seen as u32;
    }

    /// The share of the views' light in the pixels the shortest bracket
    /// does not record (0 with no views).
    pub fn light_share(&self) -> f64 {
        if self.total_light > 0.0 {
            self.light / self.total_light
        } else {
            0.0
        }
    }

    /// The exposure value, in whole stops, at or below which a bracket
    /// records every pixel added (the brightest below the 8-bit code's
    /// white, with a margin for its rounding); None when every pixel was
    /// recorded.
    pub fn stops_needed(&self) -> Option<i32> {
        (self.pixels > 0).then(|| (-(self.brightest as f64 / 0.99).log2()).floor() as i32)
    }
}

/// A bracketed LDR frame as PNG bytes: clip(`exposure` × radiance) through
/// the sRGB curve, 8 bits, as a camera with an sRGB response records it.
pub fn bracket_png(rgb: &[[f32; 3]], width: u32, height: u32, exposure: f32) -> Vec<u8> {
    let bytes: Vec<u8> = rgb
        .iter()
        .flat_map(|p| p.map(|c| linear_to_srgb8(c * exposure)))
        .collect();
    let mut out = std::io::Cursor::new(Vec::new());
    image::write_buffer_with_format(
        &mut out,
        &bytes,
        width,
        height,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .expect("encoding a PNG in memory");
    out.into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A light past the shortest bracket's white is counted, and a bracket
    /// at the stops it names records it; one every bracket records is not
    /// counted.
    #[test]
    fn unrecorded_light_names_the_bracket_that_records_it() {
        let view = [[160.0, 80.0, 20.0], [0.5, 0.5, 0.5], [128.0, 1.0, 1.0]];
        let mut light = UnrecordedLight::default();
        light.add_view(&view, 2f32.powi(-6));
        light.add_view(&[[0.2; 3]], 2f32.powi(-6));
        assert_eq!((light.pixels, light.views, light.brightest), (2, 1, 160.0));
        let share = (260.0 + 130.0) / (260.0 + 1.5 + 130.0 + 0.6);
        assert!((light.light_share() - share).abs() < 1e-9);
        let ev = light.stops_needed().expect("the lamp saturates 1/64");
        assert_eq!(ev, -8);
        for p in view {
            assert!(p.iter().all(|&c| !bracket_reading(c, 2f32.powi(ev)).1));
        }
        // Exactly white at EV -7 saturates it: -8 is needed.
        let mut at_white = UnrecordedLight::default();
        at_white.add_view(&[[128.0; 3]], 2f32.powi(-6));
        assert_eq!(at_white.stops_needed(), Some(-8));
        let mut none = UnrecordedLight::default();
        none.add_view(&view, 2f32.powi(-9));
        assert_eq!((none.pixels, none.stops_needed()), (0, None));
    }
    use crate::dataset::depth::{depth_png, PNG_DEPTH_UNIT};
    use crate::dataset::{load_dataset, BoundsSource, Dialect, LoadOptions};

    /// A written dataset reads back: the loader's ray through each pixel
    /// is the camera's, and instant-ngp's cube holds the bounds.
    #[test]
    fn a_written_capture_reads_back_with_the_cameras_rays() {
        let bounds = Aabb::new(DVec3::new(-1.0, -0.1, -0.8), DVec3::new(1.0, 1.2, 0.6));
        let (w, h) = (12u32, 8u32);
        let cams = cap_cameras(&bounds, 5, 40.0, w as f64 / h as f64, &Capture::FULL);
        let dir = std::env::temp_dir().join(format!("inlay-capture-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let frames: Vec<WrittenFrame> = cams
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let file = format!("v{i}.png");
                let rgb = vec![[0.2f32, 0.5, 2.0]; (w * h) as usize];
                std::fs::write(dir.join(&file), bracket_png(&rgb, w, h, 0.5)).unwrap();
                // A depth map on every frame but the first: pixel p at
                // z = 1 + p/100 scene units, the last one recording none.
                let depth_file = (i > 0).then(|| {
                    let name = format!("d{i}.png");
                    let mut z: Vec<f32> = (0..w * h).map(|p| 1.0 + p as f32 / 100.0).collect();
                    z[(w * h - 1) as usize] = 0.0;
                    let png = depth_png(&z, w, h, PNG_DEPTH_UNIT);
                    std::fs::write(dir.join(&name), png).unwrap();
                    name
                });
                WrittenFrame {
                    file,
                    camera: c.clone(),
                    exposure_time: Some(0.5),
                    depth_file,
                }
            })
            .collect();
        let doc = transforms_json(&frames, w, h, &bounds);
        std::fs::write(dir.join("transforms.json"), doc.to_string()).unwrap();
        let d = load_dataset(&dir, &LoadOptions::default()).unwrap();
        assert_eq!(d.dialect, Dialect::InstantNgp);
        assert_eq!(d.bounds_source, BoundsSource::AabbKey);
        assert_eq!(d.bounds, bounds);
        for (f, c) in d.frames.iter().zip(&cams) {
            let frame = CameraFrame::new(c, w, h);
            for (u, v) in [(0.5, 0.5), (11.5, 7.5), (6.0, 4.0), (3.25, 6.75)] {
                let want = frame.ray(u, v).dir;
                let got = f.pose.to_world(f.intrinsics.direction(u, v).unwrap());
                assert!((got - want).length() < 1e-9, "{u} {v}: {got} vs {want}");
            }
            assert_eq!(f.exposure_time, Some(0.5));
            if f.index == 0 {
                assert!(f.depth.is_empty());
            } else {
                assert_eq!(f.depth.len() as u32, w * h);
                assert!((f.depth[13] - 1.13).abs() < 1e-6, "{}", f.depth[13]);
                assert_eq!(f.depth[(w * h - 1) as usize], 0.0);
            }
            // 2.0 × 0.5 clips: the blue channel is a lower bound.
            assert_eq!(f.image.state[0], crate::dataset::PixelState::LowerBound);
            let g = f.image.radiance[0][1];
            assert!((g - 0.25).abs() < 0.01, "{g}");
            // Every camera sees the whole field.
            let r = 0.5 * bounds.diagonal();
            assert!(frame.sphere_visible(bounds.center(), r));
        }
        let ngp = crate::dataset::bounds::ngp_bounds(
            doc["aabb_scale"].as_f64().unwrap(),
            doc["scale"].as_f64().unwrap(),
            [0, 1, 2].map(|k| doc["offset"][k].as_f64().unwrap()),
        );
        assert!(
            ngp.contains(bounds.min) && ngp.contains(bounds.max),
            "{ngp:?}"
        );
        // Elevations lie on the cap.
        for c in &cams {
            let d = (c.position - bounds.center()).normalize();
            let el = d.y.asin().to_degrees();
            assert!(
                (CAP_LOWEST - 1e-9..=CAP_HIGHEST + 1e-9).contains(&el),
                "{el}"
            );
        }
    }

    /// A capture over part of the circle keeps its cameras on that arc
    /// and spreads them over it: each quarter of the arc holds a share of
    /// them, at low and at high elevations.
    #[test]
    fn a_capture_arc_keeps_its_cameras_on_the_arc() {
        let bounds = Aabb::new(DVec3::new(-1.0, -0.1, -1.0), DVec3::new(1.0, 1.4, 1.0));
        let arc = Capture {
            azimuth_from: 0.0,
            azimuth_to: 90.0,
        };
        let cams = cap_cameras(&bounds, 64, 40.0, 1.0, &arc);
        let mut quarters = [0; 4];
        let mut high = [0; 4];
        for c in &cams {
            let d = (c.position - bounds.center()).normalize();
            let az = d.z.atan2(d.x).to_degrees();
            assert!((-1e-9..=90.0 + 1e-9).contains(&az), "{az}");
            let q = ((az / 22.5) as usize).min(3);
            quarters[q] += 1;
            if d.y.asin().to_degrees() > 35.0 {
                high[q] += 1;
            }
        }
        for q in 0..4 {
            assert!((12..=20).contains(&quarters[q]), "{quarters:?}");
            assert!(high[q] >= 4, "{high:?}");
        }
        // The whole circle is the spiral it always was: camera i at i
        // golden angles.
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        for (i, c) in cap_cameras(&bounds, 8, 40.0, 1.0, &Capture::FULL)
            .iter()
            .enumerate()
        {
            let d = c.position - bounds.center();
            let want = DVec3::new((i as f64 * golden).cos(), 0.0, (i as f64 * golden).sin());
            let got = DVec3::new(d.x, 0.0, d.z).normalize();
            assert!((got - want).length() < 1e-9, "{i}: {got} vs {want}");
        }
        assert!(arc.problem().is_none() && Capture::FULL.problem().is_none());
        for (a, b) in [(0.0, 10.0), (90.0, 0.0), (0.0, 400.0), (f64::NAN, 90.0)] {
            let bad = Capture {
                azimuth_from: a,
                azimuth_to: b,
            };
            assert!(bad.problem().is_some(), "{a} {b}");
        }
    }
}
