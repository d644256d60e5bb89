//! The host channels' identifiers (docs/PROTOCOL.md §2.3, docs/SERVICES.md §2 and §4):
//! a reserved message-ID range at the top of the 16-bit space, like the heartbeat range,
//! not plan IDs, holding the parameter channel (`0xFF00..=0xFF7F`) and the firmware-update
//! channel (`0xFF80..=0xFFFF`). Why reserved: the update must reach a module whatever
//! robot.toml it was built from (an image built for an older robot.toml still has to
//! accept the new one), and a parameter tool must reach a module without the plan's
//! topic numbering, so their IDs cannot depend on the plan; and the top of the space
//! loses arbitration to every other frame, NRT included, so neither ever delays anything
//! the robot runs on. Parameters sit below the update so a `get`/`set` overtakes a long
//! transfer in progress.
//!
//! The engine only routes: frames of the range go to `Host::service_rx`, and frames the
//! host offers through `Host::service_tx` go out in free windows as NRT, after every
//! queued message and the heartbeat. What the frames mean is the protocols' business
//! (`rtcan_pubsub::param_bus`, `rtcan-boot`).
use crate::frame::Frame;
use crate::id::{MsgId, LAXITY_NRT};

/// Parameter request to module `m`: message ID `PARAM_REQ_BASE + m` (m < 64).
pub const PARAM_REQ_BASE: u16 = 0xFF00;
/// Parameter reply from module `m`: message ID `PARAM_REP_BASE + m` (m < 64).
pub const PARAM_REP_BASE: u16 = 0xFF40;
/// Update request to module `m`: message ID `UPDATE_REQ_BASE + m` (m < 64).
pub const UPDATE_REQ_BASE: u16 = 0xFF80;
/// Update reply from module `m`: message ID `UPDATE_REP_BASE + m` (m < 64).
pub const UPDATE_REP_BASE: u16 = 0xFFC0;
/// First message ID of the reserved range; topics are assigned below it.
pub const SERVICE_MSG_ID_START: u16 = PARAM_REQ_BASE;

/// Whether `msg` is in the reserved range (`0xFF00..=0xFFFF`: parameters and update).
pub const fn is_service(msg: MsgId) -> bool {
    msg.0 >= SERVICE_MSG_ID_START
}

/// Message ID of the parameter request to `module`; `None` if `module >= 64`.
pub const fn param_request_id(module: u8) -> Option<MsgId> {
    if module >= 64 {
        None
    } else {
        Some(MsgId(PARAM_REQ_BASE + module as u16))
    }
}

/// Message ID of `module`'s parameter reply; `None` if `module >= 64`.
pub const fn param_reply_id(module: u8) -> Option<MsgId> {
    if module >= 64 {
        None
    } else {
        Some(MsgId(PARAM_REP_BASE + module as u16))
    }
}

/// Message ID of the update request to `module`; `None` if `module >= 64`.
pub const fn request_id(module: u8) -> Option<MsgId> {
    if module >= 64 {
        None
    } else {
        Some(MsgId(UPDATE_REQ_BASE + module as u16))
    }
}

/// Message ID of `module`'s update reply; `None` if `module >= 64`.
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
        assert!(is_service(MsgId(0xFF7F)));
        assert!(is_service(MsgId(0xFF80)));
        assert!(!is_service(MsgId(0xFEFF)));
        assert!(is_service(MsgId(0xFF00)));
        assert_eq!(param_request_id(1), Some(MsgId(0xFF01)));
        assert_eq!(param_reply_id(63), Some(MsgId(0xFF7F)));
        assert_eq!(param_reply_id(64), None);
        // Get request to module 1: one frame, fragment 0: 0x1FFF8080.
        let get = CanId::new(LAXITY_NRT, MsgId(0xFF01), 0).unwrap();
        assert_eq!(get.raw(), 0x1FFF_8080);
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
