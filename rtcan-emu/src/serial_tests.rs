//! USART1 and DMA1 against RM0008 (section cited per test).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::panic
)]
use super::*;

const PCLK2: u64 = 72_000_000;
const US: u64 = 1_000_000;

fn usart_115200() -> Usart {
    let mut u = Usart::default();
    // BRR 625 at 72 MHz = 115 200 Bd (§27.3.4); UE | TE | RE (§27.6.4).
    u.write(0x08, 625, 0, PCLK2).unwrap();
    u.write(0x0C, (1 << 13) | (1 << 3) | (1 << 2), 0, PCLK2)
        .unwrap();
    u
}

// §27.3.2: TXE is set while TDR is empty; a byte written while the shift register is
// busy waits in TDR (TXE low) until the one ahead is out; TC once the last stop bit is.
// 10 bits at 72 MHz / 625 = 86.8 µs a byte.
#[test]
fn usart_tx_shift_register_and_tdr_27_3_2() {
    let mut u = usart_115200();
    let byte = u.byte_ps(PCLK2);
    assert_eq!(byte, 10 * 625 * 1_000_000_000_000 / 72_000_000);
    assert_eq!(byte / US, 86);
    let sr = |u: &mut Usart, t| u.read(0, t, PCLK2).unwrap();
    assert_eq!(sr(&mut u, 0) & 0xC0, 0xC0, "idle: TXE and TC");
    u.write(0x04, 0x41, 0, PCLK2).unwrap();
    assert_eq!(
        sr(&mut u, 0) & 0xC0,
        0x80,
        "first byte in the shifter: TXE, not TC"
    );
    u.write(0x04, 0x42, 0, PCLK2).unwrap();
    assert_eq!(sr(&mut u, 10 * US) & 0x80, 0, "second byte waits in TDR");
    assert_eq!(sr(&mut u, byte) & 0xC0, 0x80, "first out: TDR empty again");
    assert_eq!(sr(&mut u, 2 * byte) & 0xC0, 0xC0, "both out: TC");
    assert_eq!(u.tx, vec![(byte, 0x41), (2 * byte, 0x42)]);
    // Transmitter off (TE = 0): nothing goes out.
    u.write(0x0C, 1 << 13, 3 * byte, PCLK2).unwrap();
    u.write(0x04, 0x43, 3 * byte, PCLK2).unwrap();
    assert_eq!(u.tx.len(), 2);
}

// §27.3.3: RXNE with a byte in RDR, cleared by reading DR; a byte arriving while RXNE
// is set is lost and sets ORE.
#[test]
fn usart_rx_rxne_and_overrun_27_3_3() {
    let mut u = usart_115200();
    u.rx_byte(7);
    assert_ne!(u.read(0, 0, PCLK2).unwrap() & (1 << 5), 0, "RXNE");
    u.rx_byte(8);
    assert_ne!(u.read(0, 0, PCLK2).unwrap() & (1 << 3), 0, "ORE");
    assert_eq!(u.read(4, 0, PCLK2).unwrap(), 7, "the first byte kept");
    assert_eq!(
        u.read(0, 0, PCLK2).unwrap() & 0x28,
        0,
        "RXNE and ORE cleared"
    );
    // RXNEIE (bit 5) raises the line while RXNE.
    u.write(0x0C, (1 << 13) | (1 << 2) | (1 << 5), 0, PCLK2)
        .unwrap();
    assert!(!u.irq(0, PCLK2));
    u.rx_byte(9);
    assert!(u.irq(0, PCLK2));
}

fn dma_ch5(ndtr: u32, circ: bool) -> Dma {
    let mut d = Dma::default();
    let base = 0x08 + 20 * 4;
    d.write(base + 8, USART1_DR).unwrap();
    d.write(base + 12, 0x2000_0100).unwrap();
    d.write(base + 4, ndtr).unwrap();
    // MINC, peripheral → memory, TCIE, EN (+ CIRC).
    d.write(base, (1 << 7) | (u32::from(circ) << 5) | 2 | 1)
        .unwrap();
    d
}

// §13.3.3 and §13.3.6: with MINC each request goes to the next memory byte and NDTR
// counts down; in circular mode NDTR reloads at 0 and the addresses start over; HTIF at
// half, TCIF (with GIF) at the end (§13.4.1); CNDTR is write-protected while enabled.
#[test]
fn dma_circular_peripheral_to_memory_13_3_6() {
    let mut d = dma_ch5(4, true);
    let addrs: Vec<u32> = (0..6).map(|_| d.request(4, USART1_DR).unwrap()).collect();
    assert_eq!(
        addrs,
        [
            0x2000_0100,
            0x2000_0101,
            0x2000_0102,
            0x2000_0103,
            0x2000_0100,
            0x2000_0101
        ]
    );
    assert_eq!(
        d.read(0x08 + 20 * 4 + 4).unwrap(),
        2,
        "NDTR after 6 of 4 (reloaded)"
    );
    assert_eq!((d.isr >> 16) & 0xF, 0b0111, "GIF, TCIF, HTIF of channel 5");
    assert!(d.irq(4), "TCIE");
    d.write(0x04, 1 << 16).unwrap();
    assert_eq!(d.isr, 0, "CGIF5 clears the channel's flags");
    d.write(0x08 + 20 * 4 + 4, 100).unwrap();
    assert_eq!(
        d.read(0x08 + 20 * 4 + 4).unwrap(),
        2,
        "CNDTR protected while EN"
    );
    // Another peripheral, or the other direction, is not served.
    assert_eq!(d.request(4, 0x4000_4404), None);
    assert_eq!(d.request(3, USART1_DR), None);
}

// §13.3.3: in normal mode the channel stops at NDTR = 0 (requests are not served).
#[test]
fn dma_normal_mode_stops_13_3_3() {
    let mut d = dma_ch5(2, false);
    assert!(d.request(4, USART1_DR).is_some());
    assert!(d.request(4, USART1_DR).is_some());
    assert_eq!(d.request(4, USART1_DR), None);
    assert_ne!(d.isr & (2 << 16), 0, "TCIF5");
}
