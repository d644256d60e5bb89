//! The emulated run as the simulator's report: an `rtcan_sim::triskar::TriskarRun` built
//! from what the emulation measured, printed by rtcan-sim's own `triskar_text` /
//! `triskar_json` (so `rtcan sim --emulate --json` has exactly the fields of
//! `rtcan sim --json`, docs/SIM.md). Where a figure comes from differs, docs/EMULATOR.md
//! ("The report") says how:
//!
//! - HRT periods, jitter and misses, bus load, slot overlaps: rtcan-sim's `Meter` and
//!   `slots::overlaps` over the emulated bus's frames (the same code as the simulator).
//! - SRT latency: from the publication (the stamp the publisher's `Topic` wrote into its
//!   RAM, `publications`) to the end of the last fragment on the wire, against the
//!   topic's deadline, as the simulator measures it.
//! - CPU (`run.cpu`): the slot-timer → TXRQ latency and the busy time measured on the
//!   emulated core (`probe`), design `emulated`.
//! - Robot: the simulator's plant (path, gap, wall), odometry and the host-bound
//!   messages as decoded from the gateway's USART1 output, overrides from the bus.
//! - Modules: `synced` = sent a frame in the last 0.2 s (a slave that lost sync stops
//!   transmitting), safe state from the images' defmt lines; the engine's counters are
//!   read from each image's RAM at the end of the run (`engine_ram`, located through the
//!   image's DWARF); an image without debug info reports `tx_frames` from the bus only.
use std::collections::BTreeMap;

use rtcan_core::fragment::{counter_of, fragment_count};
use rtcan_core::sync::parse_sync;
use rtcan_core::{Class, Nanos};
use rtcan_model::Plan;
use rtcan_sim::cpu::{CpuReport, CpuSummary};
use rtcan_sim::metrics::{Meter, SrtStats, TopicInfo};
use rtcan_sim::run::{window, Run, SimConfig};
use rtcan_sim::triskar::{ModuleReport, TriskarConfig, TriskarRun};

use crate::robot::{raw_to_frame, EmuRobot};

const PS_NS: u64 = 1_000;

/// Parameters of the emulated run, for the report's header.
#[derive(Clone, Copy, Debug)]
pub struct RunInfo {
    pub seconds: f64,
    pub seed: u64,
    pub wall_x_m: f64,
    pub cpi: f64,
}

/// SRT latency per label: publication → end of the last fragment (fragment 0) on the
/// wire, against the topic's deadline, as the simulator measures it. The publication
/// instants come from the publisher's RAM (`publications`); the k-th transfer of a topic
/// carries the oldest publication not yet matched that is not past its deadline at the
/// first fragment's TXRQ (the engine sends a topic's messages in order and drops a
/// message at its deadline: a publication passed over that way is a miss). A topic whose
/// stamps were not located is measured from the first fragment's TXRQ (a lower bound).
fn srt_stats(
    robot: &EmuRobot,
    topics: &[TopicInfo],
    win: rtcan_sim::metrics::Window,
) -> Vec<SrtStats> {
    let mut out: Vec<SrtStats> = Vec::new();
    let srt: Vec<&TopicInfo> = topics.iter().filter(|t| t.class == Class::Srt).collect();
    for t in &srt {
        if !out.iter().any(|s| s.name == t.label) {
            out.push(SrtStats {
                name: t.label.clone(),
                ..SrtStats::default()
            });
        }
    }
    let pubs = robot.bus.publications.as_ref();
    let watched = |t: &TopicInfo| {
        pubs.and_then(|p| {
            p.topics
                .iter()
                .find(|w| w.node == t.node && w.msg_id == t.msg_id)
        })
    };
    let in_window = |at: Nanos, t: &TopicInfo| at >= win.from && at + t.deadline_ns < win.to;
    // Per topic: the transfer's start (publication, or TXRQ) and the next publication
    // not yet matched.
    let mut first: BTreeMap<usize, Nanos> = BTreeMap::new();
    let mut cursor: BTreeMap<usize, usize> = BTreeMap::new();
    let bit_ns = robot.bus.bit_ps / PS_NS;
    let ends = robot.bus.sim.wire.iter().filter(|w| w.ok);
    for (((node, f, sof), (req, _)), w) in robot.bus.log.iter().zip(&robot.bus.meta).zip(ends) {
        let Some(frame) = raw_to_frame(f) else {
            continue;
        };
        let id = frame.id();
        let Some(k) = srt
            .iter()
            .position(|t| t.node == *node && t.msg_id == id.msg_id())
        else {
            continue;
        };
        let Some(t) = srt.get(k) else { continue };
        let counter = counter_of(t.size, id.fragment());
        if counter + 1 == fragment_count(t.size) {
            let req_ns = req / PS_NS;
            let start = match watched(t) {
                Some(wt) => {
                    let c = cursor.entry(k).or_insert(0);
                    // Passed over: dropped by the engine at its deadline.
                    while let Some(&p) = wt.published.get(*c) {
                        if p + t.deadline_ns >= req_ns {
                            break;
                        }
                        if in_window(p, t) {
                            if let Some(s) = out.iter_mut().find(|s| s.name == t.label) {
                                s.lost();
                            }
                        }
                        *c += 1;
                    }
                    match wt.published.get(*c) {
                        Some(&p) if p <= sof * bit_ns => {
                            *c += 1;
                            p
                        }
                        _ => req_ns,
                    }
                }
                None => req_ns,
            };
            first.insert(k, start);
        }
        if counter == 0 {
            let Some(start) = first.remove(&k) else {
                continue;
            };
            if in_window(start, t) {
                if let Some(s) = out.iter_mut().find(|s| s.name == t.label) {
                    s.delivered(w.end.saturating_sub(start), t.deadline_ns);
                }
            }
        }
    }
    // Publications never sent whose deadline passed inside the run: misses.
    let end = robot.bus.log.last().map_or(0, |(_, _, sof)| sof * bit_ns);
    for (k, t) in srt.iter().enumerate() {
        let Some(wt) = watched(t) else { continue };
        let from = cursor.get(&k).copied().unwrap_or(0);
        for &p in wt.published.iter().skip(from) {
            if p + t.deadline_ns < end && in_window(p, t) {
                if let Some(s) = out.iter_mut().find(|s| s.name == t.label) {
                    s.lost();
                }
            }
        }
    }
    out
}

/// Safe-state transitions from a module's defmt lines (`run.rs`'s `SafeLog`): trips
/// after it had once been cleared, and whether it is required at the end.
fn safe_from_log(lines: &[String]) -> (u32, bool) {
    let (mut trips, mut was_ok, mut now) = (0, false, true);
    for l in lines {
        if l.contains("safe state cleared") {
            was_ok = true;
            now = false;
        } else if l.contains("safe state required") {
            if was_ok {
                trips += 1;
            }
            was_ok = false;
            now = true;
        }
    }
    (trips, now)
}

/// The report of an emulated run of `robot` (after `run_until(info.seconds)`); `logs`
/// are the decoded defmt lines per module, `engines` where each module's engine counters
/// are in its RAM (`engine_ram::locate` of its image; `None`: counted on the bus).
pub fn triskar_run(
    robot: &mut EmuRobot,
    plan: &Plan,
    info: RunInfo,
    logs: &[Vec<String>],
    engines: &[Option<crate::engine_ram::CountersAt>],
) -> Result<TriskarRun, String> {
    let sc = rtcan_sim::robot::scenario(plan, &[])?;
    let sim = SimConfig {
        seconds: info.seconds,
        seed: info.seed,
        record_wire: false,
        cpu: None,
        ..SimConfig::default()
    };
    let end = sim.end_ns();
    let win = window(&sim);
    let bit_ns = robot.bus.bit_ps / PS_NS;
    let wire = robot.wire();
    let mut meter = Meter::new(&sc.topics, win, bit_ns.max(1));
    // Cycles with two syncs and the longest silence, from the emulated wire (as the
    // simulator's report counts them).
    let mut syncs = rtcan_sim::sync_watch::SyncWatch::new(sc.bus().map_or(0, |b| b.cycle_ns()));
    for w in &wire {
        meter.frame(w);
        syncs.frame(w);
    }
    syncs.finish(end);
    let mut figures = meter.finish();
    figures.srt = srt_stats(robot, &sc.topics, win);
    let overlaps = match sc.bus() {
        Some(bc) => {
            // Bus time from the master's first sync frame: its slot-timer match is the
            // start of the cycle the frame names (the images' crystals are exact here).
            let origin = robot.bus.log.iter().zip(&robot.bus.meta).find_map(
                |((node, f, _), (_, boundary))| {
                    let frame = raw_to_frame(f)?;
                    let s = parse_sync(&frame, bc.slots_per_cycle)?;
                    let b = (*boundary)? / PS_NS;
                    (*node == sc.master)
                        .then(|| b.checked_sub(u64::from(s.cycle) * bc.cycle_ns()))
                        .flatten()
                },
            );
            match origin {
                Some(o) => rtcan_sim::slots::overlaps(&wire, &bc, sc.masks(), |g| g.checked_sub(o)),
                None => 0,
            }
        }
        None => 0,
    };
    let now_ps = end * PS_NS;
    let modules_cpu: Vec<CpuSummary> = robot
        .bus
        .mcus
        .iter()
        .map(|m| CpuSummary {
            name: m.name.clone(),
            load: 1.0 - m.st.asleep_ps as f64 / now_ps.max(1) as f64,
            txrq_max_ns: m.st.probe.max_ns,
            txrq_p99_ns: m.st.probe.quantile_ns(0.99),
            txrq_mean_ns: m.st.probe.mean_ns(),
            txrq_samples: m.st.probe.samples,
            timer_merged: 0,
        })
        .collect();
    let recent = end.saturating_sub(200_000_000);
    let mut modules = Vec::new();
    for (i, m) in robot.bus.mcus.iter().enumerate() {
        let name: &'static str = crate::robot::MODULES.get(i).copied().unwrap_or("?");
        let sent = robot.bus.log.iter().filter(|(n, _, _)| *n == i).count();
        let synced = robot
            .bus
            .log
            .iter()
            .rev()
            .take_while(|(_, _, sof)| sof * bit_ns >= recent)
            .any(|(n, _, _)| *n == i);
        let (safe_trips, safe_now) = safe_from_log(logs.get(i).map_or(&[][..], |l| l));
        let counters = match engines.get(i).and_then(Option::as_ref) {
            Some(at) => at.read(m).map_err(|e| format!("{}: {e}", m.name))?,
            None => rtcan_core::counters::Counters {
                tx_frames: u32::try_from(sent).unwrap_or(u32::MAX),
                ..Default::default()
            },
        };
        let motor = (1..=3).contains(&i).then(|| {
            let w = robot
                .physics
                .motors
                .get(i - 1)
                .map_or(0.0, |mo| mo.wheel_speed_rad_s());
            (w as f32, safe_now)
        });
        modules.push(ModuleReport {
            name,
            // The images' apps are generated from the same placement.
            nodes: triskar2_nodes::app::MODULE_NODES
                .iter()
                .find(|(module, _)| *module == name)
                .map_or(&[][..], |(_, nodes)| nodes),
            counters,
            synced,
            safe_trips,
            safe_now,
            safe_reason: None,
            sync_master: 0,
            motor,
            // No faults are injected under emulation: the configured master (the
            // gateway, module 0) is the one sending the sync when it is synced.
            master: name == "gateway" && synced,
            reboots: 0,
            safe_exits: 0,
            safe_times: (None, None),
            // The bus's fault confinement of this node (rtcan-sim's, which the bxCAN's ESR
            // shows); FIFO overruns and guardians live in the images' RAM, not read back.
            error_state: robot
                .bus
                .sim
                .controller(i)
                .map(|c| c.conf.state())
                .unwrap_or_default(),
            fifo_overruns: 0,
            guardian_cut_at: None,
            // Sample age is measured by the emulator's own trace (tests/robot.rs), not
            // carried into this report.
            sample_age: Vec::new(),
        });
    }
    let path = std::mem::take(&mut robot.physics.path).into_vec();
    let final_gap_m = path.last().map_or(f64::INFINITY, |s| s.gap_m);
    let rx = &robot.host_rx;
    let script = robot.script;
    let ns_s = |n: Nanos| n as f64 / 1e9;
    Ok(TriskarRun {
        run: Run {
            policy: "ours",
            figures,
            overlaps,
            wire: Vec::new(),
            // rtcan-sim's bus counted them (frames, error frames, contention, busy time).
            bus: robot.bus.sim.stats,
            counters: modules.iter().map(|m| m.counters).collect(),
            rx_ok: 0,
            rx_bad: 0,
            sim_ns: end,
            cpu: CpuReport {
                design: "emulated".into(),
                cpi: info.cpi,
                clock_hz: 72_000_000,
                cost: "emulated",
                modules: modules_cpu,
            },
        },
        path,
        min_gap_m: robot.physics.min_gap_m,
        final_gap_m,
        max_x_m: robot.physics.max_x_m,
        overrides: robot.overrides,
        odometry: rx.odometry.clone(),
        odometry_rx: rx.odometry.len() as u64,
        gateway_rx: (rx.proximity, rx.battery, rx.log, rx.last_log.clone()),
        modules,
        supervision: Vec::new(),
        // The images apply the rules but publish neither health nor tables.
        module_state: Default::default(),
        // No firmware update in an emulated run (the images have no update port yet).
        update: Vec::new(),
        booted: Vec::new(),
        update_cuts: Vec::new(),
        syncs,
        slots_live: (0, 0),
        config: TriskarConfig {
            sim,
            wall_x_m: info.wall_x_m,
            command_vx: script.vx,
            command_from_s: ns_s(script.from_ns),
            command_until_s: ns_s(script.until_ns),
            gateway_dies_at_s: None,
            module_dies_at: None,
            faults: Vec::new(),
            guardian: false,
            update: None,
            supervise: false,
        },
    })
}
