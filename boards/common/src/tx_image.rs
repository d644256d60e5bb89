//! A transmit frame as the register image of a bxCAN TX mailbox, computed ahead of time
//! (at the protocol task's priority) so that the slot-timer interrupt only stores four
//! words, TXRQ last.
use rtcan_core::frame::Frame;
use rtcan_core::id::CanId;

/// TIR: transmit request.
pub const TIR_TXRQ: u32 = 1;
/// TIR/RIR: extended identifier.
pub const TIR_IDE: u32 = 1 << 2;
/// TIR/RIR: remote frame.
pub const TIR_RTR: u32 = 1 << 1;

/// Register image of one TX mailbox (RM0008 §24.9.3): `tir` already holds TXRQ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TxImage {
    /// Identifier, IDE, RTR = 0, TXRQ.
    pub tir: u32,
    /// DLC (TGT = 0: no time stamp in the frame).
    pub tdtr: u32,
    /// Data bytes 0..3, little endian.
    pub tdlr: u32,
    /// Data bytes 4..7, little endian.
    pub tdhr: u32,
}

impl TxImage {
    /// The image that transmits `frame`.
    pub fn of(frame: &Frame) -> Self {
        let d = frame.raw_data();
        TxImage {
            tir: (frame.id().raw() << 3) | TIR_IDE | TIR_TXRQ,
            tdtr: frame.dlc() as u32,
            tdlr: u32::from_le_bytes([d[0], d[1], d[2], d[3]]),
            tdhr: u32::from_le_bytes([d[4], d[5], d[6], d[7]]),
        }
    }

    /// The frame an image (TX mailbox or, with the same layout, RX FIFO mailbox) holds:
    /// `None` for standard-ID or remote frames, which are not RTCAN.
    pub fn frame(&self) -> Option<Frame> {
        if self.tir & TIR_IDE == 0 || self.tir & TIR_RTR != 0 {
            return None;
        }
        let id = CanId::from_raw(self.tir >> 3)?;
        let (lo, hi) = (self.tdlr.to_le_bytes(), self.tdhr.to_le_bytes());
        let data = [lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]];
        Frame::from_parts(id, (self.tdtr & 0xF).min(8) as u8, data)
    }
}

/// The transmit side of a bxCAN-like controller, as the slot-timer interrupt and the
/// protocol task use it. Mailboxes are disjoint register sets and the status register
/// takes write-1 requests, so both contexts may write different mailboxes without a lock.
pub trait TxPort {
    /// Stores `image` into mailbox `mailbox` (0..=2): TDTR, TDLR, TDHR, then TIR, whose
    /// TXRQ bit starts the transmission.
    fn write(&mut self, mailbox: usize, image: &TxImage);
    /// Requests abort of the mailboxes whose bit is set in `mask` (bit m = mailbox m).
    fn abort(&mut self, mask: u8);
    /// True while the controller is bus-off.
    fn is_bus_off(&self) -> bool;
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtcan_core::id::MsgId;

    #[test]
    fn image_round_trips_and_matches_the_register_layout() {
        let id = CanId::new(17, MsgId(0x143), 2).unwrap();
        let f = Frame::from_parts(id, 5, [1, 2, 3, 4, 5, 0, 0, 0]).unwrap();
        let img = TxImage::of(&f);
        assert_eq!(img.tir, (id.raw() << 3) | 0b101);
        assert_eq!(img.tdtr, 5);
        assert_eq!(img.tdlr, 0x0403_0201);
        assert_eq!(img.tdhr, 0x0000_0005);
        assert_eq!(img.frame(), Some(f));
        // Standard ID or remote frames are not RTCAN.
        assert_eq!(
            TxImage {
                tir: img.tir & !TIR_IDE,
                ..img
            }
            .frame(),
            None
        );
        assert_eq!(
            TxImage {
                tir: img.tir | TIR_RTR,
                ..img
            }
            .frame(),
            None
        );
    }
}
