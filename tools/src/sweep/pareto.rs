//! The Pareto front of (cost, error) points: those no other point beats
//! on both at once.

/// Indices of the points of `points` (cost, error) that no other point
/// dominates (no more cost and no more error, and less of one), ordered
/// by cost. Points with a non-finite coordinate are never on the front.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    // By cost, ties by error: each point is on the front when its error is
    // below every cheaper (or equally cheap, lower-error) point's.
    order.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dominated_points_are_left_out() {
        let p = [
            (10.0, 0.5),
            (20.0, 0.2),
            (15.0, 0.6), // dominated by (10, 0.5)
            (40.0, 0.05),
            (30.0, 0.3),  // dominated by (20, 0.2)
            (20.0, 0.25), // same cost, more error than (20, 0.2)
            (f64::NAN, 0.0),
        ];
        assert_eq!(pareto_front(&p), vec![0, 1, 3]);
    }

    #[test]
    fn empty_and_single() {
        assert!(pareto_front(&[]).is_empty());
        assert_eq!(pareto_front(&[(1.0, 1.0)]), vec![0]);
    }
}
