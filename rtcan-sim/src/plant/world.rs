//! Obstacles as line segments: walls, and boxes as their four sides.

/// A wall from `a` to `b` (world coordinates, m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    pub a: (f64, f64),
    pub b: (f64, f64),
}

impl Segment {
    /// Distance along the ray `origin + t·dir` (`dir` unit length) to this segment, if
    /// the ray hits it at `t >= 0`.
    pub fn ray_hit(&self, origin: (f64, f64), dir: (f64, f64)) -> Option<f64> {
        let e = (self.b.0 - self.a.0, self.b.1 - self.a.1);
        let denom = cross(dir, e);
        if denom.abs() < 1e-12 {
            return None; // parallel: a grazing ray does not return an echo
        }
        let w = (self.a.0 - origin.0, self.a.1 - origin.1);
        let t = cross(w, e) / denom;
        let u = cross(w, dir) / denom;
        (t >= 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
    }

    /// Shortest distance from `p` to the segment.
    pub fn distance_to(&self, p: (f64, f64)) -> f64 {
        let e = (self.b.0 - self.a.0, self.b.1 - self.a.1);
        let len2 = e.0 * e.0 + e.1 * e.1;
        let s = if len2 > 0.0 {
            (((p.0 - self.a.0) * e.0 + (p.1 - self.a.1) * e.1) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let q = (self.a.0 + s * e.0, self.a.1 + s * e.1);
        ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt()
    }
}

fn cross(a: (f64, f64), b: (f64, f64)) -> f64 {
    a.0 * b.1 - a.1 * b.0
}

/// The static world the robot drives in.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct World {
    pub segments: Vec<Segment>,
}

impl World {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn with_wall(mut self, a: (f64, f64), b: (f64, f64)) -> Self {
        self.segments.push(Segment { a, b });
        self
    }

    /// Axis-aligned box from corner `min` to corner `max`.
    pub fn with_box(self, min: (f64, f64), max: (f64, f64)) -> Self {
        let (x0, y0, x1, y1) = (min.0, min.1, max.0, max.1);
        self.with_wall((x0, y0), (x1, y0))
            .with_wall((x1, y0), (x1, y1))
            .with_wall((x1, y1), (x0, y1))
            .with_wall((x0, y1), (x0, y0))
    }

    /// Nearest hit along a ray, m.
    pub fn ray_cast(&self, origin: (f64, f64), dir: (f64, f64)) -> Option<f64> {
        self.segments
            .iter()
            .filter_map(|s| s.ray_hit(origin, dir))
            .min_by(f64::total_cmp)
    }

    /// Distance from `p` to the nearest obstacle (∞ in an empty world).
    pub fn clearance(&self, p: (f64, f64)) -> f64 {
        self.segments
            .iter()
            .map(|s| s.distance_to(p))
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_hits_wall_ahead_not_behind() {
        let w = World::new().with_wall((2.0, -1.0), (2.0, 1.0));
        assert_eq!(w.ray_cast((0.5, 0.0), (1.0, 0.0)), Some(1.5));
        assert_eq!(w.ray_cast((0.5, 0.0), (-1.0, 0.0)), None);
        // Past the wall's end.
        assert_eq!(w.ray_cast((0.0, 1.5), (1.0, 0.0)), None);
    }

    #[test]
    fn nearest_side_of_a_box() {
        let w = World::new().with_box((1.0, -0.5), (2.0, 0.5));
        assert_eq!(w.ray_cast((0.0, 0.0), (1.0, 0.0)), Some(1.0));
        assert_eq!(w.clearance((0.0, 0.0)), 1.0);
        assert!((w.clearance((0.0, 1.5)) - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(World::new().clearance((0.0, 0.0)), f64::INFINITY);
    }
}
