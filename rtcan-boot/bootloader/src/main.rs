//! STM32F103 bootloader: picks the newest A/B slot whose header, CRC-32 and embedded
//! robot fingerprint check out (rtcan-boot) and jumps to it; with none valid it stays
//! here (the module keeps a bootable bootloader whatever an update did). Updates are
//! received by the application into the other slot (`rtcan_boot::update::Receiver`).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use rtcan_boot::Layout;
use rtcan_pubsub::flash::{Flash, FlashError};

/// Flash base and the slots' region (everything after the bootloader's 8 KiB).
const REGION: u32 = 0x0800_2000;
const LAYOUT: Layout = Layout {
    slot_page: [0, 30],
    slot_pages: 30,
    fingerprint_offset: 0x1D0,
};

/// The F103 flash, read-only here (the bootloader never writes: it cannot break itself
/// or a slot). Reads are plain memory reads of the slots' region.
struct Rom;

impl Flash for Rom {
    fn page_bytes(&self) -> u32 {
        1024
    }
    fn pages(&self) -> u32 {
        60
    }
    fn read(&self, addr: u32) -> Result<u16, FlashError> {
        if !addr.is_multiple_of(2) || addr >= self.pages() * self.page_bytes() {
            return Err(FlashError::OutOfRange);
        }
        // SAFETY: an aligned address inside the on-chip flash region (checked above).
        Ok(unsafe { core::ptr::read_volatile((REGION + addr) as *const u16) })
    }
    fn program(&mut self, _: u32, _: u16) -> Result<(), FlashError> {
        Err(FlashError::OutOfRange)
    }
    fn erase(&mut self, _: u32) -> Result<(), FlashError> {
        Err(FlashError::OutOfRange)
    }
}

#[entry]
fn main() -> ! {
    let rom = Rom;
    if let Some(slot) = LAYOUT.boot_slot(&rom, None) {
        if let Some(image) = LAYOUT.image_addr(&rom, slot, 0) {
            // SAFETY: the slot's image was verified (CRC-32 over its whole length): its
            // first words are the application's vector table (stack pointer, reset).
            unsafe { cortex_m::asm::bootload((REGION + image) as *const u32) }
        }
    }
    // No valid slot: wait here for a probe (or, with a CAN receiver linked in, an update).
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}
