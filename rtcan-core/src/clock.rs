//! The slot clock: maps the node-local clock to bus time. The master's local clock is
//! bus time; a slave aligns on the sync frame's start-of-frame and corrects its rate.
//!
//! Bus time is nanoseconds since slot 0 of absolute cycle 0. A slave keeps an anchor
//! (local SOF time of the last sync, and that sync's bus time `abs_cycle · cycle_ns`)
//! and a rate `local ns per bus ns = 1 + ppb / 10⁹`, measured between consecutive syncs
//! received. Integer math in 64 bits only (`mul_div` splits products so they cannot
//! overflow; 128-bit division is a long software routine on Cortex-M3 and its code
//! alone was 1.4 KiB of a 32 KiB image). Gaps between syncs longer than `MAX_GAP_NS`
//! (or three cycles, on buses with cycles longer than that) relock instead of
//! extrapolating.
//!
//! The 2014 C code measured the slot length once at start-up and then only reset the
//! phase at each sync (original-rtcan-code.md §2–3): drift was never corrected within a
//! cycle, and a missed sync sent the node to a terminal error state. Here a missed sync
//! just extrapolates with the measured rate, and the counter is unwrapped across gaps.
use crate::sync::CYCLE_COUNTER_MODULUS;
use crate::tables::BusConfig;
use crate::time::Nanos;

/// Parts per billion in one.
const PPB: i64 = 1_000_000_000;
/// Longest gap between two syncs bridged with the measured rate (8.5 s, hundreds of
/// cycles); after a longer silence the slave relocks from scratch. A bus whose cycle is
/// longer than a third of this bridges three cycles instead (the rate is measured
/// between consecutive syncs, so the gap must hold at least one cycle).
pub const MAX_GAP_NS: i64 = 1 << 33;
/// Largest rate error believed (1 %, twice the ±5000 ppm crystals are specified for);
/// a larger measurement means the master restarted or the counter jumped: relock.
pub const MAX_RATE_PPB: i64 = 10_000_000;

/// Slot clock state.
#[derive(Clone, Copy, Debug)]
pub struct SlotClock {
    master: bool,
    cycle_ns: Nanos,
    wrap: u32,
    locked: bool,
    rate_valid: bool,
    /// Local time of the anchor (master: `start`; slave: SOF of the last sync).
    anchor_local: Nanos,
    /// Bus time of the anchor.
    anchor_bus: Nanos,
    /// Absolute cycle of the last sync (slave).
    abs_cycle: u64,
    /// Cycle counter of the last sync, already reduced modulo `wrap`.
    counter: u32,
    /// Local clock rate error: local ns per bus ns = 1 + ppb / 10⁹.
    ppb: i64,
}

impl SlotClock {
    /// Master: bus time 0 (slot 0 of cycle 0) is local time `start`.
    pub fn master(bus: &BusConfig, start: Nanos) -> Self {
        let mut c = Self::slave(bus);
        c.master = true;
        c.locked = true;
        c.rate_valid = true;
        c.anchor_local = start;
        c
    }
    /// Slave, not yet locked.
    pub fn slave(bus: &BusConfig) -> Self {
        let wrap = match bus.cycle_counter_wrap {
            0 => CYCLE_COUNTER_MODULUS,
            w => w.min(CYCLE_COUNTER_MODULUS),
        };
        SlotClock {
            master: false,
            cycle_ns: bus.cycle_ns().max(1),
            wrap,
            locked: false,
            rate_valid: false,
            anchor_local: 0,
            anchor_bus: 0,
            abs_cycle: 0,
            counter: 0,
            ppb: 0,
        }
    }
    /// Slave: a sync frame with `cycle_counter` had its SOF at local time `sof`.
    /// Aligns the offset and updates the rate estimate. Returns true when locked.
    /// Master: ignored (its own sync), returns true.
    pub fn on_sync(&mut self, sof: Nanos, cycle_counter: u16) -> bool {
        if self.master {
            return true;
        }
        let counter = u32::from(cycle_counter) % self.wrap;
        if !self.locked {
            self.lock(sof, counter);
            return true;
        }
        let d_local = nanos_i64(sof) - nanos_i64(self.anchor_local);
        let cyc = nanos_i64(self.cycle_ns);
        let max_gap = MAX_GAP_NS.max(cyc.saturating_add(cyc).saturating_add(cyc));
        if d_local <= 0 || d_local > max_gap {
            // Time went backwards, a duplicate timestamp, or a gap too long to bridge:
            // start over from this sync.
            self.lock(sof, counter);
            return true;
        }
        // Cycles elapsed by the local clock (current rate), then the value congruent to
        // the counter difference nearest to it: unwraps the counter across any gap the
        // local estimate is good to within ±wrap/2 cycles.
        let cyc = nanos_i64(self.cycle_ns).max(1);
        let est_bus = mul_div(d_local, PPB, PPB + self.ppb);
        let n_est = div_round(est_bus, cyc);
        let wrap = i64::from(self.wrap);
        let diff = i64::from(counter) - i64::from(self.counter);
        let mut r = (diff - n_est).rem_euclid(wrap);
        if r > wrap / 2 {
            r -= wrap;
        }
        let d_cycles = n_est + r;
        if d_cycles == 0 {
            // The same sync again (e.g. a retransmission): nothing new.
            return true;
        }
        if d_cycles < 0 {
            self.lock(sof, counter);
            return true;
        }
        let d_bus = d_cycles.saturating_mul(cyc);
        let err = d_local - d_bus;
        // Plausibility first (|err| <= 1 % of d_bus), which also bounds err * PPB.
        if err.unsigned_abs() > d_bus.unsigned_abs() / 100 {
            self.lock(sof, counter);
            return true;
        }
        let measured = ppb_of(err, d_bus);
        if measured.abs() > MAX_RATE_PPB {
            self.lock(sof, counter);
            return true;
        }
        self.ppb = if self.rate_valid {
            // Light low-pass: SOF timestamps jitter; a real drift change still settles
            // within a few cycles.
            self.ppb + (measured - self.ppb) / 4
        } else {
            measured
        };
        self.rate_valid = true;
        self.abs_cycle = self.abs_cycle.saturating_add(d_cycles as u64);
        self.anchor_local = sof;
        self.anchor_bus = self.abs_cycle.saturating_mul(self.cycle_ns);
        self.counter = counter;
        true
    }
    /// True once the slave has a usable offset (master: always).
    pub fn is_locked(&self) -> bool {
        self.locked
    }
    /// True once the rate has been measured (second sync; master: always).
    pub fn is_rate_valid(&self) -> bool {
        self.rate_valid
    }
    /// Measured rate error of the local clock against the bus in parts per billion
    /// (positive: the local clock runs fast). 0 for the master and before the second sync.
    pub fn rate_ppb(&self) -> i64 {
        self.ppb
    }
    /// Whole cycles elapsed since the last sync received at local time `local` (master:
    /// always 0; unlocked slave: `u64::MAX`). The engine declares sync loss from it.
    pub fn cycles_since_sync(&self, local: Nanos) -> u64 {
        if self.master {
            return 0;
        }
        if !self.locked {
            return u64::MAX;
        }
        self.to_bus(local).saturating_sub(self.anchor_bus) / self.cycle_ns
    }
    /// Absolute cycle of the last sync received (`None` before lock; master: `None`).
    pub fn last_sync_cycle(&self) -> Option<u64> {
        (self.locked && !self.master).then_some(self.abs_cycle)
    }
    /// Cycle counter carried by the sync of absolute cycle `abs_cycle`.
    pub fn cycle_counter(&self, abs_cycle: u64) -> u16 {
        (abs_cycle % u64::from(self.wrap)) as u16
    }
    /// Cycle length in ns.
    pub fn cycle_ns(&self) -> Nanos {
        self.cycle_ns
    }
    /// Slave: forget the lock (e.g. after sync loss); the next sync relocks.
    pub fn unlock(&mut self) {
        if !self.master {
            self.locked = false;
            self.rate_valid = false;
            self.ppb = 0;
        }
    }
    /// Bus time (ns since slot 0 of absolute cycle 0) at local time `local`; saturates
    /// at 0 before bus time 0. Before lock a slave returns `local` unchanged.
    pub fn to_bus(&self, local: Nanos) -> Nanos {
        let d_local = nanos_i64(local) - nanos_i64(self.anchor_local);
        let d_bus = mul_div(d_local, PPB, PPB + self.ppb);
        clamp_nanos(nanos_i64(self.anchor_bus).saturating_add(d_bus))
    }
    /// Local time at which bus time `bus` occurs (within 1 ns, the inverse of `to_bus`).
    pub fn to_local(&self, bus: Nanos) -> Nanos {
        let d_bus = nanos_i64(bus) - nanos_i64(self.anchor_bus);
        let d_local = mul_div(d_bus, PPB + self.ppb, PPB);
        clamp_nanos(nanos_i64(self.anchor_local).saturating_add(d_local))
    }

    fn lock(&mut self, sof: Nanos, counter: u32) {
        self.locked = true;
        self.rate_valid = false;
        self.ppb = 0;
        self.abs_cycle = u64::from(counter);
        self.counter = counter;
        self.anchor_local = sof;
        self.anchor_bus = self.abs_cycle.saturating_mul(self.cycle_ns);
    }
}

/// `a / b` rounded to nearest (ties up), for `b > 0`.
fn div_round(a: i64, b: i64) -> i64 {
    if b <= 0 {
        return a;
    }
    (a.saturating_mul(2).saturating_add(b)).div_euclid(b.saturating_mul(2))
}

/// `err · 10⁹ / d_bus` rounded, for `|err| <= d_bus / 100` and `d_bus > 0`: both are
/// halved until `d_bus < 2^39`, so the product stays below 2^63 (gaps of 550 s and more
/// lose well under 1 ppb to the halving).
fn ppb_of(err: i64, d_bus: i64) -> i64 {
    let (mut err, mut d_bus) = (err, d_bus);
    while d_bus >= 1 << 39 {
        err >>= 1;
        d_bus >>= 1;
    }
    div_round(err.saturating_mul(PPB), d_bus)
}

/// `a * num / den` rounded, without overflow for `0 < den < 2^31` and `|num| < 2^31`:
/// `a = q * den + r` gives `q * num + r * num / den` with `|r * num| < 2^62`.
fn mul_div(a: i64, num: i64, den: i64) -> i64 {
    if den <= 0 {
        return a;
    }
    let (q, r) = (a.div_euclid(den), a.rem_euclid(den));
    q.saturating_mul(num)
        .saturating_add(div_round(r * num, den))
}

/// Nanoseconds as i64 (saturating: u64 times past 2^63 ns are 292 years away).
fn nanos_i64(t: Nanos) -> i64 {
    i64::try_from(t).unwrap_or(i64::MAX)
}

fn clamp_nanos(v: i64) -> Nanos {
    Nanos::try_from(v.max(0)).unwrap_or(0)
}
