//! Obstacle avoidance: overrides the velocity command when it heads into a close
//! obstacle (R2P paper §5, Listing 2's `avoidCollision`).

use crate::kinematics::Twist;
use crate::proximity::SENSOR_COUNT;

/// Body-frame unit vector each ranger looks along: front, left, back, right.
pub const SENSOR_DIRECTIONS: [(f32, f32); SENSOR_COUNT] =
    [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)];

/// Braking profile, distances measured by the rangers (from the robot's rim).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AvoidanceConfig {
    /// At or below this gap no motion towards the obstacle is allowed.
    pub stop_m: f32,
    /// Below this gap the approach speed is capped, falling linearly from
    /// `max_approach_m_s` at `slow_m` to 0 at `stop_m`. The cap shrinks with the gap,
    /// so the robot decelerates continuously instead of slamming to a halt.
    pub slow_m: f32,
    pub max_approach_m_s: f32,
}

impl AvoidanceConfig {
    pub const TRISKAR2: Self = Self {
        stop_m: 0.20,
        slow_m: 0.60,
        max_approach_m_s: 0.8,
    };

    /// Highest allowed speed towards an obstacle `gap_m` away.
    pub fn approach_limit(&self, gap_m: f32) -> f32 {
        let span = self.slow_m - self.stop_m;
        if gap_m >= self.slow_m {
            f32::INFINITY
        } else if gap_m <= self.stop_m || span <= 0.0 {
            0.0
        } else {
            self.max_approach_m_s * (gap_m - self.stop_m) / span
        }
    }
}

/// Filtered command and whether anything was changed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AvoidanceOutput {
    pub twist: Twist,
    /// Bit `i` set: sensor `i` limited the command.
    pub limited_mask: u8,
}

/// The obstacle-avoidance node: stateless; call on every new command and every new
/// proximity sample with the latest of the other.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleAvoidance {
    config: AvoidanceConfig,
}

impl ObstacleAvoidance {
    pub const fn new(config: AvoidanceConfig) -> Self {
        Self { config }
    }

    /// For each sensor, the component of the commanded velocity towards it is capped by
    /// [`AvoidanceConfig::approach_limit`] of its gap; motion away from or across the
    /// obstacle and rotation pass unchanged, so the robot can always back off or slide
    /// along a wall. A non-finite command or distance stops the robot (it cannot be
    /// checked, so it is not trusted).
    pub fn filter(&self, command: Twist, distance_m: [f32; SENSOR_COUNT]) -> AvoidanceOutput {
        if !command.is_finite() || distance_m.iter().any(|d| !d.is_finite()) {
            return AvoidanceOutput {
                twist: Twist::ZERO,
                limited_mask: u8::MAX,
            };
        }
        let mut t = command;
        let mut mask = 0;
        for (i, ((ux, uy), gap)) in SENSOR_DIRECTIONS.iter().zip(distance_m).enumerate() {
            let toward = t.vx * ux + t.vy * uy;
            let limit = self.config.approach_limit(gap);
            if toward > limit {
                let excess = toward - limit;
                t.vx -= excess * ux;
                t.vy -= excess * uy;
                mask |= 1 << i;
            }
        }
        AvoidanceOutput {
            twist: t,
            limited_mask: mask,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FAR: [f32; 4] = [0.8; 4];
    const N: ObstacleAvoidance = ObstacleAvoidance::new(AvoidanceConfig::TRISKAR2);

    fn tw(vx: f32, vy: f32, wz: f32) -> Twist {
        Twist { vx, vy, wz }
    }

    #[test]
    fn clear_path_passes_unchanged() {
        let out = N.filter(tw(1.5, -0.3, 0.7), FAR);
        assert_eq!(out.twist, tw(1.5, -0.3, 0.7));
        assert_eq!(out.limited_mask, 0);
    }

    #[test]
    fn stops_forward_motion_at_stop_distance_but_allows_backing_off() {
        let front = [0.2, 0.8, 0.8, 0.8];
        let out = N.filter(tw(1.0, 0.0, 0.5), front);
        assert_eq!(out.twist, tw(0.0, 0.0, 0.5));
        assert_eq!(out.limited_mask, 0b0001);
        let out = N.filter(tw(-1.0, 0.0, 0.0), front);
        assert_eq!(out.twist, tw(-1.0, 0.0, 0.0));
        assert_eq!(out.limited_mask, 0);
    }

    #[test]
    fn ramp_between_stop_and_slow() {
        // Gap 0.4 m: half-way from 0.2 to 0.6 → cap 0.4 m/s.
        let out = N.filter(tw(1.0, 0.0, 0.0), [0.4, 0.8, 0.8, 0.8]);
        assert!((out.twist.vx - 0.4).abs() < 1e-6, "{:?}", out.twist);
        // A slower command is not touched.
        let out = N.filter(tw(0.3, 0.0, 0.0), [0.4, 0.8, 0.8, 0.8]);
        assert_eq!(out.twist.vx, 0.3);
        assert_eq!(AvoidanceConfig::TRISKAR2.approach_limit(0.6), f32::INFINITY);
        assert_eq!(AvoidanceConfig::TRISKAR2.approach_limit(0.1), 0.0);
    }

    #[test]
    fn diagonal_command_keeps_the_sliding_component() {
        // Wall on the left: the leftward part is removed, forward motion stays.
        let out = N.filter(tw(0.5, 0.5, 0.0), [0.8, 0.15, 0.8, 0.8]);
        assert_eq!(out.twist, tw(0.5, 0.0, 0.0));
        assert_eq!(out.limited_mask, 0b0010);
    }

    #[test]
    fn boxed_in_stops_translation_on_both_axes() {
        let out = N.filter(tw(-0.7, -0.9, 0.0), [0.8, 0.8, 0.1, 0.1]);
        assert_eq!(out.twist, tw(0.0, 0.0, 0.0));
        assert_eq!(out.limited_mask, 0b1100);
    }

    #[test]
    fn untrusted_inputs_stop() {
        let out = N.filter(tw(0.5, 0.0, 0.0), [f32::NAN, 0.8, 0.8, 0.8]);
        assert_eq!(out.twist, Twist::ZERO);
        let out = N.filter(tw(f32::INFINITY, 0.0, 0.0), FAR);
        assert_eq!(out.twist, Twist::ZERO);
    }
}
