//! Status/heartbeat message (docs/PROTOCOL.md §9). OWNER: codec helper. Signatures fixed.
use crate::frame::Frame;
use crate::id::{CanId, MsgId, FIRST_TOPIC_MSG_ID, HEARTBEAT_BASE, LAXITY_NRT};

/// Every module sends its heartbeat once every this many cycles (engine).
pub const HEARTBEAT_PERIOD_CYCLES: u32 = 10;
/// Heartbeat DLC: fingerprint u32 little-endian, then the state byte.
pub const HEARTBEAT_DLC: u8 = 5;
/// Modules per robot (heartbeat message IDs 0x0100..0x0140).
pub const MAX_MODULES: u8 = (FIRST_TOPIC_MSG_ID - HEARTBEAT_BASE) as u8;

/// A module's heartbeat: sent every `HEARTBEAT_PERIOD_CYCLES` cycles as an NRT frame, so it
/// only uses bandwidth nothing else wants; see PROTOCOL.md §9.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Heartbeat {
    /// Module index (< 64).
    pub module: u8,
    /// Module state (middleware defined: init/run/stop/fail).
    pub state: u8,
    /// Robot-description fingerprint.
    pub fingerprint: u32,
}

/// Message ID of module `module`'s heartbeat; `None` if `module >= 64`.
pub const fn heartbeat_msg_id(module: u8) -> Option<MsgId> {
    if module >= MAX_MODULES {
        None
    } else {
        Some(MsgId(HEARTBEAT_BASE + module as u16))
    }
}

/// NRT frame, message ID HEARTBEAT_BASE + module. `None` if `module >= 64`.
pub fn heartbeat_frame(hb: Heartbeat) -> Option<Frame> {
    let id = CanId::new(LAXITY_NRT, heartbeat_msg_id(hb.module)?, 0)?;
    let [f0, f1, f2, f3] = hb.fingerprint.to_le_bytes();
    Frame::new(id, &[f0, f1, f2, f3, hb.state])
}

/// `None` if not a well-formed heartbeat (laxity not 63, message ID outside
/// 0x0100..0x0140, fragment not 0, DLC not 5).
pub fn parse_heartbeat(frame: &Frame) -> Option<Heartbeat> {
    let id = frame.id();
    let msg = id.msg_id().0;
    if id.laxity() != LAXITY_NRT
        || !(HEARTBEAT_BASE..FIRST_TOPIC_MSG_ID).contains(&msg)
        || id.fragment() != 0
        || frame.dlc() != HEARTBEAT_DLC
    {
        return None;
    }
    let &[f0, f1, f2, f3, state, ..] = frame.raw_data();
    Some(Heartbeat {
        module: (msg - HEARTBEAT_BASE) as u8,
        state,
        fingerprint: u32::from_le_bytes([f0, f1, f2, f3]),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_range() {
        let hb = Heartbeat {
            module: 63,
            state: 2,
            fingerprint: 0xDEAD_BEEF,
        };
        let f = heartbeat_frame(hb).unwrap();
        assert_eq!(f.id().raw(), 0x1F80_9F80);
        assert_eq!(f.data(), &[0xEF, 0xBE, 0xAD, 0xDE, 2]);
        assert_eq!(parse_heartbeat(&f), Some(hb));
        assert_eq!(heartbeat_frame(Heartbeat { module: 64, ..hb }), None);
    }

    #[test]
    fn malformed_rejected() {
        let good = heartbeat_frame(Heartbeat {
            module: 1,
            state: 0,
            fingerprint: 1,
        })
        .unwrap();
        let data = good.data();
        let with = |lax: u8, msg: u16, frag: u8, d: &[u8]| {
            Frame::new(CanId::new(lax, MsgId(msg), frag).unwrap(), d).unwrap()
        };
        assert!(parse_heartbeat(&with(63, 0x101, 0, data)).is_some());
        assert_eq!(parse_heartbeat(&with(62, 0x101, 0, data)), None); // SRT laxity
        assert_eq!(parse_heartbeat(&with(63, 0x140, 0, data)), None); // a topic
        assert_eq!(parse_heartbeat(&with(63, 0x0FF, 0, data)), None); // below the range
        assert_eq!(parse_heartbeat(&with(63, 0x101, 1, data)), None); // fragment
        assert_eq!(parse_heartbeat(&with(63, 0x101, 0, &data[..4])), None); // DLC 4
        assert_eq!(parse_heartbeat(&with(63, 0x101, 0, &[0; 6])), None); // DLC 6
    }
}
