//! The lights' drawing along a ray and over a pixel, and their file.

use std::path::Path;

use glam::DVec3;

use super::file::{parse_seen_lights, seen_lights_text};
use super::*;

fn light(z: f64) -> SeenLight {
    SeenLight {
        centre: DVec3::new(0.0, 0.0, z),
        radius: 0.2,
        radiance: DVec3::splat(100.0),
        views: 3,
        residual: 0.0,
    }
}

fn down_z(x: f64) -> Ray {
    Ray {
        origin: DVec3::new(x, 0.0, 5.0),
        dir: -DVec3::Z,
    }
}

/// A light before the bounds hides the field; past them the field's
/// transmittance shows it; a ray that meets none sees what is behind.
#[test]
fn the_lights_are_drawn_in_front_of_and_behind_the_field() {
    let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
    let ray = down_z(0.0);
    let (colour, opacity, behind) = (DVec3::splat(0.3), 0.75, DVec3::splat(0.1));
    let front = with_seen_lights(&[light(3.0)], &ray, &bounds, colour, opacity, behind);
    assert_eq!(front, DVec3::splat(100.0));
    let back = with_seen_lights(&[light(-3.0)], &ray, &bounds, colour, opacity, behind);
    assert_eq!(back, DVec3::splat(0.3 + 0.25 * 100.0));
    let none = with_seen_lights(&[], &ray, &bounds, colour, opacity, behind);
    assert_eq!(none, DVec3::splat(0.3 + 0.25 * 0.1));
    // Both: the nearer one, in front.
    let both = with_seen_lights(
        &[light(-3.0), light(3.0)],
        &ray,
        &bounds,
        colour,
        opacity,
        behind,
    );
    assert_eq!(both, DVec3::splat(100.0));
    // A ray that misses the box sees the light whole.
    let aside = SeenLight {
        centre: DVec3::new(3.0, 0.0, -3.0),
        ..light(0.0)
    };
    assert_eq!(
        with_seen_lights(&[aside], &down_z(3.0), &bounds, DVec3::ZERO, 0.0, behind),
        DVec3::splat(100.0)
    );
}

/// A pixel's coverage: whole well inside the disc, half at its edge, none
/// a pixel past it, and a disc far smaller than the pixel covers its area's
/// share.
#[test]
fn a_discs_coverage_ramps_over_a_pixel_and_keeps_a_small_discs_area() {
    let l = light(0.0);
    let o = DVec3::new(0.0, 0.0, 10.0);
    let at = |x: f64| (DVec3::new(x, 0.0, 0.0) - o).normalize();
    let a = 0.01; // a pixel: 0.1 units at the light's distance
    assert_eq!(disc_coverage(&l, o, at(0.0), a).0, 1.0);
    let edge = disc_coverage(&l, o, at(0.2), a).0;
    assert!((edge - 0.5).abs() < 0.01, "{edge}");
    assert_eq!(disc_coverage(&l, o, at(0.26), a).0, 0.0);
    let tiny = SeenLight { radius: 0.01, ..l };
    let c = disc_coverage(&tiny, o, at(0.0), a).0;
    let area = std::f64::consts::PI * 0.01f64.powi(2) / 0.1f64.powi(2);
    assert!((c - area).abs() < 1e-3 * area, "{c} {area}");
    // Behind the eye: nothing.
    assert_eq!(disc_coverage(&l, o, -at(0.0), a).0, 0.0);
}

/// Over a pixel: a light before the bounds covers the frame, one past them
/// only what the frame leaves uncovered; coverage 1 after.
#[test]
fn a_pixel_draws_the_nearest_light_over_or_under_the_frame() {
    let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
    let (o, d, a) = (DVec3::new(0.0, 0.0, 5.0), -DVec3::Z, 0.001);
    let frame = [0.2, 0.2, 0.2, 0.5];
    let back = DVec3::splat(0.4);
    let front = light_over_pixel(frame, back, &[light(3.0)], &bounds, o, d, a);
    assert_eq!(front, [100.0, 100.0, 100.0, 1.0]);
    let behind = light_over_pixel(frame, back, &[light(-3.0)], &bounds, o, d, a);
    assert_eq!(behind, [50.2, 50.2, 50.2, 1.0]);
    let none = light_over_pixel(frame, back, &[], &bounds, o, d, a);
    assert_eq!(none, [0.4, 0.4, 0.4, 1.0]);
    let covered = light_over_pixel([0.2, 0.2, 0.2, 1.0], back, &[light(-3.0)], &bounds, o, d, a);
    assert_eq!(covered, [0.2, 0.2, 0.2, 1.0]);
}

/// A file round-trips its lights; a bad one names its key.
#[test]
fn the_lights_file_round_trips_and_names_a_bad_key() {
    let path = Path::new("room.lights.toml");
    let lights = vec![
        SeenLight {
            centre: DVec3::new(0.198, 2.894, 0.298),
            radius: 0.0296,
            radiance: DVec3::new(8022.0, 7420.2, 6417.6),
            views: 13,
            residual: 0.017,
        },
        light(-3.0),
    ];
    let text = seen_lights_text(&lights);
    assert_eq!(parse_seen_lights(path, &text).unwrap(), lights);
    assert_eq!(
        parse_seen_lights(path, &seen_lights_text(&[])).unwrap(),
        vec![]
    );
    let bad = |from: &str, to: &str, key: &str| {
        let e = parse_seen_lights(path, &text.replacen(from, to, 1)).unwrap_err();
        assert_eq!(e.key, key, "{e}");
        assert!(e.to_string().starts_with("room.lights.toml: "), "{e}");
    };
    bad("radius = 0.0296", "radius = -1.0", "lights[0].radius");
    bad("radius = 0.0296", "radius = nan", "lights[0].radius");
    bad("8022.0", "-1.0", "lights[0].radiance");
    bad("8022.0", "1e9", "lights[0].radiance");
    bad("inlay-seen-lights", "inlay-environment", "format");
    bad("version = 1", "version = 2", "version");
    let e = parse_seen_lights(
        path,
        "format = \"inlay-seen-lights\"\nversion = 1\n[[lights]]\ncentre = [0, 1]\n",
    )
    .unwrap_err();
    assert!(e.key.starts_with("line"), "{e}");
    // Four numbers where three are asked for.
    let e =
        parse_seen_lights(path, &text.replacen("centre = [", "centre = [9.0, ", 1)).unwrap_err();
    assert!(
        e.key.starts_with("line") && e.message.contains("3 numbers"),
        "{e}"
    );
}
