//! Status/heartbeat message (docs/PROTOCOL.md §9). OWNER: codec helper. Signatures fixed.
use crate::frame::Frame;

/// A module's heartbeat: sent once per cycle... see PROTOCOL.md.
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

/// NRT frame, message ID HEARTBEAT_BASE + module.
pub fn heartbeat_frame(hb: Heartbeat) -> Option<Frame> {
    let _ = hb;
    todo!()
}

/// `None` if not a well-formed heartbeat.
pub fn parse_heartbeat(frame: &Frame) -> Option<Heartbeat> {
    let _ = frame;
    todo!()
}
