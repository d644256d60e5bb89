//! CAN filter banks of one module (bxCAN: 32-bit scale, one mask filter or two exact
//! list entries per bank). Values are 29-bit identifiers; a mask bit of 1 means "must
//! match". Topic masks cover only the message ID field `ID[22:7]`, because laxity and
//! fragment bits vary from frame to frame.
use rtcan_core::id::{FIRST_TOPIC_MSG_ID, HEARTBEAT_BASE, LAXITY_HRT, LAXITY_NRT};

/// Mask of the laxity field `ID[28:23]`.
pub const LAXITY_MASK: u32 = 0x3F << 23;
/// Shift of the message ID field.
pub const MSG_SHIFT: u32 = 7;

/// One bank's configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FilterBank {
    /// Passes identifiers with `raw & mask == id & mask`.
    Mask {
        /// Identifier bits to compare.
        id: u32,
        /// Bits that must match.
        mask: u32,
    },
    /// Passes exactly these two identifiers (only usable when laxity and fragment are
    /// fixed: single-frame HRT (laxity 0) and NRT (laxity 63) topics).
    List {
        /// The identifiers.
        ids: [u32; 2],
    },
}

/// What a bank is for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BankPurpose {
    /// The sync frame: laxity 0, message ID < 0x0100.
    Sync,
    /// Heartbeats 0x0100..0x013F.
    Heartbeat,
    /// These topics (indices into `Plan::topics`).
    Topics(Vec<usize>),
    /// Everything (software filtering by the RX table).
    AcceptAll,
}

impl BankPurpose {
    /// Names of the topics a `Topics` bank passes (empty for the other purposes), for
    /// reports and generated docs.
    pub fn topic_names<'p>(&self, plan: &'p crate::Plan) -> Vec<&'p str> {
        match self {
            BankPurpose::Topics(ts) => ts
                .iter()
                .filter_map(|t| plan.topics.get(*t))
                .map(|t| t.name.as_str())
                .collect(),
            _ => Vec::new(),
        }
    }
}

/// A configured bank.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bank {
    /// Hardware configuration.
    pub filter: FilterBank,
    /// Why it is there.
    pub purpose: BankPurpose,
}

/// The sync bank: laxity 0 and the high byte of the message ID 0.
pub fn sync_bank() -> Bank {
    Bank {
        filter: FilterBank::Mask {
            id: 0,
            mask: LAXITY_MASK | (0xFF00 << MSG_SHIFT),
        },
        purpose: BankPurpose::Sync,
    }
}

/// The heartbeat bank: message IDs 0x0100..=0x013F, any laxity.
pub fn heartbeat_bank() -> Bank {
    Bank {
        filter: FilterBank::Mask {
            id: u32::from(HEARTBEAT_BASE) << MSG_SHIFT,
            mask: 0xFFC0 << MSG_SHIFT,
        },
        purpose: BankPurpose::Heartbeat,
    }
}

/// A topic on the wire, as the filter packer sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WireTopic {
    /// Topic index.
    pub topic: usize,
    /// Message ID.
    pub msg_id: u16,
    /// Exact 29-bit identifier when it never varies (single-frame HRT or NRT).
    pub fixed_id: Option<u32>,
}

/// The full identifier of a single-frame message of fixed laxity.
pub fn fixed_id(laxity: u8, msg_id: u16) -> u32 {
    (u32::from(laxity) << 23) | (u32::from(msg_id) << MSG_SHIFT)
}

/// Laxity of single-frame HRT and NRT frames.
pub const FIXED_LAXITY: (u8, u8) = (LAXITY_HRT, LAXITY_NRT);

/// Banks passing exactly the sync frame, heartbeats and `wanted`, given every topic on the
/// wire (`all`, any order). IDs not on the wire are don't-cares, so a mask may span them.
pub fn pack(wanted: &[WireTopic], all: &[WireTopic]) -> Vec<Bank> {
    let mut banks = vec![sync_bank(), heartbeat_bank()];
    let mut wanted: Vec<WireTopic> = wanted.to_vec();
    wanted.sort_by_key(|w| w.msg_id);
    let mut forbidden: Vec<u16> = all
        .iter()
        .filter(|a| !wanted.iter().any(|w| w.msg_id == a.msg_id))
        .map(|a| a.msg_id)
        .collect();
    forbidden.sort_unstable();
    let acceptable = |base: u32, size: u32| {
        let end = base + size;
        base >= u32::from(FIRST_TOPIC_MSG_ID)
            && end <= 0x1_0000
            && forbidden.partition_point(|f| u32::from(*f) < base)
                == forbidden.partition_point(|f| u32::from(*f) < end)
    };
    // Maximal aligned blocks: aligned blocks nest or are disjoint, so taking, for each
    // uncovered ID, the largest acceptable aligned block holding it is a minimum cover.
    let mut singles: Vec<WireTopic> = Vec::new();
    let mut i = 0;
    while let Some(w) = wanted.get(i) {
        let id = u32::from(w.msg_id);
        let mut size = 1u32;
        while size < 0x1_0000 && acceptable(id & !(size * 2 - 1), size * 2) {
            size *= 2;
        }
        let base = id & !(size - 1);
        let members: Vec<WireTopic> = wanted
            .iter()
            .skip(i)
            .take_while(|x| u32::from(x.msg_id) < base + size)
            .copied()
            .collect();
        i += members.len().max(1);
        if let [only] = members.as_slice() {
            if only.fixed_id.is_some() {
                singles.push(*only);
                continue;
            }
        }
        banks.push(Bank {
            filter: FilterBank::Mask {
                id: base << MSG_SHIFT,
                mask: (!(size - 1) & 0xFFFF) << MSG_SHIFT,
            },
            purpose: BankPurpose::Topics(members.iter().map(|m| m.topic).collect()),
        });
    }
    // Exact single-frame topics go two per bank in list mode.
    for pair in singles.chunks(2) {
        match pair {
            [a, b] => banks.push(Bank {
                filter: FilterBank::List {
                    ids: [a.fixed_id.unwrap_or(0), b.fixed_id.unwrap_or(0)],
                },
                purpose: BankPurpose::Topics(vec![a.topic, b.topic]),
            }),
            [a] => banks.push(Bank {
                filter: FilterBank::Mask {
                    id: u32::from(a.msg_id) << MSG_SHIFT,
                    mask: 0xFFFF << MSG_SHIFT,
                },
                purpose: BankPurpose::Topics(vec![a.topic]),
            }),
            _ => {}
        }
    }
    banks
}

/// Whether a bank passes a 29-bit identifier.
pub fn passes(bank: &FilterBank, raw: u32) -> bool {
    match bank {
        FilterBank::Mask { id, mask } => raw & mask == id & mask,
        FilterBank::List { ids } => ids.contains(&raw),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(topic: usize, msg_id: u16) -> WireTopic {
        WireTopic {
            topic,
            msg_id,
            fixed_id: None,
        }
    }

    #[test]
    fn contiguous_block_is_one_mask() {
        let all: Vec<_> = (0..8).map(|i| w(i, 0x140 + i as u16)).collect();
        let banks = pack(&all[0..4], &all);
        assert_eq!(banks.len(), 3);
        assert_eq!(
            banks[2].filter,
            FilterBank::Mask {
                id: 0x140 << 7,
                mask: 0xFFFC << 7
            }
        );
        for raw in [0x140u32 << 7 | 5, 0x143 << 7 | (62 << 23)] {
            assert!(passes(&banks[2].filter, raw));
        }
        assert!(!passes(&banks[2].filter, 0x144 << 7));
    }

    #[test]
    fn unused_ids_are_dont_care() {
        // 0x140 and 0x143 wanted, 0x141 sent by someone else: 0x142..0x143 merge only
        // with don't-cares, 0x140 stays alone.
        let all = [w(0, 0x140), w(1, 0x141), w(2, 0x143)];
        let banks = pack(&[all[0], all[2]], &all);
        assert_eq!(banks.len(), 4);
        assert_eq!(
            banks[2].filter,
            FilterBank::Mask {
                id: 0x140 << 7,
                mask: 0xFFFF << 7
            }
        );
        // 0x143's maximal block is 0x142..=0x143 (0x140..=0x143 holds the forbidden 0x141).
        assert_eq!(
            banks[3].filter,
            FilterBank::Mask {
                id: 0x142 << 7,
                mask: 0xFFFE << 7
            }
        );
    }

    #[test]
    fn fixed_singletons_pair_in_list_banks() {
        let a = WireTopic {
            topic: 0,
            msg_id: 0x140,
            fixed_id: Some(fixed_id(0, 0x140)),
        };
        let b = w(1, 0x141);
        let c = WireTopic {
            topic: 2,
            msg_id: 0x142,
            fixed_id: Some(fixed_id(63, 0x142)),
        };
        let banks = pack(&[a, c], &[a, b, c]);
        assert_eq!(banks.len(), 3);
        assert_eq!(
            banks[2].filter,
            FilterBank::List {
                ids: [0x140 << 7, (63 << 23) | (0x142 << 7)]
            }
        );
    }

    #[test]
    fn sync_and_heartbeat_banks() {
        let s = sync_bank().filter;
        assert!(passes(&s, 0x0000_7FFF)); // sync with cycle counter 0x7FFF
        assert!(!passes(&s, 1 << 23)); // laxity 1
        assert!(!passes(&s, 0x100 << 7));
        let h = heartbeat_bank().filter;
        assert!(passes(&h, (63 << 23) | (0x13F << 7)));
        assert!(!passes(&h, 0x140 << 7));
    }
}
