//! Owned per-node tables: the simulator builds them at run time (from a plan or by
//! hand) and lends them to the engines as `NodeTables`, as firmware lends its statics.
use rtcan_core::tables::{BusConfig, CalEntry, NodeTables, RxTopic, TxTopic};

/// One node's tables, owned.
#[derive(Clone, Debug)]
pub struct OwnedTables {
    /// Bus parameters.
    pub bus: BusConfig,
    /// Module index.
    pub module: u8,
    /// Transmitted topics.
    pub tx: Vec<TxTopic>,
    /// Received topics, sorted by message ID.
    pub rx: Vec<RxTopic>,
    /// Reserved slots, sorted by slot.
    pub calendar: Vec<CalEntry>,
    /// Master only: reservation masks of the hyperperiod.
    pub master_masks: Vec<u64>,
}

impl OwnedTables {
    /// Borrowed view for `rtcan_core::Engine::new`.
    pub fn view(&self) -> NodeTables<'_> {
        NodeTables {
            bus: self.bus,
            module: self.module,
            tx: &self.tx,
            rx: &self.rx,
            calendar: &self.calendar,
            master_masks: &self.master_masks,
        }
    }

    /// Bytes of reassembly arena this node needs.
    pub fn arena_bytes(&self) -> usize {
        self.rx
            .iter()
            .map(|r| usize::from(r.arena_offset) + usize::from(r.size))
            .max()
            .unwrap_or(0)
    }
}
