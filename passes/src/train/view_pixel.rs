//! A held-out pixel rendered as its photograph gathered it: the mean over
//! the pixel's area of the field's march, the sky behind it and the lights
//! seen beside it.
//!
//! The field is marched through the centres of an even n × n split of the
//! pixel. A seen light is far brighter than anything the field holds
//! (ROOM's bulb is 8000 against a room of 0.2), so a photograph's pixel
//! that the light's disc only grazes records it at full white, while n × n
//! centre rays may all miss it: at n = 4, the bulb's edge pixels in ROOM's
//! held-out view 24 read black where Cycles' read white, and those four
//! pixels held two fifths of the view's squared error. So each cell's
//! light is read over finer rays, at least as many a pixel as the lights'
//! fit reads a pixel's coverage with ([`COVERAGE_RAYS`]), each sharing its
//! cell's march: a light's share of a pixel is then the fit's own.

use glam::DVec3;

use super::behind::Behind;
use super::pixels::{area_offsets, pixel_ray_at};
use super::seen_lights::fit::COVERAGE_RAYS;
use super::seen_lights::{with_seen_lights, SeenLight};
use crate::dataset::Frame;
use crate::field::GridField;
use crate::march::{march_ray, MarchKnobs};

/// The finer rays across each side of one of a pixel's `samples` ×
/// `samples` cells that its lights are read with: none past the cell's own
/// where there is no light, otherwise enough that the pixel holds at least
/// [`COVERAGE_RAYS`] × [`COVERAGE_RAYS`].
pub fn light_rays_per_cell(samples: u32, lights: &[SeenLight]) -> u32 {
    if lights.is_empty() {
        1
    } else {
        COVERAGE_RAYS.div_ceil(samples.max(1))
    }
}

/// The radiance of pixel `pixel` of `frame` seen through `field` (marched
/// with `march`) over `behind`, with `lights` beside it: the mean of
/// `samples` × `samples` cells ([`area_offsets`]), each the field's march
/// through the cell's centre, and where a light meets any of the cell's
/// [`light_rays_per_cell`]² finer rays, the mean over those of the light
/// drawn with that march ([`with_seen_lights`]). A ray the lens model
/// cannot invert is left out; a pixel with none reads black.
pub fn view_pixel(
    frame: &Frame,
    pixel: u32,
    field: &GridField,
    march: &MarchKnobs,
    behind: &Behind,
    lights: &[SeenLight],
    samples: u32,
) -> DVec3 {
    let n = samples.max(1);
    let k = light_rays_per_cell(n, lights);
    let fine = area_offsets(n * k);
    let (mut sum, mut count) = (DVec3::ZERO, 0u32);
    for (c, offset) in area_offsets(n).into_iter().enumerate() {
        let Some(ray) = pixel_ray_at(frame, pixel, offset) else {
            continue;
        };
        let r = march_ray(field, &ray, f64::INFINITY, march);
        let back = behind.eval(ray.dir);
        let centre = with_seen_lights(lights, &ray, &field.bounds, r.colour, r.opacity, back);
        count += 1;
        if k == 1 {
            sum += centre;
            continue;
        }
        // The cell's finer rays, row by row within the pixel's (n k)².
        let (cx, cy) = (c as u32 % n, c as u32 / n);
        let rays: Vec<_> = (0..k * k)
            .filter_map(|i| {
                let (fx, fy) = (cx * k + i % k, cy * k + i / k);
                pixel_ray_at(frame, pixel, fine[(fy * n * k + fx) as usize])
            })
            .collect();
        if rays
            .iter()
            .all(|f| lights.iter().all(|l| l.hit(f).is_none()))
        {
            sum += centre;
            continue;
        }
        let drawn: DVec3 = rays
            .iter()
            .map(|f| with_seen_lights(lights, f, &field.bounds, r.colour, r.opacity, back))
            .sum();
        sum += drawn / rays.len() as f64;
    }
    sum / count.max(1) as f64
}
