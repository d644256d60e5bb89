//! Running a scenario under one policy and measuring it.

use rtcan_core::counters::Counters;
use rtcan_core::engine::Policy;
use rtcan_core::tables::BusConfig;
use rtcan_core::{Class, Nanos};

use rtcan_core::clock::SlotClock;

use crate::bus::{Bus, BusStats, Module, NodeSetup, WireFrame};
use crate::clock::NodeClock;
use crate::fixed::FixedNode;
use crate::ideal;
use crate::metrics::{Figures, Meter, TopicInfo, Window};
use crate::policy::PolicyKind;
use crate::slots::overlaps;
use crate::tables::OwnedTables;
use crate::traffic::{stack_bytes, Gen, SizedNode, TrafficHost, WARMUP_NS};

/// Physical and run parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct SimConfig {
    /// Simulated time, s.
    pub seconds: f64,
    /// Seed of every random stream.
    pub seed: u64,
    /// SRT rate scale (1.0 = the scenario's rates).
    pub load: f64,
    /// Bit error rate (0 = none).
    pub bit_error_rate: f64,
    /// Interrupt latency of every node, ns.
    pub irq_latency_ns: Nanos,
    /// Largest clock drift of a slave, ppm (slaves get spread values up to it).
    pub drift_ppm: f64,
    /// Keep the wire log in `Run::wire` (memory grows with the run).
    pub record_wire: bool,
    /// Write the wire log as a candump file while running (memory stays bounded).
    pub wire_log: Option<std::path::PathBuf>,
    /// Without `record_wire`, still keep the frames of these message IDs in `Run::wire`
    /// (the end-to-end chains' topics, `chains::measure`: memory grows with their
    /// traffic only).
    pub keep_msg_ids: Vec<u16>,
    /// Modelled CPU of every module (`None`: handlers take no time but
    /// `irq_latency_ns`; with a model the latency comes from it, `cpu.rs`).
    pub cpu: Option<crate::cpu::CpuModel>,
    /// Per receiver and frame, probability of an error only it sees in the last-but-one
    /// bit of EOF (`Bus::set_eof_error_rate`; 0 = none).
    pub eof_error_rate: f64,
    /// Bus-level faults (`fault::apply_bus`: stuck, partition, stall) at their times
    /// (a scenario file's `faults`).
    pub faults: Vec<crate::fault::Fault>,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            seconds: 1.0,
            seed: 1,
            load: 1.0,
            bit_error_rate: 0.0,
            irq_latency_ns: 2_000,
            drift_ppm: 50.0,
            record_wire: true,
            wire_log: None,
            keep_msg_ids: Vec::new(),
            cpu: None,
            eof_error_rate: 0.0,
            faults: Vec::new(),
        }
    }
}

impl SimConfig {
    /// Moves what the run keeps of `fresh` (the bus's latest frames) to `kept`: all with
    /// `record_wire`, else the frames of `keep_msg_ids`.
    pub fn keep_wire(&self, kept: &mut Vec<WireFrame>, fresh: &mut Vec<WireFrame>) {
        if self.record_wire {
            kept.append(fresh);
        } else {
            kept.extend(
                fresh
                    .drain(..)
                    .filter(|w| self.keep_msg_ids.contains(&w.frame.id().msg_id().0)),
            );
        }
    }

    /// Interrupt latency the bus adds: 0 with a CPU model (it models the entry itself).
    pub fn node_irq_latency_ns(&self) -> Nanos {
        if self.cpu.is_some() {
            0
        } else {
            self.irq_latency_ns
        }
    }

    /// Simulated end time, ns.
    pub fn end_ns(&self) -> Nanos {
        (self.seconds * 1e9) as Nanos
    }

    /// Clock of node `n`: the master (0) is ideal; slaves get offsets and drifts spread
    /// over ±`drift_ppm` so that no two agree.
    pub fn clock(&self, n: usize) -> NodeClock {
        if n == 0 {
            return NodeClock::default();
        }
        let sign = if n % 2 == 1 { 1.0 } else { -1.0 };
        let frac = 1.0 - 0.37 * ((n - 1) / 2 % 3) as f64;
        NodeClock::new(n as u64 * 1_234_567, sign * self.drift_ppm * frac)
    }
}

/// A scenario: per-node tables, generators, and how to label topics.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Tables of every node (node 0 is the master).
    pub tables: Vec<OwnedTables>,
    /// Generators of every node.
    pub gens: Vec<Vec<Gen>>,
    /// Every transmitted topic.
    pub topics: Vec<TopicInfo>,
    /// Index of the master node.
    pub master: usize,
    /// Every node's name (robot.toml's module names), for plots and reports.
    pub names: Vec<String>,
}

impl Scenario {
    /// Bus parameters.
    pub fn bus(&self) -> Option<BusConfig> {
        self.tables.first().map(|t| t.bus)
    }

    /// Reservation masks of the hyperperiod (from the master's tables).
    pub fn masks(&self) -> &[u64] {
        self.tables
            .get(self.master)
            .map_or(&[][..], |t| t.master_masks.as_slice())
    }
}

/// The result of one run.
#[derive(Clone, Debug, Default)]
pub struct Run {
    /// Policy name.
    pub policy: &'static str,
    /// Measured figures.
    pub figures: Figures,
    /// Frames breaking temporal isolation (TDMA policies only).
    pub overlaps: u64,
    /// The wire log (empty unless recorded).
    pub wire: Vec<WireFrame>,
    /// Bus counters.
    pub bus: BusStats,
    /// Engine counters per node (engine policies only).
    pub counters: Vec<Counters>,
    /// Delivered messages whose content checked / did not check.
    pub rx_ok: u64,
    /// See `rx_ok`.
    pub rx_bad: u64,
    /// Simulated span, ns.
    pub sim_ns: Nanos,
    /// CPU model figures (empty without a model).
    pub cpu: crate::cpu::CpuReport,
}

/// Measurement window of a run.
pub fn window(cfg: &SimConfig) -> Window {
    Window {
        from: WARMUP_NS,
        to: cfg.end_ns(),
    }
}

/// Runs `sc` with the engine under `policy` (laxity encoding from the tables). Each
/// module's engine is sized by its tables (`traffic::TIERS`).
pub fn run_engine(
    sc: &Scenario,
    cfg: &SimConfig,
    kind: PolicyKind,
    policy: Policy,
) -> Result<Run, String> {
    let go = || {
        run_bus(
            sc,
            cfg,
            kind,
            |t, host, clock| SizedNode::new(t, policy, host, clock.local(0)),
            |m| {
                let c = m.counters();
                (m.host_mut(), Some(c))
            },
            |m| Some(m.clock()),
        )
    };
    match stack_bytes(&sc.tables) {
        None => go(),
        // The largest engine is built on the stack before it is boxed.
        Some(bytes) => std::thread::scope(|s| {
            std::thread::Builder::new()
                .stack_size(bytes)
                .spawn_scoped(s, go)
                .map_err(|e| format!("simulator thread: {e}"))?
                .join()
                .map_err(|_| "simulator thread panicked".to_string())?
        }),
    }
}

/// Runs `sc` on plain CAN with fixed priorities (baseline (d)).
pub fn run_fixed(sc: &Scenario, cfg: &SimConfig) -> Result<Run, String> {
    run_bus(
        sc,
        cfg,
        PolicyKind::FixedPriority,
        |t, host, _| {
            let periods: Vec<Nanos> = sc
                .topics
                .iter()
                .filter(|i| i.node == usize::from(t.module))
                .map(|i| i.period_ns)
                .collect();
            Ok(FixedNode::new(t, host, &periods))
        },
        |m| (&mut m.host, None),
        |_| None,
    )
}

/// Runs `sc` under the reference (c): the omniscient EDF over the free windows, on the
/// same event trace (regenerated from the same streams); HRT figures are those of
/// `engine_run` (same TDMA).
pub fn run_ideal(sc: &Scenario, cfg: &SimConfig, engine_run: &Run) -> Run {
    let bit_ns = sc
        .bus()
        .map_or(1_000, |b| rtcan_core::timing::bits_to_ns(1, b.bitrate));
    let mut meter = Meter::new(&sc.topics, window(cfg), bit_ns);
    let mut wire = Vec::new();
    ideal::schedule(sc, cfg.seed, cfg.end_ns(), &mut meter, |w| {
        if cfg.record_wire || cfg.keep_msg_ids.contains(&w.frame.id().msg_id().0) {
            wire.push(*w);
        }
    });
    let mut figures = meter.finish();
    figures.hrt = engine_run.figures.hrt.clone();
    figures.load.sync = engine_run.figures.load.sync;
    figures.load.hrt = engine_run.figures.load.hrt;
    Run {
        policy: PolicyKind::IdealEdf.name(),
        figures,
        overlaps: 0,
        wire,
        bus: BusStats::default(),
        counters: Vec::new(),
        rx_ok: 0,
        rx_bad: 0,
        sim_ns: cfg.end_ns(),
        cpu: engine_run.cpu.clone(),
    }
}

/// Simulated time between two hand-overs of events and frames to the meter: what is
/// kept in between is bounded by this span, not by the run.
pub const CHUNK_NS: Nanos = 50_000_000;

/// Hands node `n`'s logged events and HRT releases to the meter.
fn drain_host(meter: &mut Meter, n: usize, host: &mut TrafficHost) {
    let clock = *host.clock();
    for (tx, log) in host.topics.iter_mut().enumerate() {
        for (seq, at) in log.events.drain(..) {
            meter.event(n, tx as u8, seq, at);
        }
        for (seq, local) in log.released.drain(..) {
            meter.release(n, tx as u8, seq, clock.global_at(local));
        }
    }
}

fn run_bus<'t, M: Module>(
    sc: &'t Scenario,
    cfg: &SimConfig,
    kind: PolicyKind,
    make: impl Fn(&'t OwnedTables, TrafficHost, NodeClock) -> Result<M, String>,
    parts: impl Fn(&mut M) -> (&mut TrafficHost, Option<Counters>),
    slot_clock: impl Fn(&M) -> Option<&SlotClock>,
) -> Result<Run, String> {
    let bitrate = sc.bus().map_or(1_000_000, |b| b.bitrate);
    let mut bus = Bus::new(bitrate, cfg.bit_error_rate, cfg.seed);
    bus.set_eof_error_rate(cfg.eof_error_rate);
    for (n, t) in sc.tables.iter().enumerate() {
        let clock = cfg.clock(n);
        let gens = sc.gens.get(n).map_or(&[][..], Vec::as_slice);
        let host = TrafficHost::new(n as u8, clock, gens, t.tx.len(), cfg.seed);
        bus.add_node(
            make(t, host, clock)?,
            NodeSetup {
                clock,
                irq_latency_ns: cfg.node_irq_latency_ns(),
                cpu: cfg.cpu.clone(),
                ..NodeSetup::default()
            },
        );
    }
    let end = cfg.end_ns();
    let mut meter = Meter::new(&sc.topics, window(cfg), bus.bit_ns());
    let mut log = match &cfg.wire_log {
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
    let mut faults = cfg.faults.clone();
    faults.sort_by_key(|f| f.at);
    let mut next_fault = 0;
    while t < end {
        t = (t + CHUNK_NS).min(end);
        while let Some(f) = faults.get(next_fault).filter(|f| f.at <= t) {
            bus.run_until(f.at);
            if !crate::fault::apply_bus(&mut bus, f) {
                return Err(format!(
                    "fault {:?}: not supported by this scenario's nodes",
                    f.kind
                ));
            }
            next_fault += 1;
        }
        bus.run_until(t);
        // Events before the frames that carry them.
        for n in 0..bus.len() {
            if let Some(m) = bus.module_mut(n) {
                drain_host(&mut meter, n, parts(m).0);
            }
        }
        for w in &bus.wire {
            meter.frame(w);
        }
        if let Some((out, p)) = &mut log {
            crate::candump::write(out, &bus.wire, "can0")
                .map_err(|e| format!("{}: {e}", p.display()))?;
        }
        ov += match (
            bus.module(sc.master).and_then(&slot_clock),
            bus.clock(sc.master),
            sc.bus(),
        ) {
            (Some(sclock), Some(c0), Some(bc)) => {
                let start = c0.local(0) + bc.slot_ns;
                overlaps(&bus.wire, &bc, sc.masks(), |g| {
                    let l = c0.local(g);
                    (l >= start).then(|| sclock.to_bus(l))
                })
            }
            _ => 0,
        };
        cfg.keep_wire(&mut kept, &mut bus.wire);
        meter.expire(t);
    }
    if let Some((mut out, p)) = log {
        std::io::Write::flush(&mut out).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    let mut counters = Vec::new();
    let (mut rx_ok, mut rx_bad) = (0, 0);
    for n in 0..bus.len() {
        if let Some(m) = bus.module_mut(n) {
            let (host, c) = parts(m);
            counters.extend(c);
            rx_ok += host.rx_ok;
            rx_bad += host.rx_bad;
        }
    }
    Ok(Run {
        policy: kind.name(),
        figures: meter.finish(),
        overlaps: ov,
        wire: kept,
        bus: bus.stats,
        counters,
        rx_ok,
        rx_bad,
        sim_ns: end,
        cpu: bus.cpu_report(|n| format!("node{n}")),
    })
}

/// Topic descriptions of a scenario whose tables are `tables`, labelled by `label(node, tx)`.
pub fn topic_infos(
    tables: &[OwnedTables],
    label: impl Fn(usize, usize) -> String,
    period_slots: impl Fn(usize, usize) -> u64,
) -> Vec<TopicInfo> {
    let mut v = Vec::new();
    for (n, t) in tables.iter().enumerate() {
        for (i, topic) in t.tx.iter().enumerate() {
            v.push(TopicInfo {
                node: n,
                tx: i as u8,
                msg_id: topic.msg_id,
                class: topic.class,
                label: label(n, i),
                size: usize::from(topic.size),
                deadline_ns: if topic.class == Class::Srt {
                    topic.deadline_ns
                } else {
                    0
                },
                period_ns: period_slots(n, i) * t.bus.slot_ns,
            });
        }
    }
    v
}
