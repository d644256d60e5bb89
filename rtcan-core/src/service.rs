//! The firmware-update channel's identifiers (docs/PROTOCOL.md §2.3, docs/SERVICES.md
//! §4): a reserved message-ID range at the top of the 16-bit space, like the heartbeat
//! range, not plan IDs. Why: the update must reach a module whatever robot.toml it was
//! built from (an image built for an older robot.toml still has to accept the new one),
//! so its IDs cannot depend on the plan; and the top of the space loses arbitration to
//! every other frame, NRT included, so an update never delays anything the robot runs on.
//!
//! The engine only routes: frames of the range go to `Host::service_rx`, and frames the
//! host offers through `Host::service_tx` go out in free windows as NRT, after every
//! queued message and the heartbeat. What the frames mean is the update protocol's
//! business (`rtcan-boot`).
use crate::frame::Frame;
use crate::id::{MsgId, LAXITY_NRT};

/// Update request to module `m`: message ID `UPDATE_REQ_BASE + m` (m < 64).
pub const UPDATE_REQ_BASE: u16 = 0xFF80;
/// Update reply from module `m`: message ID `UPDATE_REP_BASE + m` (m < 64).
pub const UPDATE_REP_BASE: u16 = 0xFFC0;
/// First message ID of the reserved range; topics are assigned below it.
pub const SERVICE_MSG_ID_START: u16 = UPDATE_REQ_BASE;

/// Whether `msg` is in the reserved update range (`0xFF80..=0xFFFF`).
pub const fn is_service(msg: MsgId) -> bool {
    msg.0 >= SERVICE_MSG_ID_START
}

/// Message ID of the request to `module`; `None` if `module >= 64`.
pub const fn request_id(module: u8) -> Option<MsgId> {
    if module >= 64 {
        None
    } else {
        Some(MsgId(UPDATE_REQ_BASE + module as u16))
    }
}

/// Message ID of `module`'s reply; `None` if `module >= 64`.
pub const fn reply_id(module: u8) -> Option<MsgId> {
    if module >= 64 {
        None
    } else {
        Some(MsgId(UPDATE_REP_BASE + module as u16))
    }
}

/// Whether the engine may send `frame` for the host: NRT and in the reserved range
/// (a host bug must not put a frame with a topic's or the sync's priority on the bus).
pub fn sendable(frame: &Frame) -> bool {
    frame.id().laxity() == LAXITY_NRT && is_service(frame.id().msg_id())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::id::CanId;

    #[test]
    fn range_and_ids() {
        assert_eq!(request_id(3), Some(MsgId(0xFF83)));
        assert_eq!(reply_id(63), Some(MsgId(0xFFFF)));
        assert_eq!(request_id(64), None);
        assert!(!is_service(MsgId(0xFF7F)));
        assert!(is_service(MsgId(0xFF80)));
        // Request to module 1, first of 32 fragments, transfer 0: 0x1FFFC09F.
        let id = CanId::new(LAXITY_NRT, MsgId(0xFF81), 31).unwrap();
        assert_eq!(id.raw(), 0x1FFF_C09F);
        let f = Frame::new(id, &[0; 8]).unwrap();
        assert!(sendable(&f));
        let hrt = Frame::new(CanId::new(0, MsgId(0xFF81), 0).unwrap(), &[]).unwrap();
        assert!(!sendable(&hrt));
        let topic = Frame::new(CanId::new(LAXITY_NRT, MsgId(0x0140), 0).unwrap(), &[]).unwrap();
        assert!(!sendable(&topic));
    }
}
