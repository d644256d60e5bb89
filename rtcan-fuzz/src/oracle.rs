//! An independent model of what a receiver does with each frame, written from
//! docs/PROTOCOL.md §2 (identifier fields), §3.3 (sync reception), §7.1–§7.2 (fragment
//! field, receiver rules) and §9 (heartbeat reception) — not from rtcan-core's code: it
//! uses no rtcan-core function, keeps the whole transfer as a growing byte vector instead
//! of writing into a buffer at offsets, and splits the fragment field by arithmetic on
//! the fragment count. `engine_rx` feeds the same frames to the engine and to this model
//! and asserts that the deliveries, heartbeat events and drop counters are equal.

/// Largest payload (§7.1).
const MAX_PAYLOAD: usize = 256;
/// First heartbeat message ID and first topic message ID (§2.3).
const HEARTBEAT_FIRST: u32 = 0x0100;
const TOPIC_FIRST: u32 = 0x0140;
/// PROTOCOL §2.3: first message ID of the host channels (parameters `0xFF00..`, firmware
/// update `0xFF80..`; host-routed).
const UPDATE_FIRST: u32 = 0xFF00;
/// The laxity of NRT frames (§2.1), which heartbeats must carry (§9).
const NRT: u32 = 63;

/// Per-frame outcome counters the engine also keeps (`rtcan_core::counters::Counters`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RxCounts {
    pub unknown_id: u32,
    pub bad_dlc: u32,
    pub out_of_order: u32,
    pub other_transfer: u32,
    pub incomplete: u32,
    pub bad_size: u32,
    pub bad_sync: u32,
    pub bad_heartbeat: u32,
    pub overrun: u32,
    pub delivered: u32,
}

/// A receive topic as the model knows it: message ID and payload size.
#[derive(Clone, Copy, Debug)]
pub struct ModelTopic {
    pub msg_id: u16,
    pub size: usize,
}

/// A heartbeat as a receiver reports it (§9).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HeartbeatSeen {
    /// Same fingerprint as the receiver's: module and state byte.
    Alive { module: u8, state: u8 },
    /// Another robot description.
    Mismatch { module: u8, fingerprint: u32 },
}

/// One delivered message: receive-topic index, payload, SOF of its first fragment.
pub type Delivery = (usize, Vec<u8>, u64);

/// A transfer partly received.
#[derive(Clone, Debug)]
struct Partial {
    /// Counter of the next fragment expected.
    expect: u32,
    /// Transfer ID of the transfer.
    tid: u32,
    /// SOF of its first fragment.
    sof: u64,
    /// The bytes received so far, in order.
    bytes: Vec<u8>,
}

/// The receiver model.
pub struct Oracle {
    slots: u32,
    fingerprint: u32,
    topics: Vec<ModelTopic>,
    partial: Vec<Option<Partial>>,
    /// Counters predicted so far.
    pub counts: RxCounts,
    /// Deliveries predicted so far, in order.
    pub deliveries: Vec<Delivery>,
    /// Heartbeat events predicted so far, in order.
    pub heartbeats: Vec<HeartbeatSeen>,
    /// Well-formed sync frames seen (§3.3).
    pub valid_syncs: u32,
}

/// Frames of a payload of `size` bytes: `max(1, ceil(size / 8))` (§7.1).
pub fn frames_of(size: usize) -> u32 {
    size.div_ceil(8).max(1) as u32
}

/// Counter bits `k`: 0 for one frame, else the smallest `k` with `2^k >= count` (§7.1).
fn counter_bits(count: u32) -> u32 {
    let mut k = 0;
    while count > 1 && (1u32 << k) < count {
        k += 1;
    }
    k
}

/// DLC of the fragment with counter `c` of a `size`-byte payload: 8 for all but the last,
/// the remainder for the last (§7.1); `None` for a counter the message does not have.
pub fn dlc_of(size: usize, c: u32) -> Option<usize> {
    let count = frames_of(size);
    if c >= count {
        return None;
    }
    let offset = 8 * (count - 1 - c) as usize;
    Some(size.saturating_sub(offset).min(8))
}

impl Oracle {
    /// A receiver of `topics` (its receive table, in table order) on a bus of `slots` slots
    /// per cycle whose robot fingerprint is `fingerprint`.
    pub fn new(slots: u8, fingerprint: u32, topics: Vec<ModelTopic>) -> Self {
        Oracle {
            slots: u32::from(slots),
            fingerprint,
            partial: vec![None; topics.len()],
            topics,
            counts: RxCounts::default(),
            deliveries: Vec::new(),
            heartbeats: Vec::new(),
            valid_syncs: 0,
        }
    }

    /// The driver reported an RX overrun.
    pub fn overrun(&mut self) {
        self.counts.overrun += 1;
    }

    /// A frame with 29-bit identifier `raw`, data `data` (its length is the DLC) and
    /// start of frame `sof` passed the filters.
    pub fn frame(&mut self, raw: u32, data: &[u8], sof: u64) {
        let laxity = (raw >> 23) & 0x3F;
        let msg = (raw >> 7) & 0xFFFF;
        let field = raw & 0x7F;
        if laxity == 0 && msg < HEARTBEAT_FIRST {
            self.sync(data);
        } else if (HEARTBEAT_FIRST..TOPIC_FIRST).contains(&msg) {
            self.heartbeat(laxity, msg, field, data);
        } else if msg >= UPDATE_FIRST {
            // §2.3: the host channels (`0xFF00..=0xFFFF`) belong to the host; the
            // receive rules and their counters do not apply to it.
        } else {
            match self.topics.iter().position(|t| u32::from(t.msg_id) == msg) {
                Some(i) => self.fragment(i, field, data, sof),
                None => self.counts.unknown_id += 1,
            }
        }
    }

    /// §3.2/§3.3: DLC `ceil(slots / 8)`, bit 0 set, no bit at or above `slots`.
    fn sync(&mut self, data: &[u8]) {
        let mut mask = 0u64;
        for (i, b) in data.iter().enumerate() {
            mask |= u64::from(*b) << (8 * i);
        }
        let dlc_ok = data.len() as u32 == self.slots.div_ceil(8);
        let beyond = if self.slots >= 64 {
            0
        } else {
            mask >> self.slots
        };
        if dlc_ok && mask & 1 == 1 && beyond == 0 {
            self.valid_syncs += 1;
        } else {
            self.counts.bad_sync += 1;
        }
    }

    /// §9: laxity 63, fragment 0, DLC 5; fingerprint little-endian, then the state.
    fn heartbeat(&mut self, laxity: u32, msg: u32, field: u32, data: &[u8]) {
        if laxity != NRT || field != 0 || data.len() != 5 {
            self.counts.bad_heartbeat += 1;
            return;
        }
        let module = (msg - HEARTBEAT_FIRST) as u8;
        let fp = data
            .iter()
            .take(4)
            .rev()
            .fold(0u32, |acc, b| acc << 8 | u32::from(*b));
        let state = data.get(4).copied().unwrap_or(0);
        self.heartbeats.push(if fp == self.fingerprint {
            HeartbeatSeen::Alive { module, state }
        } else {
            HeartbeatSeen::Mismatch {
                module,
                fingerprint: fp,
            }
        });
    }

    /// §7.2, rules 1–6, for receive topic `i`.
    fn fragment(&mut self, i: usize, field: u32, data: &[u8], sof: u64) {
        let Some(topic) = self.topics.get(i).copied() else {
            return;
        };
        let Some(slot) = self.partial.get_mut(i) else {
            return;
        };
        // Every rule that drops a frame also discards the transfer in progress.
        let partial = slot.take();
        // Rule 1.
        if topic.size > MAX_PAYLOAD {
            self.counts.bad_size += 1;
            return;
        }
        let count = frames_of(topic.size);
        let k = counter_bits(count);
        let (tid, c) = if count == 1 {
            (0, field)
        } else {
            (field >> k, field & ((1 << k) - 1))
        };
        let first = c == count - 1;
        // Rule 3 (rule 2 is the `first` case).
        if !first {
            match &partial {
                Some(p) if p.expect == c => {
                    if p.tid != tid {
                        self.counts.other_transfer += 1;
                        return;
                    }
                }
                _ => {
                    self.counts.out_of_order += 1;
                    return;
                }
            }
        }
        // Rule 4.
        if dlc_of(topic.size, c) != Some(data.len()) {
            self.counts.bad_dlc += 1;
            return;
        }
        // Rules 2 and 5.
        let restarted = first && partial.is_some();
        let mut transfer = match partial {
            Some(p) if !first => p,
            _ => Partial {
                expect: c,
                tid,
                sof,
                bytes: Vec::new(),
            },
        };
        transfer.bytes.extend_from_slice(data);
        // Rule 6.
        if c == 0 {
            self.counts.delivered += 1;
            self.deliveries.push((i, transfer.bytes, transfer.sof));
            return;
        }
        transfer.expect = c - 1;
        *slot = Some(transfer);
        if restarted {
            self.counts.incomplete += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id(laxity: u32, msg: u32, field: u32) -> u32 {
        laxity << 23 | msg << 7 | field
    }

    /// The example of §7.5: a 20-byte HRT message with transfer ID 5, then transfer 6's
    /// second fragment after the first two rows (dropped, `OtherTransfer`).
    #[test]
    fn model_follows_the_protocol_example() {
        let mut o = Oracle::new(
            8,
            1,
            vec![ModelTopic {
                msg_id: 0x140,
                size: 20,
            }],
        );
        let payload: Vec<u8> = (0..20).collect();
        assert_eq!(id(0, 0x140, 0x16), 0x0000_A016);
        o.frame(0x0000_A016, &payload[0..8], 100);
        o.frame(0x0000_A015, &payload[8..16], 200);
        o.frame(0x0000_A014, &payload[16..20], 300);
        assert_eq!(o.deliveries, vec![(0, payload.clone(), 100)]);
        o.frame(0x0000_A016, &payload[0..8], 400);
        o.frame(0x0000_A015, &payload[8..16], 500);
        o.frame(0x0000_A019, &payload[8..16], 600); // transfer 6, counter 1
        assert_eq!(
            o.counts.other_transfer, 0,
            "counter 1 is not expected any more"
        );
        assert_eq!(o.counts.out_of_order, 1);
        o.frame(0x0000_A016, &payload[0..8], 700);
        o.frame(0x0000_A019, &payload[8..16], 800);
        assert_eq!(o.counts.other_transfer, 1);
        o.frame(0x0000_A014, &payload[16..20], 900);
        assert_eq!(o.counts.out_of_order, 2, "the transfer was discarded");
        assert_eq!(o.deliveries.len(), 1);
        assert_eq!(o.counts.delivered, 1);
    }

    #[test]
    fn model_counts_restarts_bad_dlc_sizes_and_single_frames() {
        let mut o = Oracle::new(
            40,
            7,
            vec![
                ModelTopic {
                    msg_id: 0x140,
                    size: 0,
                },
                ModelTopic {
                    msg_id: 0x141,
                    size: 9,
                },
                ModelTopic {
                    msg_id: 0x142,
                    size: 300,
                },
            ],
        );
        o.frame(id(63, 0x140, 0), &[], 1);
        o.frame(id(63, 0x140, 1), &[], 2); // single frame with a non-zero field
        assert_eq!(o.deliveries, vec![(0, vec![], 1)]);
        assert_eq!(o.counts.out_of_order, 1);
        // 9 bytes: 2 frames, 1 counter bit, transfer ID in bits 6..1.
        o.frame(id(5, 0x141, 3 << 1 | 1), &[1; 8], 10);
        o.frame(id(5, 0x141, 4 << 1 | 1), &[2; 8], 11); // restart with transfer 4
        assert_eq!(o.counts.incomplete, 1);
        o.frame(id(5, 0x141, 4 << 1), &[3, 4], 12); // DLC 2, expected 1
        assert_eq!(o.counts.bad_dlc, 1);
        o.frame(id(5, 0x141, 4 << 1 | 1), &[2; 8], 13);
        o.frame(id(5, 0x141, 4 << 1), &[3], 14);
        assert_eq!(
            o.deliveries.last(),
            Some(&(1, vec![2, 2, 2, 2, 2, 2, 2, 2, 3], 13))
        );
        o.frame(id(0, 0x142, 0), &[0; 8], 20);
        assert_eq!(o.counts.bad_size, 1);
        o.frame(id(1, 0x200, 0), &[], 21);
        assert_eq!(o.counts.unknown_id, 1);
    }

    #[test]
    fn model_checks_sync_and_heartbeat_formats() {
        let mut o = Oracle::new(40, 0xDEAD_BEEF, vec![]);
        o.frame(3, &[0xFF, 0xFF, 0x38, 0x8E, 0xFF], 0); // §3.5, 40 slots
        o.frame(3, &[0xFF, 0xFF, 0x38, 0x8E, 0xFF, 0x38, 0x8E, 0x03], 0); // DLC 8
        o.frame(3, &[0xFE, 0xFF, 0x38, 0x8E, 0xFF], 0); // bit 0 clear
        assert_eq!(o.valid_syncs, 1);
        assert_eq!(o.counts.bad_sync, 2);
        let mut o64 = Oracle::new(64, 0, vec![]);
        o64.frame(0x7FFF, &[0xFF; 8], 0);
        assert_eq!(o64.valid_syncs, 1, "64 slots: every mask bit is a slot");
        // §9 example: module 3, state 1.
        o.frame(0x1F80_8180, &[0xEF, 0xBE, 0xAD, 0xDE, 1], 0);
        o.frame(0x1F80_8180, &[0xEF, 0xBE, 0xAD, 0xDF, 1], 0);
        o.frame(0x0080_8180, &[0xEF, 0xBE, 0xAD, 0xDE, 1], 0); // laxity 1
        o.frame(0x1F80_8181, &[0xEF, 0xBE, 0xAD, 0xDE, 1], 0); // fragment 1
        o.frame(0x1F80_8180, &[0xEF, 0xBE, 0xAD, 0xDE], 0); // DLC 4
        assert_eq!(
            o.heartbeats,
            vec![
                HeartbeatSeen::Alive {
                    module: 3,
                    state: 1
                },
                HeartbeatSeen::Mismatch {
                    module: 3,
                    fingerprint: 0xDFAD_BEEF
                }
            ]
        );
        assert_eq!(o.counts.bad_heartbeat, 3);
        // Laxity 1 with a message ID below 0x100 is not a sync: an unknown topic.
        o.frame(1 << 23 | 3, &[1], 0);
        assert_eq!(o.counts.unknown_id, 1);
    }

    #[test]
    fn counter_bits_match_the_table_of_section_7_1() {
        let k: Vec<u32> = [1, 2, 3, 4, 5, 8, 9, 16, 17, 32]
            .iter()
            .map(|c| counter_bits(*c))
            .collect();
        assert_eq!(k, vec![0, 1, 2, 2, 3, 3, 4, 4, 5, 5]);
    }
}
