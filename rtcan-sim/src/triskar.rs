//! The `triskar2` scenario: the whole Triskar2 robot of the workspace's robot.toml on the
//! simulated bus. Six modules, each running the generated engine and `ModuleHost` of
//! its firmware image (`rtcan::robot_toml::<module>`) and the same app code
//! (`triskar2_nodes::app`), with plants in place of the hardware. A host script sends the
//! gateway a forward command; a wall stands ahead; the obstacle node must stop the robot
//! short of it.
//!
//! The generated topics are statics (one set per module namespace, as on the firmware),
//! so one process runs one triskar2 simulation at a time: [`run`] holds a process-wide
//! lock and returns every module's statics to power-on before it starts.
use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::sync::Mutex;

use rtcan::robot_toml as robot;
use rtcan_core::{Class, Nanos};
use rtcan_model::Plan;
use triskar2_nodes::app::{self as app};

use crate::bus::{Bus, NodeSetup};
use crate::controller::Filter;
use crate::metrics::{Meter, SrtStats, TopicInfo};
use crate::plant::World;
use crate::run::{window, Run, SimConfig, CHUNK_NS};
use crate::slots::overlaps;
use rtcan::pubsub::supervision::{table_bytes, ModuleTable};

pub mod module;
pub mod module_state;
pub mod physics;
pub mod report;
pub mod services;

use module::{App, Boot, Fate, Script, Shared, SimModule, SrtLog, TriskarModule};
use physics::{PathSample, Physics};

/// Scenario parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct TriskarConfig {
    /// Bus and run parameters (seconds, seed, drift, interrupt latency, bit errors).
    pub sim: SimConfig,
    /// The wall across the path, at this x (m); it spans y in [-2, 2].
    pub wall_x_m: f64,
    /// The host's forward command, m/s...
    pub command_vx: f32,
    /// ...sent from this time, s...
    pub command_from_s: f64,
    /// ...until this time, s (zero afterwards).
    pub command_until_s: f64,
    /// The gateway (master) stops executing at this time, s (failure injection).
    pub gateway_dies_at_s: Option<f64>,
    /// Any module (bus index, seconds) stops executing then (failure injection). The run
    /// then steps 1/20 cycle at a time and records the supervision table (`supervision`).
    pub module_dies_at: Option<(usize, f64)>,
    /// Scripted faults (`fault::parse`, `--fault`), on top of the two above.
    pub faults: Vec<crate::fault::Fault>,
    /// Every module has a bus guardian (`guardian.rs`).
    pub guardian: bool,
    /// A firmware update over the bus during the run (`update.rs`, `rtcan flash`).
    pub update: Option<crate::update::UpdateJob>,
    /// Step 1/20 cycle at a time and record the supervision table (`supervision`) even
    /// without `module_dies_at` (a clean run checked for false "missing").
    pub supervise: bool,
}

impl Default for TriskarConfig {
    fn default() -> Self {
        TriskarConfig {
            sim: SimConfig {
                seconds: 10.0,
                ..SimConfig::default()
            },
            wall_x_m: 1.5,
            command_vx: 0.3,
            command_from_s: 0.5,
            command_until_s: 8.0,
            gateway_dies_at_s: None,
            module_dies_at: None,
            faults: Vec::new(),
            guardian: false,
            update: None,
            supervise: false,
        }
    }
}

/// One module after the run.
#[derive(Clone, Debug, PartialEq)]
pub struct ModuleReport {
    pub name: &'static str,
    /// The nodes its app ran, in poll order: robot.toml's placement
    /// (`triskar2_nodes::app::MODULE_NODES`, generated from it).
    pub nodes: &'static [&'static str],
    pub counters: rtcan_core::counters::Counters,
    pub synced: bool,
    pub safe_trips: u32,
    pub safe_now: bool,
    /// Why the safe state is required at the end, and the sync master the module's
    /// safe-state rule follows then (issue 15: the current one, not the configured one).
    pub safe_reason: Option<rtcan::pubsub::SafeReason>,
    pub sync_master: u8,
    /// Motor modules: measured wheel speed (rad/s) and whether the controller is safe.
    pub motor: Option<(f32, bool)>,
    /// Sends the sync at the end of the run (and is running).
    pub master: bool,
    /// Times the module booted again after a scripted fault.
    pub reboots: u32,
    /// Times the module left the safe state after it had been required.
    pub safe_exits: u32,
    /// Global times of its first safe-state entry and of its last exit.
    pub safe_times: (Option<Nanos>, Option<Nanos>),
    /// Fault confinement at the end and bus-off entries of its controller.
    pub error_state: rtcan_core::confinement::ErrorState,
    /// Frames its controller lost to full receive FIFOs.
    pub fifo_overruns: u64,
    /// Its bus guardian cut it off (global time), if it has one and did.
    pub guardian_cut_at: Option<Nanos>,
    /// Age of its HRT samples at transmission (publish → SOF of the first frame), per
    /// topic it sends.
    pub sample_age: Vec<crate::sample_age::TopicAge>,
}

/// The result of a triskar2 run.
#[derive(Clone, Debug)]
pub struct TriskarRun {
    /// Bus figures, as for every scenario (SRT from the publication log, see `srt`).
    pub run: Run,
    /// Path samples (every 50 ms; in long runs every 100, 200, … ms: at most
    /// `decimate::KEEP` and the last).
    pub path: Vec<PathSample>,
    /// Smallest gap between the body and the wall, m.
    pub min_gap_m: f64,
    /// Gap at the end, m.
    pub final_gap_m: f64,
    /// Largest x reached, m.
    pub max_x_m: f64,
    /// Velocity publications the obstacle node limited.
    pub overrides: u32,
    /// Odometry as received by the gateway: (global ns, x, y, theta), decimated as
    /// `path`, the last one always kept.
    pub odometry: Vec<(Nanos, f32, f32, f32)>,
    /// Odometry messages the gateway received.
    pub odometry_rx: u64,
    /// Messages the gateway received: proximity, battery, log; the last log line.
    pub gateway_rx: (u32, u32, u32, String),
    pub modules: Vec<ModuleReport>,
    /// With `module_dies_at` or `supervise`: the module table of the current sync master
    /// every 1/20 cycle, through its wire form (`ModuleTable::encode`/`decode`).
    pub supervision: Vec<SupervisionSample>,
    /// With `module_dies_at` or `supervise`: the module-state topics' publications and
    /// every table a module received over the bus (`module_state.rs`).
    pub module_state: module_state::StateLog,
    /// With `update`: every target's result, in order, and what each module would boot
    /// at the end (slot, image length, CRC-32), by bus index.
    pub update: Vec<crate::update::UpdateResult>,
    pub booted: Vec<Option<(usize, u32, u32)>>,
    /// Per bus index: power cuts the update hit and what booted after each.
    pub update_cuts: Vec<crate::update::CutLog>,
    /// Sync frames on the wire: cycles with two syncs, longest silence.
    pub syncs: crate::sync_watch::SyncWatch,
    /// Frames outside their slots or windows as the last sync on the wire places them,
    /// whoever sent it (`sync_watch::SlotCheck`), and frames so checked.
    pub slots_live: (u64, u64),
    pub config: TriskarConfig,
}

/// The sync master's module table at one global time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupervisionSample {
    pub t_ns: Nanos,
    pub table: ModuleTable<{ MODULES.len() }>,
}

impl TriskarRun {
    /// The robot moved towards the wall and stopped without touching it.
    pub fn stopped_short(&self) -> bool {
        let last_speed = self.path.last().map_or(0.0, |s| s.vx.abs());
        self.max_x_m > 0.3 && self.min_gap_m > 0.0 && last_speed < 0.01
    }
}

/// One triskar2 simulation at a time per process (the topics are statics).
pub(crate) static LOCK: Mutex<()> = Mutex::new(());

/// Module names in bus-index order (= module INDEX of the generated code).
pub const MODULES: [&str; 6] = ["gateway", "motor1", "motor2", "motor3", "proximity", "psu"];

/// Checks that `plan` is the robot the simulator's code was generated from.
pub fn check_plan(plan: &Plan) -> Result<(), String> {
    if plan.fingerprint != robot::FINGERPRINT {
        return Err(format!(
            "{} (fingerprint {:#010x}) is not the robot the triskar2 code was generated from \
             (the workspace robot.toml, fingerprint {:#010x})",
            plan.file,
            plan.fingerprint,
            robot::FINGERPRINT
        ));
    }
    let names: Vec<&str> = plan.modules.iter().map(|m| m.name.as_str()).collect();
    if names != MODULES {
        return Err(format!("unexpected modules {names:?}"));
    }
    Ok(())
}

pub(crate) fn reset_all() {
    // The generated code resets every module's topics, status and nodes.
    rtcan::robot_toml::reset();
}

/// Runs the scenario on `plan` (which must be the workspace robot.toml), without
/// service calls.
pub fn run(plan: &Plan, cfg: &TriskarConfig) -> Result<TriskarRun, String> {
    run_with_services(plan, cfg, &services::ServiceScript::default()).map(|(r, _)| r)
}

/// [`run`] with the gateway calling `proximity_read` on `script`; also returns what the
/// service did.
pub fn run_with_services(
    plan: &Plan,
    cfg: &TriskarConfig,
    script: &services::ServiceScript,
) -> Result<(TriskarRun, services::ServiceLog), String> {
    run_all(plan, cfg, script, None).map(|(r, s, _)| (r, s))
}

/// [`run`] with the host asking for parameters over the bus through the gateway
/// (`param.rs`, `rtcan param`); also returns what the parameters did.
pub fn run_with_params(
    plan: &Plan,
    cfg: &TriskarConfig,
    params: crate::param::ParamBus,
) -> Result<(TriskarRun, crate::param::ParamLog), String> {
    run_all(plan, cfg, &services::ServiceScript::default(), Some(params)).map(|(r, _, p)| (r, p))
}

fn run_all(
    plan: &Plan,
    cfg: &TriskarConfig,
    script: &services::ServiceScript,
    params: Option<crate::param::ParamBus>,
) -> Result<(TriskarRun, services::ServiceLog, crate::param::ParamLog), String> {
    check_plan(plan)?;
    let sc = crate::robot::scenario(plan, &[])?;
    // A panicking earlier run leaves the lock poisoned; the statics are reset anyway.
    let _guard = LOCK.lock().unwrap_or_else(|p| p.into_inner());
    reset_all();
    let result = simulate(&sc, cfg, script, params, &crate::sample_age::tx_names(plan));
    reset_all();
    result
}

/// The module's generated acceptance filters as its firmware programs them: the sync
/// bank (the first) into FIFO 0, every other bank into FIFO 1, so a burst of topic
/// frames cannot overrun the FIFO the sync frame arrives in.
fn firmware_filter(filters: &[(u32, u32)]) -> Filter {
    Filter::Rules(
        filters
            .iter()
            .enumerate()
            .map(|(i, &(id, mask))| (mask, id & mask, u8::from(i > 0)))
            .collect(),
    )
}

/// `firmware_filter` plus the host channels' bank (docs/PROTOCOL.md §10), one bank for
/// both channels: the gateway takes every module's replies (`0xFF40..=0xFF7F`
/// parameters, `0xFFC0..=0xFFFF` update: message-ID mask `0xFF40`), a module its own
/// requests (`0xFF00 + m` parameters, `0xFF80 + m` update, any fragment: mask `0xFF7F`),
/// all NRT.
fn update_filter(filters: &[(u32, u32)], module: usize) -> Filter {
    let Filter::Rules(mut rules) = firmware_filter(filters) else {
        return firmware_filter(filters);
    };
    let (id, mask) = if module == 0 {
        (
            (63 << 23) | (u32::from(rtcan_core::service::PARAM_REP_BASE) << 7),
            (0x3F << 23) | (0xFF40 << 7),
        )
    } else {
        (
            (63 << 23) | ((u32::from(rtcan_core::service::PARAM_REQ_BASE) + module as u32) << 7),
            (0x3F << 23) | (0xFF7F << 7),
        )
    };
    rules.push((mask, id, 1));
    Filter::Rules(rules)
}

/// The module table of the current sync master (the first live module of the master
/// chain: the configured master, then the backups in rank order), through its wire form.
fn supervise(bus: &Bus<Box<dyn TriskarModule>>, t: Nanos) -> Option<SupervisionSample> {
    let ranks = [
        robot::gateway::BACKUP_RANK,
        robot::motor1::BACKUP_RANK,
        robot::motor2::BACKUP_RANK,
        robot::motor3::BACKUP_RANK,
        robot::proximity::BACKUP_RANK,
        robot::psu::BACKUP_RANK,
    ];
    let mut backups: Vec<(u8, usize)> = (0..MODULES.len())
        .filter_map(|n| ranks.get(n).filter(|&&r| r > 0).map(|&r| (r, n)))
        .collect();
    backups.sort_unstable();
    let reporter = core::iter::once(usize::from(robot::MASTER))
        .chain(backups.into_iter().map(|(_, n)| n))
        .find(|&n| bus.module(n).is_some_and(|m| m.alive_at(t)))?;
    let reporter = u8::try_from(reporter).ok()?;
    let m = bus.module(usize::from(reporter))?;
    let table = ModuleTable::<{ MODULES.len() }>::snapshot_after(
        m.status(),
        reporter,
        robot::FINGERPRINT,
        None,
        &m.known_health()?,
        robot::supervision::MISSING_AFTER_CYCLES,
    );
    let mut wire = [0u8; table_bytes(MODULES.len())];
    let n = table.encode(&mut wire)?;
    let table = ModuleTable::decode(wire.get(..n)?)?;
    Some(SupervisionSample { t_ns: t, table })
}

/// Which modules may send the sync: the configured master and the backups.
fn master_capable() -> [bool; MODULES.len()] {
    let ranks = [
        robot::gateway::BACKUP_RANK,
        robot::motor1::BACKUP_RANK,
        robot::motor2::BACKUP_RANK,
        robot::motor3::BACKUP_RANK,
        robot::proximity::BACKUP_RANK,
        robot::psu::BACKUP_RANK,
    ];
    let mut out = [false; MODULES.len()];
    for (n, o) in out.iter_mut().enumerate() {
        *o = n == usize::from(robot::MASTER) || ranks.get(n).is_some_and(|&r| r > 0);
    }
    out
}

/// Applies one bus-level fault (`fault::bus_actions`) now.
fn apply_bus_fault(bus: &mut Bus<Box<dyn TriskarModule>>, f: &crate::fault::Fault) {
    if crate::fault::apply_bus(bus, f) {
        return;
    }
    if let crate::fault::FaultKind::Step(d) = f.kind {
        if let Some(c) = bus.step_clock(f.module, d) {
            if let Some(module) = bus.module_mut(f.module) {
                module.set_clock(c);
            }
        }
    }
}

/// Time from a slot boundary of the master's clock to its sync's start of frame: the
/// timer interrupt latency (without a CPU model; with one, the modelled entry).
fn sync_lead_ns(sim: &SimConfig) -> Nanos {
    sim.node_irq_latency_ns()
}

fn s_to_ns(s: f64) -> Nanos {
    (s.max(0.0) * 1e9) as Nanos
}

/// The robot and the host link's state, shared by every module of one run.
pub(crate) fn new_shared(cfg: &TriskarConfig) -> Rc<RefCell<Shared>> {
    let world = World::new().with_wall((cfg.wall_x_m, -2.0), (cfg.wall_x_m, 2.0));
    Rc::new(RefCell::new(Shared {
        physics: Physics::new(world, cfg.sim.seed),
        script: Script {
            vx: cfg.command_vx,
            from_ns: s_to_ns(cfg.command_from_s),
            until_ns: s_to_ns(cfg.command_until_s),
            host: None,
        },
        odometry: crate::decimate::Decimated::default(),
        proximity_rx: 0,
        battery_rx: 0,
        log_rx: 0,
        last_log: String::new(),
        update: cfg
            .update
            .as_ref()
            .map(|j| crate::update::UpdateBus::new(j, MODULES.len(), robot::FINGERPRINT)),
        params: None,
        services: services::ServiceLog::default(),
        module_state: module_state::StateLog {
            record: cfg.supervise || cfg.module_dies_at.is_some(),
            ..Default::default()
        },
    }))
}

/// Every scripted fault of `cfg`: `faults`, plus `gateway_dies_at_s` and
/// `module_dies_at` as `Dies` faults; checked (a script that cannot happen is an error).
pub fn fault_script(cfg: &TriskarConfig) -> Result<Vec<crate::fault::Fault>, String> {
    use crate::fault::{Fault, FaultKind};
    let mut faults = cfg.faults.clone();
    let dies = |module, at| Fault {
        module,
        kind: FaultKind::Dies,
        at: s_to_ns(at),
    };
    faults.extend(cfg.gateway_dies_at_s.map(|at| dies(0, at)));
    faults.extend(cfg.module_dies_at.map(|(m, at)| dies(m, at)));
    if let Some(f) = faults.iter().find(|f| f.module >= MODULES.len()) {
        return Err(format!(
            "no module {} (modules: {})",
            f.module,
            MODULES.join(", ")
        ));
    }
    for n in 0..MODULES.len() {
        crate::fault::down_intervals(&faults, n)
            .map_err(|e| format!("{}: {e}", MODULES.get(n).unwrap_or(&"?")))?;
    }
    Ok(faults)
}

/// The six modules on a fresh bus, each with its firmware's generated filters and the
/// faults of `cfg` (`fault_script`).
pub(crate) fn build_bus(
    cfg: &TriskarConfig,
    shared: &Rc<RefCell<Shared>>,
) -> Result<Bus<Box<dyn TriskarModule>>, String> {
    let faults = fault_script(cfg)?;
    let bitrate = robot::BUS.bitrate;
    let mut bus: Bus<Box<dyn TriskarModule>> =
        Bus::new(bitrate, cfg.sim.bit_error_rate, cfg.sim.seed);
    bus.record_wire = true;
    let host_channels = cfg.update.is_some() || shared.borrow().params.is_some();
    for n in 0..MODULES.len() {
        let clock = cfg.sim.clock(n);
        let now = clock.local(0);
        let sh = shared.clone();
        // One arm per module: the generated engine, host, statics and the module's app,
        // and how to boot them again (a module that returns after a fault).
        macro_rules! module {
            ($m:ident, $name:literal, $app:expr, $srt:expr) => {{
                let mut m = SimModule::new(
                    $name,
                    robot::$m::engine(now),
                    robot::$m::host(),
                    $app,
                    &robot::$m::STATUS,
                    clock,
                    sh,
                    $srt,
                );
                m.boot = Some(Boot {
                    engine: robot::$m::engine,
                    host: robot::$m::host,
                    app: || $app,
                    reset: robot::$m::reset,
                });
                m.down = crate::fault::down_intervals(&faults, n)?;
                m.index = n;
                m.babble_from = crate::fault::babble_from(&faults, n);
                // `proximity_read`: the gateway calls, the proximity module serves.
                m.service = match n {
                    0 => Some(Box::new(services::Caller::default())),
                    4 => Some(Box::new(services::Server::default())),
                    _ => None,
                };
                m.state_io = Some(module_state::StateIo::for_module(n));
                Box::new(m)
            }};
        }
        let m: Box<dyn TriskarModule> = match n {
            0 => module!(
                gateway,
                "gateway",
                App::Gateway(app::GatewayApp::new()),
                vec![
                    (robot::gateway::topics::tx::TELEOP, || {
                        robot::gateway::topics::TELEOP.stats()
                    }),
                    (robot::gateway::topics::tx::PROXIMITY_READ_REQUEST, || {
                        robot::gateway::topics::PROXIMITY_READ_REQUEST.stats()
                    })
                ]
            ),
            1 => module!(
                motor1,
                "motor1",
                App::Motor1(app::Motor1App::new()),
                Vec::new()
            ),
            2 => module!(
                motor2,
                "motor2",
                App::Motor2(app::Motor2App::new()),
                Vec::new()
            ),
            3 => module!(
                motor3,
                "motor3",
                App::Motor3(app::Motor3App::new()),
                Vec::new()
            ),
            4 => module!(
                proximity,
                "proximity",
                App::Proximity(app::ProximityApp::new()),
                vec![
                    (robot::proximity::topics::tx::VELOCITY, || {
                        robot::proximity::topics::VELOCITY.stats()
                    }),
                    (robot::proximity::topics::tx::PROXIMITY_READ_REPLY, || {
                        robot::proximity::topics::PROXIMITY_READ_REPLY.stats()
                    })
                ]
            ),
            _ => module!(psu, "psu", App::Psu(app::PsuApp::new()), Vec::new()),
        };
        let filters = match n {
            0 => robot::gateway::FILTERS,
            1 => robot::motor1::FILTERS,
            2 => robot::motor2::FILTERS,
            3 => robot::motor3::FILTERS,
            4 => robot::proximity::FILTERS,
            _ => robot::psu::FILTERS,
        };
        bus.add_node(
            m,
            NodeSetup {
                clock,
                irq_latency_ns: cfg.sim.node_irq_latency_ns(),
                nart: false,
                filter: if host_channels {
                    update_filter(filters, n)
                } else {
                    firmware_filter(filters)
                },
                cpu: cfg.sim.cpu.clone(),
            },
        );
    }
    Ok(bus)
}

fn simulate(
    sc: &crate::run::Scenario,
    cfg: &TriskarConfig,
    script: &services::ServiceScript,
    params: Option<crate::param::ParamBus>,
    tx_names: &[Vec<String>],
) -> Result<(TriskarRun, services::ServiceLog, crate::param::ParamLog), String> {
    let shared = new_shared(cfg);
    shared.borrow_mut().services.script = script.clone();
    shared.borrow_mut().params = params;
    let mut bus = build_bus(cfg, &shared)?;
    bus.set_eof_error_rate(cfg.sim.eof_error_rate);
    let faults = fault_script(cfg)?;
    let actions = crate::fault::bus_actions(&faults)?;
    let mut next_action = 0;
    if cfg.guardian {
        let capable = master_capable();
        for (n, g) in
            crate::guardian::for_scenario(sc, |n| capable.get(n).copied().unwrap_or(false))
                .into_iter()
                .enumerate()
        {
            bus.set_guardian(n, g);
        }
    }
    let end = cfg.sim.end_ns();
    let win = window(&cfg.sim);
    let mut meter = Meter::new(&sc.topics, win, bus.bit_ns());
    let mut srt = SrtMatcher::new(&sc.topics, win);
    // The slot check on the configured master's clock: only until it first fails.
    let until = faults
        .iter()
        .filter(|f| f.module == sc.master)
        .map(|f| f.at)
        .min()
        .unwrap_or(Nanos::MAX);
    let mut syncs = crate::sync_watch::SyncWatch::new(sc.bus().map_or(0, |b| b.cycle_ns()));
    // The same check anchored on the wire, whoever the master: the sync leaves one timer
    // interrupt latency into slot 0. The sender's own frames follow its own grid: its
    // latency to the sync's start of frame varies (the guard covers it, PROTOCOL §5.3)
    // and its clock drifts from the wire's grid by up to drift_ppm over a cycle.
    let mut live = sc.bus().map(|b| {
        let drift = (b.cycle_ns() as f64 * cfg.sim.drift_ppm.abs() / 1e6) as Nanos;
        crate::sync_watch::SlotCheck::new(b.slot_ns, b.slots_per_cycle, sync_lead_ns(&cfg.sim))
            .with_tolerance(b.guard_ns + b.bit_ns() + drift)
    });
    let mut log = match &cfg.sim.wire_log {
        Some(p) => Some((
            std::io::BufWriter::new(
                std::fs::File::create(p).map_err(|e| format!("{}: {e}", p.display()))?,
            ),
            p,
        )),
        None => None,
    };
    let mut kept = Vec::new();
    let mut ov = 0;
    let mut t = 0;
    let mut supervision = Vec::new();
    let supervise_every_cycle = cfg.supervise || cfg.module_dies_at.is_some();
    // Every 1/20 cycle: a module missing for part of a cycle shows in the samples.
    let step = if supervise_every_cycle {
        (robot::BUS.cycle_ns() / 20).max(1)
    } else {
        CHUNK_NS
    };
    // In chunks: frames, fates and figures are measured as they come and dropped, so
    // memory does not grow with the run (docs/SIM.md, Memory).
    while t < end {
        t = (t + step).min(end);
        // The bus-level faults at their times within this chunk.
        while let Some(&f) = actions.get(next_action).filter(|f| f.at <= t) {
            bus.run_until(f.at);
            apply_bus_fault(&mut bus, &f);
            next_action += 1;
        }
        bus.run_until(t);
        if supervise_every_cycle {
            supervision.extend(supervise(&bus, t));
        }
        for w in &bus.wire {
            meter.frame(w);
            srt.frame(w);
            syncs.frame(w);
            if let Some(c) = &mut live {
                c.frame(w);
            }
        }
        for n in 0..bus.len() {
            if let Some(m) = bus.module_mut(n) {
                for (tx, log) in m.srt_events() {
                    srt.fates(n, *tx, log);
                }
            }
        }
        // The slot check ends with the master (the survivors then follow a backup).
        if let (Some(m), Some(c0), Some(bc)) =
            (bus.module(sc.master), bus.clock(sc.master), sc.bus())
        {
            let sclock = m.slot_clock();
            let start = c0.local(0) + bc.slot_ns;
            let wire: Vec<_> = bus.wire.iter().filter(|w| w.sof < until).copied().collect();
            ov += overlaps(&wire, &bc, sc.masks(), |g| {
                let l = c0.local(g);
                (l >= start).then(|| sclock.to_bus(l))
            });
        }
        if let Some((out, p)) = &mut log {
            crate::candump::write(out, &bus.wire, "can0")
                .map_err(|e| format!("{}: {e}", p.display()))?;
        }
        cfg.sim.keep_wire(&mut kept, &mut bus.wire);
    }
    if let Some((mut out, p)) = log {
        std::io::Write::flush(&mut out).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    shared.borrow_mut().physics.advance_to(end);

    let mut modules = Vec::new();
    let mut overrides = 0;
    for n in 0..bus.len() {
        let Some(m) = bus.module_mut(n) else { continue };
        for (tx, log) in m.srt_events() {
            srt.pending(n, *tx, log);
        }
        overrides += m.app().overrides().unwrap_or(0);
        let sample_age =
            crate::sample_age::named(m.sample_ages(), tx_names.get(n).map_or(&[][..], |v| v));
        modules.push(ModuleReport {
            name: m.name(),
            nodes: app::MODULE_NODES
                .iter()
                .find(|(module, _)| *module == m.name())
                .map_or(&[][..], |(_, nodes)| nodes),
            counters: m.counters(),
            synced: m.synced(),
            safe_trips: m.safe_trips(),
            safe_now: m.safe_now(),
            safe_reason: m.status().safe_reason(),
            sync_master: m.status().sync_master(),
            motor: m.app().motor(),
            master: m.is_master(),
            reboots: m.reboots(),
            safe_exits: m.safe_exits(),
            safe_times: m.safe_times(),
            error_state: bus
                .controller(n)
                .map(|c| c.conf.state())
                .unwrap_or_default(),
            fifo_overruns: bus
                .controller(n)
                .map_or(0, |c| c.stats.rx_overrun.iter().sum()),
            guardian_cut_at: bus.guardian(n).and_then(|g| g.tripped.map(|t| t.0)),
            sample_age,
        });
    }
    syncs.finish(end);
    let mut figures = meter.finish();
    figures.srt = srt.finish();
    let mut sh = shared.borrow_mut();
    let path = std::mem::take(&mut sh.physics.path).into_vec();
    let max_x_m = sh.physics.max_x_m;
    let final_gap_m = path.last().map_or(f64::INFINITY, |s| s.gap_m);
    let odometry = std::mem::take(&mut sh.odometry);
    let odometry_rx = odometry.seen();
    let service_log = std::mem::take(&mut sh.services);
    let param_log = sh.params.as_ref().map(|p| p.log()).unwrap_or_default();
    let run = TriskarRun {
        run: Run {
            policy: "ours",
            figures,
            overlaps: ov,
            wire: kept,
            bus: bus.stats,
            counters: modules.iter().map(|m| m.counters).collect(),
            rx_ok: 0,
            rx_bad: 0,
            sim_ns: end,
            cpu: bus.cpu_report(|n| MODULES.get(n).map_or(format!("node{n}"), |s| s.to_string())),
        },
        path,
        min_gap_m: sh.physics.min_gap_m,
        final_gap_m,
        max_x_m,
        overrides,
        odometry: odometry.into_vec(),
        odometry_rx,
        gateway_rx: (
            sh.proximity_rx,
            sh.battery_rx,
            sh.log_rx,
            std::mem::take(&mut sh.last_log),
        ),
        modules,
        supervision,
        module_state: std::mem::take(&mut sh.module_state),
        update: sh.update.as_ref().map(|u| u.results()).unwrap_or_default(),
        booted: (0..MODULES.len())
            .map(|m| sh.update.as_ref().and_then(|u| u.booted(m)))
            .collect(),
        update_cuts: (0..MODULES.len())
            .map(|m| sh.update.as_ref().map(|u| u.cuts(m)).unwrap_or_default())
            .collect(),
        syncs,
        slots_live: live.map_or((0, 0), |c| (c.bad, c.checked)),
        config: cfg.clone(),
    };
    Ok((run, service_log, param_log))
}

/// SRT latency per topic from the publications and their fates (`SrtLog`), streamed:
/// the k-th publication the engine reported sent is the k-th complete transfer of the
/// topic on the wire (a topic's messages leave the engine in order); a dropped or refused
/// publication is a miss and shifts nothing; one still pending at the end is a miss if
/// its deadline fell inside the window. Transfer ends wait in a queue until their fate
/// comes (the engine reports a transfer sent after its last frame ends).
struct SrtMatcher {
    topics: Vec<(TopicInfo, VecDeque<Nanos>, u32)>,
    stats: Vec<SrtStats>,
    win: crate::metrics::Window,
}

impl SrtMatcher {
    fn new(topics: &[TopicInfo], win: crate::metrics::Window) -> Self {
        let srt: Vec<TopicInfo> = topics
            .iter()
            .filter(|t| t.class == Class::Srt)
            .cloned()
            .collect();
        SrtMatcher {
            stats: srt
                .iter()
                .map(|t| SrtStats {
                    name: t.label.clone(),
                    ..SrtStats::default()
                })
                .collect(),
            topics: srt.into_iter().map(|t| (t, VecDeque::new(), 0)).collect(),
            win,
        }
    }

    fn frame(&mut self, w: &crate::bus::WireFrame) {
        let id = w.frame.id();
        if !w.ok || id.is_sync() {
            return;
        }
        // Fragments go out highest first; counter 0 (the fragment field also carries the
        // transfer ID, docs/PROTOCOL.md §7.1) completes the transfer.
        if let Some((_, ends, _)) = self.topics.iter_mut().find(|(t, _, _)| {
            t.node == w.node
                && t.msg_id == id.msg_id()
                && rtcan_core::fragment::counter_of(t.size, id.fragment()) == 0
        }) {
            ends.push_back(w.end);
        }
    }

    fn in_window(&self, t: &TopicInfo, at: Nanos) -> bool {
        at >= self.win.from && at + t.deadline_ns < self.win.to
    }

    /// Measures the fates `log` reported so far for (`node`, `tx`) and forgets them.
    fn fates(&mut self, node: usize, tx: u8, log: &mut SrtLog) {
        let Some(k) = self
            .topics
            .iter()
            .position(|(t, _, _)| t.node == node && t.tx == tx)
        else {
            log.done.clear();
            return;
        };
        for (at, fate) in log.done.drain(..) {
            let (Some((t, ends, base)), Some(st)) = (self.topics.get_mut(k), self.stats.get_mut(k))
            else {
                return;
            };
            let counted = at >= self.win.from && at + t.deadline_ns < self.win.to;
            let end = match fate {
                Fate::Sent(n) => {
                    while *base < n && ends.pop_front().is_some() {
                        *base += 1;
                    }
                    let e = ends.pop_front();
                    if e.is_some() {
                        *base += 1;
                    }
                    e
                }
                Fate::Dropped | Fate::Refused => None,
            };
            if counted {
                match end {
                    Some(e) => st.delivered(e.saturating_sub(at), t.deadline_ns),
                    None => st.lost(),
                }
            }
        }
    }

    /// Publications still without a fate at the end of the run.
    fn pending(&mut self, node: usize, tx: u8, log: &mut SrtLog) {
        self.fates(node, tx, log);
        let Some(k) = self
            .topics
            .iter()
            .position(|(t, _, _)| t.node == node && t.tx == tx)
        else {
            return;
        };
        let n = match self.topics.get(k) {
            Some((t, _, _)) => log
                .pending
                .iter()
                .filter(|&&at| self.in_window(t, at))
                .count(),
            None => 0,
        };
        if let Some(st) = self.stats.get_mut(k) {
            for _ in 0..n {
                st.lost();
            }
        }
    }

    fn finish(self) -> Vec<SrtStats> {
        self.stats
    }
}
