//! Measurements taken from the emulated instruction stream: the slot boundary's latency
//! (TIM2 compare match → the TXRQ store of the frame the slot-timer interrupt commits),
//! per transmit mailbox the time of its last TXRQ, and the time the core was busy.
//! These are what `rtcan_sim::cpu` models from the cost table, so the two can be
//! compared (docs/EMULATOR.md, "Emulation against the CPU model").

/// Exception number of TIM2 (IRQ 28, RM0008 table 63).
pub const EXC_TIM2: u16 = 16 + 28;
/// Histogram resolution and size, as `rtcan_sim::cpu` (10 ns bins up to 200 µs).
const BIN_NS: u64 = 10;
const BINS: usize = 20_000;

/// Slot timer → TXRQ latencies of one MCU.
#[derive(Clone, Debug)]
pub struct SlotProbe {
    /// The TIM2 interrupt line as last seen.
    line: bool,
    /// Time (ps) the line rose, while no TXRQ answered it yet.
    open: Option<u64>,
    /// What the core was doing when the line rose: (PC, PRIMASK, BASEPRI, active
    /// exception), for the worst sample (`worst`).
    at_rise: Option<(u32, bool, u8, u16)>,
    /// The worst sample's latency (ns) and `at_rise`: what delayed the slot timer most.
    pub worst: Option<(u64, (u32, bool, u8, u16))>,
    hist: Vec<u32>,
    pub samples: u64,
    sum_ns: f64,
    pub max_ns: u64,
    /// Per TX mailbox: time (ps) of its last TXRQ.
    pub txrq_ps: [u64; 3],
    /// Per TX mailbox: the slot boundary (TIM2 match, ps) its last TXRQ answered, if it
    /// was the slot's commit.
    pub boundary_ps: [Option<u64>; 3],
}

impl Default for SlotProbe {
    fn default() -> Self {
        SlotProbe {
            line: false,
            open: None,
            at_rise: None,
            worst: None,
            hist: vec![0; BINS],
            samples: 0,
            sum_ns: 0.0,
            max_ns: 0,
            txrq_ps: [0; 3],
            boundary_ps: [None; 3],
        }
    }
}

impl SlotProbe {
    /// The TIM2 line as last seen.
    pub fn line(&self) -> bool {
        self.line
    }

    /// The TIM2 line is `high` at `now` (ps): a rising edge opens a boundary.
    pub fn timer_line(&mut self, high: bool, now: u64) {
        if high && !self.line {
            self.open = Some(now);
            self.at_rise = None;
        }
        self.line = high;
    }

    /// A TXRQ store into `mailbox` at `now` (ps); `in_timer_isr`: the TIM2 handler is
    /// active (the slot's commit). The first one answers the open boundary.
    pub fn txrq(&mut self, mailbox: usize, now: u64, in_timer_isr: bool) {
        if let Some(t) = self.txrq_ps.get_mut(mailbox) {
            *t = now;
        }
        let boundary = self.open.filter(|_| in_timer_isr);
        if let Some(b) = self.boundary_ps.get_mut(mailbox) {
            *b = boundary;
        }
        if !in_timer_isr {
            return;
        }
        if let Some(open) = self.open.take() {
            let ns = now.saturating_sub(open) / 1_000;
            self.samples += 1;
            self.sum_ns += ns as f64;
            if ns > self.max_ns || self.worst.is_none() {
                self.worst = self.at_rise.map(|c| (ns, c));
            }
            self.max_ns = self.max_ns.max(ns);
            let bin = ((ns / BIN_NS) as usize).min(BINS - 1);
            if let Some(b) = self.hist.get_mut(bin) {
                *b += 1;
            }
        }
    }

    /// The core's state when the line rose (call right after a rising `timer_line`).
    pub fn core_at_rise(&mut self, pc: u32, primask: bool, basepri: u8, active: u16) {
        if self.open.is_some() && self.at_rise.is_none() {
            self.at_rise = Some((pc, primask, basepri, active));
        }
    }

    /// The TIM2 handler returned: a boundary it did not answer with a TXRQ (nothing to
    /// send in that slot) is not a sample.
    pub fn timer_isr_done(&mut self) {
        self.open = None;
    }

    /// Mean latency, ns.
    pub fn mean_ns(&self) -> f64 {
        if self.samples == 0 {
            0.0
        } else {
            self.sum_ns / self.samples as f64
        }
    }

    /// Latency quantile `q` (0..=1) at the histogram's resolution, ns (as
    /// `rtcan_sim::cpu::CpuStats`).
    pub fn quantile_ns(&self, q: f64) -> u64 {
        if self.samples == 0 {
            return 0;
        }
        let rank = ((q * self.samples as f64).ceil() as u64).max(1);
        let mut seen = 0u64;
        for (i, n) in self.hist.iter().enumerate() {
            seen += u64::from(*n);
            if seen >= rank {
                if i + 1 == BINS {
                    break;
                }
                return ((i as u64 + 1) * BIN_NS).min(self.max_ns);
            }
        }
        self.max_ns
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;

    #[test]
    fn rising_edge_to_first_txrq_in_the_handler() {
        let mut p = SlotProbe::default();
        p.timer_line(true, 1_000_000);
        p.timer_line(true, 1_500_000); // still high: not a new boundary
        p.txrq(0, 1_900_000, false); // from another handler: not the slot's commit
        p.txrq(1, 2_500_000, true);
        p.txrq(2, 2_600_000, true); // second TXRQ of the same boundary: not a sample
        assert_eq!((p.samples, p.max_ns), (1, 1_500));
        assert_eq!(p.txrq_ps, [1_900_000, 2_500_000, 2_600_000]);
        p.timer_line(false, 3_000_000);
        p.timer_line(true, 4_000_000);
        p.timer_isr_done(); // nothing sent in that slot
        p.txrq(0, 5_000_000, true);
        assert_eq!(p.samples, 1);
        p.timer_line(false, 6_000_000);
        p.timer_line(true, 7_000_000);
        p.txrq(0, 7_500_000, true);
        assert_eq!((p.samples, p.max_ns), (2, 1_500));
        assert_eq!(p.mean_ns(), 1_000.0);
        // Upper edge of the 10 ns bin, as rtcan-sim's CPU model reports it.
        assert_eq!(p.quantile_ns(0.5), 510);
        assert_eq!(p.quantile_ns(0.99), 1_500);
    }
}
