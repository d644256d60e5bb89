//! The one physical robot all simulated modules share: three DC motors with encoders,
//! the omni base, the world with its wall, four IR rangers and the battery. It advances
//! in fixed 1 ms ticks of global time with the duties the motor modules last set; the
//! modules read their sensors from it. It also records the path.
use triskar2_nodes::kinematics::Twist;

use crate::plant::{
    BatteryPack, BatteryParams, DcMotor, DcMotorParams, OmniBase, OmniGeometry, Pose2, RangerArray,
    World,
};
use crate::rng::Rng;
use rtcan_core::Nanos;

/// Physics tick, ns.
pub const TICK_NS: Nanos = 1_000_000;
/// Path sample period, ns.
pub const SAMPLE_NS: Nanos = 50_000_000;
/// Current drawn by the electronics, A.
const ELECTRONICS_A: f64 = 0.5;

/// One path sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSample {
    /// Global time, ns.
    pub t_ns: Nanos,
    /// True pose.
    pub pose: Pose2,
    /// True forward speed in the body frame, m/s.
    pub vx: f64,
    /// Wheel speeds, rad/s.
    pub wheels: [f64; 3],
    /// Gap between the body and the nearest obstacle, m.
    pub gap_m: f64,
    /// The gateway's current command (vx), m/s.
    pub cmd_vx: f32,
    /// The velocity last published by obstacle_avoid (vx), m/s.
    pub velocity_vx: f32,
}

/// The shared robot.
pub struct Physics {
    pub motors: [DcMotor; 3],
    pub duty: [f32; 3],
    pub base: OmniBase,
    pub world: World,
    pub rangers: RangerArray,
    pub battery: BatteryPack,
    rng: Rng,
    t_ns: Nanos,
    /// Samples every `SAMPLE_NS`, decimated past `decimate::KEEP` (bounded memory).
    pub path: crate::decimate::Decimated<PathSample>,
    /// Largest x reached, m.
    pub max_x_m: f64,
    /// Smallest body-to-obstacle gap seen, m.
    pub min_gap_m: f64,
    /// Gateway command currently sent, for the path table.
    pub cmd: Option<Twist>,
    /// Velocity last published by obstacle_avoid, for the path table.
    pub velocity: Option<Twist>,
}

impl Physics {
    /// The robot at the origin facing +x in `world`; `seed` drives the sensor noise.
    pub fn new(world: World, seed: u64) -> Self {
        let base = OmniBase::new(OmniGeometry::TRISKAR2, Pose2::default());
        let gap = world.clearance((0.0, 0.0)) - OmniGeometry::TRISKAR2.body_radius_m;
        Physics {
            motors: [(); 3].map(|_| DcMotor::new(DcMotorParams::TRISKAR2)),
            duty: [0.0; 3],
            base,
            world,
            rangers: RangerArray::TRISKAR2,
            battery: BatteryPack::new(BatteryParams::TRISKAR2, 0.9),
            rng: Rng::new(seed, 0x7215),
            t_ns: 0,
            path: crate::decimate::Decimated::default(),
            max_x_m: 0.0,
            min_gap_m: gap,
            cmd: None,
            velocity: None,
        }
    }

    /// Physics time, ns.
    pub fn now(&self) -> Nanos {
        self.t_ns
    }

    /// Advances whole ticks up to global time `g`.
    pub fn advance_to(&mut self, g: Nanos) {
        let dt = TICK_NS as f64 * 1e-9;
        while self.t_ns + TICK_NS <= g {
            if self.t_ns.is_multiple_of(SAMPLE_NS) {
                self.sample();
            }
            let bus_v = self.battery.terminal_v();
            let mut draw_a = ELECTRONICS_A;
            for (m, d) in self.motors.iter_mut().zip(self.duty) {
                m.step(dt, f64::from(d) * bus_v, 0.0);
                draw_a += f64::from(d) * m.current_a();
            }
            self.battery.step(dt, draw_a);
            self.base
                .step(dt, self.motors.each_ref().map(|m| m.wheel_speed_rad_s()));
            self.t_ns += TICK_NS;
            let gap = self.gap();
            self.min_gap_m = self.min_gap_m.min(gap);
            self.max_x_m = self.max_x_m.max(self.base.pose().x);
        }
    }

    fn gap(&self) -> f64 {
        let p = self.base.pose();
        self.world.clearance((p.x, p.y)) - self.base.geometry().body_radius_m
    }

    fn sample(&mut self) {
        let s = PathSample {
            t_ns: self.t_ns,
            pose: self.base.pose(),
            vx: self.base.twist().vx,
            wheels: self.motors.each_ref().map(|m| m.wheel_speed_rad_s()),
            gap_m: self.gap(),
            cmd_vx: self.cmd.map_or(0.0, |c| c.vx),
            velocity_vx: self.velocity.map_or(0.0, |v| v.vx),
        };
        self.path.push(s);
    }

    /// The four rangers' readings now, m.
    pub fn ranges_m(&mut self) -> [f32; 4] {
        let rng = &mut self.rng;
        self.rangers
            .measure(&self.world, &self.base.pose(), &mut || rng.next_u64())
            .map(|d| d as f32)
    }
}
