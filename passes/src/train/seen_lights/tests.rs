//! The lights past the bounds found from views rendered here with another
//! coverage rule than the fit's (jittered rays, not its even grid).

use glam::DVec3;

use super::*;
use crate::dataset::pixels::{FrameImage, PixelCounts};
use crate::dataset::{BoundsSource, Dialect, Intrinsics, Pose};
use crate::field::seen_lights::sphere_hit;
use crate::rng::Pcg32;

const GREY: f64 = 0.2;

/// Eight 64 × 48 views, 50° high, from a ring of radius 4 at height 1.5
/// looking at (0, 0.8, 0), of a grey world with `light` (centre, radius,
/// radiance): each pixel the mean of 24 × 24 jittered rays.
fn views(light: (DVec3, f64, DVec3)) -> Dataset {
    let (w, h) = (64u32, 48u32);
    let mut rng = Pcg32::new(7, 11);
    let frames = (0..8)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 8.0;
            let eye = DVec3::new(4.0 * a.cos(), 1.5, 4.0 * a.sin());
            let pose = Pose::looking_at(eye, DVec3::new(0.0, 0.8, 0.0), DVec3::Y);
            let intrinsics = Intrinsics::centred(w, h, 50.0);
            let mut frame = Frame {
                index: k,
                image_path: "view.exr".into(),
                pose,
                intrinsics,
                exposure_time: None,
                exif_exposure: None,
                image: FrameImage {
                    width: w,
                    height: h,
                    radiance: Vec::new(),
                    state: vec![PixelState::Value; (w * h) as usize],
                    alpha: Vec::new(),
                    counts: PixelCounts::default(),
                },
                depth: Vec::new(),
            };
            frame.image.radiance = (0..w * h)
                .map(|p| {
                    let n = 24;
                    let hits = (0..n * n)
                        .filter(|_| {
                            let o = (rng.next_f64(), rng.next_f64());
                            let ray = pixel_ray_at(&frame, p, o).unwrap();
                            sphere_hit(&ray, light.0, light.1).is_some()
                        })
                        .count();
                    let c = hits as f64 / (n * n) as f64;
                    let v = DVec3::splat(GREY) * (1.0 - c) + light.2 * c;
                    [v.x as f32, v.y as f32, v.z as f32]
                })
                .collect();
            frame
        })
        .collect();
    Dataset {
        file: "shots/transforms.json".into(),
        dialect: Dialect::InstantNgp,
        frames,
        bounds: Aabb::new(DVec3::new(-1.0, -0.1, -1.0), DVec3::new(1.0, 1.4, 1.0)),
        bounds_source: BoundsSource::AabbKey,
        counts: PixelCounts::default(),
        skipped: Vec::new(),
    }
}

fn all(d: &Dataset) -> Vec<u32> {
    (0..d.frames.len() as u32).collect()
}

/// A bulb above the box, about two pixels across: found at its place to a
/// tenth of a pixel's footprint, its intensity to 2 %, its colour's ratios
/// to 1 %; its pixels are left out and the rest kept.
#[test]
fn a_bulb_past_the_bounds_is_found_where_it_is_and_as_bright() {
    let (centre, radius) = (DVec3::new(0.3, 2.4, -0.2), 0.04);
    let radiance = DVec3::new(5000.0, 4000.0, 3000.0);
    let mut d = views((centre, radius, radiance));
    let found = find_seen_lights(&d, &all(&d), &d.bounds, GREY);
    assert!(found.inside.is_empty(), "{found:?}");
    assert_eq!(found.lights.len(), 1, "{found:?}");
    let l = found.lights[0];
    eprintln!("{l:?}: {} off", (l.centre - centre).length());
    // One pixel's footprint at the light: about 4.3 units × 50°/48.
    let footprint = 4.3 * 50f64.to_radians() / 48.0;
    assert!(
        (l.centre - centre).length() < 0.1 * footprint,
        "{:?} against {centre:?} ({footprint})",
        l.centre
    );
    let truth = std::f64::consts::PI * radius * radius * radiance;
    let ratio = l.intensity() / truth;
    eprintln!(
        "intensity {ratio:?}, {masked_note}",
        masked_note = found.spots
    );
    assert!((ratio - DVec3::ONE).abs().max_element() < 0.02, "{ratio:?}");
    let colour = l.radiance / l.radiance.x;
    assert!(
        (colour - DVec3::new(1.0, 0.8, 0.6)).abs().max_element() < 0.01,
        "{colour:?}"
    );
    assert!(l.residual < 0.05, "{l:?}");
    assert!((l.radius / radius - 1.0).abs() < 0.3, "{l:?}");
    // Every pixel holding any of its light is left out, no pixel far from it.
    let before = d.clone();
    let frames = all(&d);
    let masked = mask_seen_lights(&mut d, &found.lights, &frames);
    assert!(masked > 0);
    for (a, b) in before.frames.iter().zip(&d.frames) {
        for p in 0..a.image.radiance.len() {
            let lum = crate::sgfit::model::luminance(blobs::radiance_at(a, p as u32));
            let left_out = b.image.state[p] == PixelState::Masked;
            if lum > GREY * 1.01 {
                assert!(left_out, "pixel {p} reads {lum} and is kept");
            }
            if left_out {
                let ray = pixel_ray_at(a, p as u32, (0.5, 0.5)).unwrap();
                let v = centre - ray.origin;
                let off = (v - v.dot(ray.dir) * ray.dir).length();
                assert!(
                    off < radius + 3.0 * footprint,
                    "pixel {p} left out {off} away"
                );
            }
        }
    }
}

/// A lamp inside the bounds is the field's: found and left to it. A set
/// without spots finds nothing, and with the lights off nothing changes.
#[test]
fn a_lamp_inside_the_bounds_is_left_to_the_field() {
    let d = views((DVec3::new(0.2, 0.9, 0.1), 0.05, DVec3::splat(400.0)));
    let found = find_seen_lights(&d, &all(&d), &d.bounds, GREY);
    assert!(found.lights.is_empty(), "{found:?}");
    assert_eq!(found.inside.len(), 1, "{found:?}");
    assert!((found.inside[0] - DVec3::new(0.2, 0.9, 0.1)).length() < 0.02);
    let dim = views((DVec3::new(0.3, 2.4, -0.2), 0.04, DVec3::splat(10.0)));
    let none = find_seen_lights(&dim, &all(&dim), &dim.bounds, GREY);
    assert_eq!(
        (none.lights.len(), none.inside.len(), none.spots),
        (0, 0, 0)
    );
    let mut same = dim.clone();
    assert_eq!(mask_seen_lights(&mut same, &none.lights, &all(&dim)), 0);
    assert_eq!(same, dim);
}

/// Seen by two views only, a spot pair fixes no light.
#[test]
fn two_views_do_not_make_a_light() {
    let mut d = views((DVec3::new(0.3, 2.4, -0.2), 0.04, DVec3::splat(4000.0)));
    d.frames.truncate(2);
    let found = find_seen_lights(&d, &all(&d), &d.bounds, GREY);
    assert!(found.lights.is_empty() && found.spots == 2, "{found:?}");
}

/// `d`'s views taken as 8-bit sRGB brackets at `exposures` (a frame per
/// view and exposure, as a bracketed capture loads: linear readings, a
/// lower bound where a channel saturated).
fn bracketed(d: &Dataset, exposures: &[f32]) -> Dataset {
    use crate::dataset::capture::bracket_reading;
    let mut out = d.clone();
    out.frames = d
        .frames
        .iter()
        .flat_map(|f| {
            exposures.iter().map(move |&t| {
                let mut b = f.clone();
                b.image_path = "view.png".into();
                b.exposure_time = Some(t as f64);
                for (c, s) in b.image.radiance.iter_mut().zip(&mut b.image.state) {
                    let read = c.map(|v| bracket_reading(v, t));
                    *c = read.map(|r| r.0);
                    if read.iter().any(|r| r.1) {
                        *s = PixelState::LowerBound;
                    }
                }
                b
            })
        })
        .collect();
    out
}

/// The same bulb photographed as exposure brackets: the poses' brackets
/// merged, it is found from the shortest, which records it, as from
/// linear views; where even the shortest saturates, it is still placed,
/// and its radiance is what its unsaturated pixels and the saturated
/// ones it mostly covers say it is at least.
#[test]
fn a_bulb_in_bracketed_photographs_is_found_from_the_bracket_that_records_it() {
    let (centre, radius) = (DVec3::new(0.3, 2.4, -0.2), 0.04);
    let radiance = DVec3::new(5000.0, 4000.0, 3000.0);
    let linear = views((centre, radius, radiance));
    let footprint = 4.3 * 50f64.to_radians() / 48.0;
    let truth = std::f64::consts::PI * radius * radius * radiance;
    for (shortest, recorded) in [(1.0 / 8192.0, true), (1.0 / 512.0, false)] {
        let d = bracketed(&linear, &[1.0, 1.0 / 16.0, 1.0 / 128.0, shortest]);
        let found = find_seen_lights(&d, &all(&d), &d.bounds, GREY);
        assert_eq!(found.lights.len(), 1, "{found:?}");
        let l = found.lights[0];
        let ratio = l.intensity() / truth;
        eprintln!(
            "shortest 1/{}: {} off, intensity {ratio:?}, radius {:.4}, {} views, {} saturated",
            1.0 / shortest,
            (l.centre - centre).length(),
            l.radius,
            l.views,
            found.saturated[0]
        );
        assert_eq!(l.views, 8, "a pose counts once, however many brackets");
        assert!((l.centre - centre).length() < 0.2 * footprint, "{l:?}");
        if recorded {
            assert_eq!(found.saturated[0], 0);
            assert!((ratio - DVec3::ONE).abs().max_element() < 0.03, "{ratio:?}");
        } else {
            // A lower bound: at least white over the shortest exposure
            // (a pixel it covers whole), and not above the truth.
            assert!(found.saturated[0] > 0);
            let white = 1.0 / shortest as f64;
            let y = crate::sgfit::model::luminance(l.radiance);
            assert!(y > 0.98 * white, "{y} against white {white}");
            assert!(ratio.max_element() < 1.05, "{ratio:?}");
        }
    }
}
