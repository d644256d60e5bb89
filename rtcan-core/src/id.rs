//! The 29-bit extended identifier (docs/PROTOCOL.md §2).
//!
//! ```text
//! ID[28:23] laxity (6 bits)   0 = HRT and sync, 1..=62 SRT (lower = more urgent), 63 = NRT
//! ID[22:7]  message ID (16 bits)  unique per transmitter on the bus
//! ID[6:0]   fragment counter (7 bits), counts down, last fragment = 0
//! ```

/// Laxity field value of HRT frames (and the sync frame).
pub const LAXITY_HRT: u8 = 0;
/// Laxity field value of NRT frames: always below every SRT frame.
pub const LAXITY_NRT: u8 = 63;
/// Most urgent SRT laxity code.
pub const LAXITY_SRT_MIN: u8 = 1;
/// Least urgent SRT laxity code.
pub const LAXITY_SRT_MAX: u8 = 62;

/// Message IDs `0x0000..=0x00FF` are the sync frame: with laxity 0 the low 15 bits of the
/// identifier (message ID low byte and fragment field) carry the cycle counter.
pub const SYNC_MSG_ID_END: u16 = 0x0100;
/// Heartbeat (status) message of module `m` is `HEARTBEAT_BASE + m`, m < 64.
pub const HEARTBEAT_BASE: u16 = 0x0100;
/// First message ID available to topics.
pub const FIRST_TOPIC_MSG_ID: u16 = 0x0140;

/// Traffic class of a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Class {
    /// Hard real time: reserved slots (TDMA).
    Hrt,
    /// Soft real time: EDF by laxity in free windows.
    Srt,
    /// Best effort: free windows, below every SRT frame.
    Nrt,
}

/// 16-bit RTCAN message ID (`ID[22:7]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MsgId(pub u16);

/// A validated 29-bit extended CAN identifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CanId(u32);

impl CanId {
    /// Largest 29-bit identifier.
    pub const MAX_RAW: u32 = 0x1FFF_FFFF;

    /// Builds an identifier from its fields; `None` if laxity > 63 or fragment > 127.
    pub const fn new(laxity: u8, msg: MsgId, fragment: u8) -> Option<Self> {
        if laxity > 63 || fragment > 127 {
            return None;
        }
        Some(CanId(
            ((laxity as u32) << 23) | ((msg.0 as u32) << 7) | fragment as u32,
        ))
    }

    /// Accepts any 29-bit value (every 29-bit value has a field decoding).
    pub const fn from_raw(raw: u32) -> Option<Self> {
        if raw > Self::MAX_RAW {
            None
        } else {
            Some(CanId(raw))
        }
    }

    /// The raw 29-bit value.
    pub const fn raw(self) -> u32 {
        self.0
    }
    /// `ID[28:23]`.
    pub const fn laxity(self) -> u8 {
        (self.0 >> 23) as u8 & 0x3F
    }
    /// `ID[22:7]`.
    pub const fn msg_id(self) -> MsgId {
        MsgId((self.0 >> 7) as u16)
    }
    /// `ID[6:0]`.
    pub const fn fragment(self) -> u8 {
        self.0 as u8 & 0x7F
    }
    /// True for the sync frame: laxity 0 and message ID below `SYNC_MSG_ID_END`.
    pub const fn is_sync(self) -> bool {
        self.laxity() == LAXITY_HRT && self.msg_id().0 < SYNC_MSG_ID_END
    }
}
