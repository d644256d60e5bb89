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
use std::collections::HashMap;
use std::rc::Rc;
use std::sync::Mutex;

use rtcan::robot_toml as robot;
use rtcan_core::{Class, Nanos};
use rtcan_model::Plan;
use triskar2_nodes::app::{self as app};

use crate::bus::{Bus, NodeSetup};
use crate::controller::Filter;
use crate::metrics::{compute, SrtStats, TopicInfo};
use crate::plant::World;
use crate::run::{window, Run, SimConfig};
use crate::slots::overlaps;

pub mod module;
pub mod physics;
pub mod report;

use module::{App, Script, Shared, SimModule, TriskarModule};
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
        }
    }
}

/// One module after the run.
#[derive(Clone, Debug, PartialEq)]
pub struct ModuleReport {
    pub name: &'static str,
    pub counters: rtcan_core::counters::Counters,
    pub synced: bool,
    pub safe_trips: u32,
    pub safe_now: bool,
    /// Motor modules: measured wheel speed (rad/s) and whether the controller is safe.
    pub motor: Option<(f32, bool)>,
}

/// The result of a triskar2 run.
#[derive(Clone, Debug)]
pub struct TriskarRun {
    /// Bus figures, as for every scenario (SRT from the publication log, see `srt`).
    pub run: Run,
    /// Path samples (every 50 ms).
    pub path: Vec<PathSample>,
    /// Smallest gap between the body and the wall, m.
    pub min_gap_m: f64,
    /// Gap at the end, m.
    pub final_gap_m: f64,
    /// Largest x reached, m.
    pub max_x_m: f64,
    /// Velocity publications the obstacle node limited.
    pub overrides: u32,
    /// Odometry as received by the gateway: (global ns, x, y, theta).
    pub odometry: Vec<(Nanos, f32, f32, f32)>,
    /// Messages the gateway received: proximity, battery, log; the last log line.
    pub gateway_rx: (u32, u32, u32, String),
    pub modules: Vec<ModuleReport>,
    pub config: TriskarConfig,
}

impl TriskarRun {
    /// The robot moved towards the wall and stopped without touching it.
    pub fn stopped_short(&self) -> bool {
        let last_speed = self.path.last().map_or(0.0, |s| s.vx.abs());
        self.max_x_m > 0.3 && self.min_gap_m > 0.0 && last_speed < 0.01
    }
}

/// One triskar2 simulation at a time per process (the topics are statics).
static LOCK: Mutex<()> = Mutex::new(());

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

fn reset_all() {
    // The generated code resets every module's topics, status and nodes.
    rtcan::robot_toml::reset();
}

/// Runs the scenario on `plan` (which must be the workspace robot.toml).
pub fn run(plan: &Plan, cfg: &TriskarConfig) -> Result<TriskarRun, String> {
    check_plan(plan)?;
    let sc = crate::robot::scenario(plan, &[])?;
    // A panicking earlier run leaves the lock poisoned; the statics are reset anyway.
    let _guard = LOCK.lock().unwrap_or_else(|p| p.into_inner());
    reset_all();
    let result = simulate(&sc, cfg);
    reset_all();
    Ok(result)
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

fn s_to_ns(s: f64) -> Nanos {
    (s.max(0.0) * 1e9) as Nanos
}

fn simulate(sc: &crate::run::Scenario, cfg: &TriskarConfig) -> TriskarRun {
    let world = World::new().with_wall((cfg.wall_x_m, -2.0), (cfg.wall_x_m, 2.0));
    let shared = Rc::new(RefCell::new(Shared {
        physics: Physics::new(world, cfg.sim.seed),
        script: Script {
            vx: cfg.command_vx,
            from_ns: s_to_ns(cfg.command_from_s),
            until_ns: s_to_ns(cfg.command_until_s),
        },
        odometry: Vec::new(),
        proximity_rx: 0,
        battery_rx: 0,
        log_rx: 0,
        last_log: String::new(),
    }));
    let bitrate = robot::BUS.bitrate;
    let mut bus: Bus<Box<dyn TriskarModule>> =
        Bus::new(bitrate, cfg.sim.bit_error_rate, cfg.sim.seed);
    bus.record_wire = true;
    for n in 0..MODULES.len() {
        let clock = cfg.sim.clock(n);
        let now = clock.local(0);
        let sh = shared.clone();
        let m: Box<dyn TriskarModule> = match n {
            0 => {
                let mut m = SimModule::new(
                    "gateway",
                    robot::gateway::engine(now),
                    robot::gateway::host(),
                    App::Gateway(app::GatewayApp::new()),
                    &robot::gateway::STATUS,
                    clock,
                    sh,
                    vec![(robot::gateway::topics::tx::TELEOP, || {
                        robot::gateway::topics::TELEOP.stats().published
                    })],
                );
                m.dies_at = cfg.gateway_dies_at_s.map(s_to_ns);
                Box::new(m)
            }
            1 => Box::new(SimModule::new(
                "motor1",
                robot::motor1::engine(now),
                robot::motor1::host(),
                App::Motor1(app::Motor1App::new()),
                &robot::motor1::STATUS,
                clock,
                sh,
                Vec::new(),
            )),
            2 => Box::new(SimModule::new(
                "motor2",
                robot::motor2::engine(now),
                robot::motor2::host(),
                App::Motor2(app::Motor2App::new()),
                &robot::motor2::STATUS,
                clock,
                sh,
                Vec::new(),
            )),
            3 => Box::new(SimModule::new(
                "motor3",
                robot::motor3::engine(now),
                robot::motor3::host(),
                App::Motor3(app::Motor3App::new()),
                &robot::motor3::STATUS,
                clock,
                sh,
                Vec::new(),
            )),
            4 => Box::new(SimModule::new(
                "proximity",
                robot::proximity::engine(now),
                robot::proximity::host(),
                App::Proximity(app::ProximityApp::new()),
                &robot::proximity::STATUS,
                clock,
                sh,
                vec![(robot::proximity::topics::tx::VELOCITY, || {
                    robot::proximity::topics::VELOCITY.stats().published
                })],
            )),
            _ => Box::new(SimModule::new(
                "psu",
                robot::psu::engine(now),
                robot::psu::host(),
                App::Psu(app::PsuApp::new()),
                &robot::psu::STATUS,
                clock,
                sh,
                Vec::new(),
            )),
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
                filter: firmware_filter(filters),
                cpu: cfg.sim.cpu.clone(),
            },
        );
    }
    let end = cfg.sim.end_ns();
    bus.run_until(end);
    shared.borrow_mut().physics.advance_to(end);

    let mut events: HashMap<(usize, u8), Vec<Nanos>> = HashMap::new();
    let mut modules = Vec::new();
    let mut overrides = 0;
    for n in 0..bus.len() {
        let Some(m) = bus.module(n) else { continue };
        for (tx, log) in m.srt_events() {
            events.insert((n, *tx), log.clone());
        }
        overrides += m.app().overrides().unwrap_or(0);
        modules.push(ModuleReport {
            name: m.name(),
            counters: m.counters(),
            synced: m.synced(),
            safe_trips: m.safe_trips(),
            safe_now: m.safe_now(),
            motor: m.app().motor(),
        });
    }
    let win = window(&cfg.sim);
    let mut figures = compute(&bus.wire, &sc.topics, &HashMap::new(), win, bus.bit_ns());
    figures.srt = srt_fifo(&bus.wire, &sc.topics, &events, win);
    let ov = match (bus.module(sc.master), bus.clock(sc.master), sc.bus()) {
        (Some(m), Some(c0), Some(bc)) => {
            let sclock = m.slot_clock();
            let start = c0.local(0) + bc.slot_ns;
            let until = cfg.gateway_dies_at_s.map_or(Nanos::MAX, s_to_ns);
            let wire: Vec<_> = bus.wire.iter().filter(|w| w.sof < until).copied().collect();
            overlaps(&wire, &bc, sc.masks(), |g| {
                let l = c0.local(g);
                (l >= start).then(|| sclock.to_bus(l))
            })
        }
        _ => 0,
    };
    let mut sh = shared.borrow_mut();
    let path = std::mem::take(&mut sh.physics.path);
    let max_x_m = path
        .iter()
        .map(|s| s.pose.x)
        .fold(f64::NEG_INFINITY, f64::max);
    let final_gap_m = path.last().map_or(f64::INFINITY, |s| s.gap_m);
    TriskarRun {
        run: Run {
            policy: "ours",
            figures,
            overlaps: ov,
            wire: std::mem::take(&mut bus.wire),
            bus: bus.stats,
            counters: modules.iter().map(|m| m.counters).collect(),
            rx_ok: 0,
            rx_bad: 0,
            events,
            sim_ns: end,
            cpu: bus.cpu_report(|n| MODULES.get(n).map_or(format!("node{n}"), |s| s.to_string())),
        },
        path,
        min_gap_m: sh.physics.min_gap_m,
        final_gap_m,
        max_x_m,
        overrides,
        odometry: std::mem::take(&mut sh.odometry),
        gateway_rx: (
            sh.proximity_rx,
            sh.battery_rx,
            sh.log_rx,
            std::mem::take(&mut sh.last_log),
        ),
        modules,
        config: cfg.clone(),
    }
}

/// SRT latency per topic from the publication log: the payloads are real messages (no
/// identity bytes), and one topic's messages leave its engine queue in order, so the
/// k-th complete transfer on the wire is the k-th publication that was not dropped.
/// Drops reported by the engine are rare here (a lightly loaded bus); when a transfer
/// is missing the later ones are matched to earlier events, which overstates latency
/// and never hides a miss.
fn srt_fifo(
    wire: &[crate::bus::WireFrame],
    topics: &[TopicInfo],
    events: &HashMap<(usize, u8), Vec<Nanos>>,
    win: crate::metrics::Window,
) -> Vec<SrtStats> {
    let mut out = Vec::new();
    for t in topics.iter().filter(|t| t.class == Class::Srt) {
        // Fragments go out highest first; fragment 0 completes the transfer.
        let ends: Vec<Nanos> = wire
            .iter()
            .filter(|w| w.ok && w.node == t.node && !w.frame.id().is_sync())
            .filter(|w| w.frame.id().msg_id() == t.msg_id && w.frame.id().fragment() == 0)
            .map(|w| w.end)
            .collect();
        let ev = events.get(&(t.node, t.tx)).map_or(&[][..], Vec::as_slice);
        let mut st = SrtStats {
            name: t.label.clone(),
            ..SrtStats::default()
        };
        let mut k = 0;
        for &at in ev {
            // Transfers that ended before this event belong to earlier ones.
            while ends.get(k).is_some_and(|&e| e < at) {
                k += 1;
            }
            let end = ends.get(k).copied();
            k += 1;
            if at < win.from || at + t.deadline_ns >= win.to {
                continue;
            }
            st.count += 1;
            match end {
                Some(e) => {
                    let lat = e - at;
                    st.latencies_ns.push(lat);
                    if lat > t.deadline_ns {
                        st.misses += 1;
                    }
                }
                None => st.misses += 1,
            }
        }
        st.latencies_ns.sort_unstable();
        out.push(st);
    }
    out
}
