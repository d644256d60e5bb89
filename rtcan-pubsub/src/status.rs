//! System status as seen from one module, fed by the engine's `Host::event`:
//! sync state, the master's heartbeat age, other modules' states and fingerprints.
//! Nodes read `safe_state_required()` (motor modules stop their motors on `true`).
use core::cell::RefCell;

use critical_section::Mutex;
use rtcan_core::driver::Event;

use crate::node::NodeState;
use crate::slot_grid::SlotGrid;

/// Safety parameters of a module (generated from robot.toml).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SafetyConfig {
    /// This module's index.
    pub module: u8,
    /// The master's module index.
    pub master: u8,
    /// Cycles without a master heartbeat after which the safe state is required.
    pub max_missed_cycles: u16,
}

/// Why the safe state is required (first matching reason in this order).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SafeReason {
    /// A module announced another robot fingerprint (latched until `reset`).
    FingerprintMismatch { module: u8, fingerprint: u32 },
    /// Not (or no longer) locked on the master's sync.
    NoSync,
    /// The master's heartbeat has not been heard for more than `max_missed_cycles`.
    MasterSilent,
    /// The master announced `Fail` or `Stop`.
    MasterStopped,
    /// `module` is missing and its robot.toml rule (`on_missing`) puts this module in
    /// its safe state (`ModuleTable::safe_required`).
    ModuleMissing { module: u8 },
}

/// robot.toml's supervision as one module applies it (the generated `supervision`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Supervised {
    /// Modules on the bus (indices `0..modules`).
    pub modules: u8,
    /// A module whose heartbeat is older than this many cycles is missing.
    pub missing_after: u16,
    /// The `on_missing` rules.
    pub rules: &'static [crate::supervision::ModuleRule],
}

struct StatusState {
    synced: bool,
    master_heard: bool,
    master_age: u16,
    master_state: u8,
    mismatch: Option<(u8, u32)>,
    heard: u64,
    states: [u8; 64],
    /// Cycles since each module's last heartbeat (saturating; meaningful where `heard`).
    ages: [u16; 64],
    sync_losses: u32,
    /// The slot grid on the local clock while synchronised (synchronous HRT publishers).
    grid: Option<SlotGrid>,
    /// Cycles started since power-on (wrapping): the module-state publications' clock.
    cycles: u32,
}

const POWER_ON: StatusState = StatusState {
    synced: false,
    master_heard: false,
    master_age: 0,
    master_state: 0,
    mismatch: None,
    heard: 0,
    states: [0; 64],
    ages: [0; 64],
    sync_losses: 0,
    grid: None,
    cycles: 0,
};

/// One cycle passed: every heartbeat (the master's included) is a cycle older.
fn age(st: &mut StatusState) {
    st.cycles = st.cycles.wrapping_add(1);
    st.master_age = st.master_age.saturating_add(1);
    for a in st.ages.iter_mut() {
        *a = a.saturating_add(1);
    }
}

/// See `SystemStatus::module_missing`. When every other module is silent at once, the
/// cause is the bus or the sync (slaves that lost the sync stop their cycle and their
/// heartbeats: a master change under bit errors does this for a few cycles), not the
/// modules: the sync rules (`NoSync`, `MasterSilent`) cover it, and no module is
/// declared missing. With no third module heard to compare with, the age alone decides.
fn is_missing(st: &StatusState, me: u8, module: u8, missing_after: u16) -> bool {
    if module == me || module >= 64 {
        return false;
    }
    let heard = |m: u8| st.heard & (1u64 << m) != 0;
    let age = |m: u8| st.ages.get(usize::from(m)).copied().unwrap_or(u16::MAX);
    if !heard(module) {
        return true;
    }
    if age(module) <= missing_after {
        return false;
    }
    let mut others = (0..64u8).filter(|&m| m != me && m != module && heard(m));
    let mut any = false;
    let fresh = others.any(|m| {
        any = true;
        age(m) <= missing_after
    });
    fresh || !any
}

/// The system-status view of one module. `static STATUS: SystemStatus = SystemStatus::new(cfg);`
pub struct SystemStatus {
    config: SafetyConfig,
    /// Backup masters in rank order: after the configured master, the sync master is
    /// the first of these still heard (the arbiter's takeover order, rtcan-core arbiter).
    backups: &'static [u8],
    supervised: Option<Supervised>,
    state: Mutex<RefCell<StatusState>>,
}

impl SystemStatus {
    /// Nothing heard yet: the safe state is required until sync and the master's
    /// heartbeat arrive (on the master itself, until nothing; it is its own sync).
    pub const fn new(config: SafetyConfig) -> Self {
        Self::with_backups(config, &[])
    }

    /// As `new`, with the robot's backup masters in rank order (`[bus] backup_masters`).
    /// The safe-state rule then follows the current sync master: when the configured
    /// master is silent and a backup took over, that backup's heartbeat and state count.
    pub const fn with_backups(config: SafetyConfig, backups: &'static [u8]) -> Self {
        SystemStatus {
            config,
            backups,
            supervised: None,
            state: Mutex::new(RefCell::new(POWER_ON)),
        }
    }

    /// As `with_backups`, applying robot.toml's `on_missing` rules: the safe state is
    /// also required while a module is missing whose rule says all, or says its
    /// dependents and this module is one (`SafeReason::ModuleMissing`). Every module
    /// times every heartbeat itself, so the rule holds whoever the sync master is.
    pub const fn supervised(
        config: SafetyConfig,
        backups: &'static [u8],
        supervised: Supervised,
    ) -> Self {
        SystemStatus {
            config,
            backups,
            supervised: Some(supervised),
            state: Mutex::new(RefCell::new(POWER_ON)),
        }
    }

    /// The rules this status applies, if any.
    pub fn supervision(&self) -> Option<Supervised> {
        self.supervised
    }

    /// Modules missing now under the supervision (bit m = module m): empty without it.
    fn missing(&self, st: &StatusState) -> u64 {
        let Some(sv) = self.supervised else { return 0 };
        (0..sv.modules.min(64))
            .filter(|&m| is_missing(st, self.config.module, m, sv.missing_after))
            .fold(0, |mask, m| mask | (1u64 << m))
    }

    /// Whether `module` is missing as seen from here: never heard since power-on, or its
    /// heartbeat more than `missing_after` cycles old *while another module's is not*
    /// (`is_missing`). Never this module itself.
    pub fn module_missing(&self, module: u8, missing_after: u16) -> bool {
        self.with(|st| is_missing(st, self.config.module, module, missing_after))
    }

    /// The module whose heartbeat the safe-state rule watches now: the configured master
    /// while it is heard, else the best-ranked backup heard within `max_missed_cycles`
    /// (the one that took over the sync), else the configured master.
    fn current_master(&self, st: &StatusState) -> u8 {
        let cfg = self.config;
        // This module itself (a backup) counts while synced: it took over the sync
        // when every better-ranked master went silent (the engine reports `Synced`).
        let fresh = |m: u8| {
            (m == cfg.module && st.synced)
                || m < 64
                    && st.heard & (1u64 << m) != 0
                    && st
                        .ages
                        .get(usize::from(m))
                        .is_some_and(|&a| a <= cfg.max_missed_cycles)
        };
        if fresh(cfg.master) {
            return cfg.master;
        }
        self.backups
            .iter()
            .copied()
            .find(|&b| fresh(b))
            .unwrap_or(cfg.master)
    }

    /// The module currently followed as sync master (see `with_backups`).
    pub fn sync_master(&self) -> u8 {
        self.with(|st| self.current_master(st))
    }

    /// Cycles since `module`'s last heartbeat, `None` if never heard since power-on.
    pub fn module_age(&self, module: u8) -> Option<u16> {
        self.with(|st| {
            if module < 64 && st.heard & (1u64 << module) != 0 {
                st.ages.get(usize::from(module)).copied()
            } else {
                None
            }
        })
    }

    /// Modules heard at least once since power-on (bit m = module m).
    pub fn heard_mask(&self) -> u64 {
        self.with(|st| st.heard)
    }

    fn with<R>(&self, f: impl FnOnce(&mut StatusState) -> R) -> R {
        critical_section::with(|cs| f(&mut self.state.borrow_ref_mut(cs)))
    }

    /// Feeds an engine event.
    pub fn event(&self, event: Event) {
        let master = self.config.master;
        self.with(|st| match event {
            Event::Synced => st.synced = true,
            // Ages the master's heartbeat (same as `on_cycle`).
            Event::CycleStart => age(st),
            Event::SyncLost => {
                st.synced = false;
                st.sync_losses = st.sync_losses.saturating_add(1);
            }
            Event::FingerprintMismatch {
                module,
                fingerprint,
            } => {
                if st.mismatch.is_none() {
                    st.mismatch = Some((module, fingerprint));
                }
            }
            Event::Heartbeat { module, state } => {
                if let Some(s) = st.states.get_mut(usize::from(module)) {
                    *s = state;
                    st.heard |= 1u64 << (module & 63);
                }
                if let Some(a) = st.ages.get_mut(usize::from(module)) {
                    *a = 0;
                }
                if module == master {
                    st.master_heard = true;
                    st.master_age = 0;
                    st.master_state = state;
                }
            }
        });
    }

    /// Ages the master's heartbeat by one cycle. The engine's `Event::CycleStart` does
    /// this through `event`; call it directly only when driving the status by hand.
    pub fn on_cycle(&self) {
        self.with(age);
    }

    /// Why the safe state is required now, if it is.
    pub fn safe_reason(&self) -> Option<SafeReason> {
        let cfg = self.config;
        self.with(|st| {
            if let Some((module, fingerprint)) = st.mismatch {
                return Some(SafeReason::FingerprintMismatch {
                    module,
                    fingerprint,
                });
            }
            // The sync master does not apply the rules to itself: its nodes' stop would
            // reach every slave as `MasterStopped`, which outlives the missing module
            // (the gateway's app latches it; found by the fault campaign).
            if cfg.module == cfg.master {
                return None;
            }
            let master = self.current_master(st);
            if cfg.module == master {
                return None;
            }
            let missing = self.missing(st);
            let rule = self.supervised.and_then(|sv| {
                sv.rules
                    .iter()
                    .find(|r| {
                        r.module < 64
                            && missing & (1u64 << r.module) != 0
                            && crate::supervision::applies(r, cfg.module)
                    })
                    .map(|r| SafeReason::ModuleMissing { module: r.module })
            });
            if !st.synced {
                return Some(SafeReason::NoSync);
            }
            let (heard, age, state) = if master == cfg.master {
                (st.master_heard, st.master_age, st.master_state)
            } else {
                let i = usize::from(master);
                (
                    true,
                    st.ages.get(i).copied().unwrap_or(u16::MAX),
                    st.states.get(i).copied().unwrap_or(0),
                )
            };
            if !heard || age > cfg.max_missed_cycles {
                return Some(SafeReason::MasterSilent);
            }
            match NodeState::from_u8(state) {
                Some(NodeState::Fail) | Some(NodeState::Stop) => Some(SafeReason::MasterStopped),
                _ => rule,
            }
        })
    }

    /// Nodes must enter their safe state (motors stopped).
    pub fn safe_state_required(&self) -> bool {
        self.safe_reason().is_some()
    }

    /// Last state byte heard from `module`, `None` if never heard.
    pub fn module_state(&self, module: u8) -> Option<u8> {
        self.with(|st| {
            if module < 64 && st.heard & (1u64 << module) != 0 {
                st.states.get(usize::from(module)).copied()
            } else {
                None
            }
        })
    }

    /// Cycles started since power-on (`Event::CycleStart`, wrapping).
    pub fn cycles(&self) -> u32 {
        self.with(|st| st.cycles)
    }

    /// Times sync was lost.
    pub fn sync_losses(&self) -> u32 {
        self.with(|st| st.sync_losses)
    }

    /// Forgets everything heard (as after power-on): not synced, master not heard, no
    /// module states, no mismatch, no sync losses. For restarting a simulated module.
    pub fn clear(&self) {
        self.with(|st| *st = POWER_ON);
    }

    /// The slot grid on the local clock, written by the protocol side while the engine
    /// is synchronised (`None`: not synchronised, or not written yet).
    pub fn set_grid(&self, grid: Option<SlotGrid>) {
        self.with(|st| st.grid = grid);
    }

    /// The slot grid last written (see [`SlotGrid`]): when HRT publishers are due.
    pub fn grid(&self) -> Option<SlotGrid> {
        self.with(|st| st.grid)
    }

    /// Clears the latched fingerprint mismatch (after the operator fixed the robot).
    pub fn reset(&self) {
        self.with(|st| st.mismatch = None);
    }
}
