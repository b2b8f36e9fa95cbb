//! Convex polygons in a plane, split by lines with the "fuzzy" side tests of
//! beam tracing (Overbeck, Ramamoorthi & Mark 2007, appendix): what the exact
//! visibility of [`super::exact`] uses to subtract occluders from the light.
//!
//! Everything is `f64`. A vertex within [`Fuzz::on_line`] of a line counts as
//! on it and goes to both sides, so a polygon that merely touches a line (a
//! shared edge, a corner on an edge) is not split into a sliver and the rest.

use glam::DVec2;

/// A convex polygon, counter-clockwise or clockwise (splitting keeps the order).
pub type Polygon = Vec<DVec2>;

/// A line as the signed distance `n·p + d` (`|n| = 1`); the half-plane `≥ 0`
/// is its positive side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// Unit normal, pointing to the positive side.
    pub n: DVec2,
    /// Offset: the signed distance of the origin.
    pub d: f64,
}

impl Line {
    /// The line `a + b·x + c·y = 0` with positive side `a + b·x + c·y > 0`;
    /// `None` when `(b, c) = 0` (a line at infinity: one side holds the whole plane).
    pub fn from_coefficients(a: f64, b: f64, c: f64) -> Option<Line> {
        let len = b.hypot(c);
        (len > 0.0).then(|| Line {
            n: DVec2::new(b, c) / len,
            d: a / len,
        })
    }

    /// Signed distance of `p`.
    pub fn distance(&self, p: DVec2) -> f64 {
        self.n.dot(p) + self.d
    }
}

/// Tolerances of the splitting, in the plane's units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fuzz {
    /// A vertex closer than this to a line is on it (on both sides).
    pub on_line: f64,
    /// A piece whose mean width (area over half the perimeter) is below this
    /// is a sliver and is dropped.
    pub min_width: f64,
}

/// Where a polygon lies relative to a line.
#[derive(Clone, Debug, PartialEq)]
pub enum Split {
    /// Wholly on the negative side (vertices on the line allowed).
    Negative,
    /// Wholly on the positive side (vertices on the line allowed), or on the line.
    Positive,
    /// Cut in two.
    Both {
        /// The part on the negative side.
        negative: Polygon,
        /// The part on the positive side.
        positive: Polygon,
    },
}

/// Sutherland–Hodgman against both sides at once, with fuzzy vertex classes.
pub fn split(poly: &[DVec2], line: &Line, fuzz: &Fuzz) -> Split {
    let mut dist = [0.0f64; 16];
    let mut dist_vec = Vec::new();
    let dist: &mut [f64] = if poly.len() <= dist.len() {
        &mut dist[..poly.len()]
    } else {
        dist_vec.resize(poly.len(), 0.0);
        &mut dist_vec
    };
    let (mut any_neg, mut any_pos) = (false, false);
    for (d, p) in dist.iter_mut().zip(poly) {
        *d = line.distance(*p);
        any_neg |= *d < -fuzz.on_line;
        any_pos |= *d > fuzz.on_line;
    }
    if !any_neg {
        return Split::Positive;
    }
    if !any_pos {
        return Split::Negative;
    }
    let class = |d: f64| {
        if d > fuzz.on_line {
            1
        } else if d < -fuzz.on_line {
            -1
        } else {
            0
        }
    };
    let mut negative = Vec::with_capacity(poly.len() + 1);
    let mut positive = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let j = (i + 1) % poly.len();
        let (ci, cj) = (class(dist[i]), class(dist[j]));
        if ci >= 0 {
            positive.push(poly[i]);
        }
        if ci <= 0 {
            negative.push(poly[i]);
        }
        if ci * cj < 0 {
            // Both ends are clearly apart from the line: a well-conditioned crossing.
            let x = poly[i] + (poly[j] - poly[i]) * (dist[i] / (dist[i] - dist[j]));
            positive.push(x);
            negative.push(x);
        }
    }
    Split::Both { negative, positive }
}

/// Twice the signed area (shoelace).
fn twice_signed_area(poly: &[DVec2]) -> f64 {
    (0..poly.len())
        .map(|i| poly[i].perp_dot(poly[(i + 1) % poly.len()]))
        .sum()
}

/// Area of a polygon (either orientation).
pub fn area(poly: &[DVec2]) -> f64 {
    0.5 * twice_signed_area(poly).abs()
}

/// Whether a piece is too thin to keep: mean width below `fuzz.min_width`.
fn is_sliver(poly: &[DVec2], fuzz: &Fuzz) -> bool {
    let perimeter: f64 = (0..poly.len())
        .map(|i| (poly[(i + 1) % poly.len()] - poly[i]).length())
        .sum();
    poly.len() < 3 || area(poly) < fuzz.min_width * perimeter * 0.5
}

/// Appends to `out` the parts of convex `poly` outside the convex region
/// `⋂ {line ≥ 0}` (slivers dropped); the part inside is dropped.
///
/// One piece per line that cuts it, as in beam splitting: cut off the part
/// outside the first line and keep it, go on with the rest against the next
/// line, and drop what is left after the last.
pub fn subtract_convex(poly: Polygon, region: &[Line], fuzz: &Fuzz, out: &mut Vec<Polygon>) {
    // Wholly outside one line: untouched (the common case, checked before any cutting).
    let outside_one = region.iter().any(|l| {
        poly.iter().all(|&p| l.distance(p) <= fuzz.on_line)
            && poly.iter().any(|&p| l.distance(p) < -fuzz.on_line)
    });
    if outside_one {
        out.push(poly);
        return;
    }
    let mut rest = poly;
    for line in region {
        match split(&rest, line, fuzz) {
            Split::Positive => {}
            Split::Negative => {
                out.push(rest);
                return;
            }
            Split::Both { negative, positive } => {
                if !is_sliver(&negative, fuzz) {
                    out.push(negative);
                }
                rest = positive;
            }
        }
    }
}

/// The part of convex `poly` inside the convex region `⋂ {line ≥ 0}`, or
/// `None` when that is empty or a sliver.
pub fn intersect_convex(poly: &[DVec2], region: &[Line], fuzz: &Fuzz) -> Option<Polygon> {
    let mut rest = poly.to_vec();
    for line in region {
        match split(&rest, line, fuzz) {
            Split::Positive => {}
            Split::Negative => return None,
            Split::Both { positive, .. } => rest = positive,
        }
    }
    (!is_sliver(&rest, fuzz)).then_some(rest)
}

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Smallest coordinates.
    pub lo: DVec2,
    /// Largest coordinates.
    pub hi: DVec2,
}

impl Bounds {
    /// The bounds of a polygon's vertices.
    pub fn of(poly: &[DVec2]) -> Bounds {
        poly.iter().fold(
            Bounds {
                lo: DVec2::INFINITY,
                hi: DVec2::NEG_INFINITY,
            },
            |b, &p| Bounds {
                lo: b.lo.min(p),
                hi: b.hi.max(p),
            },
        )
    }

    /// Whether the two boxes share more than a boundary.
    pub fn overlaps(&self, other: &Bounds) -> bool {
        self.lo.cmplt(other.hi).all() && other.lo.cmplt(self.hi).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FUZZ: Fuzz = Fuzz {
        on_line: 1e-9,
        min_width: 1e-9,
    };

    fn square() -> Polygon {
        vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ]
    }

    /// The half-plane `x ≥ x0` (positive side) as a line.
    fn right_of(x0: f64) -> Line {
        Line::from_coefficients(-x0, 1.0, 0.0).unwrap()
    }

    #[test]
    fn split_square_in_two() {
        let Split::Both { negative, positive } = split(&square(), &right_of(0.25), &FUZZ) else {
            panic!("must split");
        };
        assert!((area(&negative) - 0.25).abs() < 1e-15);
        assert!((area(&positive) - 0.75).abs() < 1e-15);
    }

    #[test]
    fn touching_line_does_not_split() {
        assert_eq!(split(&square(), &right_of(1.0 + 1e-12), &FUZZ), Split::Negative);
        assert_eq!(split(&square(), &right_of(-1e-12), &FUZZ), Split::Positive);
        assert_eq!(split(&square(), &right_of(0.0), &FUZZ), Split::Positive);
    }

    #[test]
    fn subtract_square_hole_leaves_frame() {
        // Region 0.25 ≤ x ≤ 0.75, 0.25 ≤ y ≤ 0.5.
        let region = [
            right_of(0.25),
            Line::from_coefficients(0.75, -1.0, 0.0).unwrap(),
            Line::from_coefficients(-0.25, 0.0, 1.0).unwrap(),
            Line::from_coefficients(0.5, 0.0, -1.0).unwrap(),
        ];
        let mut out = Vec::new();
        subtract_convex(square(), &region, &FUZZ, &mut out);
        let total: f64 = out.iter().map(|p| area(p)).sum();
        assert!((total - (1.0 - 0.5 * 0.25)).abs() < 1e-14, "{total}");
        assert_eq!(out.len(), 4, "one piece per cutting line");
    }

    #[test]
    fn subtract_disjoint_and_covering_regions() {
        let mut out = Vec::new();
        subtract_convex(square(), &[right_of(2.0)], &FUZZ, &mut out);
        assert_eq!(out, vec![square()]);
        out.clear();
        subtract_convex(square(), &[right_of(-1.0)], &FUZZ, &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn sliver_is_dropped() {
        let fuzz = Fuzz {
            min_width: 1e-6,
            ..FUZZ
        };
        let mut out = Vec::new();
        // Cuts off a strip 1e-7 wide: below min_width.
        subtract_convex(square(), &[right_of(1e-7)], &fuzz, &mut out);
        assert!(out.is_empty(), "{out:?}");
    }

    #[test]
    fn intersect_and_bounds() {
        let region = [right_of(0.25), Line::from_coefficients(-0.5, 0.0, 1.0).unwrap()];
        let piece = intersect_convex(&square(), &region, &FUZZ).unwrap();
        assert!((area(&piece) - 0.375).abs() < 1e-15);
        let b = Bounds::of(&piece);
        assert_eq!((b.lo, b.hi), (DVec2::new(0.25, 0.5), DVec2::new(1.0, 1.0)));
        assert!(b.overlaps(&Bounds::of(&square())));
        let beside = Bounds {
            lo: DVec2::new(1.0, 0.0),
            hi: DVec2::new(2.0, 1.0),
        };
        assert!(!b.overlaps(&beside), "sharing an edge is no overlap");
        assert_eq!(intersect_convex(&square(), &[right_of(1.5)], &FUZZ), None);
    }

    #[test]
    fn line_at_infinity_is_none() {
        assert_eq!(Line::from_coefficients(1.0, 0.0, 0.0), None);
    }
}
