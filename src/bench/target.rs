//! The Pareto front of measured (frame time, error) points, and picking a configuration from it
//! for a quality target (`hybrid-rt render --target-ms T` or `--target-error E`).
//!
//! A point dominates another when it is no slower and no less accurate, and strictly better in
//! one of the two. The front is the set of points no other point dominates: for any time
//! budget the most accurate configuration within it lies on the front, and for any error bound
//! the fastest one within it does.

use anyhow::{Result, bail};

/// One measured configuration: frame time and error against the reference (lower is
/// better for both).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured {
    pub ms: f64,
    pub error: f64,
}

impl Measured {
    /// `self` is no worse than `other` in both and better in at least one.
    pub fn dominates(&self, other: &Measured) -> bool {
        self.ms <= other.ms && self.error <= other.error && (self.ms < other.ms || self.error < other.error)
    }
}

/// Indices of the points on the Pareto front, fastest first. Points with a non-finite time or
/// error are never on it. Of several identical points only the first is kept, so the front has
/// no duplicates (the others are equal to it, not dominated: they are simply left off).
pub fn pareto_front(points: &[Measured]) -> Vec<usize> {
    let finite = |p: &Measured| p.ms.is_finite() && p.error.is_finite();
    let mut front: Vec<usize> = (0..points.len())
        .filter(|&i| finite(&points[i]))
        .filter(|&i| !points.iter().any(|q| finite(q) && q.dominates(&points[i])))
        .collect();
    front.sort_by(|&a, &b| points[a].ms.total_cmp(&points[b].ms).then(a.cmp(&b)));
    front.dedup_by(|b, a| points[*a] == points[*b]);
    front
}

/// What the user asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// The most accurate configuration whose frame takes at most this many GPU ms.
    Ms(f64),
    /// The fastest configuration whose error (HDR-FLIP) is at most this.
    Error(f64),
}

/// The picked point and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Selection {
    pub index: usize,
    /// Whether the pick meets the target; when nothing does, the closest point is picked
    /// (the fastest for a time budget, the most accurate for an error bound).
    pub met: bool,
    pub why: String,
}

/// Picks a point of the front (see [`pareto_front`]) for `target`.
pub fn select(points: &[Measured], target: Target) -> Result<Selection> {
    let front = pareto_front(points);
    let (Some(&fastest), Some(&most_accurate)) = (front.first(), front.last()) else {
        bail!("no measured configuration with a finite frame time and error to choose from");
    };
    let p = |i: usize| points[i];
    Ok(match target {
        Target::Ms(t) => {
            // Along the front the error falls as the time grows: the last point within the
            // budget is the most accurate one.
            match front.iter().rev().find(|&&i| p(i).ms <= t) {
                Some(&i) => Selection {
                    index: i,
                    met: true,
                    why: format!(
                        "the most accurate measured configuration within {t} ms ({:.2} ms, FLIP {:.4})",
                        p(i).ms,
                        p(i).error
                    ),
                },
                None => Selection {
                    index: fastest,
                    met: false,
                    why: format!(
                        "no measured configuration fits in {t} ms; this is the fastest ({:.2} ms, FLIP {:.4})",
                        p(fastest).ms,
                        p(fastest).error
                    ),
                },
            }
        }
        Target::Error(e) => match front.iter().find(|&&i| p(i).error <= e) {
            Some(&i) => Selection {
                index: i,
                met: true,
                why: format!(
                    "the fastest measured configuration with FLIP <= {e} ({:.2} ms, FLIP {:.4})",
                    p(i).ms,
                    p(i).error
                ),
            },
            None => Selection {
                index: most_accurate,
                met: false,
                why: format!(
                    "no measured configuration reaches FLIP {e}; this is the most accurate ({:.2} ms, FLIP {:.4})",
                    p(most_accurate).ms,
                    p(most_accurate).error
                ),
            },
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts(v: &[(f64, f64)]) -> Vec<Measured> {
        v.iter().map(|&(ms, error)| Measured { ms, error }).collect()
    }

    #[test]
    fn front_holds_exactly_the_undominated_points() {
        let p = pts(&[(10.0, 0.3), (20.0, 0.2), (15.0, 0.35), (30.0, 0.1), (25.0, 0.2), (5.0, 0.5), (40.0, 0.1)]);
        assert_eq!(pareto_front(&p), vec![5, 0, 1, 3]);
        // Brute force: on the front iff nothing dominates it.
        let front = pareto_front(&p);
        for (i, a) in p.iter().enumerate() {
            assert_eq!(front.contains(&i), !p.iter().any(|b| b.dominates(a)), "point {i}");
        }
    }

    #[test]
    fn ties_and_non_finite_points() {
        let p = pts(&[(10.0, 0.2), (10.0, 0.2), (10.0, 0.3), (f64::NAN, 0.0), (1.0, f64::INFINITY)]);
        assert_eq!(pareto_front(&p), vec![0]);
        assert!(pareto_front(&[]).is_empty());
        assert!(select(&pts(&[(f64::NAN, 0.1)]), Target::Ms(1.0)).is_err());
    }

    #[test]
    fn selection_under_a_bound() {
        let p = pts(&[(10.0, 0.3), (20.0, 0.2), (30.0, 0.1), (25.0, 0.25)]);
        let s = select(&p, Target::Ms(22.0)).unwrap();
        assert_eq!((s.index, s.met), (1, true));
        assert_eq!(select(&p, Target::Ms(30.0)).unwrap().index, 2);
        let s = select(&p, Target::Ms(5.0)).unwrap();
        assert_eq!((s.index, s.met), (0, false));
        let s = select(&p, Target::Error(0.25)).unwrap();
        assert_eq!((s.index, s.met), (1, true));
        assert_eq!(select(&p, Target::Error(0.3)).unwrap().index, 0);
        let s = select(&p, Target::Error(0.05)).unwrap();
        assert_eq!((s.index, s.met), (2, false));
    }
}
