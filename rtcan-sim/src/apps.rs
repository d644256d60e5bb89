//! Any robot's own node code on the simulated bus: each module runs its generated engine
//! and `ModuleHost` (from `rtcan::robot!` or `rtcan::robot_toml`) and a module app that
//! polls its nodes, exactly as the firmware image's app task does. This is what the
//! `sim` crate of a workspace written by `rtcan new` runs (`cargo run -p sim`); the
//! Triskar2 scenario (`triskar.rs`) is the same idea with plants and a script around it.
//!
//! The generated topics are statics, so a process runs one robot at a time; `run`
//! resets every module's statics (through the `reset` each module gives) before and
//! after.
use std::sync::Mutex;

use rtcan_core::driver::{Mailbox, TxResult};
use rtcan_core::engine::Engine;
use rtcan_core::{Frame, Nanos};
use rtcan_model::Plan;
use rtcan_pubsub::{ModuleHost, SlotGrid, SystemStatus};

use crate::bus::{Bus, Module, NodeSetup};
use crate::controller::{Filter, SimController};
use crate::metrics::{Figures, Meter};
use crate::run::{window, SimConfig, CHUNK_NS};
use crate::sample_age::{AgeMeter, AgeStat, Tap};

/// A module's app as its image runs it: `poll` runs what is due at local time `now` and
/// returns the local time it is next due.
pub trait PollApp {
    /// Runs the nodes that are due; returns the next local due time.
    fn poll(&mut self, now: Nanos) -> Nanos;
    /// Messages the module's nodes published (accepted by their topics).
    fn published(&self) -> u64;
    /// Publications refused (pool exhausted, queue full).
    fn publish_errors(&self) -> u64;
    /// Messages the module's nodes received.
    fn received(&self) -> u64;
}

/// One module: name, generated engine and host, its status, its app, its filters.
pub struct AppModule<const RX: usize, const AR: usize, const Q: usize, A: PollApp> {
    name: &'static str,
    engine: Box<Engine<'static, RX, AR, Q>>,
    host: ModuleHost<'static>,
    status: &'static SystemStatus,
    app: A,
    ages: AgeMeter,
}

impl<const RX: usize, const AR: usize, const Q: usize, A: PollApp> AppModule<RX, AR, Q, A> {
    /// The module as it powers on at local time `now`.
    pub fn new(
        name: &'static str,
        engine: Engine<'static, RX, AR, Q>,
        host: ModuleHost<'static>,
        status: &'static SystemStatus,
        app: A,
    ) -> Self {
        AppModule {
            name,
            engine: Box::new(engine),
            host,
            status,
            app,
            ages: AgeMeter::default(),
        }
    }

    /// The app task's turn after a driver event, then the pump into the engine and the
    /// engine's timer (the order of the firmware's app and protocol tasks).
    fn step(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos> {
        // The slot grid the image's protocol task hands its app (synchronous HRT
        // publishers run `lead` before their slots on it).
        let grid = if self.engine.is_synced() {
            SlotGrid::of_clock(self.engine.clock(), now)
        } else {
            None
        };
        self.status.set_grid(grid);
        let app_next = self.app.poll(now);
        self.host.pump(&mut self.engine, now, can);
        let before = AgeMeter::loaded(can);
        let mut tap = Tap::new(&mut self.host);
        let e = self.engine.poll(now, can, &mut tap);
        self.ages.after_poll(before, &tap.taken, can);
        self.host.pump(&mut self.engine, now, can);
        // Nothing due (an app of subscribers only, an idle engine): no timer armed; a
        // timer at `Nanos::MAX` would overflow the local-to-global clock conversion.
        let next = if e == Nanos::MAX {
            app_next
        } else {
            e.min(app_next)
        };
        (next != Nanos::MAX).then_some(next)
    }
}

impl<const RX: usize, const AR: usize, const Q: usize, A: PollApp> Module
    for AppModule<RX, AR, Q, A>
{
    fn start(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos> {
        self.step(now, can)
    }
    fn wake(&mut self, now: Nanos, can: &mut SimController) -> Option<Nanos> {
        self.step(now, can)
    }
    fn rx(
        &mut self,
        frame: &Frame,
        sof: Nanos,
        now: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos> {
        self.engine.on_rx(frame, sof, can, &mut self.host);
        self.step(now, can)
    }
    fn tx_done(
        &mut self,
        mailbox: Mailbox,
        result: TxResult,
        now: Nanos,
        can: &mut SimController,
    ) -> Option<Nanos> {
        let ok = matches!(result, TxResult::Sent);
        self.ages.on_tx_done(usize::from(mailbox.0), ok, now, can);
        self.engine
            .on_tx_done(mailbox, result, now, can, &mut self.host);
        self.step(now, can)
    }
    fn rx_overrun(&mut self, _now: Nanos) {
        self.engine.on_rx_overrun();
    }
    fn error_state(
        &mut self,
        now: Nanos,
        state: rtcan_core::confinement::ErrorState,
        can: &mut SimController,
    ) -> Option<Nanos> {
        self.engine.on_error_state(now, state, can, &mut self.host);
        self.step(now, can)
    }
}

/// What the run reports of a module, whatever its engine size.
pub trait AppSim: Module {
    /// Module name.
    fn name(&self) -> &'static str;
    /// Its engine's counters.
    fn counters(&self) -> rtcan_core::counters::Counters;
    /// Synchronised at the end.
    fn synced(&self) -> bool;
    /// Safe state required at the end.
    fn safe_now(&self) -> bool;
    /// (published, publish errors, received) of its nodes.
    fn traffic(&self) -> (u64, u64, u64);
    /// Age of its HRT samples at transmission (publish → SOF of the first frame).
    fn sample_age(&self) -> AgeStat;
}

impl<const RX: usize, const AR: usize, const Q: usize, A: PollApp> AppSim
    for AppModule<RX, AR, Q, A>
{
    fn name(&self) -> &'static str {
        self.name
    }
    fn counters(&self) -> rtcan_core::counters::Counters {
        *self.engine.counters()
    }
    fn synced(&self) -> bool {
        self.engine.is_synced()
    }
    fn safe_now(&self) -> bool {
        self.status.safe_state_required()
    }
    fn traffic(&self) -> (u64, u64, u64) {
        (
            self.app.published(),
            self.app.publish_errors(),
            self.app.received(),
        )
    }
    fn sample_age(&self) -> AgeStat {
        self.ages.total()
    }
}

impl Module for Box<dyn AppSim> {
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
        state: rtcan_core::confinement::ErrorState,
        can: &mut SimController,
    ) -> Option<Nanos> {
        (**self).error_state(now, state, can)
    }
}

/// How to build one module at power-on (local time `now`), with its generated filters.
pub struct AppSpec {
    /// Builds the module.
    pub build: Box<dyn Fn(Nanos) -> Box<dyn AppSim>>,
    /// Its generated `FILTERS` (id, mask), programmed as the firmware does.
    pub filters: &'static [(u32, u32)],
    /// Its generated `reset` (topics, status, nodes back to power-on).
    pub reset: fn(),
}

/// One module after the run.
#[derive(Clone, Debug, PartialEq)]
pub struct AppModuleReport {
    pub name: &'static str,
    pub counters: rtcan_core::counters::Counters,
    pub synced: bool,
    pub safe_now: bool,
    pub published: u64,
    pub publish_errors: u64,
    pub received: u64,
    /// Age of its HRT samples at transmission (publish → SOF of the first frame).
    pub sample_age: AgeStat,
}

/// The result of a run.
#[derive(Clone, Debug)]
pub struct AppsRun {
    /// Bus figures (HRT misses per topic from the wire; SRT from the engine counters).
    pub figures: Figures,
    pub modules: Vec<AppModuleReport>,
    pub sim_ns: Nanos,
}

impl AppsRun {
    /// HRT instances missed over every HRT topic (after the warm-up).
    pub fn hrt_misses(&self) -> u64 {
        self.figures.hrt.iter().map(|h| h.misses).sum()
    }

    /// The report `cargo run -p sim` prints.
    pub fn text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "simulated {:.3} s; HRT misses {}",
            self.sim_ns as f64 / 1e9,
            self.hrt_misses()
        );
        let _ = writeln!(
            s,
            "{:<16} {:>6} {:>9} {:>8} {:>8} {:>9} {:>8} {:>8} {:>11}",
            "module",
            "synced",
            "published",
            "pub err",
            "received",
            "tx frames",
            "hrt late",
            "srt miss",
            "age max us"
        );
        for m in &self.modules {
            let _ = writeln!(
                s,
                "{:<16} {:>6} {:>9} {:>8} {:>8} {:>9} {:>8} {:>8} {:>11}",
                m.name,
                if m.synced { "yes" } else { "no" },
                m.published,
                m.publish_errors,
                m.received,
                m.counters.tx_frames,
                m.counters.hrt_late,
                m.counters.deadline_missed,
                if m.sample_age.count == 0 {
                    "-".to_string()
                } else {
                    format!("{:.1}", m.sample_age.max_ns as f64 / 1e3)
                }
            );
        }
        for h in &self.figures.hrt {
            let _ = writeln!(s, "hrt {:<20} misses {}", h.name, h.misses);
        }
        s
    }
}

/// One robot at a time per process (the generated topics are statics).
static LOCK: Mutex<()> = Mutex::new(());

/// Runs `modules` (bus-index order = the plan's module order) on the bus of `plan` for
/// `cfg.seconds`, each with the clock and interrupt latency `cfg` gives it.
pub fn run(plan: &Plan, modules: &[AppSpec], cfg: &SimConfig) -> Result<AppsRun, String> {
    if modules.len() != plan.modules.len() {
        return Err(format!(
            "{} modules given, {} has {}",
            modules.len(),
            plan.file,
            plan.modules.len()
        ));
    }
    let sc = crate::robot::scenario(plan, &[])?;
    let _guard = LOCK.lock().unwrap_or_else(|p| p.into_inner());
    let reset = || modules.iter().for_each(|m| (m.reset)());
    reset();
    let mut bus: Bus<Box<dyn AppSim>> = Bus::new(plan.bus.bitrate, cfg.bit_error_rate, cfg.seed);
    bus.record_wire = true;
    for (n, m) in modules.iter().enumerate() {
        let clock = cfg.clock(n);
        bus.add_node(
            (m.build)(clock.local(0)),
            NodeSetup {
                clock,
                irq_latency_ns: cfg.node_irq_latency_ns(),
                nart: false,
                // As the firmware programs them: the sync bank (the first) into FIFO 0,
                // the others into FIFO 1.
                filter: Filter::Rules(
                    m.filters
                        .iter()
                        .enumerate()
                        .map(|(i, &(id, mask))| (mask, id & mask, u8::from(i > 0)))
                        .collect(),
                ),
                cpu: cfg.cpu.clone(),
            },
        );
    }
    let end = cfg.end_ns();
    let mut meter = Meter::new(&sc.topics, window(cfg), bus.bit_ns());
    let mut t = 0;
    while t < end {
        t = (t + CHUNK_NS).min(end);
        bus.run_until(t);
        for w in &bus.wire {
            meter.frame(w);
        }
        bus.wire.clear();
    }
    let mut reports = Vec::new();
    for n in 0..bus.len() {
        if let Some(m) = bus.module(n) {
            let (published, publish_errors, received) = m.traffic();
            reports.push(AppModuleReport {
                name: m.name(),
                counters: m.counters(),
                synced: m.synced(),
                safe_now: m.safe_now(),
                published,
                publish_errors,
                received,
                sample_age: m.sample_age(),
            });
        }
    }
    drop(bus);
    reset();
    Ok(AppsRun {
        figures: meter.finish(),
        modules: reports,
        sim_ns: end,
    })
}
