//! Odometry node: wheel speeds → body twist (forward kinematics) → integrated pose.

use crate::kinematics::{Geometry, Twist};
use crate::step_clock::StepClock;
use crate::Nanos;
use core::f32::consts::{PI, TAU};

/// Pose in the odometry frame (where the robot was at start or at the last reset).
/// Field names match robot.toml's `Odometry` type.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    /// m
    pub x: f32,
    /// m
    pub y: f32,
    /// Heading, wrapped to (-π, π].
    pub theta: f32,
}

/// One step's result: what the odometry node publishes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryOutput {
    pub twist: Twist,
    pub pose: Pose,
}

/// Integrates the pose from wheel speeds.
///
/// The body twist is rotated into the odometry frame at the mid-step heading, which is
/// second-order accurate for a constant twist (plain Euler with the start heading drifts
/// outwards on every arc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OdometryNode {
    geometry: Geometry,
    clock: StepClock,
    pose: Pose,
}

impl OdometryNode {
    /// `period_ns`: nominal interval between wheel-speed samples; gaps longer than four
    /// periods are integrated as four periods (a lost sample must not teleport the pose).
    pub const fn new(geometry: Geometry, period_ns: Nanos) -> Self {
        Self {
            geometry,
            clock: StepClock::new(period_ns, 4 * period_ns),
            pose: Pose {
                x: 0.0,
                y: 0.0,
                theta: 0.0,
            },
        }
    }

    pub const fn pose(&self) -> Pose {
        self.pose
    }

    pub fn reset(&mut self, pose: Pose) {
        self.pose = pose;
    }

    /// Integrate the wheel speeds (rad/s) measured at `now_ns` over the time since the
    /// previous step. Non-finite speeds are treated as a zero step (pose held).
    pub fn step(&mut self, now_ns: Nanos, wheels_rad_s: [f32; 3]) -> OdometryOutput {
        let dt = self.clock.dt_s(now_ns);
        let twist = self.geometry.forward(wheels_rad_s);
        if !twist.is_finite() {
            return OdometryOutput {
                twist: Twist::ZERO,
                pose: self.pose,
            };
        }
        let mid = self.pose.theta + 0.5 * twist.wz * dt;
        let (s, c) = crate::trig::sin_cos(mid);
        self.pose.x += (c * twist.vx - s * twist.vy) * dt;
        self.pose.y += (s * twist.vx + c * twist.vy) * dt;
        self.pose.theta = wrap_angle(self.pose.theta + twist.wz * dt);
        OdometryOutput {
            twist,
            pose: self.pose,
        }
    }
}

/// Wrap to (-π, π].
pub fn wrap_angle(a: f32) -> f32 {
    let w = a - TAU * libm::floorf((a + PI) / TAU);
    // floor puts exactly +π at -π; the convention here keeps +π.
    if w <= -PI {
        w + TAU
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::TRISKAR2;

    const PERIOD: Nanos = 10_000_000;

    fn run(node: &mut OdometryNode, twist: Twist, seconds: u32) -> OdometryOutput {
        let wheels = TRISKAR2.inverse(twist);
        let steps = seconds * 100;
        let mut out = node.step(0, wheels);
        for k in 1..steps {
            out = node.step(u64::from(k) * PERIOD, wheels);
        }
        out
    }

    #[test]
    fn straight_line_forward() {
        let mut n = OdometryNode::new(TRISKAR2, PERIOD);
        let out = run(
            &mut n,
            Twist {
                vx: 0.5,
                vy: 0.0,
                wz: 0.0,
            },
            2,
        );
        assert!((out.pose.x - 1.0).abs() < 1e-4, "{:?}", out.pose);
        assert!(out.pose.y.abs() < 1e-5 && out.pose.theta.abs() < 1e-6);
        assert!((out.twist.vx - 0.5).abs() < 1e-5);
    }

    #[test]
    fn rotated_heading_moves_in_world_frame() {
        let mut n = OdometryNode::new(TRISKAR2, PERIOD);
        n.reset(Pose {
            x: 0.0,
            y: 0.0,
            theta: PI / 2.0,
        });
        // Body +x while facing +y: world +y.
        let out = run(
            &mut n,
            Twist {
                vx: 0.5,
                vy: 0.0,
                wz: 0.0,
            },
            2,
        );
        assert!(out.pose.x.abs() < 1e-4 && (out.pose.y - 1.0).abs() < 1e-4);
    }

    #[test]
    fn full_circle_returns_to_start() {
        // v = 0.5 m/s, wz = π/4 rad/s: one lap in 8 s on a circle of radius 0.6366 m.
        let mut n = OdometryNode::new(TRISKAR2, PERIOD);
        let out = run(
            &mut n,
            Twist {
                vx: 0.5,
                vy: 0.0,
                wz: PI / 4.0,
            },
            8,
        );
        assert!(
            out.pose.x.abs() < 2e-3 && out.pose.y.abs() < 2e-3,
            "{:?}",
            out.pose
        );
        assert!(out.pose.theta.abs() < 1e-3);
        // Half-way (after 4 s) the robot is at the top of the circle: (0, 2R).
        let mut n = OdometryNode::new(TRISKAR2, PERIOD);
        let half = run(
            &mut n,
            Twist {
                vx: 0.5,
                vy: 0.0,
                wz: PI / 4.0,
            },
            4,
        );
        assert!(
            (half.pose.y - 2.0 * 0.5 / (PI / 4.0)).abs() < 2e-3,
            "{:?}",
            half.pose
        );
    }

    #[test]
    fn gap_is_clamped_and_nan_holds_pose() {
        let mut n = OdometryNode::new(TRISKAR2, PERIOD);
        let w = TRISKAR2.inverse(Twist {
            vx: 1.0,
            vy: 0.0,
            wz: 0.0,
        });
        n.step(0, w); // nominal first step: 0.01 m
        n.step(1_000_000_000, w); // 1 s gap counted as 40 ms
        assert!((n.pose().x - 0.05).abs() < 1e-5, "{:?}", n.pose());
        let before = n.pose();
        n.step(1_010_000_000, [f32::NAN, 0.0, 0.0]);
        assert_eq!(n.pose(), before);
    }

    #[test]
    fn wrap_angle_range() {
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-6);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-6);
        assert!((wrap_angle(-5.0 * PI / 2.0) + PI / 2.0).abs() < 1e-5);
        assert_eq!(wrap_angle(0.25), 0.25);
    }
}
