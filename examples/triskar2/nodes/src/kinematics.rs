//! Triskar2 kinematics: body twist ↔ three omni-wheel speeds, and the 100 Hz inverse
//! kinematics node.
//!
//! Body frame: x forward, y left, z up; wz counter-clockwise. Wheel `i` sits on a circle
//! of radius `base_radius_m` at angle `WHEEL_ANGLES_DEG[i]` from +x (60°, 180°, 300°:
//! two front wheels and one at the back), and drives tangentially, counter-clockwise
//! positive, along `(-sin a, cos a)`. Its rim speed is that direction dotted with the
//! velocity of its contact point:
//!
//! `r·ω_i = -sin(a_i)·vx + cos(a_i)·vy + L·wz`
//!
//! With 120° spacing the three drive directions sum to zero and their squares to 3/2, so
//! the forward kinematics is the closed-form inverse
//! `vx = (2r/3)·Σ -sin(a_i)·ω_i`, `vy = (2r/3)·Σ cos(a_i)·ω_i`, `wz = r/(3L)·Σ ω_i`.

use crate::Nanos;

/// Wheel mounting angles, degrees from +x, counter-clockwise.
pub const WHEEL_ANGLES_DEG: [f32; 3] = [60.0, 180.0, 300.0];

const SIN_60: f32 = 0.866_025_4;

/// Drive direction `(-sin a, cos a)` of each wheel, exact for `WHEEL_ANGLES_DEG`.
pub const WHEEL_DIRECTIONS: [(f32, f32); 3] = [(-SIN_60, 0.5), (0.0, -1.0), (SIN_60, 0.5)];

/// Body velocity: m/s along x and y, rad/s about z.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Twist {
    pub vx: f32,
    pub vy: f32,
    pub wz: f32,
}

impl Twist {
    pub const ZERO: Self = Self {
        vx: 0.0,
        vy: 0.0,
        wz: 0.0,
    };

    pub fn is_finite(&self) -> bool {
        self.vx.is_finite() && self.vy.is_finite() && self.wz.is_finite()
    }
}

/// Robot geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    pub wheel_radius_m: f32,
    /// Centre-to-wheel distance `L`.
    pub base_radius_m: f32,
}

/// Triskar2 as in the 2014 gateway's inverse kinematics (`_R = 0.05`, `_L = 0.30`).
pub const TRISKAR2: Geometry = Geometry {
    wheel_radius_m: 0.05,
    base_radius_m: 0.30,
};

impl Geometry {
    /// Body twist → wheel speeds (rad/s).
    pub fn inverse(&self, t: Twist) -> [f32; 3] {
        WHEEL_DIRECTIONS.map(|(dx, dy)| {
            (dx * t.vx + dy * t.vy + self.base_radius_m * t.wz) / self.wheel_radius_m
        })
    }

    /// Wheel speeds (rad/s) → body twist.
    pub fn forward(&self, wheels: [f32; 3]) -> Twist {
        let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
        for ((dx, dy), w) in WHEEL_DIRECTIONS.iter().zip(wheels) {
            sx += dx * w;
            sy += dy * w;
            sw += w;
        }
        let r = self.wheel_radius_m;
        Twist {
            vx: 2.0 * r / 3.0 * sx,
            vy: 2.0 * r / 3.0 * sy,
            wz: r / (3.0 * self.base_radius_m) * sw,
        }
    }
}

/// Inverse kinematics node configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KinematicsConfig {
    pub geometry: Geometry,
    /// If any wheel would exceed this, all three are scaled down by the same factor,
    /// which keeps the direction of motion (clipping one wheel would curve the path).
    pub max_wheel_speed_rad_s: f32,
    /// A velocity command older than this gives zero wheel setpoints.
    pub command_timeout_ns: Nanos,
}

impl KinematicsConfig {
    /// 100 Hz node; 40 rad/s = 2 m/s wheel rim speed (the paper's top speed);
    /// 250 ms command timeout (the host streams /teleop well above 4 Hz).
    pub const TRISKAR2: Self = Self {
        geometry: TRISKAR2,
        max_wheel_speed_rad_s: 40.0,
        command_timeout_ns: 250_000_000,
    };
}

/// Inverse kinematics node: latest velocity command → wheel setpoints, stepped at 100 Hz.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InverseKinematicsNode {
    config: KinematicsConfig,
    command: Option<(Nanos, Twist)>,
}

impl InverseKinematicsNode {
    pub const fn new(config: KinematicsConfig) -> Self {
        Self {
            config,
            command: None,
        }
    }

    /// A velocity command arrived. Non-finite commands are dropped.
    pub fn on_velocity(&mut self, now_ns: Nanos, twist: Twist) {
        if twist.is_finite() {
            self.command = Some((now_ns, twist));
        }
    }

    /// Wheel setpoints (rad/s) for this period.
    pub fn step(&mut self, now_ns: Nanos) -> [f32; 3] {
        let twist = match self.command {
            Some((at, t)) if now_ns.saturating_sub(at) <= self.config.command_timeout_ns => t,
            _ => Twist::ZERO,
        };
        let wheels = self.config.geometry.inverse(twist);
        let peak = wheels.iter().fold(0.0_f32, |m, w| m.max(w.abs()));
        let max = self.config.max_wheel_speed_rad_s;
        if peak > max {
            wheels.map(|w| w * (max / peak))
        } else {
            wheels
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Twist, b: Twist, tol: f32) -> bool {
        (a.vx - b.vx).abs() < tol && (a.vy - b.vy).abs() < tol && (a.wz - b.wz).abs() < tol
    }

    #[test]
    fn directions_match_the_angles() {
        for (a, (dx, dy)) in WHEEL_ANGLES_DEG.iter().zip(WHEEL_DIRECTIONS) {
            let rad = a.to_radians();
            assert!((dx + libm::sinf(rad)).abs() < 1e-6);
            assert!((dy - libm::cosf(rad)).abs() < 1e-6);
        }
    }

    #[test]
    fn pure_rotation_turns_all_wheels_equally() {
        // wz = 1 rad/s: rim speed L·wz = 0.3 m/s → 6 rad/s each.
        let w = TRISKAR2.inverse(Twist {
            wz: 1.0,
            ..Twist::ZERO
        });
        for x in w {
            assert!((x - 6.0).abs() < 1e-5, "{w:?}");
        }
    }

    #[test]
    fn forward_motion_uses_the_front_wheels_only() {
        // vx = 1 m/s: wheels 1 and 3 at ∓sin60/0.05 = ∓17.3205 rad/s, rear wheel idle.
        let w = TRISKAR2.inverse(Twist {
            vx: 1.0,
            ..Twist::ZERO
        });
        assert!((w[0] + 17.320_508).abs() < 1e-4, "{w:?}");
        assert_eq!(w[1], 0.0);
        assert!((w[2] - 17.320_508).abs() < 1e-4, "{w:?}");
    }

    #[test]
    fn sideways_motion() {
        // vy = 1 m/s: wheels 1 and 3 at 0.5/0.05 = 10 rad/s, rear wheel -20 rad/s.
        let w = TRISKAR2.inverse(Twist {
            vy: 1.0,
            ..Twist::ZERO
        });
        assert!((w[0] - 10.0).abs() < 1e-5 && (w[1] + 20.0).abs() < 1e-5);
        assert!((w[2] - 10.0).abs() < 1e-5);
    }

    #[test]
    fn inverse_then_forward_is_identity() {
        let cases = [
            Twist {
                vx: 1.0,
                vy: 0.0,
                wz: 0.0,
            },
            Twist {
                vx: 0.0,
                vy: -0.7,
                wz: 0.0,
            },
            Twist {
                vx: 0.0,
                vy: 0.0,
                wz: 2.5,
            },
            Twist {
                vx: 0.3,
                vy: -1.2,
                wz: 0.8,
            },
            Twist {
                vx: -1.9,
                vy: 0.4,
                wz: -3.1,
            },
        ];
        for t in cases {
            let back = TRISKAR2.forward(TRISKAR2.inverse(t));
            assert!(close(back, t, 1e-5), "{t:?} -> {back:?}");
        }
    }

    #[test]
    fn forward_then_inverse_is_identity() {
        let wheels = [3.0, -7.5, 12.25];
        let back = TRISKAR2.inverse(TRISKAR2.forward(wheels));
        for (a, b) in wheels.iter().zip(back) {
            assert!((a - b).abs() < 1e-4, "{wheels:?} -> {back:?}");
        }
    }

    #[test]
    fn node_scales_all_wheels_to_the_limit_keeping_direction() {
        let mut n = InverseKinematicsNode::new(KinematicsConfig::TRISKAR2);
        // 4 m/s forward needs 69.28 rad/s: scaled by 40/69.28 to exactly 40.
        let cmd = Twist {
            vx: 4.0,
            vy: 0.0,
            wz: 0.0,
        };
        n.on_velocity(0, cmd);
        let w = n.step(10_000_000);
        assert!(
            (w[0] + 40.0).abs() < 1e-4 && (w[2] - 40.0).abs() < 1e-4,
            "{w:?}"
        );
        let t = TRISKAR2.forward(w);
        assert!((t.vx - 2.309_401).abs() < 1e-4 && t.vy.abs() < 1e-6 && t.wz.abs() < 1e-6);
    }

    #[test]
    fn node_stops_on_stale_or_missing_command() {
        let mut n = InverseKinematicsNode::new(KinematicsConfig::TRISKAR2);
        assert_eq!(n.step(0), [0.0; 3]);
        n.on_velocity(
            0,
            Twist {
                vx: 0.0,
                vy: 0.0,
                wz: 1.0,
            },
        );
        assert!(n.step(250_000_000)[0] > 5.9);
        assert_eq!(n.step(250_000_001), [0.0; 3]);
        n.on_velocity(
            1,
            Twist {
                vx: f32::NAN,
                vy: 0.0,
                wz: 0.0,
            },
        );
        assert_eq!(n.step(250_000_002), [0.0; 3]);
    }
}
