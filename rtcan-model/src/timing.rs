//! The build-time timing check (issue 10): from each module's board (clock, cost table)
//! and its plan (frames its filters accept, its TX schedule, sync processing), the
//! worst-case latency from a slot boundary to the TXRQ of its frame and its protocol CPU
//! load at 100 % bus load of the densest frames it accepts. A robot whose guard does not
//! cover latency + clock error bound (`guard-too-short`), or whose protocol load exceeds
//! the CPU (`cpu-overload`), is not admissible. `rtcan check` and the build (build.rs, the
//! proc macro) run it through `analyze`, so what `check` admits builds.
//!
//! Latency is a response-time analysis of the slot timer's path: exception entry, the
//! `slot_boundary_to_txrq` path (which already includes blocking by lower-priority
//! critical sections), blocking by one handler of the same priority already running
//! (handlers of one priority do not preempt each other), and interference by every
//! higher-priority handler at its minimum inter-arrival time, iterated to the fixpoint
//! (Joseph and Pandya 1986). Instructions become cycles with the table's CPI bound and
//! time with the board's clock. Formulas: docs/ROBOT_TOML.md, "Timing check".
use crate::costs::{CostTable, Design};
use crate::diag::{Code, Diagnostic};
use crate::model::{Board, FilterMode, Model};
use crate::plan::Plan;
use crate::units;
use rtcan_core::fragment::wire_len;
use rtcan_core::heartbeat::HEARTBEAT_DLC;
use rtcan_core::timing::{bits_to_ns, STUFFED_OVERHEAD_BITS, TAIL_BITS};
use rtcan_core::Class;
use std::fmt::Write as _;

/// Largest protocol CPU load admitted (the whole CPU: above it, frames are lost).
pub const MAX_CPU_LOAD: f64 = 1.0;

/// Frames a bxCAN receive FIFO holds (a further one is lost: locked mode).
pub const RX_FIFO_DEPTH: u64 = 3;

/// Fixpoint of `R = base + Σ ceil(R / T) · C` over `(C, T)` (cycles), from `base`; stops
/// once past `limit` (the caller's check fails anyway), so the cost stays bounded.
fn fixpoint(base: f64, higher: &[(f64, f64)], limit: f64) -> f64 {
    let mut r = base;
    for _ in 0..1000 {
        let next = base
            + higher
                .iter()
                .map(|(c, p)| (r / p).ceil().max(1.0) * c)
                .sum::<f64>();
        let done = (next - r).abs() < 1e-9;
        r = next;
        if done || r > limit {
            break;
        }
    }
    r
}

/// How a board timestamps the start of frame of a received sync.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Timestamp {
    /// bxCAN time-triggered communication mode: a 16-bit counter of bit times captured
    /// at SOF.
    Ttcm,
}

/// What the timing check needs to know about a board's CPU (the clock comes with the
/// cost table: `[meta] cpu_hz`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoardCpu {
    /// Flash wait states at the table's clock (documentation of its CPI bound).
    pub flash_wait_states: u8,
    /// SOF timestamp strategy.
    pub timestamp: Timestamp,
    /// The cost table's firmware design.
    pub design: Design,
}

/// The CPU facts of a board. Every board today is an STM32F103 at 72 MHz (2 flash wait
/// states) with TTCM stamps; `qemu` (lm3s6965 + software CAN) is checked as an F103, like
/// its filters, since that is what its figures stand for.
pub const fn board_cpu(board: Board) -> BoardCpu {
    match board {
        Board::Stm32f103c8 | Board::Stm32f103rb | Board::Stm32f103re | Board::Qemu => BoardCpu {
            flash_wait_states: 2,
            timestamp: Timestamp::Ttcm,
            design: Design::Prioritised,
        },
    }
}

/// One module's figures.
#[derive(Clone, Debug, PartialEq)]
pub struct ModuleTiming {
    /// Module name.
    pub name: String,
    /// Worst-case slot boundary → TXRQ, ns.
    pub slot_latency_worst_ns: u64,
    /// Worst-case time from a frame entering the RX FIFO to the RX interrupt done with
    /// it, ns.
    pub rx_response_worst_ns: u64,
    /// Slot clock error bound against bus time, ns (0 for the master).
    pub clock_error_ns: u64,
    /// Protocol CPU load at 100 % bus load of the densest accepted frames (1.0 = all).
    pub cpu_load: f64,
    /// Shortest frame its filters accept, ns (the RX inter-arrival bound).
    pub rx_frame_min_ns: u64,
    /// Blocking by a same-priority handler, cycles.
    pub blocking_cycles: f64,
    /// Interference by higher-priority handlers at the fixpoint, cycles.
    pub interference_cycles: f64,
}

/// The check's figures for a robot.
#[derive(Clone, Debug, PartialEq)]
pub struct Timing {
    /// The guard every module's latency plus clock error must fit, ns.
    pub guard_ns: u64,
    /// Per module, in plan order.
    pub modules: Vec<ModuleTiming>,
}

/// Shortest duration of an extended data frame with `dlc` data bytes: no stuff bits.
fn min_frame_ns(dlc: usize, bitrate: u32) -> u64 {
    let dlc = dlc.min(8) as u32;
    bits_to_ns(STUFFED_OVERHEAD_BITS + 8 * dlc + TAIL_BITS, bitrate)
}

/// Shortest frame of a message of `size` bytes (single frame: its size; else the last
/// fragment, the rest of the wire length with the transfer CRC).
fn topic_min_frame_ns(size: u16, bitrate: u32) -> u64 {
    let wire = wire_len(usize::from(size));
    let last = if wire <= 8 {
        wire
    } else {
        match wire % 8 {
            0 => 8,
            r => r,
        }
    };
    min_frame_ns(last, bitrate)
}

/// The figures of `plan` with the given cost table for every module (`None`: each
/// board's own table).
pub fn analyze(plan: &Plan, table: Option<&CostTable>) -> Result<Timing, String> {
    let mut modules = Vec::new();
    // Each design's table is parsed once, whatever the number of modules.
    let mut own: Vec<(Design, CostTable)> = Vec::new();
    for (mi, m) in plan.modules.iter().enumerate() {
        let cpu = board_cpu(m.board);
        let t = match table {
            Some(t) => t,
            None => {
                if !own.iter().any(|(d, _)| *d == cpu.design) {
                    own.push((cpu.design, cpu.design.table()?));
                }
                match own.iter().find(|(d, _)| *d == cpu.design) {
                    Some((_, t)) => t,
                    None => continue,
                }
            }
        };
        modules.push(module_timing(plan, mi, t, cpu));
    }
    Ok(Timing {
        guard_ns: plan.bus.guard_ns,
        modules,
    })
}

fn module_timing(plan: &Plan, mi: usize, t: &CostTable, cpu: BoardCpu) -> ModuleTiming {
    let bus = &plan.bus;
    let bitrate = bus.bitrate;
    let bit_ns = bits_to_ns(1, bitrate);
    let hz = f64::from(t.clock_hz);
    let ns_to_cycles = |ns: u64| ns as f64 * hz / 1e9;
    let cycles_to_ns = |c: f64| (c * 1e9 / hz).ceil() as u64;
    let Some(m) = plan.modules.get(mi) else {
        return ModuleTiming {
            name: String::new(),
            slot_latency_worst_ns: 0,
            rx_response_worst_ns: 0,
            clock_error_ns: 0,
            cpu_load: 0.0,
            rx_frame_min_ns: 0,
            blocking_cycles: 0.0,
            interference_cycles: 0.0,
        };
    };
    let several = plan.modules.len() > 1;

    // Frames the filters accept: sync, other modules' heartbeats, its received topics
    // (accept-all: every topic another module sends).
    let mut rx_min = min_frame_ns(8, bitrate);
    if several {
        rx_min = rx_min.min(min_frame_ns(usize::from(HEARTBEAT_DLC), bitrate));
    }
    let accepted: Vec<usize> = match m.filter_mode {
        FilterMode::Exact => m.rx.clone(),
        FilterMode::AcceptAll => (0..plan.topics.len()).collect(),
    };
    for tp in accepted.iter().filter_map(|i| plan.topics.get(*i)) {
        if tp.on_bus && tp.module != mi {
            rx_min = rx_min.min(topic_min_frame_ns(tp.size, bitrate));
        }
    }
    // Frames it sends: heartbeat, the sync on the master, its topics.
    let mut tx_min = min_frame_ns(usize::from(HEARTBEAT_DLC), bitrate);
    let cycle_s = bus.cycle_ns as f64 / 1e9;
    let mut tx_per_cycle = 1.0 / f64::from(plan.supervision.heartbeat_cycles.max(1));
    if m.is_master {
        tx_per_cycle += 1.0;
    }
    tx_per_cycle += m.calendar.len() as f64 / f64::from(bus.hyperperiod_cycles.max(1));
    for tp in m.tx.iter().filter_map(|i| plan.topics.get(*i)) {
        tx_min = tx_min.min(topic_min_frame_ns(tp.size, bitrate));
        if tp.class != Class::Hrt {
            tx_per_cycle += tp.rate_hz.unwrap_or(0.0) * f64::from(tp.fragments) * cycle_s;
        }
    }

    let entry = f64::from(t.irq_entry_cycles);
    let cost = |name: &str| t.cycles(t.path(name).max);
    // Every handler with its period (minimum inter-arrival), ns.
    let mut handlers: Vec<(&str, u64)> = vec![
        ("isr_can_rx", rx_min),
        ("task_rx_process", rx_min),
        ("isr_can_tx", tx_min),
        ("task_tx_done", tx_min),
        ("task_prepare_slot", bus.slot_ns),
        ("systick", t.systick_period_ns),
    ];
    if !m.is_master {
        handlers.push(("task_sync_slave", bus.cycle_ns));
    }
    // Task rows a design runs inside an interrupt count with that interrupt.
    let handlers: Vec<(&str, f64, f64)> = handlers
        .into_iter()
        .filter(|(n, _)| t.path(n).runs_in.is_none())
        .map(|(n, period)| (n, t.cycles(t.handler_max(n)), ns_to_cycles(period.max(1))))
        .filter(|(_, c, _)| *c > 0.0)
        .collect();

    let timer_prio = t.priority("isr_slot_timer");
    let blocking = handlers
        .iter()
        .filter(|(n, _, _)| t.priority(n) == timer_prio)
        .map(|(_, c, _)| entry + c)
        .fold(0.0, f64::max);
    let base = entry + t.cycles(t.path("slot_boundary_to_txrq").max) + blocking;
    let higher: Vec<(f64, f64)> = handlers
        .iter()
        .filter(|(n, _, _)| t.priority(n) > timer_prio)
        .map(|(_, c, p)| (entry + c, *p))
        .collect();
    let r = fixpoint(base, &higher, ns_to_cycles(bus.slot_ns));

    // The RX interrupt: one activation, blocked by one handler of its priority or by the
    // protocol task's critical section at the timer's ceiling, preempted by every higher
    // priority (the timer included). The FIFO holds RX_FIFO_DEPTH frames meanwhile.
    let rx_prio = t.priority("isr_can_rx");
    let rx_own = entry + t.cycles(t.handler_max("isr_can_rx"));
    let mut all = handlers.clone();
    all.push((
        "isr_slot_timer",
        t.cycles(t.handler_max("isr_slot_timer")),
        ns_to_cycles(bus.slot_ns),
    ));
    let cs = if timer_prio >= rx_prio {
        t.cycles(t.path("critical_section_slot").max)
    } else {
        0.0
    };
    let rx_blocking = all
        .iter()
        .filter(|(n, _, _)| *n != "isr_can_rx" && t.priority(n) == rx_prio)
        .map(|(_, c, _)| entry + c)
        .fold(cs, f64::max);
    let rx_higher: Vec<(f64, f64)> = all
        .iter()
        .filter(|(n, _, _)| t.priority(n) > rx_prio)
        .map(|(_, c, p)| (entry + c, *p))
        .collect();
    let fifo_cycles = ns_to_cycles(rx_min) * RX_FIFO_DEPTH as f64;
    let rx_r = fixpoint(rx_own + rx_blocking, &rx_higher, fifo_cycles);

    let load_cycles_per_s = {
        let per = |cycles: f64, period_ns: u64| cycles * 1e9 / period_ns.max(1) as f64;
        let mut l = per(entry + cost("isr_slot_timer"), bus.slot_ns)
            + per(cost("task_prepare_slot"), bus.slot_ns)
            + per(entry + cost("isr_can_rx") + cost("task_rx_process"), rx_min)
            + per(entry + cost("systick"), t.systick_period_ns)
            + (entry + cost("isr_can_tx") + cost("task_tx_done")) * tx_per_cycle
                / cycle_s.max(1e-12);
        if !m.is_master {
            l += per(cost("task_sync_slave"), bus.cycle_ns);
        }
        l
    };
    let clock_error_ns = if m.is_master {
        0
    } else {
        match cpu.timestamp {
            // The anchor SOF is quantised to one bit time, and the rate measured between
            // two quantised SOFs one cycle apart extrapolates up to one more bit time by
            // the end of the cycle.
            Timestamp::Ttcm => 2 * bit_ns,
        }
    };
    ModuleTiming {
        name: m.name.clone(),
        slot_latency_worst_ns: cycles_to_ns(r),
        rx_response_worst_ns: cycles_to_ns(rx_r),
        clock_error_ns,
        cpu_load: load_cycles_per_s / hz,
        rx_frame_min_ns: rx_min,
        blocking_cycles: blocking,
        interference_cycles: r - base,
    }
}

/// Runs the check on a plan with each board's own table; errors go to `diags`.
pub fn check(model: &Model, plan: &Plan, diags: &mut Vec<Diagnostic>) {
    match analyze(plan, None) {
        Ok(timing) => diagnose(model, plan, &timing, None, diags),
        Err(e) => diags.push(Diagnostic::new(
            Code::GuardTooShort,
            None,
            format!("embedded cost table does not parse: {e}"),
        )),
    }
}

/// Turns figures into diagnostics (`design`: the table name for the notes, `None` =
/// each board's own).
pub fn diagnose(
    model: &Model,
    plan: &Plan,
    timing: &Timing,
    table: Option<&CostTable>,
    diags: &mut Vec<Diagnostic>,
) {
    let bus = &plan.bus;
    for (mt, m) in timing.modules.iter().zip(&plan.modules) {
        let span = model
            .modules
            .iter()
            .find(|x| x.name == m.name)
            .and_then(|x| x.span.clone());
        let cpu = board_cpu(m.board);
        let own = cpu.design.table().ok();
        let (name, cpi, mhz) = table.or(own.as_ref()).map_or((String::new(), 0.0, 0), |t| {
            (t.design.clone(), t.cpi, t.clock_hz / 1_000_000)
        });
        let basis = format!(
            "cost table `{name}`, CPI {} at {mhz} MHz; docs/ROBOT_TOML.md \"Timing check\"",
            units::trim_float(cpi),
        );
        let need = mt.slot_latency_worst_ns + mt.clock_error_ns;
        if need > bus.guard_ns {
            let per_slot = bus.worst_frame_ns + need;
            let fit = (bus.requested_cycle_ns / per_slot.max(1)).min(64);
            let slots_hint = if fit >= u64::from(bus.slots_per_cycle) {
                format!(
                    " (the {} slot still holds the {} frame plus that guard)",
                    units::fmt_ns(bus.slot_ns as f64),
                    units::fmt_ns(bus.worst_frame_ns as f64)
                )
            } else if fit >= 2 {
                format!(
                    " and use at most {fit} slots per {} cycle (slot >= {} frame + guard)",
                    units::fmt_ns(bus.requested_cycle_ns as f64),
                    units::fmt_ns(bus.worst_frame_ns as f64)
                )
            } else {
                format!(
                    "; no slot of a {} cycle holds the {} frame plus that guard: use a longer cycle or a lower bitrate",
                    units::fmt_ns(bus.requested_cycle_ns as f64),
                    units::fmt_ns(bus.worst_frame_ns as f64)
                )
            };
            diags.push(
                Diagnostic::new(
                    Code::GuardTooShort,
                    span.clone(),
                    format!(
                        "module `{}`: worst-case latency from a slot boundary to its TXRQ ({}) plus its clock error bound ({}) is {}, more than the guard ({})",
                        m.name,
                        units::fmt_ns(mt.slot_latency_worst_ns as f64),
                        units::fmt_ns(mt.clock_error_ns as f64),
                        units::fmt_ns(need as f64),
                        units::fmt_ns(bus.guard_ns as f64)
                    ),
                )
                .help(format!(
                    "set `guard = \"{}\"` in `[bus]`{slots_hint}",
                    units::fmt_ns(need as f64).replace(' ', "")
                ))
                .note(basis.clone()),
            );
        }
        let fifo_ns = mt.rx_frame_min_ns * RX_FIFO_DEPTH;
        if mt.rx_response_worst_ns > fifo_ns {
            diags.push(
                Diagnostic::new(
                    Code::RxFifoOverrun,
                    span.clone(),
                    format!(
                        "module `{}`: its RX interrupt may take {} to read a frame, longer than its {RX_FIFO_DEPTH}-frame FIFO lasts at 100% bus load of the shortest frames it accepts ({} each)",
                        m.name,
                        units::fmt_ns(mt.rx_response_worst_ns as f64),
                        units::fmt_ns(mt.rx_frame_min_ns as f64)
                    ),
                )
                .help(
                    "lower the bitrate, or use exact filters (`filters = \"exact\"`) so that only longer frames reach it",
                )
                .note(basis.clone()),
            );
        }
        if mt.cpu_load > MAX_CPU_LOAD {
            diags.push(
                Diagnostic::new(
                    Code::CpuOverload,
                    span,
                    format!(
                        "module `{}`: protocol CPU load {:.0}% at 100% bus load of the shortest frames its filters accept ({} each)",
                        m.name,
                        100.0 * mt.cpu_load,
                        units::fmt_ns(mt.rx_frame_min_ns as f64)
                    ),
                )
                .help(
                    "lower the bitrate, use fewer slots per cycle, or exact filters (`filters = \"exact\"`) so that fewer frames reach the CPU",
                )
                .note(basis),
            );
        }
    }
}

/// The text report's timing section.
pub fn text(plan: &Plan) -> String {
    let mut o = String::new();
    let timing = match analyze(plan, None) {
        Ok(t) => t,
        Err(e) => return format!("\ntiming: cost table error: {e}\n"),
    };
    let _ = writeln!(
        o,
        "\ntiming (guard {}; latency = slot boundary -> TXRQ, worst case; load at 100% bus load of the shortest accepted frames):",
        units::fmt_ns(timing.guard_ns as f64)
    );
    let _ = writeln!(
        o,
        "  {:<16} {:>12} {:>12} {:>12} {:>9}",
        "module", "latency", "clock error", "margin", "cpu load"
    );
    for mt in &timing.modules {
        let need = mt.slot_latency_worst_ns + mt.clock_error_ns;
        let margin = timing.guard_ns as f64 - need as f64;
        let _ = writeln!(
            o,
            "  {:<16} {:>12} {:>12} {:>12} {:>8.1}%",
            mt.name,
            units::fmt_ns(mt.slot_latency_worst_ns as f64),
            units::fmt_ns(mt.clock_error_ns as f64),
            if margin >= 0.0 {
                units::fmt_ns(margin)
            } else {
                format!("-{}", units::fmt_ns(-margin))
            },
            100.0 * mt.cpu_load
        );
    }
    if let Some(m) = plan.modules.first() {
        if let Ok(t) = board_cpu(m.board).design.table() {
            let _ = writeln!(
                o,
                "  cost table `{}` (CPI {} at {} MHz): {}",
                t.design,
                units::trim_float(t.cpi),
                t.clock_hz / 1_000_000,
                t.source
            );
        }
    }
    o
}

/// `timing` of `rtcan check --json`: `{guard_ns, modules: [{name, slot_latency_worst_ns,
/// cpu_load}]}`.
pub fn json(plan: &Plan) -> serde_json::Value {
    match analyze(plan, None) {
        Ok(t) => serde_json::json!({
            "guard_ns": t.guard_ns,
            "modules": t.modules.iter().map(|m| serde_json::json!({
                "name": m.name,
                "slot_latency_worst_ns": m.slot_latency_worst_ns,
                "cpu_load": m.cpu_load,
            })).collect::<Vec<_>>(),
        }),
        Err(e) => serde_json::json!({ "error": e }),
    }
}
