//! USART1 (RM0008 §27) and DMA1 (§13): what the gateway's host link uses. The USART
//! shifts bytes out at the baud rate BRR sets (TXE/TC follow the shift register, §27.3.2),
//! receives bytes the host side offers (RXNE, ORE, §27.3.3) and, with CR3.DMAR, hands
//! them to DMA1 channel 5 (§13.3.7 table 78: USART1_RX on channel 5, USART1_TX on 4),
//! which writes them to memory in normal or circular mode (§13.3.3–§13.3.6).
//! Time is in picoseconds of emulated time, as in `periph`.
use crate::periph::PS;
use crate::Access;

/// USART1's data register address: what a DMA channel's CPAR names to serve it.
pub const USART1_DR: u32 = 0x4001_3804;

/// SR bits (§27.6.1).
const TXE: u32 = 1 << 7;
const TC: u32 = 1 << 6;
const RXNE: u32 = 1 << 5;
const ORE: u32 = 1 << 3;
/// CR1 bits (§27.6.4).
const UE: u32 = 1 << 13;
const TE: u32 = 1 << 3;
const RE: u32 = 1 << 2;
/// CR3.DMAR (§27.6.6).
const DMAR: u32 = 1 << 6;

/// USART1 with a one-byte transmit buffer (TDR) in front of the shift register.
#[derive(Clone, Debug, Default)]
pub struct Usart {
    pub cr1: u32,
    cr2: u32,
    pub cr3: u32,
    brr: u32,
    gtpr: u32,
    /// Bytes transmitted: (time the stop bit ends, ps; byte).
    pub tx: Vec<(u64, u8)>,
    /// End of the byte in (or queued behind) the shift register, ps.
    shift_end: u64,
    /// Received byte in RDR (RXNE while `Some`).
    rdr: Option<u8>,
    ore: bool,
    /// TC cleared by software (read SR then write DR, or write 0 to TC) until the next
    /// transmission ends.
    tc_cleared: bool,
    /// Bytes offered while the receiver was off (UE or RE clear): lost on the line.
    pub rx_lost: u64,
}

impl Usart {
    /// One frame (start, 8 data, 1 stop: M = 0, STOP = 00, §27.3.1) in ps, from BRR and
    /// the APB2 clock (baud = fPCLK / USARTDIV, USARTDIV = BRR / 16, §27.3.4).
    pub fn byte_ps(&self, pclk2: u64) -> u64 {
        let bits = if self.cr1 & (1 << 12) != 0 { 11 } else { 10 };
        let stop_extra = u64::from((self.cr2 >> 12) & 3 == 2); // 2 stop bits
        (bits + stop_extra) * u64::from(self.brr.max(16)) * PS / pclk2.max(1)
    }

    fn sr(&self, now: u64, pclk2: u64) -> u32 {
        let byte = self.byte_ps(pclk2);
        // TXE: TDR empty, i.e. the last byte written has moved into the shift register.
        let txe = now + byte >= self.shift_end;
        let tc = now >= self.shift_end && !self.tc_cleared;
        (u32::from(txe) * TXE)
            | (u32::from(tc) * TC)
            | (u32::from(self.rdr.is_some()) * RXNE)
            | (u32::from(self.ore) * ORE)
    }

    pub fn read(&mut self, off: u32, now: u64, pclk2: u64) -> Access {
        Ok(match off {
            0x00 => self.sr(now, pclk2),
            // Reading DR clears RXNE, and ORE after an SR read (§27.6.1).
            0x04 => {
                self.ore = false;
                u32::from(self.rdr.take().unwrap_or(0))
            }
            0x08 => self.brr,
            0x0C => self.cr1,
            0x10 => self.cr2,
            0x14 => self.cr3,
            0x18 => self.gtpr,
            _ => return Err(off),
        })
    }

    pub fn write(&mut self, off: u32, v: u32, now: u64, pclk2: u64) -> Access {
        match off {
            // SR: RXNE and TC are rc_w0, the rest read-only (§27.6.1).
            0x00 => {
                if v & RXNE == 0 {
                    self.rdr = None;
                }
                if v & TC == 0 {
                    self.tc_cleared = true;
                }
            }
            // DR write (§27.3.2): the byte goes to the shift register when it is free,
            // else waits in TDR (TXE low) until the byte ahead of it is out. A write
            // while TXE is low overwrites TDR on the chip; the images poll TXE first.
            0x04 => {
                if self.cr1 & (UE | TE) == UE | TE {
                    let byte = self.byte_ps(pclk2);
                    let start = now.max(self.shift_end);
                    self.shift_end = start + byte;
                    self.tx.push((self.shift_end, v as u8));
                    self.tc_cleared = false;
                }
            }
            0x08 => self.brr = v & 0xFFFF,
            0x0C => self.cr1 = v & 0x3FFF,
            0x10 => self.cr2 = v & 0x7F7F,
            0x14 => self.cr3 = v & 0x7FF,
            0x18 => self.gtpr = v & 0xFFFF,
            _ => return Err(off),
        }
        Ok(0)
    }

    /// Whether the receiver is on (UE and RE, §27.6.4).
    pub fn receiving(&self) -> bool {
        self.cr1 & (UE | RE) == UE | RE
    }

    /// Whether received bytes go to the DMA (CR3.DMAR).
    pub fn rx_dma(&self) -> bool {
        self.cr3 & DMAR != 0
    }

    /// A byte arrived in RDR (no DMA): RXNE, or ORE if the previous one was not read
    /// (the new byte is lost, §27.3.3).
    pub fn rx_byte(&mut self, b: u8) {
        if self.rdr.is_some() {
            self.ore = true;
        } else {
            self.rdr = Some(b);
        }
    }

    /// The next time (ps) after `now` the interrupt line rises by itself: TXE (with
    /// TXEIE) when TDR moves into the shift register, TC (with TCIE) when the shift
    /// register empties (§27.3.2).
    pub fn next_event(&self, now: u64, pclk2: u64) -> Option<u64> {
        let byte = self.byte_ps(pclk2);
        let txe_at = self.shift_end.saturating_sub(byte);
        let mut t: Option<u64> = None;
        if self.cr1 & (1 << 7) != 0 && now < txe_at {
            t = Some(txe_at);
        }
        if self.cr1 & (1 << 6) != 0 && now < self.shift_end {
            t = Some(t.map_or(self.shift_end, |x| x.min(self.shift_end)));
        }
        t
    }

    /// The USART1 interrupt line (§27.4, figure 287): TXEIE, TCIE, RXNEIE (also ORE).
    pub fn irq(&self, now: u64, pclk2: u64) -> bool {
        let sr = self.sr(now, pclk2);
        (self.cr1 & (1 << 7) != 0 && sr & TXE != 0)
            || (self.cr1 & (1 << 6) != 0 && sr & TC != 0)
            || (self.cr1 & (1 << 5) != 0 && sr & (RXNE | ORE) != 0)
    }
}

/// DMA1 (RM0008 §13.4): seven channels of CCR/CNDTR/CPAR/CMAR and the ISR flags.
#[derive(Clone, Debug, Default)]
pub struct Dma {
    pub isr: u32,
    /// Per channel: CCR, CNDTR, CPAR, CMAR.
    pub ch: [[u32; 4]; 7],
    /// CNDTR as last programmed: the reload value of circular mode (§13.3.6).
    reload: [u32; 7],
}

/// CCR bits (§13.4.3).
const EN: u32 = 1;
const TCIE: u32 = 1 << 1;
const HTIE: u32 = 1 << 2;
const DIR: u32 = 1 << 4;
const CIRC: u32 = 1 << 5;
const MINC: u32 = 1 << 7;

impl Dma {
    pub fn read(&self, off: u32) -> Access {
        match off {
            0x00 => Ok(self.isr),
            0x04 => Ok(0),
            0x08..=0x8F => {
                let c = ((off - 0x08) / 20) as usize;
                let r = (((off - 0x08) % 20) / 4) as usize;
                self.ch.get(c).and_then(|ch| ch.get(r)).copied().ok_or(off)
            }
            _ => Err(off),
        }
    }

    pub fn write(&mut self, off: u32, v: u32) -> Access {
        match off {
            0x04 => {
                // IFCR (§13.4.2): CGIFx clears all four flags of the channel.
                let mut clear = v;
                for c in 0..7 {
                    if v & (1 << (4 * c)) != 0 {
                        clear |= 0xF << (4 * c);
                    }
                }
                self.isr &= !clear;
            }
            0x08..=0x8F => {
                let c = ((off - 0x08) / 20) as usize;
                let r = (((off - 0x08) % 20) / 4) as usize;
                let enabled = self
                    .ch
                    .get(c)
                    .and_then(|ch| ch.first())
                    .is_some_and(|x| x & EN != 0);
                let x = self.ch.get_mut(c).and_then(|ch| ch.get_mut(r)).ok_or(off)?;
                match r {
                    0 => *x = v & 0x7FFF,
                    // CNDTR, CPAR, CMAR are write-protected while the channel is enabled
                    // (§13.4.4–§13.4.6).
                    1 if !enabled => {
                        *x = v & 0xFFFF;
                        if let Some(rl) = self.reload.get_mut(c) {
                            *rl = v & 0xFFFF;
                        }
                    }
                    _ if !enabled => *x = v,
                    _ => {}
                }
            }
            _ => return Err(off),
        }
        Ok(0)
    }

    /// A peripheral-to-memory request on channel `c` (0-based) from the peripheral at
    /// `periph` (its data register): the memory address the byte goes to, with NDTR,
    /// the flags and circular reload updated (§13.3.3–§13.3.6); `None` if the channel is
    /// off, points elsewhere, goes the other way, or has finished (normal mode).
    pub fn request(&mut self, c: usize, periph: u32) -> Option<u32> {
        let reload = *self.reload.get(c)?;
        let ch = self.ch.get_mut(c)?;
        let [ccr, ndtr, par, mar] = *ch;
        if ccr & EN == 0 || ccr & DIR != 0 || par != periph || ndtr == 0 {
            return None;
        }
        // Memory size (MSIZE bits 11:10): 8, 16, 32 bits; the index of this transfer.
        let size = 1u32 << ((ccr >> 10) & 3).min(2);
        let index = reload.saturating_sub(ndtr);
        let addr = if ccr & MINC != 0 {
            mar.wrapping_add(index * size)
        } else {
            mar
        };
        let left = ndtr - 1;
        let shift = 4 * c as u32;
        // GIF with any flag; HTIF at half, TCIF at the end (§13.4.1).
        if left == reload / 2 {
            self.isr |= (1 | 4) << shift;
        }
        if left == 0 {
            self.isr |= (1 | 2) << shift;
        }
        if let Some(n) = ch.get_mut(1) {
            *n = if left == 0 && ccr & CIRC != 0 {
                reload
            } else {
                left
            };
        }
        Some(addr)
    }

    /// The channel's interrupt line (TCIE/HTIE with their flags, §13.3.7).
    pub fn irq(&self, c: usize) -> bool {
        let ccr = self
            .ch
            .get(c)
            .and_then(|ch| ch.first())
            .copied()
            .unwrap_or(0);
        let flags = self.isr >> (4 * c as u32);
        (ccr & TCIE != 0 && flags & 2 != 0) || (ccr & HTIE != 0 && flags & 4 != 0)
    }
}

#[cfg(test)]
#[path = "serial_tests.rs"]
mod tests;
