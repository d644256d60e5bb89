//! The modelled CPU of a simulated module (issue 10): driver events no longer take zero
//! time. Each interrupt or task is a job with the cost of its firmware path from the
//! committed cost table (`rtcan_model::costs`, instructions × `cpi` cycles at 72 MHz),
//! run by a fixed-priority preemptive scheduler like the Cortex-M3 NVIC under RTIC:
//! the highest priority pending job runs; a job is preempted only by a strictly higher
//! priority; jobs of one priority run to completion in arrival order. SysTick arrives
//! periodically at its own priority. Critical sections of lower-priority code are part of
//! the table's `slot_boundary_to_txrq` row and are not modelled separately.
//!
//! A job is a list of steps, each "run for this long, then do this": the effect (the
//! engine's poll loading a mailbox, the RX FIFO read, delivering a frame to the engine)
//! happens when the modelled execution reaches it, so a slot boundary's TXRQ is as late
//! as the handlers in front of it make it. The bus (`bus.rs`) asks for the next step time
//! and executes the effects on the module; this file only keeps time.
use std::collections::VecDeque;

use rtcan_core::driver::{Mailbox, TxResult};
use rtcan_core::{Frame, Nanos};
use rtcan_model::costs::{CostTable, Design};

/// Resolution of the slot-boundary → TXRQ histogram, ns.
const HIST_BIN_NS: u64 = 10;
/// Bins of the histogram (200 µs; longer latencies count in the last bin, max is exact).
const HIST_BINS: usize = 20_000;

/// Which figure of a path every activation costs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    /// The measured maximum, every time: a stress bound (the longest paths all at once).
    Max,
    /// The measured mean: the typical load.
    Mean,
}

impl Cost {
    /// Name on the command line.
    pub const fn name(self) -> &'static str {
        match self {
            Cost::Max => "max",
            Cost::Mean => "mean",
        }
    }

    /// Parses `max` or `mean`.
    pub fn from_name(name: &str) -> Option<Cost> {
        [Cost::Max, Cost::Mean]
            .into_iter()
            .find(|c| c.name() == name)
    }
}

/// The CPU model of one module: a design's cost table at a CPI.
#[derive(Clone, Debug, PartialEq)]
pub struct CpuModel {
    /// The cost table (its `cpi` is the one used).
    pub table: CostTable,
    /// Design, for reports.
    pub design: Design,
    /// Figure charged per activation.
    pub cost: Cost,
}

impl CpuModel {
    /// The embedded table of `design` at `cpi` cycles per instruction.
    pub fn new(design: Design, cpi: f64) -> Result<CpuModel, String> {
        if !(cpi.is_finite() && (0.5..=10.0).contains(&cpi)) {
            return Err(format!("--cpi must be in [0.5, 10], got {cpi}"));
        }
        Ok(CpuModel {
            table: design.table()?.with_cpi(cpi),
            design,
            cost: Cost::Max,
        })
    }

    /// The same model charging `cost` per activation.
    pub fn with_cost(mut self, cost: Cost) -> CpuModel {
        self.cost = cost;
        self
    }

    /// Time of `instructions` plus `entries` exception entries, ns (rounded up).
    fn ns(&self, instructions: u32, entries: u32) -> Nanos {
        let cycles = self.table.cycles(instructions)
            + f64::from(entries) * f64::from(self.table.irq_entry_cycles);
        (cycles * 1e9 / f64::from(self.table.clock_hz.max(1))).ceil() as Nanos
    }

    /// Instructions of one activation of `path`.
    fn max(&self, path: &str) -> u32 {
        let p = self.table.path(path);
        match self.cost {
            Cost::Max => p.max,
            Cost::Mean => p.mean,
        }
    }

    fn prio(&self, path: &str) -> u8 {
        self.table.priority(path)
    }

    /// The longest critical section the protocol task holds on the slot timer's
    /// resource (`critical_section_slot`; 0 when the table has none).
    fn critical_section(&self) -> u32 {
        self.max("critical_section_slot")
    }

    /// The timer's path to the TXRQ alone: the table's `slot_boundary_to_txrq` max
    /// includes the worst blocking (the critical section, simulated here as such), its
    /// mean is the path alone.
    fn txrq_path(&self) -> u32 {
        let p = self.table.path("slot_boundary_to_txrq");
        match self.cost {
            Cost::Max => p
                .max
                .saturating_sub(self.table.path("critical_section_slot").max),
            Cost::Mean => p.mean,
        }
    }

    /// The work of `task` runs inside an interrupt handler in this design.
    fn inline(&self, task: &str) -> bool {
        self.table.path(task).runs_in.is_some()
    }
}

/// A task: run time, priority, and whether the design runs it inside its interrupt.
#[derive(Clone, Copy, Debug)]
struct TaskCost {
    ns: Nanos,
    prio: u8,
    inline: bool,
}

/// The model's costs in ns and priorities, looked up once (the table is keyed by name).
#[derive(Clone, Debug)]
struct Costs {
    timer_prio: u8,
    /// Timer: entry + path to the TXRQ, then the rest (with an inline preparation).
    timer_pre: Nanos,
    timer_rest: Nanos,
    /// Preparation task after each timer job: (before the critical section, the critical
    /// section at the timer's ceiling, priority); `None` when inline or empty.
    prepare: Option<(Nanos, Nanos, u8)>,
    rx_prio: u8,
    rx_entry: Nanos,
    rx_isr: Nanos,
    rx_task: TaskCost,
    sync_task: TaskCost,
    tx_prio: u8,
    tx_isr: Nanos,
    tx_task: TaskCost,
    systick: Nanos,
    systick_prio: u8,
    systick_period: Nanos,
}

impl Costs {
    fn of(m: &CpuModel) -> Costs {
        let task = |name: &str| TaskCost {
            ns: m.ns(m.max(name), 0),
            prio: m.prio(name),
            inline: m.inline(name),
        };
        let handler = m.max("isr_slot_timer");
        let to_txrq = m.txrq_path().min(handler);
        let prepare = m.max("task_prepare_slot");
        let inline_prepare = m.inline("task_prepare_slot");
        let mut rest = handler - to_txrq;
        if inline_prepare {
            rest = rest.saturating_add(prepare);
        }
        let cs = m.critical_section().min(prepare);
        Costs {
            timer_prio: m.prio("isr_slot_timer"),
            timer_pre: m.ns(to_txrq, 1),
            timer_rest: m.ns(rest, 0),
            prepare: (!inline_prepare && prepare > 0).then(|| {
                (
                    m.ns(prepare - cs, 0),
                    m.ns(cs, 0),
                    m.prio("task_prepare_slot"),
                )
            }),
            rx_prio: m.prio("isr_can_rx"),
            rx_entry: m.ns(0, 1),
            rx_isr: m.ns(m.max("isr_can_rx"), 0),
            rx_task: task("task_rx_process"),
            sync_task: task("task_sync_slave"),
            tx_prio: m.prio("isr_can_tx"),
            tx_isr: m.ns(m.max("isr_can_tx"), 1),
            tx_task: TaskCost {
                inline: m.inline("task_tx_done") || m.max("task_tx_done") == 0,
                ..task("task_tx_done")
            },
            systick: m.ns(m.max("systick"), 1),
            systick_prio: m.prio("systick"),
            systick_period: m.table.systick_period_ns.max(1),
        }
    }
}

/// What a step does when the modelled execution reaches its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    /// Nothing (the rest of a handler, SysTick, slot preparation).
    None,
    /// The slot timer's work: the module's `wake` (engine poll: loads, aborts).
    Wake,
    /// The RX interrupt reads one frame from FIFO `fifo`.
    PopRx {
        /// FIFO index.
        fifo: usize,
    },
    /// The frame reaches the engine (reassembly, delivery, sync correction).
    Rx {
        /// The frame.
        frame: Frame,
        /// Its SOF timestamp, local time.
        sof: Nanos,
    },
    /// Internal (never returned by `advance`): the TX handler queues its completion for
    /// the protocol task, which runs `ns` at `prio` and then has the `TxDone` effect.
    Spawn {
        /// The task's run time, ns.
        ns: Nanos,
        /// Its priority.
        prio: u8,
        /// Mailbox.
        mailbox: Mailbox,
        /// Result.
        result: TxResult,
    },
    /// A transmit completion reaches the engine.
    TxDone {
        /// Mailbox.
        mailbox: Mailbox,
        /// Result.
        result: TxResult,
    },
}

/// Which handler a job is (for de-duplicating pending interrupts and statistics).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Timer,
    Rx(usize),
    Tx,
    /// One activation of the protocol task (`boards/app`'s `protocol`, bound to a
    /// pended interrupt): it drains the RX queue, then the TX queue, then prepares the
    /// next slot once.
    Protocol,
    SysTick,
}

/// Work handed to the protocol task (`Cpu::pend_protocol`).
#[derive(Clone, Copy, Debug)]
enum Work {
    /// One received frame: (run time, effect).
    Rx(Nanos, Effect),
    /// One mailbox completion: (run time, effect).
    Tx(Nanos, Effect),
    /// The slot preparation: (time before the critical section, the critical section).
    Prepare(Nanos, Nanos),
}

#[derive(Clone, Debug)]
struct Job {
    kind: Kind,
    prio: u8,
    seq: u64,
    started: bool,
    /// Steps still to run: (remaining ns, effect at its end).
    steps: VecDeque<(Nanos, Effect)>,
    /// Priority of the job's last step (a critical section at the resource's ceiling).
    ceiling: Option<u8>,
    /// A protocol activation whose last two steps are the slot preparation.
    prepares: bool,
}

impl Job {
    /// Priority now: the ceiling while in the last step, if it has one.
    fn priority(&self) -> u8 {
        match self.ceiling {
            Some(c) if self.steps.len() <= 1 => c.max(self.prio),
            _ => self.prio,
        }
    }
}

/// Figures of one module's CPU over a run.
#[derive(Clone, Debug, PartialEq)]
pub struct CpuStats {
    /// Time the CPU executed handlers, ns.
    pub busy_ns: Nanos,
    /// Slot timer activations answered by the load of a TDMA frame (HRT or sync).
    pub txrq_samples: u64,
    /// Sum of their timer → TXRQ latencies, ns.
    pub txrq_sum_ns: u64,
    /// Largest latency, ns.
    pub txrq_max_ns: Nanos,
    /// Timer interrupts merged into one already pending (the handler was too late).
    pub timer_merged: u64,
    hist: Vec<u32>,
}

impl Default for CpuStats {
    fn default() -> Self {
        CpuStats {
            busy_ns: 0,
            txrq_samples: 0,
            txrq_sum_ns: 0,
            txrq_max_ns: 0,
            timer_merged: 0,
            hist: vec![0; HIST_BINS],
        }
    }
}

impl CpuStats {
    fn record_txrq(&mut self, ns: Nanos) {
        self.txrq_samples += 1;
        self.txrq_sum_ns += ns;
        self.txrq_max_ns = self.txrq_max_ns.max(ns);
        let bin = usize::try_from(ns / HIST_BIN_NS)
            .unwrap_or(usize::MAX)
            .min(HIST_BINS - 1);
        if let Some(b) = self.hist.get_mut(bin) {
            *b += 1;
        }
    }

    /// Mean timer → TXRQ latency, ns.
    pub fn txrq_mean_ns(&self) -> f64 {
        if self.txrq_samples == 0 {
            0.0
        } else {
            self.txrq_sum_ns as f64 / self.txrq_samples as f64
        }
    }

    /// Quantile `q` (0..=1) of the timer → TXRQ latency, ns: the upper edge of the
    /// histogram bin holding it (never above the exact max).
    pub fn txrq_quantile_ns(&self, q: f64) -> Nanos {
        if self.txrq_samples == 0 {
            return 0;
        }
        let rank = ((q * self.txrq_samples as f64).ceil() as u64).max(1);
        let mut seen = 0u64;
        for (i, n) in self.hist.iter().enumerate() {
            seen += u64::from(*n);
            if seen >= rank {
                if i + 1 == HIST_BINS {
                    break; // the overflow bin: only the max is known
                }
                return ((i as u64 + 1) * HIST_BIN_NS).min(self.txrq_max_ns);
            }
        }
        self.txrq_max_ns
    }
}

/// One module's CPU figures in a run report (docs/SIM.md, `cpu.modules[]`).
#[derive(Clone, Debug, PartialEq)]
pub struct CpuSummary {
    /// Module name.
    pub name: String,
    /// Fraction of the simulated time the CPU ran handlers (0..=1).
    pub load: f64,
    /// Slot timer → TXRQ latency over the activations that loaded a frame: max, ns.
    pub txrq_max_ns: Nanos,
    /// The same, 99th percentile (10 ns bins), ns.
    pub txrq_p99_ns: Nanos,
    /// The same, mean, ns.
    pub txrq_mean_ns: f64,
    /// Activations behind those figures.
    pub txrq_samples: u64,
    /// Timer interrupts merged into a pending one.
    pub timer_merged: u64,
}

/// The CPU model of a run (design, CPI) and every module's figures.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CpuReport {
    /// Design name (`prioritised`, `single-priority`).
    pub design: String,
    /// Cycles per instruction used.
    pub cpi: f64,
    /// Core clock, Hz.
    pub clock_hz: u32,
    /// `max` or `mean` per activation.
    pub cost: &'static str,
    /// Per module, in bus order.
    pub modules: Vec<CpuSummary>,
}

impl CpuReport {
    /// Terminal lines (empty without a model).
    pub fn text(&self) -> String {
        if self.modules.is_empty() {
            return String::new();
        }
        let mut s = format!(
            "CPU model: design {}, CPI {}, {} MHz, {} path costs\nmodule        CPU load  slot->TXRQ max / p99 / mean [us]  samples  timer merged\n",
            self.design,
            self.cpi,
            self.clock_hz / 1_000_000,
            self.cost
        );
        for m in &self.modules {
            s.push_str(&format!(
                "{:<12} {:>8.2}%  {:>10.3} / {:.3} / {:.3} {:>14} {:>13}\n",
                m.name,
                100.0 * m.load,
                m.txrq_max_ns as f64 / 1e3,
                m.txrq_p99_ns as f64 / 1e3,
                m.txrq_mean_ns / 1e3,
                m.txrq_samples,
                m.timer_merged
            ));
        }
        s
    }

    /// The `cpu` object of a JSON report (`None` without a model).
    pub fn json_value(&self) -> Option<serde_json::Value> {
        if self.modules.is_empty() {
            return None;
        }
        let mods: Vec<serde_json::Value> = self
            .modules
            .iter()
            .map(|m| {
                serde_json::json!({
                    "name": m.name,
                    "load": crate::report::num(m.load),
                    "slot_to_txrq_ns": {
                        "max": m.txrq_max_ns,
                        "p99": m.txrq_p99_ns,
                        "mean": crate::report::num(m.txrq_mean_ns),
                        "samples": m.txrq_samples,
                    },
                    "timer_merged": m.timer_merged,
                })
            })
            .collect();
        Some(serde_json::json!({
            "design": self.design.to_string(),
            "cpi": crate::report::num(self.cpi),
            "clock_hz": self.clock_hz,
            "cost": self.cost.to_string(),
            "modules": mods,
        }))
    }
}

/// The scheduler state of one module's CPU.
#[derive(Clone, Debug)]
pub struct Cpu {
    model: CpuModel,
    costs: Costs,
    jobs: Vec<Job>,
    /// Index in `jobs` of the running job and since when its current step runs.
    running: Option<(usize, Nanos)>,
    next_systick: Nanos,
    seq: u64,
    /// The slot timer interrupt whose poll has not run yet (or is running): the
    /// boundary the next TXRQ answers, wherever the poll that loads it runs (the
    /// single-priority driver also polls at the end of its RX handler).
    open_boundary: Option<Nanos>,
    /// Counters.
    pub stats: CpuStats,
}

impl Cpu {
    /// An idle CPU; SysTick's first interrupt one period after time 0.
    pub fn new(model: CpuModel) -> Cpu {
        let next_systick = model.table.systick_period_ns;
        Cpu {
            costs: Costs::of(&model),
            model,
            jobs: Vec::new(),
            running: None,
            next_systick,
            seq: 0,
            open_boundary: None,
            stats: CpuStats::default(),
        }
    }

    /// The model.
    pub fn model(&self) -> &CpuModel {
        &self.model
    }

    /// Figures after a run of `sim_ns` ns.
    pub fn summary(&self, name: &str, sim_ns: Nanos) -> CpuSummary {
        CpuSummary {
            name: name.to_string(),
            load: self.stats.busy_ns as f64 / sim_ns.max(1) as f64,
            txrq_max_ns: self.stats.txrq_max_ns,
            txrq_p99_ns: self.stats.txrq_quantile_ns(0.99),
            txrq_mean_ns: self.stats.txrq_mean_ns(),
            txrq_samples: self.stats.txrq_samples,
            timer_merged: self.stats.timer_merged,
        }
    }

    /// Time of the next step end or SysTick, global ns.
    pub fn next_event(&self) -> Nanos {
        let step_end = self.running.and_then(|(j, since)| {
            let job = self.jobs.get(j)?;
            job.steps.front().map(|(left, _)| since + left)
        });
        step_end.map_or(self.next_systick, |t| t.min(self.next_systick))
    }

    /// Charges the running job's current step with the time up to `now`.
    fn account(&mut self, now: Nanos) {
        if let Some((j, since)) = self.running {
            let ran = now.saturating_sub(since);
            if let Some((left, _)) = self.jobs.get_mut(j).and_then(|job| job.steps.front_mut()) {
                *left = left.saturating_sub(ran);
            }
            self.stats.busy_ns += ran;
            self.running = Some((j, now));
        }
    }

    /// Picks the job to run: highest priority; among equals, one already started (it
    /// was preempted, its frame is on the stack), then the earliest arrival.
    fn dispatch(&mut self, now: Nanos) {
        let best = self
            .jobs
            .iter()
            .enumerate()
            .max_by_key(|(_, j)| (j.priority(), j.started, std::cmp::Reverse(j.seq)))
            .map(|(i, _)| i);
        if let Some(i) = best {
            if let Some(j) = self.jobs.get_mut(i) {
                j.started = true;
            }
        }
        self.running = best.map(|i| (i, now));
    }

    fn push(&mut self, now: Nanos, kind: Kind, prio: u8, steps: VecDeque<(Nanos, Effect)>) {
        self.account(now);
        self.seq += 1;
        self.jobs.push(Job {
            kind,
            prio,
            seq: self.seq,
            started: false,
            steps,
            ceiling: None,
            prepares: false,
        });
        self.dispatch(now);
    }

    /// Hands `work` to the protocol task at `prio`. Like the firmware's pended
    /// interrupt, requests made before an activation starts merge into it: its RX work
    /// runs first, then its TX completions, then one preparation (`Driver::run`); a
    /// request made after it started waits for the next activation.
    fn pend_protocol(&mut self, now: Nanos, prio: u8, work: Work) {
        self.account(now);
        let idx = match self
            .jobs
            .iter()
            .position(|j| j.kind == Kind::Protocol && j.prio == prio && !j.started)
        {
            Some(i) => i,
            None => {
                self.seq += 1;
                self.jobs.push(Job {
                    kind: Kind::Protocol,
                    prio,
                    seq: self.seq,
                    started: false,
                    steps: VecDeque::new(),
                    ceiling: None,
                    prepares: false,
                });
                self.jobs.len() - 1
            }
        };
        let ceiling = self.costs.timer_prio;
        let Some(job) = self.jobs.get_mut(idx) else {
            return;
        };
        let prep = if job.prepares { 2 } else { 0 };
        match work {
            Work::Rx(ns, effect) => {
                let at = job
                    .steps
                    .iter()
                    .take(job.steps.len() - prep)
                    .take_while(|(_, e)| matches!(e, Effect::Rx { .. }))
                    .count();
                job.steps.insert(at, (ns, effect));
            }
            Work::Tx(ns, effect) => {
                let at = job.steps.len() - prep;
                job.steps.insert(at, (ns, effect));
            }
            Work::Prepare(before, cs) => {
                if !job.prepares {
                    job.prepares = true;
                    job.steps.push_back((before, Effect::None));
                    job.steps.push_back((cs, Effect::None));
                    job.ceiling = (cs > 0).then_some(ceiling);
                }
            }
        }
        self.dispatch(now);
    }

    /// A job of `kind` that has not reached its effect yet is pending (a second
    /// interrupt request of the same source merges into it, as NVIC pending bits do).
    fn pending(&self, kind: Kind) -> bool {
        self.jobs.iter().any(|j| {
            j.kind == kind
                && j.steps
                    .iter()
                    .any(|(_, e)| matches!(e, Effect::Wake | Effect::PopRx { .. }))
        })
    }

    /// The slot timer fired (its compare matched) at `now`.
    pub fn timer(&mut self, now: Nanos) {
        if self.pending(Kind::Timer) {
            self.stats.timer_merged += 1;
            return;
        }
        self.open_boundary = Some(now);
        let c = &self.costs;
        let steps = VecDeque::from([(c.timer_pre, Effect::Wake), (c.timer_rest, Effect::None)]);
        let prio = c.timer_prio;
        self.push(now, Kind::Timer, prio, steps);
    }

    /// A receive FIFO has frames (its interrupt is requested) at `now`.
    pub fn rx_irq(&mut self, now: Nanos, fifo: usize) {
        if self.pending(Kind::Rx(fifo)) {
            return;
        }
        // The handler reads the FIFO first; the rest of its path follows the read.
        let steps = VecDeque::from([(self.costs.rx_entry, Effect::PopRx { fifo })]);
        let prio = self.costs.rx_prio;
        self.push(now, Kind::Rx(fifo), prio, steps);
    }

    /// The RX handler read `frame` (step `PopRx` done) at `now`: the rest of the handler,
    /// then the protocol processing, inside the handler or as a task per the design.
    pub fn rx_read(&mut self, now: Nanos, frame: Frame, sof: Nanos, sync: bool) {
        let task = if sync {
            self.costs.sync_task
        } else {
            self.costs.rx_task
        };
        let (isr_rest, work, inline, prio) = (self.costs.rx_isr, task.ns, task.inline, task.prio);
        let effect = Effect::Rx { frame, sof };
        self.account(now);
        let Some((j, _)) = self.running else {
            return;
        };
        if let Some(job) = self.jobs.get_mut(j) {
            if inline {
                job.steps.push_back((isr_rest + work, effect));
                return;
            }
            job.steps.push_back((isr_rest, Effect::None));
        }
        self.pend_protocol(now, prio, Work::Rx(work, effect));
    }

    /// A transmit interrupt for `mailbox` at `now`: the handler, then the completion
    /// reaches the engine inside it or in the protocol task (`task_tx_done`), per design.
    pub fn tx_irq(&mut self, now: Nanos, mailbox: Mailbox, result: TxResult) {
        let c = &self.costs;
        let effect = Effect::TxDone { mailbox, result };
        let prio = c.tx_prio;
        if c.tx_task.inline {
            let steps = VecDeque::from([(c.tx_isr + c.tx_task.ns, effect)]);
            self.push(now, Kind::Tx, prio, steps);
            return;
        }
        // The handler queues the completion at its end; the protocol task takes it.
        let spawn = Effect::Spawn {
            ns: c.tx_task.ns,
            prio: c.tx_task.prio,
            mailbox,
            result,
        };
        let steps = VecDeque::from([(c.tx_isr, spawn)]);
        self.push(now, Kind::Tx, prio, steps);
    }

    /// An effect just executed at `now` loaded a TDMA frame (a TXRQ of an HRT fragment
    /// or the sync): if a slot timer interrupt is open, this answers it.
    pub fn loaded(&mut self, now: Nanos) {
        if let Some(b) = self.open_boundary.take() {
            self.stats.record_txrq(now.saturating_sub(b));
        }
    }

    /// The timer's `Wake` effect ran (whether or not it loaded anything).
    pub fn wake_done(&mut self) {
        self.open_boundary = None;
    }

    /// Advances to `now` (= `next_event()`): raises SysTick when due, finishes the
    /// running job's step if it is done and returns its effect for the bus to execute.
    pub fn advance(&mut self, now: Nanos) -> Effect {
        self.account(now);
        if now >= self.next_systick {
            self.next_systick += self.costs.systick_period;
            let steps = VecDeque::from([(self.costs.systick, Effect::None)]);
            let prio = self.costs.systick_prio;
            self.push(now, Kind::SysTick, prio, steps);
        }
        let Some((j, _)) = self.running else {
            return Effect::None;
        };
        let Some(job) = self.jobs.get_mut(j) else {
            return Effect::None;
        };
        match job.steps.front() {
            Some(&(
                0,
                Effect::Spawn {
                    ns,
                    prio,
                    mailbox,
                    result,
                },
            )) => {
                job.steps.pop_front();
                let effect = Effect::TxDone { mailbox, result };
                self.pend_protocol(now, prio, Work::Tx(ns, effect));
                Effect::None
            }
            Some(&(0, effect)) => {
                job.steps.pop_front();
                effect
            }
            _ => Effect::None,
        }
    }

    /// After the bus executed the effect returned by `advance`: retires the running job
    /// if it has no steps left (spawning the slot preparation after a timer job) and
    /// dispatches the next.
    pub fn retire(&mut self, now: Nanos) {
        let Some((j, _)) = self.running else {
            return;
        };
        let done = self.jobs.get(j).is_some_and(|job| job.steps.is_empty());
        if !done {
            return;
        }
        let job = self.jobs.swap_remove(j);
        self.running = None;
        self.dispatch(now);
        if let (Kind::Timer, Some((before, cs, prio))) = (job.kind, self.costs.prepare) {
            // The preparation ends by handing the plan to the timer under its lock.
            self.pend_protocol(now, prio, Work::Prepare(before, cs));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run_to_effect(cpu: &mut Cpu) -> (Nanos, Effect) {
        loop {
            let t = cpu.next_event();
            let e = cpu.advance(t);
            if e != Effect::None {
                return (t, e);
            }
            cpu.retire(t);
        }
    }

    /// A prioritised table with round numbers, so the expected times are plain sums.
    const TEST_TABLE: &str = r#"
[meta]
cpu_hz = 72000000
cpi = 1.0
[priorities]
isr_slot_timer = 4
isr_can_rx = 3
isr_can_tx = 3
task_protocol = 2
systick = 1
[paths.isr_slot_timer]
max = 100
mean = 50
samples = 1
[paths.slot_boundary_to_txrq]
max = 80
mean = 40
samples = 1
[paths.isr_can_rx]
max = 150
mean = 150
samples = 1
[paths.isr_can_tx]
max = 50
mean = 50
samples = 1
[paths.task_rx_process]
max = 600
mean = 300
samples = 1
[paths.task_sync_slave]
max = 900
mean = 900
samples = 1
[paths.task_prepare_slot]
max = 300
mean = 100
samples = 1
[paths.task_tx_done]
max = 200
mean = 100
samples = 1
[paths.systick]
max = 60
mean = 60
samples = 1
[paths.critical_section_slot]
max = 40
mean = 20
samples = 1
"#;

    fn test_model(cost: Cost) -> CpuModel {
        CpuModel {
            table: CostTable::parse(TEST_TABLE).unwrap(),
            design: Design::Prioritised,
            cost,
        }
    }

    /// ns of `cycles` at 72 MHz, rounded up as the model does.
    fn ns(cycles: f64) -> Nanos {
        (cycles * 1e9 / 72e6).ceil() as Nanos
    }

    #[test]
    fn prioritised_timer_preempts_rx_processing() {
        let mut cpu = Cpu::new(test_model(Cost::Max));
        // An RX interrupt at 0: the FIFO read after the 12-cycle entry (167 ns).
        cpu.rx_irq(0, 0);
        let (t, e) = run_to_effect(&mut cpu);
        assert_eq!((t, e), (167, Effect::PopRx { fifo: 0 }));
        let frame = Frame::new(rtcan_core::CanId::from_raw(0x100).unwrap(), &[1]).unwrap();
        cpu.rx_read(t, frame, 0, false);
        cpu.retire(t);
        // The timer fires at 1000 while the RX ISR's rest (150 instr) runs: its TXRQ
        // comes 12 + min(80 - 40, 100) cycles after it (the table's 80 include the
        // 40-instruction critical section, simulated as such).
        cpu.timer(1_000);
        let (t, e) = run_to_effect(&mut cpu);
        assert_eq!(e, Effect::Wake);
        assert_eq!(t, 1_000 + ns(52.0));
        cpu.loaded(t);
        cpu.wake_done();
        cpu.retire(t);
        // Then the rest of the timer (60), the rest of the RX ISR, and the RX task (600)
        // before the preparation task spawned after the timer (same priority, later).
        let (t2, e) = run_to_effect(&mut cpu);
        assert!(matches!(e, Effect::Rx { .. }));
        let isr_end = 167 + ns(150.0) + ns(52.0) + ns(60.0);
        assert_eq!(t2, isr_end + ns(600.0));
        assert_eq!(cpu.stats.txrq_samples, 1);
        assert_eq!(cpu.stats.txrq_max_ns, ns(52.0));
        // The mean model charges the means: the TXRQ after 12 + min(40, 50) cycles.
        let mut cpu = Cpu::new(test_model(Cost::Mean));
        cpu.timer(0);
        let (t, e) = run_to_effect(&mut cpu);
        assert_eq!((t, e), (ns(52.0), Effect::Wake));
    }

    #[test]
    fn a_critical_section_at_the_ceiling_blocks_the_timer() {
        let mut cpu = Cpu::new(test_model(Cost::Max));
        cpu.timer(0);
        let (t, _) = run_to_effect(&mut cpu);
        cpu.loaded(t);
        cpu.wake_done();
        cpu.retire(t);
        // The timer's rest (100 - 40 = 60 instr), then the preparation: 260 at priority
        // 2, then 40 at the timer's ceiling.
        let timer_end = ns(52.0) + ns(60.0);
        let cs_start = timer_end + ns(260.0);
        let mut now = t;
        while now < cs_start {
            now = cpu.next_event();
            let _ = cpu.advance(now);
            cpu.retire(now);
        }
        assert_eq!(now, cs_start);
        // A timer interrupt 10 ns into the critical section waits for its end.
        cpu.timer(cs_start + 10);
        let (t, e) = run_to_effect(&mut cpu);
        assert_eq!(e, Effect::Wake);
        assert_eq!(t, cs_start + ns(40.0) + ns(52.0));
        cpu.loaded(t);
        assert_eq!(cpu.stats.txrq_max_ns, ns(40.0) - 10 + ns(52.0));
        // Outside the critical section the preparation is preempted at once.
        let mut cpu = Cpu::new(test_model(Cost::Max));
        cpu.timer(0);
        let (t, _) = run_to_effect(&mut cpu);
        cpu.wake_done();
        cpu.retire(t);
        cpu.timer(timer_end + 100);
        let (t, e) = run_to_effect(&mut cpu);
        assert_eq!((t, e), (timer_end + 100 + ns(52.0), Effect::Wake));
    }

    #[test]
    fn tx_completion_reaches_the_engine_from_the_task() {
        let mut cpu = Cpu::new(test_model(Cost::Max));
        cpu.tx_irq(0, Mailbox(1), TxResult::Sent);
        let (t, e) = run_to_effect(&mut cpu);
        assert_eq!(
            e,
            Effect::TxDone {
                mailbox: Mailbox(1),
                result: TxResult::Sent
            }
        );
        // ISR (12 + 50) then the task (200), nothing else pending.
        assert_eq!(t, ns(62.0) + ns(200.0));
        // A second timer request while the first has not run its poll merges into it.
        cpu.retire(t);
        cpu.timer(t);
        cpu.timer(t + 10);
        assert_eq!(cpu.stats.timer_merged, 1);
    }

    /// The firmware's protocol task is one pended interrupt: requests made before it
    /// runs merge into one activation, which handles the mailbox completion before the
    /// preparation and prepares once (a model that queued one preparation per timer
    /// interrupt delayed completions behind stacked preparations: the paper master's
    /// one HRT miss at CPI 2.0 with max costs, round 5).
    #[test]
    fn protocol_requests_merge_into_one_activation_completions_first() {
        let mut cpu = Cpu::new(test_model(Cost::Max));
        cpu.timer(0);
        let (t, e) = run_to_effect(&mut cpu);
        assert_eq!((t, e), (ns(52.0), Effect::Wake));
        cpu.wake_done();
        cpu.retire(t);
        // A mailbox completes while the timer's rest runs: its ISR waits (priority 3).
        cpu.tx_irq(t + 1, Mailbox(0), TxResult::Sent);
        let timer_end = ns(52.0) + ns(60.0);
        assert_eq!(cpu.next_event(), timer_end);
        assert_eq!(cpu.advance(timer_end), Effect::None);
        cpu.retire(timer_end);
        // A second boundary 10 ns into the TX ISR preempts it; its preparation request
        // merges into the activation that has not started.
        let t2 = timer_end + 10;
        cpu.timer(t2);
        let (t3, e) = run_to_effect(&mut cpu);
        assert_eq!((t3, e), (t2 + ns(52.0), Effect::Wake));
        cpu.wake_done();
        cpu.retire(t3);
        let isr_end = timer_end + ns(62.0) + ns(52.0) + ns(60.0);
        let (t4, e) = run_to_effect(&mut cpu);
        assert_eq!(
            (t4, e),
            (
                isr_end + ns(200.0),
                Effect::TxDone {
                    mailbox: Mailbox(0),
                    result: TxResult::Sent
                }
            ),
            "the completion before the preparation"
        );
        cpu.retire(t4);
        // One preparation (260 + 40 at the ceiling), then idle until SysTick.
        let mut now = t4;
        let mut last_busy = t4;
        while now < 1_000_000 {
            now = cpu.next_event();
            let busy = cpu.stats.busy_ns;
            let _ = cpu.advance(now);
            if cpu.stats.busy_ns > busy {
                last_busy = now;
            }
            cpu.retire(now);
        }
        assert_eq!(last_busy, t4 + ns(260.0) + ns(40.0));
        assert_eq!(
            cpu.stats.busy_ns, last_busy,
            "no idle gap, nothing else ran"
        );
    }

    #[test]
    fn single_priority_timer_waits_for_the_rx_handler() {
        let mut cpu = Cpu::new(CpuModel::new(Design::SinglePriority, 1.0).unwrap());
        cpu.rx_irq(0, 0);
        let (t, _) = run_to_effect(&mut cpu);
        let frame = Frame::new(rtcan_core::CanId::from_raw(0x100).unwrap(), &[1]).unwrap();
        cpu.rx_read(t, frame, 0, true);
        cpu.retire(t);
        cpu.timer(1_000);
        let (t_rx, e) = run_to_effect(&mut cpu);
        assert!(matches!(e, Effect::Rx { .. }), "RX first: same priority");
        // 5168 + 2497 instructions inside the RX interrupt.
        assert_eq!(
            t_rx,
            167 + ((5168.0 + 2497.0) * 1e9 / 72e6_f64).ceil() as Nanos
        );
        cpu.retire(t_rx);
        let (t, e) = run_to_effect(&mut cpu);
        assert_eq!(e, Effect::Wake);
        assert_eq!(t, t_rx + ((12.0 + 274.0) * 1e9 / 72e6_f64).ceil() as Nanos);
        // A second compare while the first is pending merges into it.
        cpu.timer(t);
        assert_eq!(cpu.stats.timer_merged, 0, "the first already ran its poll");
    }

    #[test]
    fn systick_interrupts_at_its_period_and_is_busy_time() {
        let mut cpu = Cpu::new(CpuModel::new(Design::Prioritised, 1.0).unwrap());
        let mut t = 0;
        while t < 10_500_000 {
            t = cpu.next_event();
            let _ = cpu.advance(t);
            cpu.retire(t);
        }
        // 10 SysTicks of (12 + 60) cycles = 1000 ns each.
        assert_eq!(cpu.stats.busy_ns, 10 * 1_000);
        assert!(CpuModel::new(Design::Prioritised, 0.0).is_err());
        assert!(CpuModel::new(Design::Prioritised, f64::NAN).is_err());
    }

    #[test]
    fn quantiles_come_from_the_histogram() {
        let mut s = CpuStats::default();
        for ns in 1..=100 {
            s.record_txrq(ns * 100);
        }
        assert_eq!(s.txrq_max_ns, 10_000);
        assert_eq!(s.txrq_quantile_ns(0.99), 9_910);
        assert_eq!(s.txrq_quantile_ns(0.5), 5_010);
        assert_eq!(s.txrq_mean_ns(), 5_050.0);
        s.record_txrq(10_000_000);
        assert_eq!(s.txrq_quantile_ns(1.0), 10_000_000);
    }
}
