//! The slot clock: maps the node-local clock to bus time. The master's local clock is
//! bus time; a slave aligns on the sync frame's start-of-frame and corrects its rate.
//!
//! Bus time is nanoseconds since slot 0 of absolute cycle 0. A slave keeps an anchor
//! (local SOF time of the last sync, and that sync's bus time `abs_cycle · cycle_ns`)
//! and a rate `local ns per bus ns = 1 + A`, measured between consecutive syncs
//! received. The rate is kept as two fixed-point factors, `A · 2^40` and the inverse's
//! `B · 2^40` (bus per local `= 1 + B`), so mapping a time either way is one multiply and
//! a shift, and a sync costs one 64-bit division (the rate measurement): the Cortex-M3
//! has no 64-bit divide, and each `__aeabi_ldivmod` is hundreds of instructions (18 of
//! them made a slave's sync cost 3 000, issue 10). Counter unwrapping divides in 32 bits
//! (one instruction) whenever the numbers fit. No 128-bit division (a long software
//! routine whose code alone was 1.4 KiB of a 32 KiB image); 128-bit products are a few
//! multiply instructions. Gaps between syncs longer than `MAX_GAP_NS` (or three cycles,
//! on buses with cycles longer than that) relock instead of extrapolating.
//!
//! The 2014 C code measured the slot length once at start-up and then only reset the
//! phase at each sync (original-rtcan-code.md §2–3): drift was never corrected within a
//! cycle, and a missed sync sent the node to a terminal error state. Here a missed sync
//! just extrapolates with the measured rate, and the counter is unwrapped across gaps.
use crate::sync::CYCLE_COUNTER_MODULUS;
use crate::tables::BusConfig;
use crate::time::Nanos;

/// Fraction bits of the rate factors.
const Q: u32 = 40;
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
    /// Local clock rate error: local ns per bus ns = 1 + rate_q40 / 2^40.
    rate_q40: i64,
    /// Its inverse: bus ns per local ns = 1 + inv_q40 / 2^40.
    inv_q40: i64,
    /// `2^40 / cycle_ns` as a 32.32 fixed-point number (`recip_hi` whole, `recip_lo`
    /// fraction), so a sync measures the rate with two 32 × 32 multiplies and no shift by
    /// a variable amount (a library call at opt-level z); 0 for cycles of 256 ns or less
    /// and of 2^32 ns and more (then the 64-bit division).
    recip_hi: u64,
    recip_lo: u64,
    /// `cycle_ns / 100`: the plausibility bound of a one-cycle sync gap (`|err| · 100 <=
    /// d_bus` for whole ns), precomputed for the fast path of the next sync.
    err_max: u64,
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
            rate_q40: 0,
            inv_q40: 0,
            recip_hi: 0,
            recip_lo: 0,
            err_max: 0,
        }
        .with_reciprocal()
    }

    /// Precomputes `recip_hi`, `recip_lo` and `err_max` (64-bit divisions, at
    /// construction only).
    fn with_reciprocal(mut self) -> Self {
        let cyc = self.cycle_ns.max(1);
        self.err_max = cyc / 100;
        if cyc > 256 && cyc >> 32 == 0 {
            self.recip_hi = (1u64 << Q) / cyc;
            // The remainder is below `cyc` < 2^32: shifted by 32 it still fits.
            self.recip_lo = (((1u64 << Q) % cyc) << 32) / cyc;
        }
        self
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
        let d_local = nanos_diff(sof, self.anchor_local);
        // The common case first: the next sync, one cycle after the last, within the
        // plausibility bound. The general path below finds the same: its estimate of the
        // elapsed cycles (rate within 1 %) rounds to 1, the counter difference is 1, and
        // it applies the same bound. This skips the estimate's rounding division, the
        // counter unwrap and the 64-bit products (issue 10: the sync's CPU time).
        let cyc_u = self.cycle_ns;
        let next = if self.counter + 1 >= self.wrap {
            0
        } else {
            self.counter + 1
        };
        if counter == next && d_local > 0 {
            let err = d_local - nanos_i64(cyc_u);
            if err.unsigned_abs() <= self.err_max {
                return self.accept_next(sof, counter, err);
            }
        }
        self.on_sync_general(sof, counter, d_local)
    }

    /// `on_sync` of a locked slave, any gap: unwraps the counter, checks plausibility.
    fn on_sync_general(&mut self, sof: Nanos, counter: u32, d_local: i64) -> bool {
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
        let est_bus = scale(d_local, self.inv_q40).max(0);
        let n_est = i64::try_from(div_round_u(est_bus.unsigned_abs(), cyc.unsigned_abs()))
            .unwrap_or(i64::MAX);
        let wrap = i64::from(self.wrap);
        let diff = i64::from(counter) - i64::from(self.counter);
        let mut r = rem_euclid_small(diff.saturating_sub(n_est), self.wrap);
        if r > wrap / 2 {
            r -= wrap;
        }
        let d_cycles = n_est.saturating_add(r);
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
        // Plausibility first (|err| <= 1 % of d_bus), which also bounds the measurement.
        if err.unsigned_abs().saturating_mul(100) > d_bus.unsigned_abs() {
            self.lock(sof, counter);
            return true;
        }
        self.accept(sof, counter, d_cycles, err, d_bus)
    }

    /// `accept(sof, counter, 1, err, cycle_ns)` for the next sync (`|err| <= err_max`),
    /// in 32-bit pieces: the rate from the reciprocal without the general `measure`'s
    /// range checks, the anchor moved by one cycle. Same result (the test
    /// `next_sync_fast_path_matches_the_general_path` compares them field by field).
    fn accept_next(&mut self, sof: Nanos, counter: u32, err: i64) -> bool {
        if self.recip_hi == 0 {
            // Cycles of 256 ns or less, or of 2^32 ns and more: the exact division.
            return self.accept(sof, counter, 1, err, nanos_i64(self.cycle_ns));
        }
        // recip_hi != 0 means 256 < cycle_ns < 2^32, so |err| <= err_max = cycle_ns / 100
        // < 2^26: `e` is exact in 32 bits (and below 2^31, the bound `measure` checks), and
        // e · recip_hi, e · recip_lo are 32 × 32 → 64 multiplies (both factors < 2^32).
        let e = err.unsigned_abs() as u32;
        let (hi, lo) = (self.recip_hi as u32, self.recip_lo as u32);
        let per_cycle =
            u64::from(e) * u64::from(hi) + ((u64::from(e) * u64::from(lo) + (1 << 31)) >> 32);
        // per_cycle <= (2^26 · 2^40 / cycle_ns) + 1 < 2^40: fits an i64 as is.
        let q = per_cycle as i64;
        let measured = if err < 0 { -q } else { q };
        if measured.unsigned_abs() > MAX_RATE_Q40 {
            self.lock(sof, counter);
            return true;
        }
        let rate = if self.rate_valid {
            self.rate_q40 + div4(measured - self.rate_q40)
        } else {
            measured
        };
        self.set_rate(rate);
        self.rate_valid = true;
        if (self.abs_cycle | self.anchor_bus) >> 62 == 0 {
            // Both below 2^62 and cycle_ns < 2^32: the sums cannot overflow, the plain
            // additions equal the saturating ones below (which cost 20 instructions).
            self.abs_cycle += 1;
            self.anchor_bus += self.cycle_ns;
        } else {
            self.abs_cycle = self.abs_cycle.saturating_add(1);
            self.anchor_bus = self.anchor_bus.saturating_add(self.cycle_ns);
        }
        self.anchor_local = sof;
        self.counter = counter;
        true
    }

    /// A plausible sync `d_cycles` (> 0) cycles after the last, its SOF `err` ns off the
    /// current anchor's prediction at rate 1 (`d_bus = d_cycles · cycle_ns`): measure
    /// the rate, low-pass it, move the anchor.
    fn accept(&mut self, sof: Nanos, counter: u32, d_cycles: i64, err: i64, d_bus: i64) -> bool {
        let measured = self.measure(err, d_cycles, d_bus);
        if measured.unsigned_abs() > MAX_RATE_Q40 {
            self.lock(sof, counter);
            return true;
        }
        let rate = if self.rate_valid {
            // Light low-pass: SOF timestamps jitter; a real drift change still settles
            // within a few cycles.
            self.rate_q40 + div4(measured - self.rate_q40)
        } else {
            measured
        };
        self.set_rate(rate);
        self.rate_valid = true;
        self.abs_cycle = self.abs_cycle.saturating_add(d_cycles.unsigned_abs());
        self.anchor_local = sof;
        // `abs_cycle · cycle_ns`, by an addition (`d_bus` is the cycles just added).
        self.anchor_bus = self.anchor_bus.saturating_add(d_bus.unsigned_abs());
        self.counter = counter;
        true
    }

    /// `err / d_bus · 2^40` with `d_bus = d_cycles · cycle_ns`: `err · 2^40 / cycle_ns`
    /// from the 32.32 reciprocal (rounded), then divided by `d_cycles` in 16-bit digits
    /// (32-bit divides) if syncs were missed; the 64-bit division only for cycles of
    /// 256 ns or less or ≥ 4.29 s, errors ≥ 2^31 ns or gaps of 2^16 cycles and more.
    fn measure(&self, err: i64, d_cycles: i64, d_bus: i64) -> i64 {
        let (e, n) = (err.unsigned_abs(), d_cycles.unsigned_abs());
        if self.recip_hi == 0 || e >> 31 != 0 || n >> 16 != 0 || n == 0 {
            return rate_q40_of(err, d_bus);
        }
        // e < 2^31, recip_hi < 2^32 (cycle > 256 ns) and recip_lo < 2^32: both products
        // fit; off the exact quotient by under one unit (the truncated fraction).
        // 32 × 32 → 64 multiplies (all three operands are below 2^32).
        let (e32, hi, lo) = (e as u32 as u64, self.recip_hi as u32, self.recip_lo as u32);
        let per_cycle = e32 * u64::from(hi) + ((e32 * u64::from(lo) + (1 << 31)) >> 32);
        let q = if n == 1 {
            per_cycle
        } else {
            div_by_u16(per_cycle, n as u32)
        };
        let q = i64::try_from(q).unwrap_or(i64::MAX);
        if err < 0 {
            -q
        } else {
            q
        }
    }

    fn set_rate(&mut self, rate_q40: i64) {
        self.rate_q40 = rate_q40;
        self.inv_q40 = inverse_q40(rate_q40);
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
        // 10⁹ / 2^40 = 1 953 125 / 2^31; |rate_q40| < 2^34 keeps the product below 2^55.
        (self.rate_q40.saturating_mul(1_953_125) + (1 << 30)) >> 31
    }
    /// Local ns per bus ns, as `2^16 ·` a length: the local length of `bus_ns` × 2^16,
    /// rounded (for the engine's slot map; a multiply, no division).
    pub fn local_q16(&self, bus_ns: Nanos) -> u64 {
        if bus_ns >> 29 == 0 && self.rate_q40.unsigned_abs() <= MAX_RATE_Q40 {
            // A slot of up to 0.5 s: `d · rate` fits in 64 bits (no 128-bit product), and
            // with d < 2^32 it is a 32 × 64 product (two multiplies, not three). |rate| <=
            // 1 % + 2^-40 keeps |extra| <= d · 2^16, so the sum is >= 0 (no clamp).
            let d = bus_ns as u32;
            let extra = (i64::from(d) * self.rate_q40 + (1 << (Q - 17))) >> (Q - 16);
            return ((u64::from(d) << 16) as i64 + extra) as u64;
        }
        let d = nanos_i64(bus_ns);
        clamp_nanos(scale(d.saturating_mul(1 << 16), self.rate_q40))
    }
    /// Bus ns per local ns × 2^32, rounded (the engine's inverse slot map).
    pub fn bus_per_local_q32(&self) -> u64 {
        let v = (1i64 << 32) + ((self.inv_q40 + (1 << (Q - 33))) >> (Q - 32));
        v.max(0).unsigned_abs()
    }
    /// The absolute cycle whose slot 0 is nearest to local time `local`: near the last
    /// sync a 32-bit division, else a 64-bit one.
    pub fn nearest_cycle(&self, local: Nanos) -> u64 {
        if local == self.anchor_local && self.anchor_bus != Nanos::MAX {
            // The sync just handled (or the master's start): no arithmetic.
            return self.abs_cycle;
        }
        let bus = self.to_bus(local);
        match bus.checked_sub(self.anchor_bus) {
            Some(d) if self.anchor_bus != Nanos::MAX => {
                self.abs_cycle.saturating_add(div_round_u(d, self.cycle_ns))
            }
            _ => div_round_u(bus, self.cycle_ns),
        }
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
    /// The cycle of the sync just handled at local time `sof`: its absolute cycle and the
    /// bus and local time of its slot 0, i.e. the anchor itself (what `nearest_cycle`,
    /// `cycle_start_bus` and `to_local` give there, without the three calls); `None`
    /// when `sof` is not the anchor.
    #[inline]
    pub fn anchor_cycle(&self, sof: Nanos) -> Option<(u64, Nanos, Nanos)> {
        (self.locked && sof == self.anchor_local && self.anchor_bus != Nanos::MAX).then_some((
            self.abs_cycle,
            self.anchor_bus,
            self.anchor_local,
        ))
    }
    /// Bus time of slot 0 of absolute cycle `abs_cycle` (`abs_cycle · cycle_ns`,
    /// saturating); the anchor's, kept, for the cycle of the last sync.
    pub fn cycle_start_bus(&self, abs_cycle: u64) -> Nanos {
        if abs_cycle == self.abs_cycle && self.locked {
            return self.anchor_bus;
        }
        abs_cycle.saturating_mul(self.cycle_ns)
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
            self.set_rate(0);
        }
    }
    /// Bus time (ns since slot 0 of absolute cycle 0) at local time `local`; saturates
    /// at 0 before bus time 0. Before lock a slave returns `local` unchanged.
    pub fn to_bus(&self, local: Nanos) -> Nanos {
        let d_local = nanos_i64(local) - nanos_i64(self.anchor_local);
        let d_bus = scale(d_local, self.inv_q40);
        clamp_nanos(nanos_i64(self.anchor_bus).saturating_add(d_bus))
    }
    /// Local time at which bus time `bus` occurs (within 1 ns, the inverse of `to_bus`).
    pub fn to_local(&self, bus: Nanos) -> Nanos {
        if bus == self.anchor_bus {
            // The start of the cycle of the last sync (the engine's cycle map at a sync).
            return self.anchor_local;
        }
        let d_bus = nanos_i64(bus) - nanos_i64(self.anchor_bus);
        let d_local = scale(d_bus, self.rate_q40);
        clamp_nanos(nanos_i64(self.anchor_local).saturating_add(d_local))
    }

    fn lock(&mut self, sof: Nanos, counter: u32) {
        self.locked = true;
        self.rate_valid = false;
        self.set_rate(0);
        self.abs_cycle = u64::from(counter);
        self.counter = counter;
        self.anchor_local = sof;
        self.anchor_bus = self.abs_cycle.saturating_mul(self.cycle_ns);
    }
}

/// `MAX_RATE_PPB` in units of 2^-40 (rounded up).
const MAX_RATE_Q40: u64 = (MAX_RATE_PPB as u64 * (1 << 31)).div_ceil(1_953_125);

/// `d · (1 + k / 2^40)`, rounded, saturating: the slot clock's only mapping (no
/// division). For `|d| < 2^29` (a cycle, or a gap of half a second) and a rate factor
/// within `MAX_RATE_PPB` the product fits in 64 bits (a few instructions); else a
/// 128-bit product.
fn scale(d: i64, k: i64) -> i64 {
    if d.unsigned_abs() >> 29 == 0 && k.unsigned_abs() <= MAX_RATE_Q40 {
        return d + ((d * k + (1 << (Q - 1))) >> Q);
    }
    let p = (i128::from(d) * i128::from(k) + (1 << (Q - 1))) >> Q;
    d.saturating_add(i64::try_from(p).unwrap_or(if p < 0 { i64::MIN } else { i64::MAX }))
}

/// `B = 1 / (1 + A) − 1 = −A + A² − A³ + …` in units of 2^-40, summed until the term
/// vanishes (|A| <= 1 % (`MAX_RATE_PPB`): at most 6 terms, each 100 times smaller;
/// 50 ppm: 2 terms). No division, 64-bit products only: `A^k · A` from both shifted by 6
/// bits (|A^k| <= |A| < 2^34, so the product stays below 2^56), off by under 2 units of
/// 2^-40 in all (10⁻¹²).
fn inverse_q40(a: i64) -> i64 {
    if a.unsigned_abs() > MAX_RATE_Q40 {
        return 0;
    }
    // |A| <= MAX_RATE_Q40 < 2^34, so A >> 6 fits in an i32, and every term from A² on
    // is below 2^27 units: each product is one 32 × 32 → 64 multiply and the terms are
    // 32-bit (64 × 64 products and 64-bit terms cost three times as much, issue 10).
    if a.unsigned_abs() < 1 << 26 {
        // |A| < 2^26 units (61 ppm: every crystal's tolerance): the loop below stops
        // after A², as A³'s term rounds to 0 (A² < 2^12 units, so (A² >> 6) · (A >> 6)
        // < 2^26 and adding 2^27 stays below 2^28). The same value without the loop.
        let a6 = i64::from((a >> 6) as i32);
        return -a + ((a6 * a6 + (1 << 27)) >> 28);
    }
    let a6 = (a >> 6) as i32;
    let mut sum = -a;
    // A^(k+1) with the sign flipped: the series alternates.
    let next = |t6: i32| -(((i64::from(t6) * i64::from(a6) + (1 << 27)) >> 28) as i32);
    let mut term = next(a6);
    for _ in 1..6 {
        if term == 0 {
            break;
        }
        sum -= i64::from(term);
        term = next(term >> 6);
    }
    sum
}

/// `err · 2^40 / d_bus` rounded, for `|err| <= d_bus / 100` and `d_bus > 0`: the one
/// 64-bit division of a sync. The numerator is shifted as far as it fits in 62 bits and
/// the quotient shifted up the rest, so long gaps lose quotient bits (about 7 ppb at
/// a 3000 s gap), never overflow.
fn rate_q40_of(err: i64, d_bus: i64) -> i64 {
    if d_bus <= 0 {
        return 0;
    }
    let headroom = err.unsigned_abs().leading_zeros().saturating_sub(2);
    let s = headroom.min(Q);
    let q = div_round(err << s, d_bus);
    q.saturating_mul(1 << (Q - s))
}

/// `x / 4` rounded toward zero (as `/`), by shifts: a signed 64-bit division by a
/// constant is a library call at opt-level z.
fn div4(x: i64) -> i64 {
    (x + ((x >> 63) & 3)) >> 2
}

/// `x / d` rounded down for `0 < d < 2^16`: four 32-bit divisions (one instruction
/// each on the Cortex-M3) of 16-bit digits, instead of a 64-bit library division.
fn div_by_u16(x: u64, d: u32) -> u64 {
    let d = d.clamp(1, 0xFFFF);
    let (mut q, mut r) = (0u64, 0u32);
    for shift in [48u32, 32, 16, 0] {
        let cur = (r << 16) | ((x >> shift) as u32 & 0xFFFF);
        q = (q << 16) | u64::from(cur / d);
        r = cur % d;
    }
    q
}

/// `a / b` rounded to nearest (ties up), for `b > 0`.
fn div_round(a: i64, b: i64) -> i64 {
    if b <= 0 {
        return a;
    }
    (a.saturating_mul(2).saturating_add(b)).div_euclid(b.saturating_mul(2))
}

/// `a / b` rounded to nearest (ties up), `b` 0 read as 1: one 32-bit division when
/// `a < 2^30` and `b < 2^31` (a 10 ms cycle and gaps up to 1 s), else a 64-bit one.
fn div_round_u(a: u64, b: u64) -> u64 {
    let b = b.max(1);
    if (a >> 30) | (b >> 31) == 0 {
        let (a, b) = (a as u32, b as u32);
        return u64::from((2 * a + b) / (2 * b));
    }
    a.saturating_add(b / 2) / b
}

/// `x mod m` in `0..m` (m > 0): a 32-bit division when `x` fits in an `i32`.
fn rem_euclid_small(x: i64, m: u32) -> i64 {
    let m = m.max(1);
    match (i32::try_from(x), i32::try_from(m)) {
        (Ok(x), Ok(m)) => i64::from(x.rem_euclid(m)),
        _ => x.rem_euclid(i64::from(m)),
    }
}

/// Nanoseconds as i64 (saturating: u64 times past 2^63 ns are 292 years away).
fn nanos_i64(t: Nanos) -> i64 {
    i64::try_from(t).unwrap_or(i64::MAX)
}

/// `nanos_i64(a) - nanos_i64(b)` (cannot overflow: both are in `0..=i64::MAX`), by one
/// subtraction while both times are below 2^63 ns (always, short of 292 years).
fn nanos_diff(a: Nanos, b: Nanos) -> i64 {
    if (a | b) >> 63 == 0 {
        a.wrapping_sub(b) as i64
    } else {
        nanos_i64(a) - nanos_i64(b)
    }
}

fn clamp_nanos(v: i64) -> Nanos {
    Nanos::try_from(v.max(0)).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_factor_inverts_within_1e12() {
        for ppm in [
            -10_000i64, -5_000, -1_000, -1, 0, 1, 37, 1_000, 5_000, 10_000,
        ] {
            let a = (ppm as f64 * 1e-6 * (1u64 << Q) as f64).round() as i64;
            let b = inverse_q40(a);
            let exact = -(a as f64) / (1.0 + a as f64 / (1u64 << Q) as f64);
            assert!((b as f64 - exact).abs() <= 3.0, "{ppm} ppm: {b} vs {exact}");
            // A long gap maps there and back within 1 ns.
            let d = 1i64 << 33;
            assert!((scale(scale(d, a), b) - d).abs() <= 1, "{ppm} ppm");
        }
    }

    #[test]
    fn inverse_series_in_32_bits_equals_the_64_bit_series() {
        // The series as first written, all in 64 bits.
        let reference = |a: i64| {
            let (mut sum, mut term) = (0i64, a);
            for _ in 0..6 {
                if term == 0 {
                    break;
                }
                sum -= term;
                term = -(((term >> 6) * (a >> 6) + (1 << 27)) >> 28);
            }
            sum
        };
        let max = MAX_RATE_Q40 as i64;
        let mut a = -max;
        while a <= max {
            assert_eq!(inverse_q40(a), reference(a), "{a}");
            a += 7_919_977;
        }
        let near = (1i64 << 26) - 1;
        for a in [
            -max,
            -1,
            0,
            1,
            63,
            64,
            -64,
            -65,
            max,
            near,
            -near,
            near + 1,
            -near - 1,
            near - 63,
            -near + 63,
        ] {
            assert_eq!(inverse_q40(a), reference(a), "{a}");
        }
        // Every value near the edge of the loop-free range.
        for a in (near - 5_000..near + 5_000).chain(-near - 5_000..-near + 5_000) {
            assert_eq!(inverse_q40(a), reference(a), "{a}");
        }
    }

    #[test]
    fn rate_measurement_is_exact_to_the_ppb_and_never_overflows() {
        // 1000 ppm over one 10 ms cycle, and over 3000 s (shifted quotient).
        for d_bus in [10_000_000i64, 3_000_000_000_000] {
            for ppm in [1_000i64, -1_000, 10_000] {
                let err = d_bus / 1_000_000 * ppm;
                let q = rate_q40_of(err, d_bus);
                let ppb = (q.saturating_mul(1_953_125) + (1 << 30)) >> 31;
                assert!((ppb - ppm * 1_000).abs() <= 8, "{d_bus} {ppm}: {ppb}");
            }
        }
        assert_eq!(rate_q40_of(0, 1_000), 0);
        assert_eq!(rate_q40_of(5, 0), 0);
        assert_eq!(rate_q40_of(i64::MAX / 200, i64::MAX / 100) >> 36, 1 << 3);
    }

    #[test]
    fn reciprocal_measurement_matches_the_division() {
        let bus = |slot_ns: u64| crate::tables::BusConfig {
            bitrate: 1_000_000,
            slots_per_cycle: 60,
            slot_ns,
            hyperperiod_cycles: 1,
            cycle_counter_wrap: 1 << 15,
            laxity: crate::laxity::LaxityEncoding::Linear { unit_ns: 1 },
            guard_ns: 0,
            fingerprint: 0,
        };
        for slot_ns in [166_666u64, 200_000, 1_000, 70_000_000, 100_000_000] {
            let clk = SlotClock::slave(&bus(slot_ns));
            let cyc = nanos_i64(clk.cycle_ns);
            assert_eq!(clk.recip_hi == 0, cyc >= 1 << 32 || cyc <= 256, "{slot_ns}");
            for n in [1i64, 2, 3, 255, 65_535, 65_536, 100_000] {
                let d_bus = n * cyc;
                for err in [
                    0,
                    1,
                    -1,
                    12_345,
                    -(d_bus / 100),
                    d_bus / 100,
                    d_bus / 1_000_000,
                ] {
                    let exact = (i128::from(err) << Q) / i128::from(d_bus);
                    let got = i128::from(clk.measure(err, n, d_bus));
                    // Units of 2^-40 (10⁻¹²): a few are far below a ppb; the division
                    // fallback (errors of 2^31 ns and more) resolves 2^(40 - s) units,
                    // s = the numerator's headroom (`rate_q40_of`).
                    let s = (err.unsigned_abs().leading_zeros().saturating_sub(2)).min(Q);
                    let tol = (1i128 << (Q - s)).max(exact.abs() >> 30).max(8);
                    if err.abs() > d_bus / 100 {
                        continue; // outside the plausibility bound, never measured
                    }
                    assert!(
                        (got - exact).abs() <= tol,
                        "{slot_ns} {n} {err}: {got} vs {exact}"
                    );
                }
            }
        }
        for x in [0u64, 1, 65_535, 1 << 40, u64::MAX] {
            for d in [1u32, 2, 7, 65_535] {
                assert_eq!(div_by_u16(x, d), x / u64::from(d), "{x} / {d}");
            }
        }
    }

    #[test]
    fn next_sync_fast_path_matches_the_general_path() {
        let bus = |slot_ns: u64, wrap: u32| crate::tables::BusConfig {
            bitrate: 1_000_000,
            slots_per_cycle: 60,
            slot_ns,
            hyperperiod_cycles: 1,
            cycle_counter_wrap: wrap,
            laxity: crate::laxity::LaxityEncoding::Linear { unit_ns: 1 },
            guard_ns: 0,
            fingerprint: 0,
        };
        let mut taken = 0;
        for (slot_ns, wrap) in [
            (166_666u64, 1 << 15),
            (200_000, 4),
            (1_000, 1 << 15),
            (4, 2),
        ] {
            let cyc = 60 * slot_ns as i64;
            // A slave at +300 ppm with jitter, then syncs near and beyond the ±1 % bound,
            // a counter jump, a wrap of the counter.
            let mut fast = SlotClock::slave(&bus(slot_ns, wrap));
            fast.on_sync(1_000_000, 0);
            let (mut t, mut c) = (1_000_000i64, 0u32);
            let steps: [(i64, u32); 12] = [
                (cyc + cyc * 3 / 10_000, 1),
                (cyc + cyc * 3 / 10_000 + 7, 1),
                (cyc - 5, 1),
                (cyc + cyc / 100, 1),
                (cyc + cyc / 100 + 1, 1),
                (cyc - cyc / 100, 1),
                (cyc - cyc / 100 - 1, 1),
                (2 * cyc + 3, 2),
                (cyc, 1),
                (cyc + 1, 0),
                (cyc / 2, 1),
                (cyc + 2, 1),
            ];
            for (k, (dt, dc)) in steps.iter().enumerate() {
                t += dt;
                c = (c + dc) % fast.wrap;
                let mut general = fast;
                let d_local = t - nanos_i64(general.anchor_local);
                let uses_fast = general.locked
                    && *dc == 1
                    && d_local > 0
                    && (d_local - cyc).unsigned_abs() <= general.err_max;
                taken += usize::from(uses_fast);
                if general.locked {
                    general.on_sync_general(t as Nanos, c, d_local);
                } else {
                    general.on_sync(t as Nanos, c as u16);
                }
                fast.on_sync(t as Nanos, c as u16);
                assert_eq!(
                    format!("{fast:?}"),
                    format!("{general:?}"),
                    "slot {slot_ns} step {k}"
                );
            }
        }
        assert!(taken >= 12, "the fast path ran {taken} times");
        // Anchors at the end of time: the fast path saturates like the general one.
        for (abs, anchor) in [
            (u64::MAX - 1, u64::MAX - 5),
            (1 << 62, 1 << 62),
            (3, 1 << 63),
        ] {
            let cyc = 60 * 166_666u64;
            let mut fast = SlotClock::slave(&bus(166_666, 1 << 15));
            fast.on_sync(1_000_000, 0);
            fast.abs_cycle = abs;
            fast.anchor_bus = anchor;
            let mut general = fast;
            let t = 1_000_000 + cyc + 3;
            general.on_sync_general(t, 1, nanos_i64(t) - 1_000_000);
            fast.on_sync(t, 1);
            assert_eq!(
                format!("{fast:?}"),
                format!("{general:?}"),
                "{abs} {anchor}"
            );
        }
        for x in [
            -9i64,
            -8,
            -7,
            -5,
            -4,
            -3,
            -1,
            0,
            1,
            3,
            4,
            5,
            7,
            i64::MIN + 3,
            i64::MAX,
        ] {
            assert_eq!(div4(x), x / 4, "{x}");
        }
    }

    #[test]
    fn nanos_diff_equals_the_saturated_difference() {
        let t = [
            0u64,
            1,
            7,
            1 << 40,
            (1 << 63) - 1,
            1 << 63,
            u64::MAX - 1,
            u64::MAX,
        ];
        for a in t {
            for b in t {
                assert_eq!(nanos_diff(a, b), nanos_i64(a) - nanos_i64(b), "{a} {b}");
            }
        }
    }

    #[test]
    fn rounded_division_agrees_on_the_32_and_64_bit_paths() {
        for a in [0u64, 1, 4, 5, 6, (1 << 30) - 1, 1 << 30, 1 << 40, 1 << 62] {
            for b in [1u64, 2, 3, 10, (1 << 31) - 1, 1 << 31, 1 << 35] {
                let exact = ((u128::from(a) * 2 + u128::from(b)) / (2 * u128::from(b))) as u64;
                assert_eq!(div_round_u(a, b), exact, "{a} / {b}");
            }
        }
        assert_eq!(div_round_u(u64::MAX, 1), u64::MAX, "saturates");
        assert_eq!(div_round_u(9, 0), 9, "0 is read as 1");
        for x in [-70_000i64, -1, 0, 5, 1 << 40, i64::MIN + 1] {
            for m in [1u32, 7, 32_768] {
                assert_eq!(
                    rem_euclid_small(x, m),
                    x.rem_euclid(i64::from(m)),
                    "{x} mod {m}"
                );
            }
        }
    }
}
