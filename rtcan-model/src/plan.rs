//! The plan: everything the code generator, the simulator and `rtcan check` need,
//! derived once from the model (admission, message IDs, filters, calendars, load,
//! fingerprint).
use crate::diag::{Code, Diagnostic};
use crate::filters::{self, Bank, WireTopic};
use crate::lock::Lock;
use crate::model::{Board, FilterMode, Model, MsgType, Node};
use crate::schedule::{self, HrtTopic};
use crate::{ids, units};
use rtcan_core::admission::HrtRequest;
use rtcan_core::fragment::{fragment_count, wire_len};
use rtcan_core::id::{LAXITY_HRT, LAXITY_NRT};
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::{BusConfig, CalEntry, RxTopic, TxTopic};
use rtcan_core::{Class, MsgId};

/// Bus parameters after discretisation and admission.
#[derive(Clone, Debug, PartialEq)]
pub struct BusPlan {
    /// Bit rate, bit/s.
    pub bitrate: u32,
    /// Slots per cycle (slot 0 = sync).
    pub slots_per_cycle: u8,
    /// Slot length, ns.
    pub slot_ns: u64,
    /// Cycle length actually run (`slot_ns * slots_per_cycle`), ns.
    pub cycle_ns: u64,
    /// Cycle length as written in robot.toml, ns.
    pub requested_cycle_ns: u64,
    /// Hyperperiod of the HRT calendar in slots.
    pub hyperperiod_slots: u64,
    /// Hyperperiod in cycles.
    pub hyperperiod_cycles: u32,
    /// Where the master's 15-bit cycle counter wraps (a multiple of the hyperperiod).
    pub cycle_counter_wrap: u32,
    /// SRT laxity encoding.
    pub laxity: LaxityEncoding,
    /// Guard, ns.
    pub guard_ns: u64,
    /// Worst-case 8-byte frame incl. intermission, ns.
    pub worst_frame_ns: u64,
    /// Master module index.
    pub master: usize,
    /// Backup masters in order.
    pub backup_masters: Vec<usize>,
}

impl BusPlan {
    /// The constant every module's tables carry.
    pub fn config(&self, fingerprint: u32) -> BusConfig {
        BusConfig {
            bitrate: self.bitrate,
            slots_per_cycle: self.slots_per_cycle,
            slot_ns: self.slot_ns,
            hyperperiod_cycles: self.hyperperiod_cycles,
            cycle_counter_wrap: self.cycle_counter_wrap,
            laxity: self.laxity,
            guard_ns: self.guard_ns,
            fingerprint,
        }
    }
}

/// A subscription, resolved.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SubscriberPlan {
    /// Node index.
    pub node: usize,
    /// Module of the node.
    pub module: usize,
    /// Queue length.
    pub queue: u16,
}

/// A topic, planned.
#[derive(Clone, Debug, PartialEq)]
pub struct TopicPlan {
    /// Name.
    pub name: String,
    /// Message type index (`Plan::types`).
    pub ty: usize,
    /// Class.
    pub class: Class,
    /// Message ID.
    pub msg_id: MsgId,
    /// Payload bytes.
    pub size: u16,
    /// Frames per message.
    pub fragments: u8,
    /// Publishing node.
    pub publisher: usize,
    /// Publishing module.
    pub module: usize,
    /// Subscribers in file order.
    pub subscribers: Vec<SubscriberPlan>,
    /// Sent on the bus (some subscriber is on another module).
    pub on_bus: bool,
    /// HRT: period in slots.
    pub period_slots: Option<u32>,
    /// HRT on the bus: first slot, counted from slot 0 of cycle 0.
    pub phase_slot: Option<u32>,
    /// HRT: requested period, ns.
    pub requested_period_ns: Option<f64>,
    /// SRT: relative deadline, ns.
    pub deadline_ns: Option<u64>,
    /// SRT/NRT: declared average rate, Hz.
    pub rate_hz: Option<f64>,
    /// HRT: how long before each of its slots the publisher runs, ns (`lead`).
    pub lead_ns: Option<u64>,
}

impl TopicPlan {
    /// HRT: actual period in ns.
    pub fn actual_period_ns(&self, bus: &BusPlan) -> Option<u64> {
        self.period_slots.map(|p| u64::from(p) * bus.slot_ns)
    }
}

/// A module, planned.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModulePlan {
    /// Name.
    pub name: String,
    /// Index (heartbeat ID = HEARTBEAT_BASE + index).
    pub index: u8,
    /// Board.
    pub board: Board,
    /// Sends the sync frame.
    pub is_master: bool,
    /// Filter mode.
    pub filter_mode: FilterMode,
    /// CAN filter banks in bank order.
    pub banks: Vec<Bank>,
    /// Nodes on this module.
    pub nodes: Vec<usize>,
    /// Topics this module sends on the bus, sorted by message ID (index = TxIndex).
    pub tx: Vec<usize>,
    /// Topics this module receives from the bus, sorted by message ID (index = RxIndex).
    pub rx: Vec<usize>,
    /// This module's HRT slots over the hyperperiod, sorted by slot.
    pub calendar: Vec<CalEntry>,
    /// Bytes of the RX reassembly arena.
    pub rx_arena_bytes: usize,
}

/// Bus load in frames per cycle against the non-sync slots.
#[derive(Clone, Debug, PartialEq)]
pub struct Load {
    /// Frames per cycle the bus can carry outside the sync slot (`slots - 1`).
    pub capacity: f64,
    /// HRT reserved slots per cycle (average over the hyperperiod).
    pub hrt: f64,
    /// SRT frames per cycle from declared rates.
    pub srt: f64,
    /// NRT frames per cycle from declared rates.
    pub nrt: f64,
    /// SRT/NRT topics on the bus without a declared rate (not counted).
    pub uncounted: Vec<usize>,
}

impl Load {
    /// Free-window capacity left for SRT/NRT, frames per cycle.
    pub fn free(&self) -> f64 {
        self.capacity - self.hrt
    }
    /// Payload bit rate of `frames` per cycle (8 bytes per frame).
    pub fn kbps(frames: f64, bus: &BusPlan) -> f64 {
        frames * 64.0 / (bus.cycle_ns as f64 / 1e9) / 1e3
    }
}

/// The complete plan of a robot.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// File name as given.
    pub file: String,
    /// Bus.
    pub bus: BusPlan,
    /// Message types.
    pub types: Vec<MsgType>,
    /// Modules.
    pub modules: Vec<ModulePlan>,
    /// Nodes.
    pub nodes: Vec<Node>,
    /// Topics in file order.
    pub topics: Vec<TopicPlan>,
    /// Master: reservation mask of every cycle of the hyperperiod.
    pub master_masks: Vec<u64>,
    /// Admission search steps.
    pub admission_steps: u64,
    /// Bus load.
    pub load: Load,
    /// Robot fingerprint carried in heartbeats: FNV-1a 32 of the canonical plan, or with
    /// a lock of the lock's lineage and the bus contract (fingerprint.rs).
    pub fingerprint: u32,
    /// Robot name, writable / link / ROS 2 topics (not part of the fingerprint: they do
    /// not change the bus).
    pub bridge: crate::bridge_keys::BridgeDecl,
    /// Lineage of the robot.lock the plan was made with.
    pub lineage: Option<u32>,
    /// What the lock held that this plan had to move, with reasons.
    pub moves: Vec<crate::lock::Move>,
    /// IDs the lock retired or this plan retires, with the topic each carried: only an
    /// image built from an older robot.toml still sends them, and the host tools name
    /// that topic (`rtcan monitor` "STALE IMAGES", `rtcan decode`).
    pub retired: Vec<crate::lock::Retired>,
    /// End-to-end chains with their bounds (`[chains]`; filled by `analyze`).
    pub chains: Vec<crate::chains::ChainBound>,
    /// Request/reply services (`[services]`); their topics are in `topics`.
    pub services: Vec<crate::services::Service>,
    /// `[params]`, from the model.
    pub params: Vec<crate::params::ParamDecl>,
    /// A supervised robot's module-state topics (`module_state`); they are in `topics`.
    pub module_state: Option<crate::module_state::StateTopics>,
    /// `on_missing` rules and the heartbeat period (filled by `analyze`).
    pub supervision: crate::supervision::Supervision,
}

/// Per-module tables, ready to be emitted as `rtcan_core::tables` constants.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModuleTables {
    /// Bus configuration (with the fingerprint).
    pub bus: BusConfig,
    /// Module index.
    pub module: u8,
    /// Transmitted topics.
    pub tx: Vec<TxTopic>,
    /// Received topics, sorted by msg_id.
    pub rx: Vec<RxTopic>,
    /// HRT calendar, sorted by slot.
    pub calendar: Vec<CalEntry>,
    /// Master masks (empty on slaves).
    pub master_masks: Vec<u64>,
}

impl ModuleTables {
    /// Borrowed view for `rtcan_core::Engine::new` (the simulator owns its tables at run
    /// time; firmware has them as generated constants).
    pub fn view(&self) -> rtcan_core::tables::NodeTables<'_> {
        rtcan_core::tables::NodeTables {
            bus: self.bus,
            module: self.module,
            tx: &self.tx,
            rx: &self.rx,
            calendar: &self.calendar,
            master_masks: &self.master_masks,
        }
    }

    /// Bytes of reassembly arena the receive topics need (`wire_len`: the payload).
    pub fn arena_bytes(&self) -> usize {
        self.rx
            .iter()
            .map(|r| usize::from(r.arena_offset) + wire_len(usize::from(r.size)))
            .max()
            .unwrap_or(0)
    }
}

impl Plan {
    /// A topic by name.
    pub fn topic(&self, name: &str) -> Option<&TopicPlan> {
        self.topics.iter().find(|t| t.name == name)
    }
    /// A service by name.
    pub fn service(&self, name: &str) -> Option<&crate::services::Service> {
        self.services.iter().find(|s| s.name == name)
    }
    /// A module by name.
    pub fn module(&self, name: &str) -> Option<&ModulePlan> {
        self.modules.iter().find(|m| m.name == name)
    }
    /// Slots reserved per hyperperiod (sync slots not counted).
    pub fn reserved_slots(&self) -> u64 {
        self.modules.iter().map(|m| m.calendar.len() as u64).sum()
    }
    /// The tables of module `index`.
    pub fn tables(&self, index: usize) -> Option<ModuleTables> {
        let m = self.modules.get(index)?;
        let topic = |t: &usize| self.topics.get(*t);
        let tx =
            m.tx.iter()
                .filter_map(topic)
                .map(|t| TxTopic {
                    msg_id: t.msg_id,
                    class: t.class,
                    size: t.size,
                    deadline_ns: t.deadline_ns.unwrap_or(0),
                })
                .collect();
        let mut offset = 0u16;
        let mut rx = Vec::new();
        for t in m.rx.iter().filter_map(topic) {
            rx.push(RxTopic {
                msg_id: t.msg_id,
                size: t.size,
                arena_offset: offset,
            });
            offset = offset.saturating_add(wire_len(usize::from(t.size)) as u16);
        }
        Some(ModuleTables {
            bus: self.bus.config(self.fingerprint),
            module: m.index,
            tx,
            rx,
            calendar: m.calendar.clone(),
            master_masks: if m.is_master {
                self.master_masks.clone()
            } else {
                Vec::new()
            },
        })
    }
}

/// Largest multiple of `hyper` that fits the 15-bit cycle counter (at least `hyper`).
pub fn counter_wrap(hyper_cycles: u32) -> u32 {
    let h = hyper_cycles.max(1);
    ((1u32 << 15) / h).max(1) * h
}

/// Most message blocks of one topic on one module: `rtcan_pubsub::Topic` keeps its free
/// blocks in one `u32` mask.
pub const MAX_POOL_BLOCKS: usize = 32;

/// Message blocks topic `t` needs on module `mi` (the formula of
/// `rtcan_pubsub::pool_blocks` with one loan, as rtcan-codegen sizes the pool):
/// local subscribers × (queue + 1) + what the engine side holds + 1 loan. The queue is
/// the topic's longest subscriber queue (`rtcan_pubsub::Topic` has one queue length).
pub fn pool_blocks(t: &TopicPlan, mi: usize) -> usize {
    let subs = t.subscribers.iter().filter(|s| s.module == mi).count();
    let queue = usize::from(
        t.subscribers
            .iter()
            .map(|s| s.queue)
            .max()
            .unwrap_or(1)
            .max(1),
    );
    let remote = match (t.module == mi && t.on_bus, t.class) {
        (false, _) => 0,
        (true, Class::Hrt) => 2,
        (true, _) => queue + 1,
    };
    subs * queue + subs + remote + 1
}

/// `pool-too-large` for every topic whose pool on some module exceeds
/// [`MAX_POOL_BLOCKS`]: found here, so `rtcan check` refuses what would not build.
fn pool_limits(model: &Model, topics: &[TopicPlan], diags: &mut Vec<Diagnostic>) {
    for (i, t) in topics.iter().enumerate() {
        let mut modules: Vec<usize> = t.subscribers.iter().map(|s| s.module).collect();
        modules.push(t.module);
        modules.sort_unstable();
        modules.dedup();
        for mi in modules {
            let n = pool_blocks(t, mi);
            if n <= MAX_POOL_BLOCKS {
                continue;
            }
            let subs = t.subscribers.iter().filter(|s| s.module == mi).count();
            let queue = t
                .subscribers
                .iter()
                .map(|s| s.queue)
                .max()
                .unwrap_or(1)
                .max(1);
            diags.push(
                Diagnostic::new(
                    Code::PoolTooLarge,
                    model.topics.get(i).and_then(|x| x.spans.name.clone()),
                    format!(
                        "topic `{}` needs {n} message blocks on module `{}`; a topic has at most {MAX_POOL_BLOCKS}",
                        t.name,
                        model.modules.get(mi).map_or("?", |m| m.name.as_str())
                    ),
                )
                .help("shorten its subscriber queues")
                .note(format!(
                    "{subs} local subscriber(s) with queues of {queue} (each holds its queue plus the message it reads), {} for the bus, 1 loan",
                    n - subs * (usize::from(queue) + 1) - 1
                )),
            );
        }
    }
}

/// Plans a validated model. Errors (schedule, filters, table sizes) are pushed to `diags`;
/// a plan is returned only when there are none.
pub fn build(model: &Model, file: &str, diags: &mut Vec<Diagnostic>) -> Option<Plan> {
    build_locked(model, file, None, diags)
}

/// [`build`] keeping the allocation of `lock` (robot.lock) where possible.
pub fn build_locked(
    model: &Model,
    file: &str,
    lock: Option<&Lock>,
    diags: &mut Vec<Diagnostic>,
) -> Option<Plan> {
    let start = diags.len();
    let bus = &model.bus;
    let mut moves = Vec::new();
    let assigned = match lock {
        Some(l) => crate::lock::assign_ids(model, l, &mut moves),
        None => ids::assign(model),
    };
    // IDs from 0xFF00 are the host channels' (parameters, update; docs/PROTOCOL.md §2.3).
    let below_services = |ids: &Vec<u16>| {
        ids.iter()
            .all(|&i| !rtcan_core::service::is_service(MsgId(i)))
    };
    let Some(msg_ids) = assigned.filter(below_services) else {
        diags.push(Diagnostic::new(
            Code::TableTooLarge,
            None,
            "too many topics for the message IDs below the host channels (0x0140..0xFF00)",
        ));
        return None;
    };

    let mut topics: Vec<TopicPlan> = Vec::new();
    for (i, t) in model.topics.iter().enumerate() {
        let size = model.topic_size(t);
        topics.push(TopicPlan {
            name: t.name.clone(),
            ty: t.ty,
            class: t.class,
            msg_id: MsgId(msg_ids.get(i).copied().unwrap_or(0)),
            size: size as u16,
            fragments: fragment_count(size),
            publisher: t.publisher,
            module: model.node_module(t.publisher),
            subscribers: t
                .subscribers
                .iter()
                .map(|s| SubscriberPlan {
                    node: s.node,
                    module: model.node_module(s.node),
                    queue: s.queue,
                })
                .collect(),
            on_bus: model.on_bus(t),
            period_slots: t.period_slots,
            phase_slot: None,
            requested_period_ns: t.requested_period_ns,
            deadline_ns: t.deadline_ns,
            rate_hz: t.rate_hz,
            lead_ns: t.lead_ns,
        });
    }

    pool_limits(model, &topics, diags);

    // HRT admission over the topics on the bus, in message-ID order so that the phases
    // do not depend on the order of sections in the file.
    let mut hrt: Vec<HrtTopic> = topics
        .iter()
        .enumerate()
        .filter(|(_, t)| t.on_bus && t.class == Class::Hrt)
        .filter_map(|(i, t)| {
            Some(HrtTopic {
                topic: i,
                request: HrtRequest {
                    period_slots: t.period_slots?,
                    fragments: t.fragments,
                },
            })
        })
        .collect();
    hrt.sort_by_key(|h| topics.get(h.topic).map(|t| t.msg_id));
    let names: Vec<&str> = topics.iter().map(|t| t.name.as_str()).collect();
    let placed = lock.and_then(|l| crate::lock::place(model, &hrt, &names, &msg_ids, l));
    let admitted = match placed.map_or_else(|| schedule::admit(model, &hrt), Ok) {
        Ok(a) => {
            for (h, p) in hrt.iter().zip(&a.placements) {
                if let Some(t) = topics.get_mut(h.topic) {
                    t.phase_slot = Some(p.phase_slot);
                }
            }
            Some(a)
        }
        Err(d) => {
            diags.push(d);
            None
        }
    };
    if let Some(l) = lock {
        phase_moves(l, &topics, &mut moves);
    }
    let slots = u64::from(bus.slots);
    let hyper = admitted
        .as_ref()
        .map_or(slots, |a| a.stats.hyperperiod_slots.max(slots));
    let hyper_cycles = u32::try_from(hyper / slots).unwrap_or(u32::MAX);

    // Modules: filters, tx/rx, calendars.
    let wire: Vec<WireTopic> = topics
        .iter()
        .enumerate()
        .filter(|(_, t)| t.on_bus)
        .map(|(i, t)| WireTopic {
            topic: i,
            msg_id: t.msg_id.0,
            fixed_id: match (t.class, t.fragments) {
                (Class::Hrt, 1) => Some(filters::fixed_id(LAXITY_HRT, t.msg_id.0)),
                (Class::Nrt, 1) => Some(filters::fixed_id(LAXITY_NRT, t.msg_id.0)),
                _ => None,
            },
        })
        .collect();
    let mut modules = Vec::new();
    for (mi, m) in model.modules.iter().enumerate() {
        let mut tx: Vec<usize> = topics
            .iter()
            .enumerate()
            .filter(|(_, t)| t.on_bus && t.module == mi)
            .map(|(i, _)| i)
            .collect();
        tx.sort_by_key(|i| topics.get(*i).map(|t| t.msg_id));
        let mut rx: Vec<usize> = topics
            .iter()
            .enumerate()
            .filter(|(_, t)| {
                t.on_bus && t.module != mi && t.subscribers.iter().any(|s| s.module == mi)
            })
            .map(|(i, _)| i)
            .collect();
        rx.sort_by_key(|i| topics.get(*i).map(|t| t.msg_id));
        let rx_set: std::collections::HashSet<usize> = rx.iter().copied().collect();
        let wanted: Vec<WireTopic> = wire
            .iter()
            .filter(|w| rx_set.contains(&w.topic))
            .copied()
            .collect();
        let locked_banks = lock.and_then(|l| l.banks.get(&m.name));
        let name_of = |i: usize| topics.get(i).map_or_else(String::new, |t| t.name.clone());
        let banks = match m.filters {
            FilterMode::Exact => {
                match locked_banks.map(|b| crate::lock::reuse_banks(b, &wanted, &wire, &name_of)) {
                    Some(Ok(b)) => b,
                    Some(Err(reason)) => {
                        let b = filters::pack(&wanted, &wire);
                        moves.push(crate::lock::Move {
                            subject: m.name.clone(),
                            what: "filters",
                            from: format!("{} banks", locked_banks.map_or(0, Vec::len)),
                            to: format!("{} banks", b.len()),
                            reason,
                        });
                        b
                    }
                    None => filters::pack(&wanted, &wire),
                }
            }
            FilterMode::AcceptAll => vec![Bank {
                filter: filters::FilterBank::Mask { id: 0, mask: 0 },
                purpose: filters::BankPurpose::AcceptAll,
            }],
        };
        if banks.len() > usize::from(m.board.filter_banks()) {
            let groups = banks.len() - 2;
            diags.push(
                Diagnostic::new(
                    Code::FilterBanksExhausted,
                    m.span.clone(),
                    format!(
                        "module `{}` needs {} CAN filter banks (sync, heartbeats and {groups} for its {} subscribed topics); board {} has {}",
                        m.name,
                        banks.len(),
                        rx.len(),
                        m.board.name(),
                        m.board.filter_banks()
                    ),
                )
                .help(format!(
                    "set `filters = \"accept-all\"` in `[modules.{}]` to accept every frame and drop unwanted ones in software",
                    m.name
                ))
                .note("topics with the same set of receiving modules share one filter: subscribing whole groups needs fewer banks"),
            );
        }
        if tx.len() > 256 {
            diags.push(Diagnostic::new(
                Code::TableTooLarge,
                m.span.clone(),
                format!(
                    "module `{}` sends {} topics on the bus; at most 256",
                    m.name,
                    tx.len()
                ),
            ));
        }
        let rx_arena_bytes: usize = rx
            .iter()
            .filter_map(|i| topics.get(*i))
            .map(|t| wire_len(usize::from(t.size)))
            .sum();
        if rx_arena_bytes > usize::from(u16::MAX) {
            diags.push(Diagnostic::new(
                Code::TableTooLarge,
                m.span.clone(),
                format!(
                    "module `{}` needs {rx_arena_bytes} bytes of receive buffers; at most 65535",
                    m.name
                ),
            ));
        }
        let mut calendar = Vec::new();
        for (k, ti) in tx.iter().enumerate() {
            let Some(t) = topics.get(*ti) else { continue };
            let (Some(p), Some(phase)) = (t.period_slots, t.phase_slot) else {
                continue;
            };
            let mut first = u64::from(phase);
            while first < hyper {
                for j in 0..u64::from(t.fragments) {
                    calendar.push(CalEntry {
                        slot: u32::try_from((first + j) % hyper).unwrap_or(0),
                        tx: k as u8,
                        fragment: t.fragments - 1 - j as u8,
                    });
                }
                first += u64::from(p);
            }
        }
        calendar.sort_by_key(|c| c.slot);
        if let Some(old) = lock.and_then(|l| l.modules.get(&m.name)) {
            if usize::from(*old) != mi {
                moves.push(crate::lock::Move {
                    subject: m.name.clone(),
                    what: "module-index",
                    from: old.to_string(),
                    to: mi.to_string(),
                    reason: "modules are numbered in file order (heartbeat ID = 0x100 + index): add new modules after the existing ones".to_string(),
                });
            }
        }
        modules.push(ModulePlan {
            name: m.name.clone(),
            index: mi as u8,
            board: m.board,
            is_master: mi == bus.master,
            filter_mode: m.filters,
            banks,
            nodes: model
                .nodes
                .iter()
                .enumerate()
                .filter(|(_, n)| n.module == mi)
                .map(|(i, _)| i)
                .collect(),
            tx,
            rx,
            calendar,
            rx_arena_bytes,
        });
    }

    // Load: HRT reservations plus declared SRT/NRT average rates, against slots - 1.
    let cycle_s = (bus.slot_ns * slots) as f64 / 1e9;
    let reserved = admitted.as_ref().map_or(0, |a| a.stats.reserved_slots);
    let mut load = Load {
        capacity: (slots - 1) as f64,
        hrt: reserved as f64 / f64::from(hyper_cycles.max(1)),
        srt: 0.0,
        nrt: 0.0,
        uncounted: Vec::new(),
    };
    let mut heaviest: Option<(usize, f64)> = None;
    for (i, t) in topics
        .iter()
        .enumerate()
        .filter(|(_, t)| t.on_bus && t.class != Class::Hrt)
    {
        match t.rate_hz {
            Some(hz) => {
                let frames = hz * f64::from(t.fragments) * cycle_s;
                if t.class == Class::Srt {
                    load.srt += frames;
                } else {
                    load.nrt += frames;
                }
                if heaviest.is_none_or(|(_, f)| frames > f) {
                    heaviest = Some((i, frames));
                }
            }
            None => load.uncounted.push(i),
        }
    }
    let total = load.hrt + load.srt + load.nrt;
    if admitted.is_some() && total > load.capacity + 1e-9 {
        let span = heaviest
            .and_then(|(i, _)| model.topics.get(i))
            .and_then(|t| t.spans.timing.clone());
        let bp = BusPlan {
            cycle_ns: bus.slot_ns * slots,
            ..bus_plan(model, hyper, hyper_cycles)
        };
        diags.push(
            Diagnostic::new(
                Code::BusOverload,
                span,
                format!(
                    "bus load {:.1}% of capacity: HRT {} + SRT {} + NRT {} frames per cycle, capacity {} ({} kbit/s of payload)",
                    100.0 * total / load.capacity,
                    units::trim_float(load.hrt),
                    units::trim_float(load.srt),
                    units::trim_float(load.nrt),
                    units::trim_float(load.capacity),
                    units::trim_float(Load::kbps(load.capacity, &bp))
                ),
            )
            .help(format!(
                "the heaviest SRT/NRT topic is `{}`: lower its rate, or free HRT slots",
                heaviest.and_then(|(i, _)| topics.get(i)).map_or("?", |t| t.name.as_str())
            )),
        );
    }

    if diags.len() > start {
        return None;
    }
    let admitted = admitted?;
    let retired = lock.map_or_else(Vec::new, |l| {
        let named: Vec<(String, u16)> = topics
            .iter()
            .map(|t| (t.name.clone(), t.msg_id.0))
            .collect();
        crate::lock::retired_in_plan(l, &named, &|i| crate::lock::layout(model, i))
    });
    let mut plan = Plan {
        file: file.to_string(),
        bus: bus_plan(model, hyper, hyper_cycles),
        types: model.types.clone(),
        modules,
        nodes: model.nodes.clone(),
        topics,
        master_masks: admitted.masks,
        admission_steps: admitted.stats.steps,
        load,
        fingerprint: 0,
        bridge: model.bridge.clone(),
        lineage: lock.map(|l| l.lineage),
        retired,
        moves,
        chains: Vec::new(),
        services: model.services.clone(),
        params: model.params.clone(),
        module_state: model.module_state.clone(),
        supervision: Default::default(),
    };
    plan.fingerprint = crate::fingerprint::of(&plan);
    Some(plan)
}

/// A locked HRT phase that changed, with why.
fn phase_moves(lock: &Lock, topics: &[TopicPlan], moves: &mut Vec<crate::lock::Move>) {
    for t in topics {
        let Some(lt) = lock.topics.get(&t.name) else {
            continue;
        };
        let (Some(old), Some(new)) = (lt.phase, t.phase_slot) else {
            continue;
        };
        if old == new {
            continue;
        }
        let reason = if lt.period != t.period_slots {
            format!(
                "period changed: {} -> {} slots",
                lt.period.unwrap_or(0),
                t.period_slots.unwrap_or(0)
            )
        } else if lt.msg_id != t.msg_id.0 {
            "its message ID moved".to_string()
        } else {
            "the HRT set does not fit around the locked phases: full re-admission".to_string()
        };
        moves.push(crate::lock::Move {
            subject: t.name.clone(),
            what: "phase",
            from: old.to_string(),
            to: new.to_string(),
            reason,
        });
    }
}

fn bus_plan(model: &Model, hyper: u64, hyper_cycles: u32) -> BusPlan {
    let bus = &model.bus;
    BusPlan {
        bitrate: bus.bitrate,
        slots_per_cycle: bus.slots,
        slot_ns: bus.slot_ns,
        cycle_ns: bus.slot_ns * u64::from(bus.slots),
        requested_cycle_ns: bus.cycle_ns,
        hyperperiod_slots: hyper,
        hyperperiod_cycles: hyper_cycles,
        cycle_counter_wrap: counter_wrap(hyper_cycles),
        laxity: bus.laxity,
        guard_ns: bus.guard_ns,
        worst_frame_ns: bus.worst_frame_ns,
        master: bus.master,
        backup_masters: bus.backup_masters.clone(),
    }
}
