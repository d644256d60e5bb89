//! When each SRT message was published, read from the publishing image's RAM without a
//! memory hook (a hook sends every access of that MCU through Unicorn's slow path).
//!
//! `rtcan_pubsub::Topic` stamps every block it publishes (`PoolState::stamps[block]` =
//! the publisher's `now`, the slot timer's clock: TIM2 ticks since the timer was enabled,
//! 125 ns each). The bus reads each SRT topic's stamp array in the publisher's RAM at
//! every start of frame (`Bus::publications`): a changed entry is a new publication. No
//! publication is missed: a block is stamped again only after its message left (its
//! frames start, and with them a read) or was dropped at its deadline (then nothing is
//! measured for it anyway). The stamp becomes bus time through the emulated TIM2's start
//! (`Tim2::started_ps`): exact to one 125 ns tick.
//!
//! The array's address comes from the image's DWARF (`engine_ram::find_struct`: the
//! topic's static, named as rtcan-codegen names it, e.g. `TELEOP`), its length from the
//! model (`rtcan_model::plan::pool_blocks`, the formula the generated code is sized
//! with).
use rtcan_core::{Class, Nanos};
use rtcan_model::Plan;

use crate::mcu::Mcu;

/// One SRT topic's stamps in its publisher's RAM and the publications seen.
#[derive(Clone, Debug)]
pub struct Watched {
    /// Topic name and its publishing module (index in the plan).
    pub topic: String,
    pub node: usize,
    pub msg_id: rtcan_core::MsgId,
    addr: u32,
    blocks: usize,
    last: Vec<u64>,
    /// Publication instants (bus time, ns) in the order they were seen.
    pub published: Vec<Nanos>,
}

/// The SRT topics whose stamps were located.
#[derive(Clone, Debug, Default)]
pub struct Publications {
    pub topics: Vec<Watched>,
}

impl Publications {
    /// Every SRT topic on the bus, located in the image of its publisher (`images` in
    /// the plan's module order). Topics whose static is not in the image's DWARF (an
    /// image without debug info, or a topic the image never publishes) are left out:
    /// `missing` names them.
    pub fn locate(plan: &Plan, images: &[Vec<u8>]) -> (Publications, Vec<String>) {
        let mut out = Publications::default();
        let mut missing = Vec::new();
        for t in plan
            .topics
            .iter()
            .filter(|t| t.class == Class::Srt && t.on_bus)
        {
            let Some(elf) = images.get(t.module) else {
                missing.push(t.name.clone());
                continue;
            };
            let stat = t.name.to_ascii_uppercase();
            match crate::engine_ram::find_struct(elf, &stat, "PoolState", "stamps") {
                Ok(fields) => {
                    let Some(&(_, addr)) = fields.iter().find(|(n, _)| n == "stamps") else {
                        missing.push(t.name.clone());
                        continue;
                    };
                    let blocks = rtcan_model::plan::pool_blocks(t, t.module);
                    out.topics.push(Watched {
                        topic: t.name.clone(),
                        node: t.module,
                        msg_id: t.msg_id,
                        addr,
                        blocks,
                        last: vec![0; blocks],
                        published: Vec::new(),
                    });
                }
                Err(_) => missing.push(t.name.clone()),
            }
        }
        (out, missing)
    }

    /// Reads every watched stamp array; new stamps become publications (bus time).
    pub fn poll(&mut self, mcus: &[Mcu]) {
        for w in &mut self.topics {
            let Some(m) = mcus.get(w.node) else { continue };
            let Some(origin_ps) = m.st.tim.first().and_then(|t| t.started_ps) else {
                continue;
            };
            let bytes = m.read_mem(w.addr, 8 * w.blocks);
            let mut new: Vec<Nanos> = Vec::new();
            for (k, last) in w.last.iter_mut().enumerate() {
                let Some(b) = bytes.get(8 * k..8 * k + 8) else {
                    continue;
                };
                let mut a = [0u8; 8];
                a.copy_from_slice(b);
                let v = u64::from_le_bytes(a);
                // 0: never stamped (SRAM is cleared at reset).
                if v != *last && v != 0 {
                    new.push(origin_ps / 1_000 + v);
                }
                *last = v;
            }
            new.sort_unstable();
            w.published.extend(new);
        }
    }

    /// The publications of `topic` (empty if it is not watched).
    pub fn of(&self, topic: &str) -> Option<&[Nanos]> {
        self.topics
            .iter()
            .find(|w| w.topic == topic)
            .map(|w| &w.published[..])
    }
}
