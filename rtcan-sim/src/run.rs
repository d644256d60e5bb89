//! Running a scenario under one policy and measuring it.
use std::collections::HashMap;

use rtcan_core::counters::Counters;
use rtcan_core::engine::Policy;
use rtcan_core::tables::BusConfig;
use rtcan_core::{Class, Nanos};

use rtcan_core::clock::SlotClock;

use crate::bus::{Bus, BusStats, Module, NodeSetup, WireFrame};
use crate::clock::NodeClock;
use crate::fixed::FixedNode;
use crate::ideal;
use crate::metrics::{compute, Figures, TopicInfo, Window};
use crate::policy::PolicyKind;
use crate::slots::overlaps;
use crate::tables::OwnedTables;
use crate::traffic::{EngineNode, Gen, TrafficHost, WARMUP_NS};

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
    /// Keep the wire log (needed for candump and plots).
    pub record_wire: bool,
    /// Modelled CPU of every module (`None`: handlers take no time but
    /// `irq_latency_ns`; with a model the latency comes from it, `cpu.rs`).
    pub cpu: Option<crate::cpu::CpuModel>,
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
            cpu: None,
        }
    }
}

impl SimConfig {
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
pub struct Scenario {
    /// Tables of every node (node 0 is the master).
    pub tables: Vec<OwnedTables>,
    /// Generators of every node.
    pub gens: Vec<Vec<Gen>>,
    /// Every transmitted topic.
    pub topics: Vec<TopicInfo>,
    /// Index of the master node.
    pub master: usize,
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
    /// Events per (node, tx): global times by sequence number.
    pub events: HashMap<(usize, u8), Vec<Nanos>>,
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

/// Runs `sc` with the engine under `policy` (laxity encoding from the tables).
pub fn run_engine(sc: &Scenario, cfg: &SimConfig, kind: PolicyKind, policy: Policy) -> Run {
    run_bus(
        sc,
        cfg,
        kind,
        |t, host, clock| EngineNode::new(t, policy, host, clock.local(0)),
        |m| (&m.host, Some(*m.engine.counters())),
        |m| Some(m.engine.clock()),
    )
}

/// Runs `sc` on plain CAN with fixed priorities (baseline (d)).
pub fn run_fixed(sc: &Scenario, cfg: &SimConfig) -> Run {
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
            FixedNode::new(t, host, &periods)
        },
        |m| (&m.host, None),
        |_| None,
    )
}

/// Runs `sc` with the bound (c): the engine run's event trace scheduled by the
/// omniscient EDF; HRT figures are those of `engine_run` (same TDMA).
pub fn run_ideal(sc: &Scenario, cfg: &SimConfig, engine_run: &Run) -> Run {
    let wire = ideal::schedule(sc, &engine_run.events, cfg.end_ns());
    let bit_ns = sc
        .bus()
        .map_or(1_000, |b| rtcan_core::timing::bits_to_ns(1, b.bitrate));
    let mut figures = compute(&wire, &sc.topics, &engine_run.events, window(cfg), bit_ns);
    figures.hrt = engine_run.figures.hrt.clone();
    figures.load.sync = engine_run.figures.load.sync;
    figures.load.hrt = engine_run.figures.load.hrt;
    Run {
        policy: PolicyKind::IdealEdf.name(),
        figures,
        overlaps: 0,
        wire: if cfg.record_wire { wire } else { Vec::new() },
        bus: BusStats::default(),
        counters: Vec::new(),
        rx_ok: 0,
        rx_bad: 0,
        events: engine_run.events.clone(),
        sim_ns: cfg.end_ns(),
        cpu: engine_run.cpu.clone(),
    }
}

fn run_bus<'t, M: Module>(
    sc: &'t Scenario,
    cfg: &SimConfig,
    kind: PolicyKind,
    make: impl Fn(&'t OwnedTables, TrafficHost, NodeClock) -> M,
    parts: impl Fn(&M) -> (&TrafficHost, Option<Counters>),
    slot_clock: impl Fn(&M) -> Option<&SlotClock>,
) -> Run {
    let bitrate = sc.bus().map_or(1_000_000, |b| b.bitrate);
    let mut bus = Bus::new(bitrate, cfg.bit_error_rate, cfg.seed);
    for (n, t) in sc.tables.iter().enumerate() {
        let clock = cfg.clock(n);
        let gens = sc.gens.get(n).map_or(&[][..], Vec::as_slice);
        let host = TrafficHost::new(n as u8, clock, gens, t.tx.len(), cfg.seed);
        bus.add_node(
            make(t, host, clock),
            NodeSetup {
                clock,
                irq_latency_ns: cfg.node_irq_latency_ns(),
                cpu: cfg.cpu.clone(),
                ..NodeSetup::default()
            },
        );
    }
    let end = cfg.end_ns();
    bus.run_until(end);
    let mut events = HashMap::new();
    let mut counters = Vec::new();
    let (mut rx_ok, mut rx_bad) = (0, 0);
    for n in 0..bus.len() {
        if let Some(m) = bus.module(n) {
            let (host, c) = parts(m);
            for (tx, log) in host.topics.iter().enumerate() {
                events.insert((n, tx as u8), log.events.clone());
            }
            counters.extend(c);
            rx_ok += host.rx_ok;
            rx_bad += host.rx_bad;
        }
    }
    let figures = compute(&bus.wire, &sc.topics, &events, window(cfg), bus.bit_ns());
    let ov = match (
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
    Run {
        policy: kind.name(),
        figures,
        overlaps: ov,
        wire: if cfg.record_wire {
            std::mem::take(&mut bus.wire)
        } else {
            Vec::new()
        },
        bus: bus.stats,
        counters,
        rx_ok,
        rx_bad,
        events,
        sim_ns: end,
        cpu: bus.cpu_report(|n| format!("node{n}")),
    }
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
