//! A simulated Triskar2 module: the generated engine (`rtcan::robot_toml::<m>::engine`)
//! with the generated `ModuleHost`, the module's app from `triskar2_nodes::app`, and
//! hardware backed by the shared [`Physics`]. The bus drives it through
//! [`Module`](crate::bus::Module) exactly like a firmware driver drives an engine.
use std::cell::RefCell;
use std::rc::Rc;

use rtcan::core::clock::SlotClock;
use rtcan::core::counters::Counters;
use rtcan::core::driver::{Mailbox, TxResult};
use rtcan::core::{Engine, Frame, Nanos};
use rtcan::pubsub::topic::TopicStats;
use rtcan::pubsub::{ModuleHost, SystemStatus};
use triskar2_nodes::app::{
    GatewayApp, GatewayHw, Motor1App, Motor2App, Motor3App, MotorCtrl, MotorHw, ProximityApp,
    ProximityHw, PsuApp, PsuHw,
};
use triskar2_nodes::kinematics::Twist;
use triskar2_nodes::tasks::obstacle_avoid;

use super::physics::Physics;
use crate::bus::Module;
use crate::clock::NodeClock;
use crate::controller::SimController;

/// Shared state of one simulation: the robot and what the gateway's host link saw.
pub struct Shared {
    pub physics: Physics,
    pub script: Script,
    /// Odometry messages received by the gateway: (global ns, x, y, theta).
    pub odometry: crate::decimate::Decimated<(Nanos, f32, f32, f32)>,
    /// Proximity, battery and log messages received by the gateway.
    pub proximity_rx: u32,
    pub battery_rx: u32,
    pub log_rx: u32,
    /// Last log line text received by the gateway.
    pub last_log: String,
    /// A firmware update over the bus, if the run has one.
    pub update: Option<crate::update::UpdateBus>,
    /// Parameters over the bus, if the run has them (`param.rs`).
    pub params: Option<crate::param::ParamBus>,
    /// The `proximity_read` service: script, calls, answers (`services.rs`).
    pub services: super::services::ServiceLog,
    /// The module-state topics: what was published and received (`module_state.rs`).
    pub module_state: super::module_state::StateLog,
}

/// What the host (ROS) sends through the gateway.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Script {
    /// Forward command, m/s.
    pub vx: f32,
    /// Sent from this global time, ns...
    pub from_ns: Nanos,
    /// ...until this one (then zero is sent).
    pub until_ns: Nanos,
    /// A live host's command (`rtcan_sim::live`): replaces the script while set.
    pub host: Option<Twist>,
}

impl Script {
    fn command(&self, g: Nanos) -> Twist {
        if let Some(t) = self.host {
            return t;
        }
        let vx = if g >= self.from_ns && g < self.until_ns {
            self.vx
        } else {
            0.0
        };
        Twist {
            vx,
            vy: 0.0,
            wz: 0.0,
        }
    }
}

/// Hardware of every module kind, backed by the shared robot.
pub struct PlantHw<'a> {
    shared: &'a mut Shared,
    global: Nanos,
    motor: usize,
}

impl MotorHw for PlantHw<'_> {
    fn encoder_count(&mut self) -> u16 {
        self.shared
            .physics
            .motors
            .get(self.motor)
            .map_or(0, |m| m.encoder_count())
    }
    fn set_duty(&mut self, duty: f32) {
        if let Some(d) = self.shared.physics.duty.get_mut(self.motor) {
            *d = duty;
        }
    }
}

impl ProximityHw for PlantHw<'_> {
    fn ranges_m(&mut self) -> [f32; 4] {
        self.shared.physics.ranges_m()
    }
}

impl PsuHw for PlantHw<'_> {
    fn voltage_v(&mut self) -> f32 {
        self.shared.physics.battery.terminal_v() as f32
    }
    fn current_a(&mut self) -> f32 {
        self.shared.physics.battery.current_a() as f32
    }
}

impl GatewayHw for PlantHw<'_> {
    fn velocity_command(&mut self, _now: Nanos) -> Option<Twist> {
        let c = self.shared.script.command(self.global);
        self.shared.physics.cmd = Some(c);
        Some(c)
    }
    fn odometry(&mut self, _now: Nanos, m: &rtcan::robot_toml::Odometry) {
        self.shared.odometry.push((self.global, m.x, m.y, m.theta));
    }
    fn proximity(&mut self, _now: Nanos, _m: &rtcan::robot_toml::Proximity) {
        self.shared.proximity_rx += 1;
    }
    fn battery(&mut self, _now: Nanos, _m: &rtcan::robot_toml::Battery) {
        self.shared.battery_rx += 1;
    }
    fn log(&mut self, _now: Nanos, m: &rtcan::robot_toml::LogLine) {
        self.shared.log_rx += 1;
        let end = m.text.iter().position(|&b| b == 0).unwrap_or(m.text.len());
        self.shared.last_log = String::from_utf8_lossy(m.text.get(..end).unwrap_or(&[])).into();
    }
}

/// A module's app (generated from robot.toml's placement of the nodes), polled with
/// plant-backed hardware; the variant is the module's board (which motor it drives).
pub enum App {
    Gateway(GatewayApp),
    Motor1(Motor1App),
    Motor2(Motor2App),
    Motor3(Motor3App),
    Proximity(ProximityApp),
    Psu(PsuApp),
}

impl App {
    fn poll(&mut self, now: Nanos, hw: &mut PlantHw<'_>) -> Nanos {
        let next = match self {
            App::Gateway(a) => a.poll(now, hw),
            App::Motor1(a) => a.poll(now, hw),
            App::Motor2(a) => a.poll(now, hw),
            App::Motor3(a) => a.poll(now, hw),
            App::Proximity(a) => a.poll(now, hw),
            App::Psu(a) => a.poll(now, hw),
        };
        // The commanded velocity, from whichever module robot.toml runs the obstacle
        // node on.
        if let Some(t) = self.task::<obstacle_avoid::Task>() {
            hw.shared.physics.velocity = t.last_velocity;
        }
        next
    }

    /// The task of a node of type `T` on this module, wherever robot.toml placed it.
    pub fn task<T: 'static>(&self) -> Option<&T> {
        match self {
            App::Gateway(a) => a.task(),
            App::Motor1(a) => a.task(),
            App::Motor2(a) => a.task(),
            App::Motor3(a) => a.task(),
            App::Proximity(a) => a.task(),
            App::Psu(a) => a.task(),
        }
    }

    /// Whether this module runs node `T` (e.g. `tasks::kinematics::Task`).
    pub fn runs<T: 'static>(&self) -> bool {
        self.task::<T>().is_some()
    }

    /// Measured wheel speed and whether the controller is in its safe state.
    pub fn motor(&self) -> Option<(f32, bool)> {
        self.task::<MotorCtrl>()
            .map(|c| (c.speed_rad_s(), c.is_safe()))
    }

    /// Velocity publications obstacle_avoid limited.
    pub fn overrides(&self) -> Option<u32> {
        self.task::<obstacle_avoid::Task>().map(|t| t.overrides)
    }
}

/// What the scenario reads from a module after (or during) a run.
pub trait Inspect {
    fn name(&self) -> &'static str;
    fn counters(&self) -> Counters;
    fn synced(&self) -> bool;
    fn slot_clock(&self) -> &SlotClock;
    /// Times the safe state became required after the module had been running.
    fn safe_trips(&self) -> u32;
    /// Sends the sync (and is running).
    fn is_master(&self) -> bool;
    /// Times booted again after a scripted fault.
    fn reboots(&self) -> u32;
    /// Times the safe state was left (required, then no longer required).
    fn safe_exits(&self) -> u32;
    /// Global times of the first safe-state entry and of the last exit, if any.
    fn safe_times(&self) -> (Option<Nanos>, Option<Nanos>);
    /// Its local clock changed (a clock step, `Bus::step_clock`).
    fn set_clock(&mut self, clock: NodeClock);
    fn safe_now(&self) -> bool;
    fn app(&self) -> &App;
    /// SRT publications so far, per transmit index (drained by the measurement).
    fn srt_events(&mut self) -> &mut [(u8, SrtLog)];
    /// This module's system status (heartbeat ages: the supervision table's input).
    fn status(&self) -> &'static SystemStatus;
    /// The health of every module as this module's supervisor last knew it (its own
    /// included): the rows' counters of a table it would publish now.
    fn known_health(
        &self,
    ) -> Option<[rtcan::pubsub::EngineHealth; rtcan::robot_toml::supervision::MODULES]>;
    /// The module stops executing at this global time (failure injection).
    fn set_dies_at(&mut self, at: Option<Nanos>);
    /// Still executing at global time `g`.
    fn alive_at(&self, g: Nanos) -> bool;
    /// Age of its HRT samples at transmission, per engine tx index.
    fn sample_ages(&self) -> &[crate::sample_age::AgeStat];
}

/// An SRT topic whose publications are followed: tx index, how to read the topic's
/// statistics, the statistics already accounted for.
pub type SrtCounter = (u8, fn() -> TopicStats, TopicStats);

/// What became of one publication.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fate {
    /// The engine reported it sent: the `k`-th complete transfer of the topic.
    Sent(u32),
    /// Dropped by the engine at (or before, hopeless) its deadline.
    Dropped,
    /// Never handed to the engine (its queue for the topic was full, or refused).
    Refused,
}

/// The publications of one SRT topic, matched to what happened to them by the topic's
/// own counters (published, sent, deadline misses, overflows): one topic's messages
/// leave the engine in publication order, so the fates apply in order, and a lost
/// message does not shift the later ones.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SrtLog {
    /// Publications awaiting their fate (global times), oldest first.
    pub pending: std::collections::VecDeque<Nanos>,
    /// Publications and their fates not yet measured, in the order of the fates.
    pub done: Vec<(Nanos, Fate)>,
    sent: u32,
}

impl SrtLog {
    /// The module lost power: publications not yet sent are lost with it.
    pub fn power_lost(&mut self) {
        let lost = self.pending.drain(..).map(|at| (at, Fate::Dropped));
        self.done.extend(lost);
    }

    /// Accounts for the change from `old` to `new` seen at global time `now`.
    pub fn update(&mut self, old: &TopicStats, new: &TopicStats, now: Nanos) {
        let d = |a: u32, b: u32| b.wrapping_sub(a);
        for _ in 0..d(old.published, new.published) {
            self.pending.push_back(now);
        }
        // Refusals happen as a publication is handed over: the newest ones.
        let refused = d(old.remote_overflows, new.remote_overflows)
            + d(old.not_submittable, new.not_submittable);
        for _ in 0..refused {
            if let Some(at) = self.pending.pop_back() {
                self.done.push((at, Fate::Refused));
            }
        }
        for _ in 0..d(old.sent, new.sent) {
            if let Some(at) = self.pending.pop_front() {
                self.done.push((at, Fate::Sent(self.sent)));
                self.sent += 1;
            }
        }
        for _ in 0..d(old.deadline_misses, new.deadline_misses) {
            if let Some(at) = self.pending.pop_front() {
                self.done.push((at, Fate::Dropped));
            }
        }
    }
}

/// How a module boots: its generated engine, host and statics reset, and its app.
pub struct Boot<const RX: usize, const AR: usize, const Q: usize> {
    pub engine: fn(Nanos) -> Engine<'static, RX, AR, Q>,
    pub host: fn() -> ModuleHost<'static>,
    pub app: fn() -> App,
    pub reset: fn(),
}

/// A simulated module, generic over the engine sizes the generated code chose.
pub struct SimModule<const RX: usize, const AR: usize, const Q: usize> {
    pub name: &'static str,
    /// Bus index (= the generated module index).
    pub index: usize,
    pub engine: Box<Engine<'static, RX, AR, Q>>,
    pub host: ModuleHost<'static>,
    pub app: App,
    pub status: &'static SystemStatus,
    pub clock: NodeClock,
    pub shared: Rc<RefCell<Shared>>,
    /// Global intervals `[from, to)` in which the module is down (power loss; `to` =
    /// `Nanos::MAX`: never returns), in time order (`fault::down_intervals`).
    pub down: Vec<(Nanos, Nanos)>,
    /// How to boot the module again when it returns (`None`: it cannot return).
    pub boot: Option<Boot<RX, AR, Q>>,
    /// Index in `down` of the interval the module is in or next enters.
    next_down: usize,
    /// Times the module booted again.
    pub reboots: u32,
    /// Down (or babbling: not running its software) at the last event it saw.
    dead: bool,
    /// Global time from which the module babbles (`fault::FaultKind::Babble`).
    pub babble_from: Option<Nanos>,
    /// SRT topics to log: tx index and how to read the topic's publication count.
    pub srt: Vec<SrtCounter>,
    pub srt_log: Vec<(u8, SrtLog)>,
    /// The module's part in a request/reply service, run after its app.
    pub service: Option<Box<dyn super::services::ServiceHook>>,
    /// The module's side of the module-state topics, run after its app.
    pub state_io: Option<super::module_state::StateIo>,
    was_ok: bool,
    trips: u32,
    exits: u32,
    first_trip_at: Option<Nanos>,
    last_exit_at: Option<Nanos>,
    /// Sample age at transmission of its HRT topics.
    ages: crate::sample_age::AgeMeter,
    /// HRT samples the engine took in the last engine call.
    taken: crate::sample_age::Taken,
}

impl<const RX: usize, const AR: usize, const Q: usize> SimModule<RX, AR, Q> {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: &'static str,
        engine: Engine<'static, RX, AR, Q>,
        host: ModuleHost<'static>,
        app: App,
        status: &'static SystemStatus,
        clock: NodeClock,
        shared: Rc<RefCell<Shared>>,
        srt: Vec<(u8, fn() -> TopicStats)>,
    ) -> Self {
        let srt_log = srt.iter().map(|&(tx, _)| (tx, SrtLog::default())).collect();
        SimModule {
            name,
            index: 0,
            engine: Box::new(engine),
            host,
            app,
            status,
            clock,
            shared,
            down: Vec::new(),
            boot: None,
            next_down: 0,
            reboots: 0,
            dead: false,
            babble_from: None,
            srt: srt
                .into_iter()
                .map(|(tx, f)| (tx, f, TopicStats::default()))
                .collect(),
            srt_log,
            service: None,
            state_io: None,
            was_ok: false,
            trips: 0,
            exits: 0,
            first_trip_at: None,
            last_exit_at: None,
            ages: crate::sample_age::AgeMeter::default(),
            taken: crate::sample_age::Taken::default(),
        }
    }

    /// Whether the module runs at local time `now`, after booting it again if it has
    /// just returned; `Err(wake)` while down: the local time to wake at (its return).
    fn alive(&mut self, now: Nanos, can: &mut SimController) -> Result<(), Option<Nanos>> {
        let global = self.clock.global_at(now);
        while let Some(&(from, to)) = self.down.get(self.next_down) {
            if global < from {
                break;
            }
            if global < to {
                // Power is off: the controller loses what it held.
                self.dead = true;
                can.power_off();
                return Err((to != Nanos::MAX).then(|| self.clock.local(to)));
            }
            can.power_off();
            self.next_down += 1;
            self.reboot(now);
        }
        self.dead = false;
        if self.babble_from.is_some_and(|b| global >= b) {
            // The software ignores the schedule: every free mailbox gets the flood frame
            // (reloaded as each one is sent); the engine no longer runs.
            let frame = rtcan::core::CanId::from_raw(crate::fault::BABBLE_RAW)
                .and_then(|id| Frame::from_parts(id, 8, [0xBA; 8]));
            for mb in 0..rtcan::core::driver::MAILBOXES {
                if let (None, Some(f)) = (can.mailbox(mb), frame) {
                    rtcan::core::Controller::load(can, Mailbox(mb as u8), &f);
                }
            }
            // Still a master? Its sync stops with its software.
            self.dead = true;
            return Err(None);
        }
        Ok(())
    }

    /// Power-on again: this module's statics, engine, host and app as at boot; the
    /// engine listens before it sends (a running master may have taken over).
    fn reboot(&mut self, now: Nanos) {
        let Some(boot) = &self.boot else {
            return;
        };
        (boot.reset)();
        let mut engine = (boot.engine)(now);
        engine.listen_first();
        *self.engine = engine;
        self.host = (boot.host)();
        self.app = (boot.app)();
        self.was_ok = false;
        self.reboots += 1;
        if let Some(u) = self.shared.borrow_mut().update.as_mut() {
            u.power_on(self.index);
        }
        if let Some(p) = self.shared.borrow_mut().params.as_mut() {
            p.power_on(self.index);
        }
        if let Some(svc) = self.service.as_mut() {
            svc.reboot(&mut self.shared.borrow_mut());
        }
        if let Some(io) = self.state_io.as_mut() {
            io.reboot();
        }
        // The topics' counters start again from zero; what was pending died with it.
        for (tx, _, seen) in self.srt.iter_mut() {
            *seen = TopicStats::default();
            if let Some((_, log)) = self.srt_log.iter_mut().find(|l| l.0 == *tx) {
                log.power_lost();
            }
        }
    }

    /// An engine call with the module's host and its side of the update channel (if
    /// the run has one); a power cut the update hit takes the module down from now.
    fn engine_call<R>(
        &mut self,
        now: Nanos,
        can: &mut SimController,
        f: impl FnOnce(
            &mut Engine<'static, RX, AR, Q>,
            &mut SimController,
            &mut crate::update::WithUpdate<'_>,
        ) -> R,
    ) -> R {
        let g = self.clock.global_at(now);
        let shared = self.shared.clone();
        let mut sh = shared.borrow_mut();
        let both = &mut *sh;
        let mut h = crate::update::WithUpdate {
            host: &mut self.host,
            bus: both.update.as_mut(),
            params: both.params.as_mut(),
            module: self.index,
            now: g,
            cut: None,
            taken: crate::sample_age::Taken::default(),
        };
        let r = f(&mut self.engine, can, &mut h);
        let cut = h.cut;
        self.taken = h.taken;
        drop(sh);
        if let Some(d) = cut {
            // Down from now: the next event finds the power off (`alive`).
            let at = self.next_down.min(self.down.len());
            self.down.insert(at, (g, g.saturating_add(d)));
        }
        r
    }

    fn motor_index(&self) -> usize {
        match self.app {
            App::Motor2(_) => 1,
            App::Motor3(_) => 2,
            _ => 0,
        }
    }

    /// After a driver event: physics up to now, the app, the pump into the engine,
    /// the engine's timer; returns the next local wake-up.
    fn run(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos> {
        if let Err(wake) = self.alive(now, can) {
            return wake;
        }
        let global = self.clock.global_at(now);
        // The slot grid the image's protocol task hands its app (synchronous HRT
        // publishers run `lead` before their slots on it).
        let grid = if self.engine.is_synced() {
            rtcan::pubsub::SlotGrid::of_clock(self.engine.clock(), now)
        } else {
            None
        };
        self.status.set_grid(grid);
        let motor = self.motor_index();
        let (app_next, svc_next) = {
            let mut shared = self.shared.borrow_mut();
            shared.physics.advance_to(global);
            let mut hw = PlantHw {
                shared: &mut shared,
                global,
                motor,
            };
            let next = self.app.poll(now, &mut hw);
            let svc = self
                .service
                .as_mut()
                .and_then(|s| s.poll(now, global, &mut shared));
            let mut state_next = None;
            if let Some(io) = self.state_io.as_mut() {
                let own = rtcan::pubsub::EngineHealth::new(
                    self.engine.counters(),
                    &self.engine.error_state(),
                );
                let master = self.engine.is_master();
                state_next = io.poll(
                    self.status,
                    own,
                    master,
                    now,
                    global,
                    &mut shared.module_state,
                );
            }
            let svc = match (svc, state_next) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            };
            (next, svc)
        };
        let app_next = svc_next.map_or(app_next, |s| s.min(app_next));
        for (k, (tx, stats, seen)) in self.srt.iter_mut().enumerate() {
            let now_stats = stats();
            if let Some((_, log)) = self.srt_log.get_mut(k).filter(|l| l.0 == *tx) {
                log.update(seen, &now_stats, global);
            }
            *seen = now_stats;
        }
        let safe = self.status.safe_state_required();
        if !safe {
            if self.trips > self.exits {
                self.exits += 1;
                self.last_exit_at = Some(global);
            }
            self.was_ok = true;
        } else if self.was_ok {
            self.was_ok = false;
            self.trips += 1;
            self.first_trip_at.get_or_insert(global);
        }
        self.host.pump(&mut self.engine, now, can);
        let before = crate::sample_age::AgeMeter::loaded(can);
        let e = self.engine_call(now, can, |e, can, h| e.poll(now, can, h));
        self.ages.after_poll(before, &self.taken, can);
        // A slot handler may have freed queue room.
        self.host.pump(&mut self.engine, now, can);
        Some(if e == Nanos::MAX {
            app_next
        } else {
            e.min(app_next)
        })
    }
}

impl<const RX: usize, const AR: usize, const Q: usize> Module for SimModule<RX, AR, Q> {
    fn start(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos> {
        self.run(now, can)
    }

    fn wake(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos> {
        self.run(now, can)
    }

    fn rx(
        &mut self,
        frame: &Frame,
        sof: Nanos,
        now: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos> {
        if let Err(wake) = self.alive(now, can) {
            return wake;
        }
        let lost = self
            .service
            .as_mut()
            .is_some_and(|s| s.lose(frame, &mut self.shared.borrow_mut()));
        if lost {
            return self.run(now, can);
        }
        self.engine_call(now, can, |e, can, h| e.on_rx(frame, sof, can, h));
        self.run(now, can)
    }

    fn tx_done(
        &mut self,
        mailbox: Mailbox,
        result: TxResult,
        now: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos> {
        if let Err(wake) = self.alive(now, can) {
            return wake;
        }
        let ok = matches!(result, TxResult::Sent);
        self.ages.on_tx_done(usize::from(mailbox.0), ok, now, can);
        self.engine_call(now, can, |e, can, h| {
            e.on_tx_done(mailbox, result, now, can, h)
        });
        self.run(now, can)
    }

    fn rx_overrun(&mut self, _now: Nanos) {
        if !self.dead {
            self.engine.on_rx_overrun();
        }
    }

    fn error_state(
        &mut self,
        now: Nanos,
        state: rtcan::core::confinement::ErrorState,
        can: &mut SimController,
    ) -> Option<Nanos> {
        if let Err(wake) = self.alive(now, can) {
            return wake;
        }
        self.engine_call(now, can, |e, can, h| e.on_error_state(now, state, can, h));
        self.run(now, can)
    }
}

impl<const RX: usize, const AR: usize, const Q: usize> Inspect for SimModule<RX, AR, Q> {
    fn name(&self) -> &'static str {
        self.name
    }
    fn counters(&self) -> Counters {
        *self.engine.counters()
    }
    fn synced(&self) -> bool {
        self.engine.is_synced()
    }
    fn slot_clock(&self) -> &SlotClock {
        self.engine.clock()
    }
    fn safe_trips(&self) -> u32 {
        self.trips
    }
    fn is_master(&self) -> bool {
        !self.dead && self.engine.is_master()
    }
    fn reboots(&self) -> u32 {
        self.reboots
    }
    fn safe_exits(&self) -> u32 {
        self.exits
    }
    fn safe_times(&self) -> (Option<Nanos>, Option<Nanos>) {
        (self.first_trip_at, self.last_exit_at)
    }
    fn set_clock(&mut self, clock: NodeClock) {
        self.clock = clock;
    }
    fn safe_now(&self) -> bool {
        self.status.safe_state_required()
    }
    fn app(&self) -> &App {
        &self.app
    }
    fn srt_events(&mut self) -> &mut [(u8, SrtLog)] {
        &mut self.srt_log
    }
    fn status(&self) -> &'static SystemStatus {
        self.status
    }
    fn known_health(
        &self,
    ) -> Option<[rtcan::pubsub::EngineHealth; rtcan::robot_toml::supervision::MODULES]> {
        self.state_io.as_ref().map(|io| *io.sv.health())
    }
    fn set_dies_at(&mut self, at: Option<Nanos>) {
        self.down = at.map(|a| vec![(a, Nanos::MAX)]).unwrap_or_default();
        self.next_down = 0;
    }
    fn sample_ages(&self) -> &[crate::sample_age::AgeStat] {
        &self.ages.by_tx
    }
    fn alive_at(&self, g: Nanos) -> bool {
        !self.down.iter().any(|&(from, to)| g >= from && g < to)
            && self.babble_from.is_none_or(|b| g < b)
    }
}

/// A module of any engine size, as the bus holds it.
pub trait TriskarModule: Module + Inspect {}
impl<T: Module + Inspect> TriskarModule for T {}

impl Module for Box<dyn TriskarModule> {
    fn start(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos> {
        (**self).start(now, can)
    }
    fn wake(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos> {
        (**self).wake(now, can)
    }
    fn rx(
        &mut self,
        frame: &Frame,
        sof: Nanos,
        now: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos> {
        (**self).rx(frame, sof, now, can)
    }
    fn tx_done(
        &mut self,
        mailbox: Mailbox,
        result: TxResult,
        now: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos> {
        (**self).tx_done(mailbox, result, now, can)
    }
    fn rx_overrun(&mut self, now: Nanos) {
        (**self).rx_overrun(now)
    }
    fn error_state(
        &mut self,
        now: Nanos,
        state: rtcan::core::confinement::ErrorState,
        can: &mut SimController,
    ) -> Option<Nanos> {
        (**self).error_state(now, state, can)
    }
}
