//! On-chip flash as the parameter store and the bootloader see it, with the STM32F103's
//! rules (RM0008 §3.3): pages erase to 0xFFFF half-words, programming is by half-word
//! and only onto an erased half-word (anything else sets PGERR and writes nothing).
//! `F103Flash` is a model with exactly these rules, for host tests and the simulator.

/// A flash error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FlashError {
    /// Address outside the region, or not half-word aligned.
    OutOfRange,
    /// Programming a half-word that is not erased (F103 PGERR).
    NotErased,
    /// The operation was cut short (power cut injected by the model).
    PowerCut,
}

/// A region of flash in pages of `page_bytes()`; addresses are region offsets.
pub trait Flash {
    /// Page size in bytes (1 KiB on the F103 up to 128 KiB parts).
    fn page_bytes(&self) -> u32;
    /// Pages in the region.
    fn pages(&self) -> u32;
    /// Reads the half-word at `addr`.
    fn read(&self, addr: u32) -> Result<u16, FlashError>;
    /// Programs the half-word at `addr` (must be erased).
    fn program(&mut self, addr: u32, value: u16) -> Result<(), FlashError>;
    /// Erases page `page` to 0xFFFF.
    fn erase(&mut self, page: u32) -> Result<(), FlashError>;
}

/// F103 flash page size.
pub const F103_PAGE_BYTES: u32 = 1024;

/// A model of `PAGES` pages of F103 flash, with a power cut that can be armed to hit
/// after a number of operations (program or erase); a cut erase leaves the page
/// partially erased (its first half), a cut program writes nothing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct F103Flash<const PAGES: usize> {
    words: [[u16; 512]; PAGES],
    /// Erases per page (wear).
    pub erases: [u32; PAGES],
    /// Operations left before the power cut (`None`: no cut armed).
    pub cut_after: Option<u32>,
    /// Programs and erases performed.
    pub ops: u32,
}

impl<const PAGES: usize> Default for F103Flash<PAGES> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const PAGES: usize> F103Flash<PAGES> {
    /// Every page erased.
    pub const fn new() -> Self {
        F103Flash {
            words: [[0xFFFF; 512]; PAGES],
            erases: [0; PAGES],
            cut_after: None,
            ops: 0,
        }
    }

    fn slot(&self, addr: u32) -> Result<(usize, usize), FlashError> {
        if !addr.is_multiple_of(2) {
            return Err(FlashError::OutOfRange);
        }
        let page = usize::try_from(addr / F103_PAGE_BYTES).map_err(|_| FlashError::OutOfRange)?;
        let word =
            usize::try_from((addr % F103_PAGE_BYTES) / 2).map_err(|_| FlashError::OutOfRange)?;
        if page >= PAGES {
            return Err(FlashError::OutOfRange);
        }
        Ok((page, word))
    }

    /// Counts an operation; `Err(PowerCut)` when the armed cut hits (then every later
    /// operation fails too, until `cut_after` is cleared: the power is off).
    fn tick(&mut self) -> Result<(), FlashError> {
        match self.cut_after {
            Some(0) => Err(FlashError::PowerCut),
            Some(n) => {
                self.cut_after = Some(n - 1);
                self.ops += 1;
                Ok(())
            }
            None => {
                self.ops += 1;
                Ok(())
            }
        }
    }

    /// Flips bits of the half-word at `addr` (a corruption no program could make).
    pub fn corrupt(&mut self, addr: u32, xor: u16) {
        if let Ok((p, w)) = self.slot(addr) {
            if let Some(v) = self.words.get_mut(p).and_then(|pg| pg.get_mut(w)) {
                *v ^= xor;
            }
        }
    }
}

impl<const PAGES: usize> Flash for F103Flash<PAGES> {
    fn page_bytes(&self) -> u32 {
        F103_PAGE_BYTES
    }
    fn pages(&self) -> u32 {
        u32::try_from(PAGES).unwrap_or(u32::MAX)
    }
    fn read(&self, addr: u32) -> Result<u16, FlashError> {
        let (p, w) = self.slot(addr)?;
        self.words
            .get(p)
            .and_then(|pg| pg.get(w))
            .copied()
            .ok_or(FlashError::OutOfRange)
    }
    fn program(&mut self, addr: u32, value: u16) -> Result<(), FlashError> {
        let (p, w) = self.slot(addr)?;
        let cell = self
            .words
            .get(p)
            .and_then(|pg| pg.get(w))
            .copied()
            .ok_or(FlashError::OutOfRange)?;
        if cell != 0xFFFF {
            return Err(FlashError::NotErased);
        }
        self.tick()?;
        if let Some(c) = self.words.get_mut(p).and_then(|pg| pg.get_mut(w)) {
            *c = value;
        }
        Ok(())
    }
    fn erase(&mut self, page: u32) -> Result<(), FlashError> {
        let p = usize::try_from(page).map_err(|_| FlashError::OutOfRange)?;
        if p >= PAGES {
            return Err(FlashError::OutOfRange);
        }
        let cut = self.tick().is_err();
        if let Some(pg) = self.words.get_mut(p) {
            let n = if cut { pg.len() / 2 } else { pg.len() };
            for c in pg.iter_mut().take(n) {
                *c = 0xFFFF;
            }
        }
        if cut {
            return Err(FlashError::PowerCut);
        }
        if let Some(e) = self.erases.get_mut(p) {
            *e += 1;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f103_rules() {
        let mut f = F103Flash::<2>::new();
        assert_eq!(f.read(0), Ok(0xFFFF));
        f.program(2, 0x1234).unwrap();
        assert_eq!(f.read(2), Ok(0x1234));
        // Only onto erased: even writing the same value again is refused.
        assert_eq!(f.program(2, 0x1234), Err(FlashError::NotErased));
        assert_eq!(f.program(2, 0x0000), Err(FlashError::NotErased));
        assert_eq!(f.program(3, 0), Err(FlashError::OutOfRange));
        assert_eq!(f.program(2048, 0), Err(FlashError::OutOfRange));
        assert_eq!(f.read(2048), Err(FlashError::OutOfRange));
        f.erase(0).unwrap();
        assert_eq!(f.read(2), Ok(0xFFFF));
        assert_eq!(f.erases, [1, 0]);
        assert_eq!(f.erase(2), Err(FlashError::OutOfRange));
    }

    #[test]
    fn power_cut_stops_everything_after_it() {
        let mut f = F103Flash::<1>::new();
        f.program(0, 1).unwrap();
        f.cut_after = Some(1);
        f.program(2, 2).unwrap();
        assert_eq!(f.program(4, 3), Err(FlashError::PowerCut));
        assert_eq!(f.read(4), Ok(0xFFFF));
        // A cut erase leaves the page half erased.
        let mut f = F103Flash::<1>::new();
        f.program(0, 1).unwrap();
        f.program(1000, 7).unwrap();
        f.cut_after = Some(0);
        assert_eq!(f.erase(0), Err(FlashError::PowerCut));
        assert_eq!(f.read(0), Ok(0xFFFF));
        assert_eq!(f.read(1000), Ok(7));
        assert_eq!(f.erases, [0]);
    }
}
