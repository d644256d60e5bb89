//! Three-wheel omnidirectional base: wheel speeds → body twist → pose.
//!
//! The twist is found by solving the 3×3 wheel equations
//! `r ω_i = -sin(a_i) vx + cos(a_i) vy + L wz` directly (Cramer's rule) for any wheel
//! angles, so the plant does not share the node crate's closed-form 120° inverse: a bug
//! in one shows up as a mismatch against the other.

/// Body velocity: m/s, m/s, rad/s (x forward, y left, counter-clockwise).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Twist2 {
    pub vx: f64,
    pub vy: f64,
    pub wz: f64,
}

/// World pose: m, m, rad (heading unwrapped: it counts whole turns).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose2 {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

impl Pose2 {
    /// A body-frame point in world coordinates.
    pub fn transform(&self, bx: f64, by: f64) -> (f64, f64) {
        let (s, c) = self.theta.sin_cos();
        (self.x + c * bx - s * by, self.y + s * bx + c * by)
    }
}

/// Wheel layout.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OmniGeometry {
    pub wheel_radius_m: f64,
    /// Centre-to-wheel distance `L`.
    pub base_radius_m: f64,
    /// Wheel angles from +x, rad.
    pub wheel_angles_rad: [f64; 3],
    /// Radius of the robot's footprint, for collision checks.
    pub body_radius_m: f64,
}

impl OmniGeometry {
    /// Triskar2: r = 0.05 m, L = 0.30 m, wheels at 60°, 180°, 300°, 60 cm footprint.
    pub const TRISKAR2: Self = Self {
        wheel_radius_m: 0.05,
        base_radius_m: 0.30,
        wheel_angles_rad: [
            std::f64::consts::FRAC_PI_3,
            std::f64::consts::PI,
            5.0 * std::f64::consts::FRAC_PI_3,
        ],
        body_radius_m: 0.30,
    };

    /// Row `i` of the wheel equations: coefficients of (vx, vy, wz) in `r ω_i`.
    fn rows(&self) -> [[f64; 3]; 3] {
        self.wheel_angles_rad
            .map(|a| [-a.sin(), a.cos(), self.base_radius_m])
    }

    /// Body twist → wheel speeds, rad/s.
    pub fn wheel_speeds(&self, t: Twist2) -> [f64; 3] {
        self.rows()
            .map(|[a, b, c]| (a * t.vx + b * t.vy + c * t.wz) / self.wheel_radius_m)
    }

    /// Wheel speeds → body twist; `None` if the wheel layout is singular.
    pub fn twist(&self, wheels_rad_s: [f64; 3]) -> Option<Twist2> {
        let [r0, r1, r2] = self.rows();
        let rhs = wheels_rad_s.map(|w| w * self.wheel_radius_m);
        let det = det3(r0, r1, r2);
        if det.abs() < 1e-12 {
            return None;
        }
        // Cramer: replace column j with the right-hand side.
        let col = |j: usize| {
            let sub = |row: [f64; 3], v: f64| {
                let mut r = row;
                if let Some(x) = r.get_mut(j) {
                    *x = v;
                }
                r
            };
            let [v0, v1, v2] = rhs;
            det3(sub(r0, v0), sub(r1, v1), sub(r2, v2)) / det
        };
        Some(Twist2 {
            vx: col(0),
            vy: col(1),
            wz: col(2),
        })
    }
}

fn det3([a0, a1, a2]: [f64; 3], [b0, b1, b2]: [f64; 3], [c0, c1, c2]: [f64; 3]) -> f64 {
    a0 * (b1 * c2 - b2 * c1) - a1 * (b0 * c2 - b2 * c0) + a2 * (b0 * c1 - b1 * c0)
}

/// The moving base.
#[derive(Clone, Debug, PartialEq)]
pub struct OmniBase {
    geometry: OmniGeometry,
    pose: Pose2,
    twist: Twist2,
}

impl OmniBase {
    pub fn new(geometry: OmniGeometry, pose: Pose2) -> Self {
        Self {
            geometry,
            pose,
            twist: Twist2::default(),
        }
    }

    pub fn geometry(&self) -> &OmniGeometry {
        &self.geometry
    }

    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// The body twist of the last step.
    pub fn twist(&self) -> Twist2 {
        self.twist
    }

    /// Move for `dt_s` with the wheels at constant speeds (no slip). The constant body
    /// twist is integrated exactly (a circular arc), so the plant's pose is the ground
    /// truth odometry is judged against.
    pub fn step(&mut self, dt_s: f64, wheels_rad_s: [f64; 3]) {
        let Some(t) = self.geometry.twist(wheels_rad_s) else {
            return;
        };
        if dt_s.is_nan()
            || dt_s <= 0.0
            || !(t.vx.is_finite() && t.vy.is_finite() && t.wz.is_finite())
        {
            return;
        }
        self.twist = t;
        let th0 = self.pose.theta;
        let dth = t.wz * dt_s;
        // ∫ R(θ0 + wz τ) dτ over [0, dt]: (S, C) below; straight-line limit for small wz.
        let (s_int, c_int) = if dth.abs() < 1e-9 {
            (th0.cos() * dt_s, th0.sin() * dt_s)
        } else {
            (
                ((th0 + dth).sin() - th0.sin()) / t.wz,
                (th0.cos() - (th0 + dth).cos()) / t.wz,
            )
        };
        self.pose.x += s_int * t.vx - c_int * t.vy;
        self.pose.y += c_int * t.vx + s_int * t.vy;
        self.pose.theta = th0 + dth;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const G: OmniGeometry = OmniGeometry::TRISKAR2;

    #[test]
    fn twist_inverts_wheel_speeds() {
        let t = Twist2 {
            vx: 0.4,
            vy: -1.1,
            wz: 2.3,
        };
        let back = G.twist(G.wheel_speeds(t)).unwrap();
        assert!((back.vx - t.vx).abs() < 1e-12);
        assert!((back.vy - t.vy).abs() < 1e-12);
        assert!((back.wz - t.wz).abs() < 1e-12);
    }

    #[test]
    fn forward_wheel_speeds_match_the_layout() {
        let w = G.wheel_speeds(Twist2 {
            vx: 1.0,
            vy: 0.0,
            wz: 0.0,
        });
        let s = 3f64.sqrt() / 2.0 / 0.05;
        assert!((w[0] + s).abs() < 1e-12 && w[1].abs() < 1e-12 && (w[2] - s).abs() < 1e-12);
    }

    #[test]
    fn singular_layout_is_rejected() {
        let g = OmniGeometry {
            wheel_angles_rad: [0.0, 0.0, PI],
            ..G
        };
        assert_eq!(g.twist([1.0, 1.0, 1.0]), None);
    }

    #[test]
    fn circle_is_exact_in_one_or_many_steps() {
        // v = 0.5 m/s, wz = π/4: radius 2/π m; after 2 s (quarter turn) at (R, R).
        let t = Twist2 {
            vx: 0.5,
            vy: 0.0,
            wz: PI / 4.0,
        };
        let r = 0.5 / (PI / 4.0);
        let w = G.wheel_speeds(t);
        let mut one = OmniBase::new(G, Pose2::default());
        one.step(2.0, w);
        let mut many = OmniBase::new(G, Pose2::default());
        for _ in 0..400 {
            many.step(0.005, w);
        }
        for p in [one.pose(), many.pose()] {
            assert!((p.x - r).abs() < 1e-9 && (p.y - r).abs() < 1e-9, "{p:?}");
            assert!((p.theta - PI / 2.0).abs() < 1e-9);
        }
    }

    #[test]
    fn sideways_in_rotated_frame() {
        let mut b = OmniBase::new(
            G,
            Pose2 {
                x: 1.0,
                y: 2.0,
                theta: PI / 2.0,
            },
        );
        // Body +y (left) while facing +y: world -x.
        b.step(
            1.0,
            G.wheel_speeds(Twist2 {
                vx: 0.0,
                vy: 0.3,
                wz: 0.0,
            }),
        );
        let p = b.pose();
        assert!(
            (p.x - 0.7).abs() < 1e-12 && (p.y - 2.0).abs() < 1e-12,
            "{p:?}"
        );
    }
}
