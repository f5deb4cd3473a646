//! Surfaces the photographs leave open, completed by the planes through
//! the surfaces they place.
//!
//! A plain surface looks the same from every side, so a translucent sheet
//! of its colour in front of it renders the same pixels, and a trainer
//! that reads photographs alone leaves its weight spread along the ray
//! ([`super::spread`]). Where the same photographs place a surface (an
//! edge, a shadow, a texture, a contact) the weight gathers within a
//! spacing or two. A floor or a wall is plain over most of its area but
//! placed along its edges and under its objects, and all those placed
//! points lie on one plane. So after a first training the planes through
//! the placed points are found (RANSAC, then least squares), and each
//! training pixel whose weight spreads wide is given, as its depth, the
//! plane the ray meets inside the spread (the largest, where several). A second
//! training holds those pixels to that depth with the depth maps' loss
//! ([`super::depth`]); every other pixel trains on its photograph alone.
//! A medium in front of a plane (foliage) keeps its own weight wherever
//! its colour differs from what the plane shows.

use glam::DVec3;
use rayon::prelude::*;

use super::geometry::SURFACE_OPACITY;
use super::lattice::{lattice_stride, Lattice};
use super::pixels::pixel_ray;
use super::plane_colour::{PlaneColours, PLANE_COLOUR_REACH};
use super::spread::{weighted_samples, RayWeights};
use crate::dataset::{Dataset, Frame, PixelState};
use crate::field::{GridField, RadianceField};
use crate::geometry::Ray;
use crate::march::{MarchKnobs, MarchSample};
use crate::rng::Pcg32;

/// A pixel's surface counts as placed, and its expected depth a point a
/// plane may pass through, where its weight spreads less than this many
/// node spacings: a trained surface the photographs pin spreads over a
/// spacing or two. Of the opaque training pixels of DOG's Cycles set
/// after one run, 37 % spread less than 2 spacings and 25 % 3 or more
/// (`docs/benchmarks.md`, issue 25's forty-fourth pass).
pub const PLACED_SPREAD: f64 = 2.0;

/// A pixel's surface counts as open, and is completed where a plane meets
/// its ray, where its weight spreads this many node spacings or more (the
/// pixels between the two neither place a plane nor are completed).
pub const OPEN_SPREAD: f64 = 3.0;

/// A placed point lies on a plane within this many node spacings.
pub const PLANE_TOLERANCE: f64 = 1.0;

/// A plane is kept where it holds at least this share of the placed
/// points: on the Cycles sets the planes below it were a bounding box's
/// face, a layer of the floor's own scatter, or a slant through
/// unrelated points.
pub const PLANE_SHARE: f64 = 0.05;

/// At most this many planes are found.
pub const MAX_PLANES: usize = 8;

/// Random triples of points RANSAC tries for each plane.
pub const PLANE_TRIES: usize = 800;

/// The share of a ray's weight left out at each end of the stretch in
/// which a plane may complete it.
pub const SPREAD_TAIL: f64 = 0.02;

/// The largest relative difference between the colour a pixel's weight
/// carries in front of a plane and the colour at the plane for which the
/// weight in front counts as a sheet of the plane's own colour (what
/// photographs cannot tell from the plane) rather than a medium.
pub const SAME_COLOUR: f64 = 0.15;

/// A plane n·x + d = 0, n a unit vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// The unit normal n.
    pub normal: DVec3,
    /// d.
    pub offset: f64,
}

impl Plane {
    /// The plane through three points, or None where they lie on a line.
    pub fn through(a: DVec3, b: DVec3, c: DVec3) -> Option<Self> {
        let n = (b - a).cross(c - a);
        let length = n.length();
        (length > 1e-12 * (b - a).length_squared().max(1e-300)).then(|| {
            let normal = n / length;
            Self {
                normal,
                offset: -normal.dot(a),
            }
        })
    }

    /// The signed distance of `x` from the plane.
    pub fn distance(&self, x: DVec3) -> f64 {
        self.normal.dot(x) + self.offset
    }

    /// Where `ray` meets the plane (its parameter t, any sign), or None
    /// where it runs parallel to it.
    pub fn hit(&self, ray: &Ray) -> Option<f64> {
        let across = self.normal.dot(ray.dir);
        (across.abs() > 1e-9 * ray.dir.length()).then(|| -self.distance(ray.origin) / across)
    }
}

/// The least-squares plane through `points` (the normal along the
/// covariance's least eigenvector), or None for fewer than three.
pub fn fit_plane(points: &[DVec3]) -> Option<Plane> {
    if points.len() < 3 {
        return None;
    }
    let centre = points.iter().copied().sum::<DVec3>() / points.len() as f64;
    let mut m = vec![vec![0.0; 3]; 3];
    for p in points {
        let d = (*p - centre).to_array();
        for (i, row) in m.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v += d[i] * d[j];
            }
        }
    }
    let (values, vectors) = crate::eigen::jacobi_eigen(m);
    let least = (0..3).min_by(|&i, &j| values[i].total_cmp(&values[j]))?;
    let normal =
        DVec3::new(vectors[0][least], vectors[1][least], vectors[2][least]).try_normalize()?;
    Some(Plane {
        normal,
        offset: -normal.dot(centre),
    })
}

/// The planes through `points`, largest first: each the plane through
/// three random points that holds the most within `tolerance` (of
/// [`PLANE_TRIES`], weighed on [`PLANE_SAMPLE`] points), refitted by least squares to those it holds, which
/// then leave the search; it stops at [`MAX_PLANES`] or at a plane holding
/// fewer than `least` points. Each comes with the number it holds.
pub fn find_planes(
    points: &[DVec3],
    tolerance: f64,
    least: usize,
    seed: u64,
) -> Vec<(Plane, usize)> {
    let mut rng = Pcg32::new(seed, 17);
    let mut rest = points.to_vec();
    let mut planes = Vec::new();
    let least = least.max(3);
    while planes.len() < MAX_PLANES && rest.len() >= least {
        let mut pick = || rest[(rng.next_u32() as usize) % rest.len()];
        let tries: Vec<Plane> = (0..PLANE_TRIES)
            .filter_map(|_| Plane::through(pick(), pick(), pick()))
            .collect();
        let held = |p: &Plane, among: &[DVec3]| {
            among
                .iter()
                .filter(|x| p.distance(**x).abs() < tolerance)
                .count()
        };
        let step = rest.len().div_ceil(PLANE_SAMPLE).max(1);
        let sample: Vec<DVec3> = rest.iter().step_by(step).copied().collect();
        let Some(best) = tries
            .par_iter()
            .map(|p| (held(p, &sample), *p))
            .max_by_key(|(n, _)| *n)
            .map(|(_, p)| p)
        else {
            break;
        };
        let near: Vec<DVec3> = rest
            .iter()
            .copied()
            .filter(|x| best.distance(*x).abs() < tolerance)
            .collect();
        let plane = fit_plane(&near).unwrap_or(best);
        let count = held(&plane, &rest);
        if count < least {
            break;
        }
        rest.retain(|x| plane.distance(*x).abs() >= tolerance);
        planes.push((plane, count));
    }
    planes
}

/// What the planes make of one dataset's training pixels
/// ([`complete_plain_surfaces`]).
#[derive(Debug, Clone, Default)]
pub struct Completion {
    /// The planes found, each with the number of placed points it holds.
    pub planes: Vec<(Plane, usize)>,
    /// The placed points they were found among (on the lattice of
    /// [`PLANE_PIXELS`]).
    pub placed: usize,
    /// Open pixels were read on every `stride`-th pixel of every
    /// `stride`-th row ([`COMPLETION_PIXELS`]); 1 where every pixel was.
    pub stride: u32,
    /// Training pixels read whose surface was open.
    pub open: usize,
    /// Of those, the pixels a plane completed.
    pub completed: usize,
    /// Of the open pixels a plane met, those left alone because the weight
    /// in front of the plane carries another colour (a medium).
    pub media: usize,
    /// Training pixels given a depth in all: those completed and, where
    /// the pixels were read on a lattice, the pixels between whose lattice
    /// pixels around them all were completed by one plane.
    pub depths: usize,
    /// Each frame's depth map (its pixels' z-depth, 0 where none), for
    /// the frames given; empty for the others.
    pub depth: Vec<Vec<f32>>,
    /// How long the completion took (the CPU's march over the training
    /// pixels read, each marched once but where a plane meets it).
    pub elapsed: std::time::Duration,
}

/// A plane within this many node spacings of a face of the field's
/// bounds, and parallel to it, is that face: where the photographs see
/// past the bounds the field paints what lies beyond on its faces, sharp
/// where the box cuts it, and the rays that enter through a face meet it
/// first (ROOM's `render-views` set placed 30 % of its points on its top
/// and two open sides). It completes no pixel.
pub const BOUNDS_FACE: f64 = 2.0;

/// Whether `plane` is parallel to a face of `bounds` (within 2°) and lies
/// within `margin` of it across the face.
pub fn on_a_face_of(plane: &Plane, bounds: &crate::geometry::Aabb, margin: f64) -> bool {
    let cos = 2f64.to_radians().cos();
    (0..3).any(|axis| {
        plane.normal[axis].abs() >= cos
            && [bounds.min, bounds.max].iter().any(|corner| {
                let mut at = bounds.center();
                at[axis] = corner[axis];
                plane.distance(at).abs() <= margin
            })
    })
}

/// `plane` with its normal turned toward the side most of the rays that
/// placed the points it holds (within `tolerance`) came from: a surface
/// the photographs place from one side (a wall's lit face) says nothing of
/// rays that reach it from the other (its back face, a thickness behind).
pub fn facing_its_cameras(plane: Plane, placed: &[(DVec3, DVec3)], tolerance: f64) -> Plane {
    let toward: i64 = placed
        .iter()
        .filter(|(x, _)| plane.distance(*x).abs() < tolerance)
        .map(|(_, d)| if plane.normal.dot(*d) < 0.0 { 1 } else { -1 })
        .sum();
    if toward >= 0 {
        plane
    } else {
        Plane {
            normal: -plane.normal,
            offset: -plane.offset,
        }
    }
}

/// Pixels the search for planes reads at most over all the frames: more
/// are read on every n-th pixel of every n-th row, n the least that keeps
/// it under (a million placed points at most).
pub const PLANE_PIXELS: u64 = 1 << 20;

/// Points each RANSAC try is weighed on at most: an even share of those
/// still unclaimed (the best try is then refitted to all it holds). The
/// measured sets placed 11 000–50 000 points, so every try weighed them
/// all; a capture of a million weighs a sixteenth.
pub const PLANE_SAMPLE: usize = 1 << 16;

/// The lattice on which the search for planes reads `pixels` pixels: every
/// n-th pixel of every n-th row, n the least that reads at most
/// [`PLANE_PIXELS`] (about: n² × that where rows do not divide evenly).
pub fn plane_stride(pixels: u64) -> u32 {
    lattice_stride(pixels, PLANE_PIXELS)
}

/// Training pixels the completion marches at most over all the frames:
/// more are marched on every n-th pixel of every n-th row, and each pixel
/// between takes the plane the lattice pixels around it agree on
/// ([`complete_plain_surfaces`]). The march costs about 1.3 µs a pixel on
/// the 2-core machine (23 s for 17.7 million), so this caps it near 6 s;
/// the bundled sets (0.3 million pixels in the Cycles sets, 0.8 million
/// in the `render-views` ones) are marched whole.
pub const COMPLETION_PIXELS: u64 = 1 << 22;

/// The planes through the surfaces `field` places in `frames` of
/// `dataset` (read on a lattice over [`PLANE_PIXELS`]), and for each of
/// those frames a depth map that gives each open pixel the depth of the
/// plane its ray meets within the stretch that holds its weight (but for
/// [`SPREAD_TAIL`] at each end, widened by a spacing), the one holding the
/// most placed points where it meets several (a plane found by chance
/// among scattered points is small), where the weight in front of the
/// plane is of the plane's colour ([`same_colour_in_front`]: the field's
/// at the plane, or the photographs' on it nearby where the ray's weight
/// does not reach it, [`PlaneColours`]). A plane completes
/// only rays that reach it from the side its points were placed from
/// ([`facing_its_cameras`]), and a face of the bounds none
/// ([`on_a_face_of`]). Frames that record depth already are left out
/// (their maps empty). Over [`COMPLETION_PIXELS`] pixels the open ones are
/// read on a lattice, and each pixel between lattice pixels takes the
/// depth of the plane that completed all of the (up to four) around it,
/// none where they differ.
pub fn complete_plain_surfaces(
    dataset: &Dataset,
    frames: &[u32],
    field: &GridField,
    march: &MarchKnobs,
    seed: u64,
) -> Completion {
    complete_on_lattice(dataset, frames, field, march, seed, COMPLETION_PIXELS)
}

/// [`complete_plain_surfaces`], marching at most about `most` pixels.
fn complete_on_lattice(
    dataset: &Dataset,
    frames: &[u32],
    field: &GridField,
    march: &MarchKnobs,
    seed: u64,
    most: u64,
) -> Completion {
    let started = std::time::Instant::now();
    let spacing = field.spacing().min_element();
    let frames: Vec<u32> = frames
        .iter()
        .copied()
        .filter(|&f| dataset.frames[f as usize].depth.is_empty())
        .collect();
    let size = |f: u32| {
        let k = &dataset.frames[f as usize].intrinsics;
        (k.width, k.height)
    };
    let all: u64 = frames
        .iter()
        .map(|&f| size(f).0 as u64 * size(f).1 as u64)
        .sum();
    let search = plane_stride(all);
    let stride = lattice_stride(all, most);
    // A pixel's ray and how its weight lies, where it is usable and the
    // field makes it opaque; and where it places its surface, the colour
    // it gathers (the colour the photographs show there).
    let read = |f: u32, p: u32| {
        let frame = &dataset.frames[f as usize];
        if frame.image.state[p as usize] == PixelState::Masked {
            return None;
        }
        let ray = pixel_ray(frame, p)?;
        let samples = weighted_samples(field, &ray, march);
        let w = RayWeights::of(&samples, SPREAD_TAIL)?;
        let colour = (w.spread < PLACED_SPREAD * spacing)
            .then(|| samples.iter().map(|s| s.weight * s.colour).sum::<DVec3>() / w.opacity);
        Some((ray, w, colour))
    };
    // Each frame's lattice marched once: each of its pixels whose surface
    // is open (its index on the lattice), with the stretch that holds its
    // weight (but for the tails) widened by a spacing. And each placed
    // point with the direction of the ray that placed it (and its colour),
    // read on the search's lattice in its order; its pixels on the
    // completion's lattice are not marched again (every pixel of both,
    // where both read every pixel).
    let mut open: Vec<Vec<(u32, f64, f64)>> = Vec::with_capacity(frames.len());
    let mut placed: Vec<(DVec3, DVec3)> = Vec::new();
    let mut placed_colours: Vec<DVec3> = Vec::new();
    for &f in &frames {
        let (w, h) = size(f);
        let lattice = Lattice::new(w, h, stride);
        let reads: Vec<Option<(Ray, RayWeights, Option<DVec3>)>> = (0..lattice.len())
            .into_par_iter()
            .map(|i| read(f, lattice.pixel(i)))
            .collect();
        let searched = Lattice::new(w, h, search);
        let points: Vec<(DVec3, DVec3, DVec3)> = (0..searched.len())
            .into_par_iter()
            .filter_map(|i| {
                let p = searched.pixel(i);
                match lattice.index(p) {
                    Some(j) => reads[j as usize],
                    None => read(f, p),
                }
            })
            .filter_map(|(ray, w, colour)| Some((ray.at(w.mean), ray.dir, colour?)))
            .collect();
        for (x, d, colour) in points {
            placed.push((x, d));
            placed_colours.push(colour);
        }
        open.push(
            (0..lattice.len())
                .zip(reads)
                .filter_map(|(i, read)| {
                    let (_, w, _) = read?;
                    (w.spread >= OPEN_SPREAD * spacing).then_some((
                        i,
                        w.front - spacing,
                        w.back + spacing,
                    ))
                })
                .collect(),
        );
    }
    let points: Vec<DVec3> = placed.iter().map(|(x, _)| *x).collect();
    let least = (PLANE_SHARE * points.len() as f64).ceil() as usize;
    let tolerance = PLANE_TOLERANCE * spacing;
    let planes: Vec<(Plane, usize)> = find_planes(&points, tolerance, least, seed)
        .into_iter()
        .filter(|(p, _)| !on_a_face_of(p, &field.bounds, BOUNDS_FACE * spacing))
        .map(|(p, n)| (facing_its_cameras(p, &placed, tolerance), n))
        .collect();
    let faces: Vec<Plane> = planes.iter().map(|(p, _)| *p).collect();
    let seen = PlaneColours::new(
        &faces,
        &placed,
        &placed_colours,
        tolerance,
        PLANE_COLOUR_REACH * spacing,
    );
    let mut completion = Completion {
        stride,
        placed: placed.len(),
        depth: vec![Vec::new(); dataset.frames.len()],
        ..Completion::default()
    };
    /// What became of one pixel: nothing (no surface, or not open), open
    /// with no plane to complete it, completed by a plane (its index), or
    /// left to a medium.
    #[derive(Clone, Copy, PartialEq)]
    enum Fate {
        Untouched,
        Open,
        Completed(usize),
        Medium,
    }
    // An open pixel's fate, `stretch` along its ray holding its weight.
    let fate = |frame: &Frame, p: u32, stretch: std::ops::RangeInclusive<f64>| {
        let Some(ray) = pixel_ray(frame, p) else {
            return Fate::Open;
        };
        let Some((k, t)) = planes
            .iter()
            .enumerate()
            .filter(|(_, (plane, _))| plane.normal.dot(ray.dir) < 0.0)
            .filter_map(|(k, (plane, n))| plane.hit(&ray).map(|t| (k, t, n)))
            .filter(|(_, t, _)| stretch.contains(t))
            .max_by_key(|(_, _, n)| **n)
            .map(|(k, t, _)| (k, t))
        else {
            return Fate::Open;
        };
        // The colour rule reads the samples themselves: marched again for
        // the pixels a plane meets alone.
        let samples = weighted_samples(field, &ray, march);
        let plane_seen = seen.near(k, ray.at(t));
        if same_colour_in_front(field, &ray, &samples, t - spacing, t + spacing, plane_seen) {
            Fate::Completed(k)
        } else {
            Fate::Medium
        }
    };
    for (&f, open) in frames.iter().zip(&open) {
        let frame = &dataset.frames[f as usize];
        let forward = frame.pose.forward();
        let (w, h) = size(f);
        let lattice = Lattice::new(w, h, stride);
        let met: Vec<(u32, Fate)> = open
            .par_iter()
            .map(|&(i, front, back)| (i, fate(frame, lattice.pixel(i), front..=back)))
            .collect();
        let mut fates = vec![Fate::Untouched; lattice.len() as usize];
        for &(i, fate) in &met {
            fates[i as usize] = fate;
        }
        completion.open += open.len();
        for (_, fate) in &met {
            completion.media += (*fate == Fate::Medium) as usize;
            completion.completed += matches!(fate, Fate::Completed(_)) as usize;
        }
        // Each pixel's plane: its own on the lattice; between, the one all
        // the lattice pixels around it were completed by.
        let plane_of = |x: u32, y: u32| {
            let mut agreed = None;
            for i in lattice.around(x, y) {
                match (fates[i as usize], agreed) {
                    (Fate::Completed(k), None) => agreed = Some(k),
                    (Fate::Completed(k), Some(a)) if k == a => {}
                    _ => return None,
                }
            }
            agreed
        };
        let depth: Vec<f32> = (0..w * h)
            .into_par_iter()
            .map(|p| {
                let Some(k) = plane_of(p % w, p / w) else {
                    return 0.0;
                };
                if frame.image.state[p as usize] == PixelState::Masked {
                    return 0.0;
                }
                let Some(ray) = pixel_ray(frame, p) else {
                    return 0.0;
                };
                let plane = &planes[k].0;
                match plane.hit(&ray) {
                    Some(t) if t > 0.0 && plane.normal.dot(ray.dir) < 0.0 => {
                        (t * ray.dir.dot(forward)) as f32
                    }
                    _ => 0.0,
                }
            })
            .collect();
        completion.depths += depth.iter().filter(|&&z| z > 0.0).count();
        completion.depth[f as usize] = depth;
    }
    completion.planes = planes;
    completion.elapsed = started.elapsed();
    completion
}

/// Whether the weight `ray`'s `samples` ([`weighted_samples`] through
/// `field`) gather in front of `near` (a plane's stretch [`near`, `far`]
/// along it) carry the plane's colour: their weighted mean colour within
/// [`SAME_COLOUR`] of it (relative to the plane's, summed over the
/// channels). The plane's colour is the weighted mean over the stretch,
/// or the field's colour at its middle where the stretch holds no weight.
/// Where the stretch holds less than [`SURFACE_OPACITY`] × 0.1 (the ray
/// spent before it), the field's colour there is what lies behind the
/// surface it shows, which the ray never delivers; the colour the
/// photographs show on the plane nearby (`seen`, [`PlaneColours::near`])
/// then counts as the plane's too, and either one matching is enough.
/// True where less than [`SURFACE_OPACITY`] × 0.1 lies in front: no
/// medium to keep.
pub fn same_colour_in_front(
    field: &dyn RadianceField,
    ray: &Ray,
    samples: &[MarchSample],
    near: f64,
    far: f64,
    seen: Option<DVec3>,
) -> bool {
    let (mut front, mut front_weight) = (DVec3::ZERO, 0.0);
    let (mut plane, mut plane_weight) = (DVec3::ZERO, 0.0);
    for s in samples {
        if s.t < near {
            front += s.weight * s.colour;
            front_weight += s.weight;
        } else if s.t <= far {
            plane += s.weight * s.colour;
            plane_weight += s.weight;
        }
    }
    if front_weight < 0.1 * SURFACE_OPACITY {
        return true;
    }
    let front = front / front_weight;
    let within = |colour: DVec3| {
        let scale = colour.abs().element_sum().max(1e-12);
        (front - colour).abs().element_sum() <= SAME_COLOUR * scale
    };
    let stretch = if plane_weight > 1e-6 {
        plane / plane_weight
    } else {
        field.colour(ray.at(0.5 * (near + far)), ray.dir)
    };
    within(stretch) || (plane_weight < 0.1 * SURFACE_OPACITY && seen.is_some_and(within))
}

#[cfg(test)]
mod tests {
    use glam::UVec3;

    use super::*;
    use crate::dataset::pixels::PixelCounts;
    use crate::dataset::{BoundsSource, Dialect, Pose};
    use crate::field::DEFAULT_OCCUPANCY_BLOCK;
    use crate::geometry::Aabb;
    use crate::train::geometry::tests::{frame, march};
    use crate::train::spread::ray_weights;

    /// Three points on a line make no plane; a ray meets a plane where
    /// the distance says and never one it runs along.
    #[test]
    fn a_plane_through_three_points_is_met_where_its_distance_says() {
        let p = Plane::through(DVec3::ZERO, DVec3::X, DVec3::Z).unwrap();
        assert!((p.normal.abs() - DVec3::Y).length() < 1e-12, "{p:?}");
        assert!((p.distance(DVec3::new(3.0, 2.0, -1.0)).abs() - 2.0).abs() < 1e-12);
        let ray = Ray {
            origin: DVec3::new(0.2, 3.0, 0.1),
            dir: DVec3::new(0.0, -0.5, 0.0),
        };
        assert!((p.hit(&ray).unwrap() - 6.0).abs() < 1e-12);
        let along = Ray {
            origin: DVec3::Y,
            dir: DVec3::X,
        };
        assert_eq!(p.hit(&along), None);
        assert_eq!(Plane::through(DVec3::ZERO, DVec3::X, 2.0 * DVec3::X), None);
    }

    /// Points on a tilted plane give it back to rounding, and points
    /// scattered ±ε about it give its normal within ε over the patch's
    /// size.
    #[test]
    fn the_least_squares_plane_is_the_plane_the_points_lie_on() {
        let normal = DVec3::new(0.3, 0.9, -0.2).normalize();
        let offset = 0.37;
        let (u, v) = normal.any_orthonormal_pair();
        let mut rng = Pcg32::new(3, 1);
        let on: Vec<DVec3> = (0..200)
            .map(|_| {
                let [a, b] = rng.next_2d();
                -offset * normal + (2.0 * a - 1.0) * u + (2.0 * b - 1.0) * v
            })
            .collect();
        let p = fit_plane(&on).unwrap();
        assert!((p.normal.dot(normal).abs() - 1.0).abs() < 1e-12, "{p:?}");
        assert!(on.iter().all(|x| p.distance(*x).abs() < 1e-12));
        let noisy: Vec<DVec3> = on
            .iter()
            .map(|x| *x + 1e-3 * (2.0 * rng.next_f64() - 1.0) * normal)
            .collect();
        let q = fit_plane(&noisy).unwrap();
        assert!(q.normal.dot(normal).abs() > 1.0 - 1e-5, "{q:?}");
        assert_eq!(fit_plane(&on[..2]), None);
    }

    /// A floor of 400 points, a wall of 150 and 40 points scattered
    /// between: the floor first, then the wall, each holding its own
    /// points; the scattered ones make no plane of the least size.
    #[test]
    fn ransac_finds_the_planes_largest_first_and_no_plane_in_scatter() {
        let mut rng = Pcg32::new(9, 2);
        let mut points = Vec::new();
        for _ in 0..400 {
            let [a, b] = rng.next_2d();
            points.push(DVec3::new(2.0 * a - 1.0, 0.0, 2.0 * b - 1.0));
        }
        for _ in 0..150 {
            let [a, b] = rng.next_2d();
            points.push(DVec3::new(1.5, 0.5 + a, 2.0 * b - 1.0));
        }
        for _ in 0..40 {
            let [a, b] = rng.next_2d();
            points.push(DVec3::new(a - 0.5, 0.2 + rng.next_f64(), b - 0.5));
        }
        let planes = find_planes(&points, 0.01, 30, 5);
        assert_eq!(planes.len(), 2, "{planes:?}");
        let (floor, wall) = (planes[0], planes[1]);
        assert!(
            floor.0.normal.y.abs() > 1.0 - 1e-9 && floor.1 >= 400,
            "{floor:?}"
        );
        assert!(floor.1 < 400 + 5, "{floor:?}");
        assert!(
            wall.0.normal.x.abs() > 1.0 - 1e-9 && wall.1 >= 150,
            "{wall:?}"
        );
        assert!((wall.0.distance(DVec3::new(1.5, 0.0, 0.0))).abs() < 1e-9);
    }

    /// A plane parallel to a face of the bounds and within the margin of
    /// it is that face; one further in, or tilted by 5°, is not.
    #[test]
    fn a_plane_on_a_face_of_the_bounds_is_told_from_one_inside_them() {
        let bounds = Aabb::new(DVec3::new(-1.0, -0.1, -1.0), DVec3::new(1.0, 1.4, 1.0));
        let at = |normal: DVec3, x: DVec3| Plane {
            normal,
            offset: -normal.dot(x),
        };
        let margin = 0.03;
        assert!(on_a_face_of(
            &at(DVec3::Y, 1.38 * DVec3::Y),
            &bounds,
            margin
        ));
        assert!(on_a_face_of(
            &at(-DVec3::X, DVec3::new(0.99, 0.0, 0.0)),
            &bounds,
            margin
        ));
        assert!(on_a_face_of(
            &at(DVec3::Z, DVec3::new(0.0, 0.0, -1.02)),
            &bounds,
            margin
        ));
        assert!(!on_a_face_of(&at(DVec3::Y, DVec3::ZERO), &bounds, margin));
        assert!(!on_a_face_of(
            &at(DVec3::X, DVec3::new(0.9, 0.0, 0.0)),
            &bounds,
            margin
        ));
        let tilted = DVec3::new(5f64.to_radians().sin(), 5f64.to_radians().cos(), 0.0);
        assert!(!on_a_face_of(&at(tilted, 1.4 * DVec3::Y), &bounds, margin));
    }

    /// A plane's normal is turned toward the rays that placed its points
    /// (most of them), whichever way it was found; points off the plane
    /// have no say.
    #[test]
    fn a_plane_faces_the_cameras_that_placed_it() {
        let up = Plane {
            normal: DVec3::Y,
            offset: 0.0,
        };
        let down = Plane {
            normal: -DVec3::Y,
            offset: 0.0,
        };
        let seen_from_above: Vec<(DVec3, DVec3)> = (0..10)
            .map(|i| {
                (
                    DVec3::new(i as f64 * 0.1, 0.0, 0.0),
                    DVec3::new(0.3, -1.0, 0.0),
                )
            })
            .chain((0..3).map(|i| (DVec3::new(i as f64, 0.0, 1.0), DVec3::Y)))
            .chain((0..20).map(|i| (DVec3::new(i as f64, 5.0, 0.0), DVec3::Y)))
            .collect();
        for p in [up, down] {
            assert_eq!(facing_its_cameras(p, &seen_from_above, 0.01), up);
        }
        let seen_from_below: Vec<(DVec3, DVec3)> =
            seen_from_above.iter().map(|(x, d)| (*x, -*d)).collect();
        assert_eq!(facing_its_cameras(up, &seen_from_below, 0.01), down);
    }

    /// Up to [`PLANE_PIXELS`] every pixel; a hundred 800 × 800 views
    /// (64 million) on every eighth of every eighth row: a million.
    #[test]
    fn planes_are_sought_on_a_lattice_of_a_million_pixels_at_most() {
        assert_eq!(plane_stride(0), 1);
        assert_eq!(plane_stride(PLANE_PIXELS), 1);
        assert_eq!(plane_stride(PLANE_PIXELS + 1), 2);
        assert_eq!(plane_stride(100 * 800 * 800), 8);
        let read = (800u64.div_ceil(8)).pow(2) * 100;
        assert!(read <= PLANE_PIXELS, "{read}");
    }

    /// A field over [−1, 1]³ of 33 nodes a side: an opaque grey floor at
    /// y = −0.5, bare where x < 0 and z < 0; from two nodes above it, a
    /// grey haze of optical depth 2 where x > 0 (what photographs of a plain floor
    /// leave); a green one of the same density where x < 0 and z > 0 (a
    /// medium).
    fn hazy_floor() -> GridField {
        let n = 33u32;
        let h = 2.0 / (n - 1) as f64;
        let mut nodes = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let (x, y, z) = (
                        -1.0 + i as f64 * h,
                        -1.0 + j as f64 * h,
                        -1.0 + k as f64 * h,
                    );
                    let above = y > -0.5 + 1.5 * h && y <= 0.5;
                    nodes.push(if y <= -0.5 {
                        [0.5, 0.5, 0.5, 400.0]
                    } else if above && x > 0.5 * h {
                        [0.5, 0.5, 0.5, 2.0]
                    } else if above && x < -0.5 * h && z > 0.5 * h {
                        [0.1, 0.6, 0.1, 2.0]
                    } else {
                        [0.5, 0.5, 0.5, 0.0]
                    });
                }
            }
        }
        let bounds = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        GridField::new(UVec3::splat(n), bounds, nodes, DEFAULT_OCCUPANCY_BLOCK)
    }

    /// The floor's bare quarter places it, so the first plane found is the
    /// floor, holding nearly all the placed points; the grey haze's pixels take the floor's depth; the green
    /// medium's are left alone; a frame that records depth, and one not
    /// asked for, get no map.
    /// Where a ray's weight is spent in front of the plane, the plane's
    /// colour is the one the photographs show on it nearby, not the
    /// field's there (the back face behind the surface it shows); where
    /// the plane's stretch holds weight, that weight's colour stands.
    #[test]
    fn a_plane_the_ray_never_reaches_is_of_the_colour_seen_on_it() {
        let field = hazy_floor();
        let ray = Ray {
            origin: DVec3::ZERO,
            dir: DVec3::X,
        };
        let tan = DVec3::new(0.6, 0.5, 0.4);
        let blue = DVec3::new(0.1, 0.2, 0.6);
        let sample = |t: f64, weight: f64, colour: DVec3| MarchSample {
            x: ray.at(t),
            t,
            a: t - 0.05,
            b: t + 0.05,
            sigma: 1.0,
            colour,
            transmittance: 1.0,
            weight,
        };
        // 0.9 of the weight smeared in front, the wall's colour; a
        // hundredth at the plane, the back face's.
        let mut spent: Vec<MarchSample> = (0..4)
            .map(|i| sample(0.5 + 0.1 * i as f64, 0.225, tan))
            .collect();
        spent.push(sample(1.1, 0.01, blue));
        let same = |samples: &[MarchSample], seen| {
            same_colour_in_front(&field, &ray, samples, 1.0, 1.2, seen)
        };
        assert!(!same(&spent, None), "against the back face: a medium");
        assert!(same(&spent, Some(DVec3::new(0.62, 0.5, 0.41))));
        assert!(
            !same(&spent, Some(DVec3::new(0.1, 0.6, 0.1))),
            "a green plane"
        );
        // Weight at the plane: its own colour, whatever was seen near.
        let mut reached = spent.clone();
        reached.last_mut().unwrap().weight = 0.3;
        assert!(!same(&reached, Some(tan)));
        reached.last_mut().unwrap().colour = tan;
        assert!(same(&reached, Some(blue)));
        // Spent before the plane, the field's colour there still counts
        // where it matches (a thick surface of one colour).
        let mut thick = spent.clone();
        thick.last_mut().unwrap().colour = tan;
        assert!(same(&thick, Some(DVec3::new(0.1, 0.6, 0.1))));
        assert!(same(&thick, None));
    }

    #[test]
    fn open_pixels_over_a_placed_floor_take_its_depth_and_a_medium_keeps_its_own() {
        let field = hazy_floor();
        let h = 2.0 / 32.0;
        let at = |eye: DVec3| {
            let mut f = frame();
            f.pose = Pose::looking_at(eye, DVec3::new(0.0, -0.5, 0.0), DVec3::Z);
            f
        };
        let mut recorded = at(DVec3::new(0.0, 3.0, 0.5));
        recorded.depth = vec![1.0; 32 * 32];
        let dataset = Dataset {
            file: "transforms.json".into(),
            dialect: Dialect::InstantNgp,
            frames: vec![
                at(DVec3::new(0.3, 2.5, 0.2)),
                at(DVec3::new(-1.2, 2.2, 0.6)),
                at(DVec3::new(1.0, 2.4, -1.1)),
                recorded,
            ],
            bounds: field.bounds,
            bounds_source: BoundsSource::AabbKey,
            counts: PixelCounts::default(),
            skipped: Vec::new(),
        };
        let c = complete_plain_surfaces(&dataset, &[0, 1, 3], &field, &march(), 1);
        // Where the field's floor lies: the expected depth of a ray down
        // onto its bare quarter.
        let down = Ray {
            origin: DVec3::new(-0.5, 0.9, -0.5),
            dir: -DVec3::Y,
        };
        let surface = down
            .at(ray_weights(&field, &down, &march(), 0.0).unwrap().mean)
            .y;
        let (floor, held) = c.planes[0];
        assert!(floor.normal.y.abs() > 0.999, "{:?}", c.planes);
        assert!(held as f64 > 0.9 * c.placed as f64, "{c:?}");
        let y = -floor.offset / floor.normal.y;
        assert!((y - surface).abs() < 0.5 * h, "{floor:?} against {surface}");
        assert!(c.open > 0 && c.completed > 0 && c.media > 0, "{c:?}");
        assert!(c.completed + c.media <= c.open);
        assert!(c.depth[2].is_empty() && c.depth[3].is_empty());
        let (mut checked, mut under_grey) = (0, 0);
        for f in [0usize, 1] {
            let frame = &dataset.frames[f];
            assert_eq!(c.depth[f].len(), 32 * 32);
            for (p, &z) in c.depth[f].iter().enumerate() {
                if z == 0.0 {
                    continue;
                }
                let ray = pixel_ray(frame, p as u32).unwrap();
                let x = ray.at(z as f64 / ray.dir.dot(frame.pose.forward()));
                // On the floor; never deep under the green medium, where
                // every camera's ray crosses its whole depth.
                assert!(floor.distance(x).abs() < 1e-4, "{x}");
                assert!(!(x.x < -0.3 && x.z > 0.3), "{x}");
                under_grey += (x.x > 0.3) as usize;
                checked += 1;
            }
        }
        assert_eq!(checked, c.completed);
        assert_eq!(c.depths, c.completed, "every pixel read: none filled");
        assert!(under_grey > 200, "{under_grey} of {checked}");
    }

    /// Read on a lattice (every second pixel of every second row), each
    /// pixel between takes the depth of the plane all the lattice pixels
    /// around it were completed by: the depth the full march gives it
    /// wherever both give one, never one under the medium, and most of the
    /// full march's.
    #[test]
    fn pixels_between_a_lattice_take_the_plane_their_neighbours_agree_on() {
        let field = hazy_floor();
        let mut frame = frame();
        frame.pose = Pose::looking_at(
            DVec3::new(0.3, 2.5, 0.2),
            DVec3::new(0.0, -0.5, 0.0),
            DVec3::Z,
        );
        let dataset = Dataset {
            file: "transforms.json".into(),
            dialect: Dialect::InstantNgp,
            frames: vec![frame.clone()],
            bounds: field.bounds,
            bounds_source: BoundsSource::AabbKey,
            counts: PixelCounts::default(),
            skipped: Vec::new(),
        };
        let full = complete_on_lattice(&dataset, &[0], &field, &march(), 1, u64::MAX);
        let read = complete_on_lattice(&dataset, &[0], &field, &march(), 1, 32 * 32 / 4);
        assert_eq!((full.stride, read.stride), (1, 2));
        assert_eq!(read.planes, full.planes, "the same placed points");
        assert!(read.completed < read.depths, "{read:?}");
        let (mut both, mut only_full) = (0, 0);
        for (p, (&a, &b)) in full.depth[0].iter().zip(&read.depth[0]).enumerate() {
            if b > 0.0 {
                let ray = pixel_ray(&frame, p as u32).unwrap();
                let x = ray.at(b as f64 / ray.dir.dot(frame.pose.forward()));
                assert!(!(x.x < -0.3 && x.z > 0.3), "{x}");
            }
            match (a > 0.0, b > 0.0) {
                (true, true) => {
                    assert!((a - b).abs() <= 1e-5 * a, "pixel {p}: {a} against {b}");
                    both += 1;
                }
                (true, false) => only_full += 1,
                _ => {}
            }
        }
        assert!(
            both > 2 * only_full,
            "{both} given by both, {only_full} by the full march alone"
        );
    }
}
