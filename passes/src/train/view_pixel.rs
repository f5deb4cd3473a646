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
use crate::geometry::Ray;
use crate::march::{march_ray, MarchKnobs};

/// Where a held-out pixel's rays pass, in pixels from its top-left corner:
/// the centres of its n × n cells ([`area_offsets`]), and within each cell
/// the finer rays its lights are read with. Made once a view.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelSplit {
    /// Each cell's centre, row by row.
    pub cells: Vec<(f64, f64)>,
    /// Each cell's finer rays (its centre alone where there is no light),
    /// k × k of them, k enough that the pixel holds at least
    /// [`COVERAGE_RAYS`] × [`COVERAGE_RAYS`]: the pixel's (n k)² rays
    /// ([`area_offsets`]) split among its cells.
    pub fine: Vec<Vec<(f64, f64)>>,
}

impl PixelSplit {
    /// The split of a pixel into `samples` × `samples` cells, each read
    /// with finer rays where there are `lights`.
    pub fn new(samples: u32, lights: &[SeenLight]) -> Self {
        let n = samples.max(1);
        let k = if lights.is_empty() {
            1
        } else {
            COVERAGE_RAYS.div_ceil(n)
        };
        let all = area_offsets(n * k);
        let fine = (0..n * n)
            .map(|c| {
                let (cx, cy) = (c % n, c / n);
                (0..k * k)
                    .map(|i| all[((cy * k + i / k) * n * k + cx * k + i % k) as usize])
                    .collect()
            })
            .collect();
        Self {
            cells: area_offsets(n),
            fine,
        }
    }
}

/// The radiance of pixel `pixel` of `frame` seen through `field` (marched
/// with `march`) over `behind`, with `lights` beside it: the mean of
/// `split`'s cells, each the field's march through the cell's centre, and
/// where a light meets any of the cell's finer rays, the mean over those
/// of the light drawn with that march ([`with_seen_lights`]). A ray the
/// lens model cannot invert is left out; a pixel with none reads black.
pub fn view_pixel(
    frame: &Frame,
    pixel: u32,
    field: &GridField,
    march: &MarchKnobs,
    behind: &Behind,
    lights: &[SeenLight],
    split: &PixelSplit,
) -> DVec3 {
    let bounds = &field.bounds;
    let (mut sum, mut count) = (DVec3::ZERO, 0u32);
    for (&offset, fine) in split.cells.iter().zip(&split.fine) {
        let Some(ray) = pixel_ray_at(frame, pixel, offset) else {
            continue;
        };
        let r = march_ray(field, &ray, f64::INFINITY, march);
        let back = behind.eval(ray.dir);
        let draw = |ray: &Ray| with_seen_lights(lights, ray, bounds, r.colour, r.opacity, back);
        count += 1;
        // The cell as its centre ray reads it unless a finer ray meets a
        // light, then as the mean of its finer rays.
        let (mut drawn, mut rays, mut lit) = (DVec3::ZERO, 0u32, false);
        if fine.len() > 1 {
            for f in fine.iter().filter_map(|&o| pixel_ray_at(frame, pixel, o)) {
                lit |= lights.iter().any(|l| l.hit(&f).is_some());
                drawn += draw(&f);
                rays += 1;
            }
        }
        sum += if lit { drawn / rays as f64 } else { draw(&ray) };
    }
    sum / count.max(1) as f64
}
