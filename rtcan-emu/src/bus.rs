//! The CAN bus between emulated bxCANs: idle-bus arbitration by identifier at bit times,
//! frame length from rtcan-core's bit-exact stuffing count for extended data frames.
use crate::bxcan::RawFrame;
use crate::mcu::Mcu;
use rtcan_core::frame::Frame;
use rtcan_core::id::CanId;
use rtcan_core::timing::exact_bits;

/// Bits a frame occupies on the bus, intermission included.
pub fn frame_bits(f: &RawFrame) -> u64 {
    if f.ide && !f.rtr {
        if let Some(fr) =
            CanId::from_raw(f.id).and_then(|id| Frame::from_parts(id, f.dlc.min(8), f.data))
        {
            return u64::from(exact_bits(&fr));
        }
    }
    // Worst case with stuffing (ISO 11898-1): standard 47 + 10 per byte... bounded form.
    let data = 8 * u64::from(f.dlc.min(8));
    let stuffable = if f.ide { 54 } else { 34 } + data;
    stuffable + (stuffable - 1) / 4 + 13
}

/// Intermission bits after EOF (included in `frame_bits`).
const INTERMISSION: u64 = 3;

/// A frame on the wire.
#[derive(Clone, Debug)]
pub struct Transfer {
    pub node: usize,
    pub mailbox: usize,
    pub frame: RawFrame,
    pub sof_bit: u64,
    /// The bit after the last EOF bit (the intermission follows).
    pub end_bit: u64,
    /// The receivers have taken the frame (at the last-but-one EOF bit).
    pub received: bool,
}

/// ISO 11898-1 §10.7: a frame is valid for its receivers at the last-but-one bit of EOF
/// (when bxCAN raises the RX interrupt), for its transmitter at the end of EOF; the
/// intermission (3 bits) follows before the next SOF.
const RX_VALID_BEFORE_EOF_END: u64 = 1;

/// Bus of several MCUs, all with the same bit time.
pub struct Bus {
    pub mcus: Vec<Mcu>,
    pub on_wire: Option<Transfer>,
    /// Frames delivered: (sender, frame, SOF bit).
    pub log: Vec<(usize, RawFrame, u64)>,
    /// Per `log` entry: when the sender's code requested it (TXRQ, ps) and, for a frame
    /// the slot-timer interrupt committed, the slot boundary (TIM2 match, ps).
    pub meta: Vec<(u64, Option<u64>)>,
    pub bit_ps: u64,
    /// Bit time until which the bus is busy (end of the last frame).
    idle_from: u64,
}

impl Bus {
    pub fn new(mcus: Vec<Mcu>, bit_ps: u64) -> Bus {
        Bus {
            mcus,
            on_wire: None,
            log: Vec::new(),
            meta: Vec::new(),
            bit_ps,
            idle_from: 0,
        }
    }

    /// Resets MCU `node` (power cycle or NRST) while the bus runs. A frame it was sending
    /// is cut short: the others see an error frame and drop it (ISO 11898-1), modelled as
    /// the frame never arriving.
    pub fn reset_node(&mut self, node: usize) -> Result<(), String> {
        if self.on_wire.as_ref().is_some_and(|t| t.node == node) {
            self.on_wire = None;
        }
        match self.mcus.get_mut(node) {
            Some(m) => m.reset().map_err(|e| format!("{e:?}")),
            None => Err(format!("no node {node}")),
        }
    }

    /// Bits the MCUs may run ahead of an idle bus: less than the shortest frame (44 bits
    /// with intermission), so no node can miss a frame end by running ahead.
    const LOOK_AHEAD: u64 = 40;

    /// On an idle bus with no pending request: runs every MCU up to `LOOK_AHEAD` bits or
    /// its first transmit request, and returns the bit at which the earliest request can
    /// start a frame (nodes that ran past it had no request by then: they do not contend,
    /// and nothing reaches them before that frame ends).
    fn look_ahead(&mut self, bit: u64, end_bit: u64) -> Result<u64, String> {
        let horizon = (bit + Self::LOOK_AHEAD).min(end_bit);
        let mut first: Option<u64> = None;
        for m in &mut self.mcus {
            m.st.txrq_at = None;
            m.st.stop_on_txrq = true;
            let r = m.run_until(horizon * self.bit_ps);
            m.st.stop_on_txrq = false;
            r?;
            if let Some(t) = m.st.txrq_at {
                first = Some(first.map_or(t, |f| f.min(t)));
            }
        }
        Ok(match first {
            // SOF on the first bit boundary after the request.
            Some(t) => (t / self.bit_ps + 1).clamp(bit + 1, horizon),
            None => horizon,
        })
    }

    /// Current bus time in bits.
    pub fn bit(&self) -> u64 {
        self.mcus.iter().map(|m| m.now()).min().unwrap_or(0) / self.bit_ps.max(1)
    }

    /// Runs all MCUs and the bus to time `until` (ps), one bit at a time between frames
    /// and frame by frame on the wire.
    pub fn run_until(&mut self, until: u64) -> Result<(), String> {
        let mut bit = self.mcus.iter().map(|m| m.now()).min().unwrap_or(0) / self.bit_ps;
        let end_bit = until / self.bit_ps;
        while bit < end_bit {
            // Next decision point: the end of the frame on the wire; on an idle bus with
            // nothing pending, the bit after the first transmit request within a look-ahead.
            let idle = self.on_wire.is_none() && bit >= self.idle_from;
            let pending = self.mcus.iter().any(|m| m.st.can.tx_candidate().is_some());
            let step_to = match &self.on_wire {
                Some(t) if !t.received => t.end_bit - RX_VALID_BEFORE_EOF_END,
                Some(t) => t.end_bit,
                None if idle && !pending => self.look_ahead(bit, end_bit)?,
                None => bit + 1,
            }
            .min(end_bit);
            for m in &mut self.mcus {
                m.run_until(step_to * self.bit_ps)?;
            }
            bit = step_to;
            if let Some(mut t) = self.on_wire.take() {
                if !t.received && bit + RX_VALID_BEFORE_EOF_END >= t.end_bit {
                    for (i, m) in self.mcus.iter_mut().enumerate() {
                        if i != t.node {
                            m.st.can.receive(&t.frame, t.sof_bit);
                        }
                    }
                    t.received = true;
                }
                if bit >= t.end_bit {
                    if let Some(m) = self.mcus.get_mut(t.node) {
                        m.st.can.tx_finished(t.mailbox, true, bit);
                    }
                    self.log.push((t.node, t.frame, t.sof_bit));
                    let meta = self.mcus.get(t.node).map_or((0, None), |m| {
                        let p = &m.st.probe;
                        (
                            p.txrq_ps.get(t.mailbox).copied().unwrap_or(0),
                            p.boundary_ps.get(t.mailbox).copied().flatten(),
                        )
                    });
                    self.meta.push(meta);
                    self.idle_from = bit + INTERMISSION;
                } else {
                    self.on_wire = Some(t);
                }
                continue;
            }
            if bit < self.idle_from {
                continue;
            }
            // Arbitration among the nodes offering a frame (lowest key wins, ties impossible
            // between distinct RTCAN identifiers).
            let mut best: Option<(u64, usize, usize, RawFrame)> = None;
            for (i, m) in self.mcus.iter().enumerate() {
                if let Some((mb, f)) = m.st.can.tx_candidate() {
                    let k = f.arbitration_key();
                    if best.as_ref().is_none_or(|b| k < b.0) {
                        best = Some((k, i, mb, f));
                    }
                }
            }
            if let Some((_, node, mb, f)) = best {
                for (i, m) in self.mcus.iter_mut().enumerate() {
                    if i != node {
                        if let Some((lost_mb, _)) = m.st.can.tx_candidate() {
                            m.st.can.tx_lost(lost_mb);
                        }
                    }
                }
                if let Some(m) = self.mcus.get_mut(node) {
                    m.st.can.tx_started(mb, bit);
                }
                let len = frame_bits(&f);
                self.on_wire = Some(Transfer {
                    node,
                    mailbox: mb,
                    frame: f,
                    sof_bit: bit,
                    end_bit: bit + len - INTERMISSION,
                    received: false,
                });
            }
        }
        Ok(())
    }
}
