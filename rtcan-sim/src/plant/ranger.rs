//! Sharp IR rangers on the robot's rim, measuring the world.

use super::noise::NoiseSource;
use super::omni::Pose2;
use super::world::World;

/// Where a ranger sits and where it looks, in the body frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RangerMount {
    /// Direction the ranger looks (and the bearing of its mounting point), rad from +x.
    pub angle_rad: f64,
    /// Distance of the ranger from the robot's centre, m.
    pub radius_m: f64,
}

/// One ranger's characteristics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrRanger {
    pub min_m: f64,
    /// Nothing within range reads as `max_m`.
    pub max_m: f64,
    /// Standard deviation of additive Gaussian noise, m.
    pub noise_std_m: f64,
}

impl IrRanger {
    /// Sharp GP2Y0A21-class: 0.10–0.80 m, ±1 cm noise.
    pub const SHARP: Self = Self {
        min_m: 0.10,
        max_m: 0.80,
        noise_std_m: 0.01,
    };

    /// Exact distance from the ranger to the first obstacle along its beam (no noise,
    /// no clamping), `None` if there is none.
    pub fn true_range(&self, world: &World, pose: &Pose2, mount: &RangerMount) -> Option<f64> {
        let (s, c) = mount.angle_rad.sin_cos();
        let origin = pose.transform(c * mount.radius_m, s * mount.radius_m);
        let heading = pose.theta + mount.angle_rad;
        world.ray_cast(origin, (heading.cos(), heading.sin()))
    }

    /// What the ranger reports: true range plus noise, clamped into `min_m..=max_m`.
    pub fn measure(
        &self,
        world: &World,
        pose: &Pose2,
        mount: &RangerMount,
        noise: &mut impl NoiseSource,
    ) -> f64 {
        let truth = self.true_range(world, pose, mount).unwrap_or(self.max_m);
        let noisy = if self.noise_std_m > 0.0 {
            truth + self.noise_std_m * noise.gaussian()
        } else {
            truth
        };
        noisy.clamp(self.min_m, self.max_m)
    }
}

/// The proximity module's four rangers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RangerArray {
    pub ranger: IrRanger,
    /// Front, left, back, right (the node crate's sensor order).
    pub mounts: [RangerMount; 4],
}

impl RangerArray {
    /// Four Sharp rangers on the 0.30 m rim, facing front, left, back and right.
    pub const TRISKAR2: Self = Self {
        ranger: IrRanger::SHARP,
        mounts: [
            RangerMount {
                angle_rad: 0.0,
                radius_m: 0.30,
            },
            RangerMount {
                angle_rad: std::f64::consts::FRAC_PI_2,
                radius_m: 0.30,
            },
            RangerMount {
                angle_rad: std::f64::consts::PI,
                radius_m: 0.30,
            },
            RangerMount {
                angle_rad: -std::f64::consts::FRAC_PI_2,
                radius_m: 0.30,
            },
        ],
    };

    pub fn measure(&self, world: &World, pose: &Pose2, noise: &mut impl NoiseSource) -> [f64; 4] {
        self.mounts
            .map(|m| self.ranger.measure(world, pose, &m, noise))
    }
}

#[cfg(test)]
mod tests {
    use super::super::noise::splitmix64;
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn noiseless() -> RangerArray {
        RangerArray {
            ranger: IrRanger {
                noise_std_m: 0.0,
                ..IrRanger::SHARP
            },
            ..RangerArray::TRISKAR2
        }
    }

    /// A generator that must not be called.
    fn never() -> u64 {
        panic!("noise drawn with noise_std_m = 0")
    }

    #[test]
    fn exact_distance_to_walls_from_the_rim() {
        // Robot at origin; wall 0.75 m ahead (0.45 m from the front ranger), wall 0.5 m
        // to the left (0.2 m from the left ranger); nothing behind or to the right.
        let w = World::new()
            .with_wall((0.75, -5.0), (0.75, 5.0))
            .with_wall((-5.0, 0.5), (5.0, 0.5));
        let r = noiseless().measure(&w, &Pose2::default(), &mut never);
        assert!(
            (r[0] - 0.45).abs() < 1e-12 && (r[1] - 0.2).abs() < 1e-12,
            "{r:?}"
        );
        assert_eq!((r[2], r[3]), (0.8, 0.8));
    }

    #[test]
    fn readings_follow_the_robot_heading() {
        let w = World::new().with_wall((0.75, -5.0), (0.75, 5.0));
        // Turned left by 90°: the wall at +x is now seen by the right ranger.
        let pose = Pose2 {
            x: 0.0,
            y: 0.0,
            theta: FRAC_PI_2,
        };
        let r = noiseless().measure(&w, &pose, &mut never);
        assert!((r[3] - 0.45).abs() < 1e-12, "{r:?}");
        assert_eq!((r[0], r[1], r[2]), (0.8, 0.8, 0.8));
    }

    #[test]
    fn clamped_to_the_valid_band() {
        let w = World::new().with_wall((0.35, -5.0), (0.35, 5.0));
        let r = noiseless().measure(&w, &Pose2::default(), &mut never);
        assert_eq!(r[0], 0.1);
    }

    #[test]
    fn noise_is_seeded_and_has_the_given_spread() {
        let w = World::new().with_wall((0.8, -5.0), (0.8, 5.0));
        let a = RangerArray::TRISKAR2;
        let (mut s1, mut s2) = (99_u64, 99_u64);
        let mut g1 = || splitmix64(&mut s1);
        let mut g2 = || splitmix64(&mut s2);
        let xs: Vec<f64> = (0..5000)
            .map(|_| a.measure(&w, &Pose2::default(), &mut g1)[0])
            .collect();
        let ys: Vec<f64> = (0..5000)
            .map(|_| a.measure(&w, &Pose2::default(), &mut g2)[0])
            .collect();
        assert_eq!(xs, ys, "same seed, same readings");
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64).sqrt();
        assert!((mean - 0.5).abs() < 1e-3, "{mean}");
        assert!((sd - 0.01).abs() < 1e-3, "{sd}");
    }
}
