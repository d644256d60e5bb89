//! The Triskar2 robot as a live bus for host tools (`rtcan-host`): stepped to any
//! simulated time by the caller (who paces it to the wall clock or not), frames handed
//! out as they complete on the wire, and the gateway taking its velocity command from
//! the host ([`Live::set_teleop`]) instead of the scripted one of the `triskar2` scenario.
//!
//! Like [`crate::triskar::run`], a `Live` holds the process-wide lock on the generated
//! topic statics for its whole life: one live robot per process.
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::MutexGuard;

use rtcan::robot_toml as robot;
use rtcan_core::Nanos;
use rtcan_model::Plan;
use triskar2_nodes::kinematics::Twist;

use crate::bus::{Bus, WireFrame};
use crate::triskar::module::{Shared, TriskarModule};
use crate::triskar::{self, TriskarConfig, LOCK};

/// A running simulated Triskar2.
pub struct Live {
    bus: Bus<Box<dyn TriskarModule>>,
    shared: Rc<RefCell<Shared>>,
    _guard: MutexGuard<'static, ()>,
}

impl Live {
    /// Powers the robot of `plan` (the workspace robot.toml) on at time 0, standing
    /// still: no command until the host sends one.
    pub fn start(plan: &Plan, seed: u64) -> Result<Self, String> {
        Self::start_with(plan, seed, false)
    }

    /// [`Live::start`] with every module's firmware-update port on (factory-flashed
    /// slots, `update::UpdateBus::relay`) and the gateway relaying the host channels'
    /// frames between the host (`relay_to_bus`, `relay_from_bus`) and the bus, as the
    /// gateway firmware does for `rtcan flash --serial`.
    pub fn start_with_updates(plan: &Plan, seed: u64) -> Result<Self, String> {
        Self::start_with(plan, seed, true)
    }

    fn start_with(plan: &Plan, seed: u64, updates: bool) -> Result<Self, String> {
        triskar::check_plan(plan)?;
        let guard = LOCK.lock().unwrap_or_else(|p| p.into_inner());
        triskar::reset_all();
        let mut cfg = TriskarConfig::default();
        cfg.sim.seed = seed;
        // No scripted command: the host drives.
        cfg.command_vx = 0.0;
        // A wall far away, so a host can drive for a while.
        cfg.wall_x_m = 1000.0;
        if updates {
            // No target of its own: the host's frames drive the update (`relay`); the
            // config only turns the update filter banks on.
            cfg.update = Some(crate::update::UpdateJob {
                targets: Vec::new(),
                start_ns: 0,
                config: rtcan_boot::sender::Config::default(),
                flash: Vec::new(),
                cut: None,
            });
        }
        let shared = triskar::new_shared(&cfg);
        if updates {
            shared.borrow_mut().update = Some(crate::update::UpdateBus::relay(
                triskar::MODULES.len(),
                robot::FINGERPRINT,
            ));
        }
        let mut bus = triskar::build_bus(&cfg, &shared)?;
        bus.record_wire = true;
        Ok(Live {
            bus,
            shared,
            _guard: guard,
        })
    }

    /// Simulated time reached, ns.
    pub fn now(&self) -> Nanos {
        self.bus.now()
    }

    /// Runs the bus up to `until` (simulated ns) and returns the frames that completed
    /// on the wire meanwhile (destroyed frames are not returned: a sniffer never sees them).
    pub fn step_to(&mut self, until: Nanos) -> Vec<WireFrame> {
        self.bus.run_until(until);
        let frames = self.bus.wire.iter().filter(|w| w.ok).copied().collect();
        self.bus.wire.clear();
        self.shared.borrow_mut().physics.advance_to(until);
        frames
    }

    /// The gateway publishes this command on `teleop` from its next period on.
    pub fn set_teleop(&mut self, vx: f32, vy: f32, wz: f32) {
        self.shared.borrow_mut().script.host = Some(Twist { vx, vy, wz });
    }

    /// Robot pose in the world (x, y m), for tests of what a command did.
    pub fn pose_m(&self) -> (f64, f64) {
        let p = self.shared.borrow().physics.base.pose();
        (p.x, p.y)
    }

    /// A host-channel frame from the host for the bus (`update::UpdateBus::relay_to_bus`);
    /// `false` if refused (not an NRT host-channel frame, or no update ports).
    pub fn relay_to_bus(&mut self, frame: rtcan_core::Frame) -> bool {
        self.shared
            .borrow_mut()
            .update
            .as_mut()
            .is_some_and(|u| u.relay_to_bus(frame))
    }

    /// The host-channel frames the gateway received since the last call.
    pub fn relay_from_bus(&mut self) -> Vec<rtcan_core::Frame> {
        self.shared
            .borrow_mut()
            .update
            .as_mut()
            .map(|u| u.relay_from_bus())
            .unwrap_or_default()
    }

    /// What module `m` would boot now: (slot, image length, CRC-32).
    pub fn booted(&self, m: usize) -> Option<(usize, u32, u32)> {
        self.shared.borrow().update.as_ref()?.booted(m)
    }

    /// Module names in bus-index order.
    pub fn modules(&self) -> &'static [&'static str] {
        &triskar::MODULES
    }

    /// The bus bit rate, bit/s.
    pub fn bitrate(&self) -> u32 {
        robot::BUS.bitrate
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        triskar::reset_all();
    }
}
