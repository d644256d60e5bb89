//! `pub mod <module>`: one module's engine tables, CAN filters, engine sizes, topic
//! statics, typed node handles and `ModuleHost` glue.
use crate::{lit, names, tables, Options};
use proc_macro2::TokenStream;
use quote::quote;
use rtcan_core::Class;
use rtcan_model::filters::{BankPurpose, FilterBank};
use rtcan_model::{ModulePlan, Plan, TopicPlan};

/// Largest pool `rtcan_pubsub::Topic` supports (one `u32` free mask).
const MAX_POOL: usize = 32;

/// A topic as one module holds it.
struct Local<'p> {
    topic: &'p TopicPlan,
    /// Local subscriber nodes, in robot.toml order (index = subscriber slot).
    subs: Vec<usize>,
    /// Queue length of every local subscriber and of the queue towards the engine:
    /// `rtcan_pubsub::Topic` has one `Q` per topic, so it is the topic's longest queue.
    queue: u16,
    /// Sent on the bus from this module.
    remote: Option<Class>,
}

impl Local<'_> {
    /// Pool blocks (the formula `rtcan_pubsub::Topic` is sized with, one loan).
    fn pool(&self) -> usize {
        rtcan_pubsub::pool_blocks(
            self.subs.len(),
            usize::from(self.queue),
            self.remote_blocks(),
            1,
        )
    }

    /// Blocks the engine side may hold (see `rtcan_pubsub::pool_blocks`).
    fn remote_blocks(&self) -> usize {
        match self.remote {
            None => 0,
            Some(Class::Hrt) => 2,
            Some(_) => usize::from(self.queue) + 1,
        }
    }
}

fn locals(plan: &Plan, mi: usize) -> Vec<Local<'_>> {
    plan.topics
        .iter()
        .filter(|t| t.module == mi || t.subscribers.iter().any(|s| s.module == mi))
        .map(|t| Local {
            topic: t,
            subs: t
                .subscribers
                .iter()
                .filter(|s| s.module == mi)
                .map(|s| s.node)
                .collect(),
            queue: t
                .subscribers
                .iter()
                .map(|s| s.queue)
                .max()
                .unwrap_or(1)
                .max(1),
            remote: (t.module == mi && t.on_bus).then_some(t.class),
        })
        .collect()
}

/// (banks, flat `(id, mask)` pairs, doc line per bank).
fn filters(m: &ModulePlan, plan: &Plan) -> (Vec<TokenStream>, Vec<TokenStream>, String) {
    let mut docs = String::new();
    let mut banks = Vec::new();
    let mut flat = Vec::new();
    for b in &m.banks {
        let doc = match &b.purpose {
            BankPurpose::Sync => "sync frame".to_string(),
            BankPurpose::Heartbeat => "heartbeats".to_string(),
            BankPurpose::AcceptAll => "everything (software filtering by the RX table)".into(),
            BankPurpose::Topics(_) => format!("topics {}", b.purpose.topic_names(plan).join(", ")),
        };
        docs.push_str(&format!("\n{}. {doc}", banks.len()));
        match b.filter {
            FilterBank::Mask { id, mask } => {
                let (i, k) = (lit::hex(u64::from(id)), lit::hex(u64::from(mask)));
                banks.push(quote! { ::rtcan::FilterBank::Mask { id: #i, mask: #k } });
                flat.push(quote! { (#i, #k) });
            }
            FilterBank::List { ids: [a, b] } => {
                let (a, b) = (lit::hex(u64::from(a)), lit::hex(u64::from(b)));
                let full = lit::hex(u64::from(rtcan_core::CanId::MAX_RAW));
                banks.push(quote! { ::rtcan::FilterBank::List { ids: [#a, #b] } });
                flat.push(quote! { (#a, #full) });
                flat.push(quote! { (#b, #full) });
            }
        }
    }
    (banks, flat, docs)
}

/// `compile_error!`s for topics whose pool exceeds what `rtcan_pubsub::Topic` supports
/// (the model accepts queue lengths up to 255; a pool is a `u32` free mask).
pub fn pool_errors(plan: &Plan) -> TokenStream {
    let mut errs = Vec::new();
    for (mi, m) in plan.modules.iter().enumerate() {
        for l in locals(plan, mi) {
            let n = l.pool();
            if n > MAX_POOL {
                let msg = format!(
                    "{}: topic `{}` needs {n} message blocks on module `{}` ({} local subscriber(s) with queues of {}, {} for the bus, 1 loan); a topic has at most {MAX_POOL}: shorten its subscriber queues",
                    plan.file,
                    l.topic.name,
                    m.name,
                    l.subs.len(),
                    l.queue,
                    l.remote_blocks()
                );
                errs.push(quote! { ::core::compile_error!(#msg); });
            }
        }
    }
    quote! { #(#errs)* }
}

/// `<TOPIC>_SLOTS` of an HRT topic's publisher: its slots on the bus and its lead time
/// (R2P §3.4.5 synchronous publishers); `None` for a topic that stays on its module
/// (no slot: the publisher runs at its period).
fn hrt_slots(plan: &Plan, t: &TopicPlan) -> TokenStream {
    let c = names::ident(&format!("{}_SLOTS", t.name.to_ascii_uppercase()));
    let doc = format!(
        "Topic `{}`'s HRT slots and its publisher's lead time (robot.toml `lead`): run the publisher at `next_due` (`rtcan::pubsub::SlotEvery`).",
        t.name
    );
    let value = match (t.phase_slot, t.period_slots, t.lead_ns) {
        (Some(phase), Some(period), Some(lead)) => {
            let b = &plan.bus;
            let (phase, period) = (lit::int(phase), lit::int(period));
            let (slots, slot_ns, cycle_ns, lead) = (
                lit::int(u32::from(b.slots_per_cycle)),
                lit::int(b.slot_ns),
                lit::int(b.cycle_ns),
                lit::int(lead),
            );
            quote! {
                Some(::rtcan::pubsub::HrtSlots {
                    phase_slot: #phase,
                    period_slots: #period,
                    slots_per_cycle: #slots,
                    slot_ns: #slot_ns,
                    cycle_ns: #cycle_ns,
                    lead_ns: #lead,
                })
            }
        }
        _ => quote! { None },
    };
    quote! {
        #[doc = #doc]
        pub const #c: Option<::rtcan::pubsub::HrtSlots> = #value;
    }
}

/// The generated `pub mod <name>` of module `mi`.
pub fn module(plan: &Plan, mi: usize, opts: &Options) -> TokenStream {
    let (Some(m), Some(t)) = (plan.modules.get(mi), plan.tables(mi)) else {
        return quote!();
    };
    let name = names::ident(&m.name);
    let index = lit::int(m.index);
    let locals = locals(plan, mi);
    let kick = match &opts.kick {
        Some(k) => quote!(::core::option::Option::Some(#k as fn())),
        None => quote!(::core::option::Option::None),
    };

    // ---- topic statics ----
    // Pool sizes and engine indices live in their own submodules (`pool`, `tx`, `rx`),
    // named like the topic: no topic name can clash with another item.
    let pool_consts = locals.iter().map(|l| {
        let c = names::upper(&l.topic.name);
        let (s, q, r) = (lit::usize(l.subs.len()), lit::int(l.queue), lit::usize(l.remote_blocks()));
        let too_big = format!(
            "topic `{}` on module `{}` needs more than {MAX_POOL} pool blocks: shorten its subscriber queues",
            l.topic.name, m.name
        );
        let max = lit::usize(MAX_POOL);
        quote! {
            pub const #c: usize = ::rtcan::pubsub::pool_blocks(#s, #q, #r, 1);
            const _: () = ::core::assert!(#c <= #max, #too_big);
        }
    });
    let topic_items = locals.iter().map(|l| {
        let c = names::upper(&l.topic.name);
        let alias = names::camel_suffixed(&l.topic.name, "Topic");
        let ty = plan
            .types
            .get(l.topic.ty)
            .map(|t| names::ident(&t.name))
            .unwrap_or_else(|| names::ident("u8"));
        let (s, q) = (lit::usize(l.subs.len()), lit::int(l.queue));
        let remote = match l.remote {
            None => quote!(None),
            Some(Class::Hrt) => quote!(Hrt),
            Some(Class::Srt) => quote!(Srt),
            Some(Class::Nrt) => quote!(Nrt),
        };
        let doc = format!(
            "Topic `{}` on this module: {} local subscriber(s), queues of {}, {}.",
            l.topic.name,
            l.subs.len(),
            l.queue,
            match (l.remote, l.topic.module == mi && l.topic.on_bus) {
                (Some(_), _) => "sent on the bus",
                (None, _) if l.topic.module == mi => "local only",
                _ => "received from the bus",
            }
        );
        quote! {
            #[doc = #doc]
            pub type #alias = ::rtcan::pubsub::Topic<super::super::#ty, { pool::#c }, #s, #q>;
            #[doc = #doc]
            pub static #c: #alias = ::rtcan::pubsub::Topic::new(&cells::#c, ::rtcan::pubsub::Remote::#remote, #kick);
        }
    });
    // The mutable half of each topic (all-zero initial value, so .bss: no flash copy).
    let cell_items = locals.iter().map(|l| {
        let c = names::upper(&l.topic.name);
        let ty = plan
            .types
            .get(l.topic.ty)
            .map(|t| names::ident(&t.name))
            .unwrap_or_else(|| names::ident("u8"));
        let (s, q) = (lit::usize(l.subs.len()), lit::int(l.queue));
        let doc = format!("State of topic `{}` (used through `topics::{c}`).", l.topic.name);
        quote! {
            #[doc = #doc]
            pub static #c: ::rtcan::pubsub::TopicCells<super::super::super::#ty, { super::pool::#c }, #s, #q> =
                ::rtcan::pubsub::TopicCells::new();
        }
    });
    let topic_statics: Vec<_> = locals.iter().map(|l| names::upper(&l.topic.name)).collect();
    let tx_consts = m.tx.iter().enumerate().filter_map(|(k, ti)| {
        let t = plan.topics.get(*ti)?;
        let c = names::upper(&t.name);
        let k = lit::usize(k);
        Some(quote! { pub const #c: u8 = #k; })
    });
    let rx_consts = m.rx.iter().enumerate().filter_map(|(k, ti)| {
        let t = plan.topics.get(*ti)?;
        let c = names::upper(&t.name);
        let k = lit::usize(k);
        Some(quote! { pub const #c: u8 = #k; })
    });
    let tx_ports: Vec<_> =
        m.tx.iter()
            .filter_map(|ti| plan.topics.get(*ti))
            .map(|t| names::upper(&t.name))
            .collect();
    let rx_ports: Vec<_> =
        m.rx.iter()
            .filter_map(|ti| plan.topics.get(*ti))
            .map(|t| names::upper(&t.name))
            .collect();

    // ---- nodes and their typed handles ----
    let node_mods = m.nodes.iter().filter_map(|ni| {
        let node = plan.nodes.get(*ni)?;
        let nid = names::ident(&node.name);
        let nname = &node.name;
        let prio = lit::int(node.priority);
        let handles = locals.iter().flat_map(|l| {
            let t = l.topic;
            let c = names::upper(&t.name);
            let ty = plan
                .types
                .get(t.ty)
                .map(|x| names::ident(&x.name))
                .unwrap_or_else(|| names::ident("u8"));
            let (s, q) = (lit::usize(l.subs.len()), lit::int(l.queue));
            let generics = quote! { 'static, super::super::super::#ty, { super::super::topics::pool::#c }, #s, #q };
            let mut out = Vec::new();
            if t.publisher == *ni {
                let f = names::ident(&format!("{}_pub", t.name));
                let doc = format!("Publisher of topic `{}` (the only one).", t.name);
                out.push(quote! {
                    #[doc = #doc]
                    pub fn #f() -> ::rtcan::pubsub::Publisher<#generics> {
                        super::super::topics::#c.publisher()
                    }
                });
            }
            if t.publisher == *ni && t.class == Class::Hrt {
                out.push(hrt_slots(plan, t));
            }
            if let Some(slot) = l.subs.iter().position(|s| s == ni) {
                let f = names::ident(&format!("{}_sub", t.name));
                let slot = lit::usize(slot);
                let doc = format!("This node's subscription to topic `{}`.", t.name);
                out.push(quote! {
                    #[doc = #doc]
                    pub fn #f() -> ::rtcan::pubsub::Subscriber<#generics> {
                        super::super::topics::#c.subscriber::<#slot>()
                    }
                });
            }
            out
        });
        let doc = format!("Node `{nname}` (priority {}): its lifecycle and typed handles for exactly the topics it declares.", node.priority);
        Some(quote! {
            #[doc = #doc]
            pub mod #nid {
                /// Lifecycle (its state goes into the module's heartbeat).
                pub static NODE: ::rtcan::pubsub::Node = ::rtcan::pubsub::Node::new(#nname);
                /// Task priority from robot.toml (1 = lowest).
                pub const PRIORITY: u8 = #prio;
                #(#handles)*
            }
        })
    });
    let nnodes = lit::usize(m.nodes.len());
    let node_refs: Vec<_> = m
        .nodes
        .iter()
        .filter_map(|ni| plan.nodes.get(*ni))
        .map(|n| names::ident(&n.name))
        .collect();

    // ---- engine tables ----
    let tx = t.tx.iter().map(tables::tx);
    let rx = t.rx.iter().map(tables::rx);
    let cal = t.calendar.iter().map(tables::cal);
    let (ntx, nrx, ncal) = (
        lit::usize(t.tx.len()),
        lit::usize(t.rx.len()),
        lit::usize(t.calendar.len()),
    );
    let masks = if m.is_master {
        quote!(&super::MASTER_MASKS)
    } else {
        quote!(&[])
    };
    let arena = lit::usize(m.rx_arena_bytes);
    // The engine queue holds this module's heartbeat plus, per SRT/NRT topic it sends,
    // as many messages as that topic's own queue towards the engine.
    let queue: usize = 1 + locals
        .iter()
        .filter(|l| matches!(l.remote, Some(Class::Srt | Class::Nrt)))
        .map(|l| usize::from(l.queue))
        .sum::<usize>();
    let queue = lit::usize(queue);
    let (banks, flat, bank_docs) = filters(m, plan);
    let services = crate::services::module_services(plan, mi);
    let module_state = crate::supervision::module_glue(plan, mi);
    let banks_doc = format!(
        "bxCAN filter banks (32-bit scale, 29-bit identifiers), in bank order: the sync frame, heartbeats and exactly this module's subscriptions.\n{bank_docs}"
    );
    let accept_all = m.filter_mode == rtcan_model::FilterMode::AcceptAll;
    let is_master = m.is_master;
    // Backup-master rank, 1 = first to take over (robot.toml `backup_masters` order); 0 = none.
    let backup_rank = plan
        .bus
        .backup_masters
        .iter()
        .position(|&b| b == mi)
        .map_or(0u8, |p| u8::try_from(p + 1).unwrap_or(u8::MAX));
    // Backup masters in rank order: the safe-state rule follows the current sync master.
    let backups: Vec<u8> = plan
        .bus
        .backup_masters
        .iter()
        .map(|&b| u8::try_from(b).unwrap_or(u8::MAX))
        .collect();
    let safety = quote! {
        ::rtcan::pubsub::SafetyConfig {
            module: INDEX,
            master: super::MASTER,
            // Three missed master heartbeats of the default period.
            max_missed_cycles: (3 * ::rtcan::core::engine::HEARTBEAT_CYCLES) as u16,
        }
    };
    // A supervised robot (robot.toml `on_missing`) applies its rules on every module.
    let status = if plan.supervision.rules.is_empty() {
        quote!(::rtcan::pubsub::SystemStatus::with_backups(#safety, &[#(#backups),*]))
    } else {
        quote! {
            ::rtcan::pubsub::SystemStatus::supervised(#safety, &[#(#backups),*], ::rtcan::pubsub::Supervised {
                modules: super::supervision::MODULES as u8,
                missing_after: super::supervision::MISSING_AFTER_CYCLES,
                rules: super::supervision::RULES,
            })
        }
    };
    let doc = format!(
        "Module `{}` (index {}, board {}{}).",
        m.name,
        m.index,
        m.board.name(),
        if m.is_master { ", bus master" } else { "" }
    );
    let mismatch = format!(
        "module `{}`: tables do not match the engine's sizes",
        m.name
    );

    let params = crate::params::params(plan, mi);

    quote! {
        #[doc = #doc]
        pub mod #name {
            /// Module index (heartbeat message ID = `HEARTBEAT_BASE + INDEX`).
            pub const INDEX: u8 = #index;
            /// Sends the sync frame.
            pub const IS_MASTER: bool = #is_master;
            /// Topics this module sends on the bus, in message-ID order (index = tx index).
            pub const TX: [::rtcan::core::TxTopic; #ntx] = [#(#tx),*];
            /// Topics this module receives, sorted by message ID (index = rx index).
            pub const RX: [::rtcan::core::RxTopic; #nrx] = [#(#rx),*];
            /// This module's HRT slots over the hyperperiod, sorted by slot.
            pub const CALENDAR: [::rtcan::core::CalEntry; #ncal] = [#(#cal),*];
            /// Everything the engine of this module needs.
            pub const TABLES: ::rtcan::core::NodeTables<'static> = ::rtcan::core::NodeTables {
                bus: super::BUS,
                module: INDEX,
                tx: &TX,
                rx: &RX,
                calendar: &CALENDAR,
                master_masks: #masks,
            };
            /// Receive topics (engine `RX`).
            pub const RX_COUNT: usize = #nrx;
            /// Reassembly arena bytes (engine `ARENA`).
            pub const ARENA_BYTES: usize = #arena;
            /// SRT/NRT transmit queue capacity (engine `Q`).
            pub const QUEUE_CAPACITY: usize = #queue;
            /// This module's engine.
            pub type Engine<'t> = ::rtcan::core::Engine<'t, RX_COUNT, ARENA_BYTES, QUEUE_CAPACITY>;
            /// Backup-master rank (robot.toml `backup_masters`, 1 = first); 0: not a backup.
            pub const BACKUP_RANK: u8 = #backup_rank;
            /// A new engine on [`TABLES`] (`now`: local time), with its backup-master rank.
            pub fn engine(now: ::rtcan::core::Nanos) -> Engine<'static> {
                let mut engine = ::rtcan::core::Engine::new(TABLES, now);
                engine.set_backup(BACKUP_RANK, &super::MASTER_MASKS);
                engine.set_heartbeat_cycles(super::supervision::HEARTBEAT_CYCLES);
                engine
            }
            const _: () = ::core::assert!(::rtcan::tables_fit(&TABLES, RX_COUNT, ARENA_BYTES), #mismatch);
            #[doc = #banks_doc]
            pub const FILTER_BANKS: &[::rtcan::FilterBank] = &[#(#banks),*];
            /// The same acceptance as `(id, mask)` pairs (a list bank is two exact pairs).
            pub const FILTERS: &[(u32, u32)] = &[#(#flat),*];
            /// One accept-everything bank (`filters = "accept-all"`): the RX table filters.
            pub const ACCEPT_ALL: bool = #accept_all;

            /// This module's topics: every topic its nodes publish or subscribe.
            pub mod topics {
                #(#topic_items)*
                /// The mutable state of each topic above, zero-initialised (.bss) so
                /// that it takes no flash; the topic statics are immutable (.rodata).
                pub mod cells {
                    #(#cell_items)*
                }
                /// Pool blocks per topic (`rtcan::pubsub::pool_blocks`).
                pub mod pool {
                    #(#pool_consts)*
                }
                /// Engine transmit index of each topic sent on the bus (`NodeTables::tx`).
                pub mod tx {
                    #(#tx_consts)*
                }
                /// Engine receive index of each topic received from the bus (`NodeTables::rx`).
                pub mod rx {
                    #(#rx_consts)*
                }
            }

            /// This module's nodes.
            pub mod nodes {
                #(#node_mods)*
            }

            #services

            #params
            #module_state

            /// Transmit topics in `TX` order, for `ModuleHost`.
            pub static TX_PORTS: [&dyn ::rtcan::pubsub::TxPort; #ntx] = [#(&topics::#tx_ports),*];
            /// Receive topics in `RX` order, for `ModuleHost`.
            pub static RX_PORTS: [&dyn ::rtcan::pubsub::RxPort; #nrx] = [#(&topics::#rx_ports),*];
            /// System status as seen from this module (sync, master heartbeat, fingerprints).
            pub static STATUS: ::rtcan::pubsub::SystemStatus = #status;
            /// The nodes whose worst state goes into this module's heartbeat.
            pub static NODES: [&::rtcan::pubsub::Node; #nnodes] = [#(&nodes::#node_refs::NODE),*];
            /// Every static of this module back to power-on: topics (blocks held by live
            /// handles stay allocated), system status, node states. For a simulator or a
            /// test that runs the module more than once in one process.
            pub fn reset() {
                #(topics::#topic_statics.reset();)*
                STATUS.clear();
                for node in NODES.iter() {
                    node.reset();
                }
            }
            /// The engine's `Host`: dispatches tx/rx indices to this module's topics.
            pub fn host() -> ::rtcan::pubsub::ModuleHost<'static> {
                ::rtcan::pubsub::ModuleHost::new(&TX_PORTS, &RX_PORTS, &STATUS, &NODES)
            }
        }
    }
}
