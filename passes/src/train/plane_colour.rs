//! The colour the photographs show on a plane near a point: the mean
//! colour of the placed points the plane holds about it. The completion's
//! colour rule ([`super::planes::same_colour_in_front`]) compares a ray's
//! weight in front of a plane with the plane's colour; where the ray's own
//! weight does not reach the plane (spent in front of it), the field's
//! colour there is whatever lies behind the surface it shows, which no
//! photograph sees along that ray (CUPS' back wall: the bluish back face
//! behind the lit front one, `docs/benchmarks.md`, issue 25's
//! forty-seventh pass). The points the photographs placed on the plane
//! near it tell its colour instead.

use std::collections::HashMap;

use glam::{DVec3, IVec2};

use super::planes::Plane;

/// Node spacings about a point within which a plane's placed points give
/// its colour there: far enough to gather the points of a plain surface
/// the rays left open (a wall's open stretch spans tens of spacings), near
/// enough to keep a surface's parts of other colours apart (a third of the
/// bundled scenes' width at 128³).
pub const PLANE_COLOUR_REACH: f64 = 40.0;

/// Cells across the reach: a plane's colour is read on square cells of
/// this fraction of the reach laid over it, so that it costs one lookup a
/// ray however many points and rays there are.
pub const PLANE_COLOUR_CELLS: i32 = 4;

/// Placed points a plane must hold within the reach for their colour to
/// stand for it: one or two are as likely a stray point as the surface.
pub const PLANE_COLOUR_POINTS: usize = 3;

/// The colour each plane shows about each point of it, read from the
/// placed points on it ([`PlaneColours::new`]).
#[derive(Debug, Clone)]
pub struct PlaneColours {
    cell: f64,
    planes: Vec<PlaneCells>,
}

/// One plane's cells: the axes across it, the first cell of the rectangle
/// its points' cells (and the reach about them) cover, the rectangle's
/// width in cells, and each cell's colour.
#[derive(Debug, Clone)]
struct PlaneCells {
    axes: (DVec3, DVec3),
    first: IVec2,
    width: i32,
    colours: Vec<Option<DVec3>>,
}

impl PlaneCells {
    /// The cell of `x`'s projection onto the plane.
    fn cell_of(&self, x: DVec3, cell: f64) -> IVec2 {
        IVec2::new(
            (x.dot(self.axes.0) / cell).floor() as i32,
            (x.dot(self.axes.1) / cell).floor() as i32,
        )
    }
}

impl PlaneColours {
    /// Lays square cells of `reach` / [`PLANE_COLOUR_CELLS`] over each
    /// plane of `planes` and files under it each placed point (position,
    /// direction of the ray that placed it, colour) that lies on it
    /// (within `tolerance`) and was placed from the side it faces: its
    /// colour is the one that side shows. A cell's colour is the mean of
    /// the points filed in the cells whose centres lie within `reach` of
    /// its centre, none where fewer than [`PLANE_COLOUR_POINTS`] are.
    /// `colours` holds one colour for each of `placed`; `reach` is in the
    /// points' units.
    pub fn new(
        planes: &[Plane],
        placed: &[(DVec3, DVec3)],
        colours: &[DVec3],
        tolerance: f64,
        reach: f64,
    ) -> PlaneColours {
        debug_assert_eq!(placed.len(), colours.len(), "a colour for each point");
        let cell = reach / PLANE_COLOUR_CELLS as f64;
        let r = PLANE_COLOUR_CELLS;
        let within: Vec<IVec2> = (-r..=r)
            .flat_map(|j| (-r..=r).map(move |i| IVec2::new(i, j)))
            .filter(|d| d.length_squared() <= r * r)
            .collect();
        let planes = planes
            .iter()
            .map(|plane| {
                let mut cells = PlaneCells {
                    axes: plane.normal.any_orthonormal_pair(),
                    first: IVec2::ZERO,
                    width: 0,
                    colours: Vec::new(),
                };
                let mut filed: HashMap<IVec2, (DVec3, usize)> = HashMap::new();
                for (&(x, d), &c) in placed.iter().zip(colours) {
                    if plane.distance(x).abs() < tolerance && plane.normal.dot(d) < 0.0 {
                        let e = filed.entry(cells.cell_of(x, cell)).or_default();
                        e.0 += c;
                        e.1 += 1;
                    }
                }
                let Some(low) = filed.keys().copied().reduce(IVec2::min) else {
                    return cells;
                };
                let high = filed.keys().copied().fold(low, IVec2::max);
                cells.first = low - IVec2::splat(r);
                let size = high - low + IVec2::splat(2 * r + 1);
                cells.width = size.x;
                cells.colours = (0..size.y)
                    .flat_map(|j| (0..size.x).map(move |i| IVec2::new(i, j)))
                    .map(|at| {
                        let (sum, count) = within
                            .iter()
                            .filter_map(|d| filed.get(&(cells.first + at + *d)))
                            .fold((DVec3::ZERO, 0), |(s, n), (c, m)| (s + *c, n + m));
                        (count >= PLANE_COLOUR_POINTS).then(|| sum / count as f64)
                    })
                    .collect();
                cells
            })
            .collect();
        PlaneColours { cell, planes }
    }

    /// The colour plane `k` shows about `x` (its cell's, [`Self::new`]);
    /// None where too few points lie within the reach.
    pub fn near(&self, k: usize, x: DVec3) -> Option<DVec3> {
        let cells = self.planes.get(k)?;
        let at = cells.cell_of(x, self.cell) - cells.first;
        let height = cells.colours.len() as i32 / cells.width.max(1);
        if at.x < 0 || at.y < 0 || at.x >= cells.width || at.y >= height {
            return None;
        }
        cells.colours[(at.y * cells.width + at.x) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    /// The cells give exactly what a search of all the points gives: the
    /// mean colour of those on the plane, placed from its side, whose
    /// cell's centre lies within the reach of the query's cell's centre.
    #[test]
    fn a_planes_colour_about_a_point_is_the_mean_of_its_points_within_reach() {
        let mut rng = Pcg32::new(7, 1);
        let mut within = |a: f64, b: f64| a + (b - a) * rng.next_f64();
        let plane = Plane {
            normal: DVec3::new(0.3, 1.0, -0.2).normalize(),
            offset: 0.1,
        };
        let (tolerance, reach) = (0.01, 0.3);
        let cell = reach / PLANE_COLOUR_CELLS as f64;
        let mut placed = Vec::new();
        let mut colours = Vec::new();
        for _ in 0..2000 {
            let x = DVec3::new(within(-1.0, 1.0), 0.0, within(-1.0, 1.0));
            let x = x - (plane.distance(x) + within(-0.02, 0.02)) * plane.normal;
            let up = within(0.0, 1.0) < 0.2;
            placed.push((x, if up { plane.normal } else { -plane.normal }));
            colours.push(DVec3::new(
                within(0.0, 1.0),
                within(0.0, 1.0),
                within(0.0, 1.0),
            ));
        }
        let filed = PlaneColours::new(&[plane], &placed, &colours, tolerance, reach);
        let (u, v) = plane.normal.any_orthonormal_pair();
        let cell_of = |x: DVec3| ((x.dot(u) / cell).floor(), (x.dot(v) / cell).floor());
        let (mut some, mut none) = (0, 0);
        for _ in 0..300 {
            let at = DVec3::new(within(-1.6, 1.6), within(-1.0, 1.0), within(-1.6, 1.6));
            let (a, b) = cell_of(at);
            let near: Vec<DVec3> = placed
                .iter()
                .zip(&colours)
                .filter(|((x, d), _)| {
                    let (i, j) = cell_of(*x);
                    plane.distance(*x).abs() < tolerance
                        && plane.normal.dot(*d) < 0.0
                        && ((i - a).powi(2) + (j - b).powi(2)).sqrt() * cell <= reach
                })
                .map(|(_, c)| *c)
                .collect();
            let expected = (near.len() >= PLANE_COLOUR_POINTS)
                .then(|| near.iter().sum::<DVec3>() / near.len() as f64);
            match (filed.near(0, at), expected) {
                (Some(got), Some(want)) => {
                    assert!((got - want).length() < 1e-12);
                    some += 1;
                }
                (got, want) => {
                    assert_eq!(got, want, "at {at}");
                    none += 1;
                }
            }
        }
        assert!(
            some > 100 && none > 20,
            "{some} with a colour, {none} without"
        );
        assert_eq!(filed.near(1, DVec3::ZERO), None, "no such plane");
        let empty = PlaneColours::new(&[plane], &[], &[], tolerance, reach);
        assert_eq!(empty.near(0, DVec3::ZERO), None, "a plane with no points");
    }

    /// A plane's colour is the side its points were placed from: a wall's
    /// back face, placed by rays from behind, lends it none.
    #[test]
    fn a_plane_takes_its_colour_from_the_side_it_faces() {
        let plane = Plane {
            normal: DVec3::Y,
            offset: 0.0,
        };
        let red = DVec3::new(1.0, 0.0, 0.0);
        let blue = DVec3::new(0.0, 0.0, 1.0);
        let mut placed = Vec::new();
        let mut colours = Vec::new();
        for i in 0..5 {
            let x = DVec3::new(0.01 * i as f64, 0.0, 0.0);
            placed.push((x, -DVec3::Y));
            colours.push(red);
            placed.push((x, DVec3::Y));
            colours.push(blue);
        }
        let filed = PlaneColours::new(&[plane], &placed, &colours, 0.01, 0.5);
        assert_eq!(filed.near(0, DVec3::ZERO), Some(red));
        // None within reach far along the plane.
        assert_eq!(filed.near(0, DVec3::new(1.0, 0.0, 0.0)), None);
    }
}
