//! Planar shapes for the simulator: segments, circles, rays, and the robot's
//! rectangle.

/// A point or vector on the plane, metres.
pub type Point = (f64, f64);

/// A straight wall piece.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// One end.
    pub a: Point,
    /// The other end.
    pub b: Point,
}

/// A round obstacle (a person).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Circle {
    /// Centre.
    pub c: Point,
    /// Radius, m.
    pub r: f64,
}

fn cross(a: Point, b: Point) -> f64 {
    a.0 * b.1 - a.1 * b.0
}

fn sub(a: Point, b: Point) -> Point {
    (a.0 - b.0, a.1 - b.1)
}

fn dot(a: Point, b: Point) -> f64 {
    a.0 * b.0 + a.1 * b.1
}

impl Segment {
    /// A segment from `a` to `b`.
    pub const fn new(a: Point, b: Point) -> Self {
        Segment { a, b }
    }

    /// Distance along the ray from `origin` in unit direction `dir` to this
    /// segment, if the ray hits it.
    pub fn ray_hit(&self, origin: Point, dir: Point) -> Option<f64> {
        self.ray_hit_at(origin, dir).map(|(t, _)| t)
    }

    /// Where the ray from `origin` along `dir` hits this segment: the ray's
    /// parameter (in lengths of `dir`) and the share of the way from `a` to
    /// `b`.
    pub fn ray_hit_at(&self, origin: Point, dir: Point) -> Option<(f64, f64)> {
        let e = sub(self.b, self.a);
        let denom = cross(dir, e);
        if denom.abs() < 1e-12 {
            return None;
        }
        let w = sub(self.a, origin);
        let t = cross(w, e) / denom;
        let s = cross(w, dir) / denom;
        (t >= 0.0 && (0.0..=1.0).contains(&s)).then_some((t, s))
    }

    /// Whether this segment crosses the segment `p`–`q` (touching counts).
    pub fn crosses(&self, p: Point, q: Point) -> bool {
        let d1 = cross(sub(self.b, self.a), sub(p, self.a));
        let d2 = cross(sub(self.b, self.a), sub(q, self.a));
        let d3 = cross(sub(q, p), sub(self.a, p));
        let d4 = cross(sub(q, p), sub(self.b, p));
        d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && !(d1 == 0.0 && d2 == 0.0 && (d3 != 0.0 || d4 != 0.0))
    }

    /// The shortest distance from `p` to the segment.
    pub fn distance_to(&self, p: Point) -> f64 {
        let e = sub(self.b, self.a);
        let len2 = dot(e, e);
        let t = if len2 > 0.0 { (dot(sub(p, self.a), e) / len2).clamp(0.0, 1.0) } else { 0.0 };
        let closest = (self.a.0 + t * e.0, self.a.1 + t * e.1);
        (p.0 - closest.0).hypot(p.1 - closest.1)
    }
}

impl Circle {
    /// Distance along the ray from `origin` in unit direction `dir` to the
    /// circle's edge, if the ray hits it from outside.
    pub fn ray_hit(&self, origin: Point, dir: Point) -> Option<f64> {
        let oc = sub(origin, self.c);
        let b = dot(oc, dir);
        let c = dot(oc, oc) - self.r * self.r;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let t = -b - disc.sqrt();
        (t >= 0.0).then_some(t)
    }
}

/// A convex quadrilateral given counter-clockwise (the robot's footprint in
/// the world).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad(pub [Point; 4]);

impl Quad {
    fn edges(&self) -> impl Iterator<Item = (Point, Point)> + '_ {
        (0..4).map(move |i| (self.0[i], self.0[(i + 1) % 4]))
    }

    /// Whether `p` lies inside (or on the edge).
    pub fn contains(&self, p: Point) -> bool {
        self.edges().all(|(a, b)| cross(sub(b, a), sub(p, a)) >= 0.0)
    }

    /// Whether the segment touches the quadrilateral.
    pub fn touches_segment(&self, s: &Segment) -> bool {
        self.contains(s.a) || self.contains(s.b) || self.edges().any(|(a, b)| s.crosses(a, b))
    }

    /// Whether the circle touches the quadrilateral.
    pub fn touches_circle(&self, c: &Circle) -> bool {
        self.contains(c.c) || self.edges().any(|(a, b)| Segment::new(a, b).distance_to(c.c) <= c.r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_hits_segment_ahead_only() {
        let wall = Segment::new((2.0, -1.0), (2.0, 1.0));
        assert_eq!(wall.ray_hit((0.0, 0.0), (1.0, 0.0)), Some(2.0));
        assert_eq!(wall.ray_hit((0.0, 0.0), (-1.0, 0.0)), None);
        assert_eq!(wall.ray_hit((0.0, 5.0), (1.0, 0.0)), None);
    }

    #[test]
    fn ray_hits_circle_edge() {
        let c = Circle { c: (5.0, 0.0), r: 1.0 };
        assert!((c.ray_hit((0.0, 0.0), (1.0, 0.0)).unwrap() - 4.0).abs() < 1e-12);
        assert_eq!(c.ray_hit((0.0, 0.0), (0.0, 1.0)), None);
    }

    #[test]
    fn quad_touches() {
        let q = Quad([(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)]);
        assert!(q.touches_segment(&Segment::new((0.5, 5.0), (0.5, -5.0))));
        assert!(q.touches_segment(&Segment::new((0.0, 0.0), (0.1, 0.1))));
        assert!(!q.touches_segment(&Segment::new((1.5, 5.0), (1.5, -5.0))));
        assert!(q.touches_circle(&Circle { c: (1.5, 0.0), r: 0.6 }));
        assert!(!q.touches_circle(&Circle { c: (1.7, 0.0), r: 0.6 }));
    }
}
