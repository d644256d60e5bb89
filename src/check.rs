//! Compile-time checks the generated code runs on its own tables (`const _: () = assert!(..)`),
//! so tables edited or generated out of step with the engine's const generics do not build.
use crate::core::engine::check_tables;
use crate::core::fragment::wire_len;
use crate::core::tables::{NodeTables, RxTopic};

/// Bytes of reassembly arena the receive table needs (end of its last buffer).
pub const fn arena_bytes(mut rx: &[RxTopic]) -> usize {
    let mut end = 0;
    while let [r, rest @ ..] = rx {
        let e = r.arena_offset as usize + wire_len(r.size as usize);
        if e > end {
            end = e;
        }
        rx = rest;
    }
    end
}

/// The tables fit an `Engine<'_, RX, ARENA, _>`: one reassembly state per receive topic,
/// and everything `rtcan_core::engine::check_tables` checks (buffers inside the arena
/// and not overlapping, receive table sorted, calendar sorted and naming only existing
/// transmit topics and fragments), so the generated const assertion covers all of it.
pub const fn tables_fit(t: &NodeTables<'_>, rx_count: usize, arena: usize) -> bool {
    t.rx.len() == rx_count && check_tables(t, rx_count, arena).is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::{BusConfig, CalEntry, Class, MsgId, TxTopic};

    const BUS: BusConfig = BusConfig {
        bitrate: 1_000_000,
        slots_per_cycle: 10,
        slot_ns: 100_000,
        hyperperiod_cycles: 1,
        cycle_counter_wrap: 32_768,
        laxity: crate::core::laxity::LaxityEncoding::Linear { unit_ns: 100_000 },
        guard_ns: 0,
        fingerprint: 0,
    };

    fn tables<'a>(rx: &'a [RxTopic], cal: &'a [CalEntry], tx: &'a [TxTopic]) -> NodeTables<'a> {
        NodeTables {
            bus: BUS,
            module: 0,
            tx,
            rx,
            calendar: cal,
            master_masks: &[],
        }
    }

    #[test]
    fn arena_and_order_checks() {
        let rx = [
            RxTopic {
                msg_id: MsgId(0x140),
                size: 8,
                arena_offset: 0,
            },
            RxTopic {
                msg_id: MsgId(0x141),
                size: 12,
                arena_offset: 8,
            },
        ];
        let tx = [TxTopic {
            msg_id: MsgId(0x142),
            class: Class::Hrt,
            size: 8,
            deadline_ns: 0,
        }];
        let cal = [CalEntry {
            slot: 1,
            tx: 0,
            fragment: 0,
        }];
        assert_eq!(arena_bytes(&rx), 8 + 12);
        assert!(tables_fit(&tables(&rx, &cal, &tx), 2, 20));
        assert!(
            !tables_fit(&tables(&rx, &cal, &tx), 2, 19),
            "arena too small"
        );
        assert!(!tables_fit(&tables(&rx, &cal, &tx), 1, 20), "rx count");
        let unsorted = [rx[1], rx[0]];
        assert!(!tables_fit(&tables(&unsorted, &cal, &tx), 2, 20));
        // A buffer starting inside the previous one does not build.
        let overlap = [
            rx[0],
            RxTopic {
                arena_offset: 6,
                ..rx[1]
            },
        ];
        assert!(!tables_fit(&tables(&overlap, &cal, &tx), 2, 20), "overlap");
        let bad_cal = [CalEntry {
            slot: 1,
            tx: 1,
            fragment: 0,
        }];
        assert!(
            !tables_fit(&tables(&rx, &bad_cal, &tx), 2, 22),
            "tx index out of table"
        );
    }
}
