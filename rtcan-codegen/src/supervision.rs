//! `pub mod supervision`: robot.toml's `on_missing` rules as
//! `rtcan::pubsub::ModuleRule`s, the heartbeat period every module's engine uses and the
//! age past which a module is missing (docs/SERVICES.md §1).
use crate::lit;
use proc_macro2::TokenStream;
use quote::quote;
use rtcan_model::supervision::OnMissing;
use rtcan_model::Plan;

/// The generated `supervision` module.
pub fn supervision(plan: &Plan) -> TokenStream {
    let s = &plan.supervision;
    let rules = s.rules.iter().map(|r| {
        let module = lit::usize(r.module);
        let on_missing = match r.on_missing {
            OnMissing::SafeAll => quote!(SafeAll),
            OnMissing::SafeDependents => quote!(SafeDependents),
            OnMissing::Warn => quote!(Warn),
        };
        let mask = r
            .dependents
            .iter()
            .filter(|&&d| d < 64)
            .fold(0u64, |m, &d| m | (1u64 << d));
        let mask = lit::hex(mask);
        quote! {
            ::rtcan::pubsub::ModuleRule {
                module: #module,
                on_missing: ::rtcan::pubsub::OnMissing::#on_missing,
                dependents: #mask,
            }
        }
    });
    let supervised = !s.rules.is_empty();
    let beats = lit::int(u8::try_from(s.heartbeat_cycles).unwrap_or(u8::MAX));
    let missing = if supervised {
        quote!(::rtcan::pubsub::supervision::missing_after(
            HEARTBEAT_CYCLES
        ))
    } else {
        quote!(::rtcan::pubsub::supervision::MISSING_AFTER_CYCLES)
    };
    let modules = lit::usize(plan.modules.len());
    // The heartbeats of a cycle are due by mid-cycle (`heartbeats_overdue`).
    let due = lit::int(plan.bus.cycle_ns / 2);
    // Module-state publications: every this many cycles (`module_state::RATE_HZ`).
    let every = (1e9 / (rtcan_model::module_state::RATE_HZ * plan.bus.cycle_ns as f64)).round();
    let every = lit::int(if every >= 1.0 { every as u32 } else { 1 });
    quote! {
        /// Supervision (robot.toml `on_missing`, docs/SERVICES.md §1).
        pub mod supervision {
            /// Modules on the bus: the module table has one row each.
            pub const MODULES: usize = #modules;
            /// Some module declares `on_missing`: heartbeats every `HEARTBEAT_CYCLES`.
            pub const SUPERVISED: bool = #supervised;
            /// Heartbeat period of every module's engine, cycles.
            pub const HEARTBEAT_CYCLES: u8 = #beats;
            /// A module whose heartbeat is older than this (cycles) is missing.
            pub const MISSING_AFTER_CYCLES: u16 = #missing;
            /// Phase of the cycle (ns after its start) by which its heartbeats are due:
            /// past it the module table counts a module silent since the previous
            /// cycle as missing (`rtcan::pubsub::supervision::table_missing_after_at`).
            pub const HEARTBEAT_DUE_NS: u64 = #due;
            /// What a missing module means, per module that declares it.
            pub const RULES: &[::rtcan::pubsub::ModuleRule] = &[#(#rules),*];
            /// The module table as this robot has it.
            pub type Table = ::rtcan::pubsub::ModuleTable<MODULES>;
            /// Health and table publications every this many cycles (and the table at
            /// once on a change: `rtcan::pubsub::Supervisor`).
            pub const PUBLISH_CYCLES: u32 = #every;
            /// One module's side of the module-state topics.
            pub type Supervisor = ::rtcan::pubsub::Supervisor<MODULES>;
        }
    }
}

/// The node of `module` that publishes and subscribes its module-state topics: its
/// first node (`rtcan_model::module_state::append`).
fn first_node(plan: &Plan, module: usize) -> Option<(usize, &rtcan_model::model::Node)> {
    plan.nodes
        .iter()
        .enumerate()
        .find(|(_, n)| n.module == module)
}

/// `pub mod module_state` of module `mi` on a supervised robot: publish its health and
/// (sync-capable) its table, read the healths and tables it receives. Empty on a robot
/// without `on_missing`.
pub fn module_glue(plan: &Plan, mi: usize) -> TokenStream {
    let Some(s) = &plan.module_state else {
        return TokenStream::new();
    };
    let ty = |i: usize| {
        let name = plan.types.get(i).map_or("u8", |t| t.name.as_str());
        crate::names::ident(name)
    };
    let (hty, sty) = (ty(s.health_ty), ty(s.state_ty));
    let topic_name = |t: usize| plan.topics.get(t).map_or("", |x| x.name.as_str());
    let node = first_node(plan, mi).map(|(_, n)| crate::names::ident(&n.name));
    let handle = |t: usize, suffix: &str| {
        let node = node.clone()?;
        let f = crate::names::ident(&format!("{}_{suffix}", topic_name(t)));
        Some(quote!(super::nodes::#node::#f()))
    };
    let own = |list: &[(usize, usize)]| list.iter().find(|(m, _)| *m == mi).map(|&(_, t)| t);
    let publish_health = match own(&s.health).and_then(|t| handle(t, "pub")) {
        Some(p) => quote! {
            let mut b = [0u8; ::rtcan::pubsub::supervision::HEALTH_BYTES];
            let _ = h.encode(&mut b);
            match <super::super::#hty as ::rtcan::pubsub::Message>::decode(&b) {
                Some(v) => #p.send(v, now).is_ok(),
                None => false,
            }
        },
        None => quote! {
            let _ = (h, now);
            false
        },
    };
    let publish_table = match own(&s.tables).and_then(|t| handle(t, "pub")) {
        Some(p) => quote! {
            let mut b = [0u8; ::rtcan::pubsub::supervision::table_bytes(super::super::supervision::MODULES)];
            if t.encode(&mut b).is_none() {
                return false;
            }
            match <super::super::#sty as ::rtcan::pubsub::Message>::decode(&b) {
                Some(v) => #p.send(v, now).is_ok(),
                None => false,
            }
        },
        None => quote! {
            let _ = (t, now);
            false
        },
    };
    // Subscriptions of this module's first node, with the module each comes from.
    let subs = |list: &[(usize, usize)]| -> Vec<(TokenStream, TokenStream)> {
        list.iter()
            .filter(|&&(_, t)| {
                plan.topics.get(t).is_some_and(|x| {
                    x.subscribers
                        .iter()
                        .any(|sub| first_node(plan, mi).is_some_and(|(i, _)| i == sub.node))
                })
            })
            .filter_map(|&(m, t)| {
                let m = lit::usize(m);
                Some((quote!(#m), handle(t, "sub")?))
            })
            .collect()
    };
    let health_rx = subs(&s.health).into_iter().map(|(m, sub)| {
        quote! {
            while let Some(msg) = #sub.try_recv() {
                let mut b = [0u8; ::rtcan::pubsub::supervision::HEALTH_BYTES];
                ::rtcan::pubsub::Message::encode(&*msg, &mut b);
                if let Some(h) = ::rtcan::pubsub::EngineHealth::decode(&b) {
                    f(#m, h);
                }
            }
        }
    });
    let table_rx = subs(&s.tables).into_iter().map(|(_, sub)| {
        quote! {
            while let Some(msg) = #sub.try_recv() {
                let mut b = [0u8; ::rtcan::pubsub::supervision::table_bytes(super::super::supervision::MODULES)];
                ::rtcan::pubsub::Message::encode(&*msg, &mut b);
                if let Some(t) = super::super::supervision::Table::decode(&b) {
                    f(t);
                }
            }
        }
    });
    let sync_capable = own(&s.tables).is_some();
    quote! {
        /// This module's side of the module-state topics (docs/SERVICES.md §1), driven by
        /// a `supervision::Supervisor` in the module's glue.
        pub mod module_state {
            /// This module publishes a module table while it is the sync master.
            pub const SYNC_CAPABLE: bool = #sync_capable;
            /// Publishes this module's health (`health_<module>`); false if refused.
            pub fn publish_health(h: ::rtcan::pubsub::EngineHealth, now: ::rtcan::core::Nanos) -> bool {
                #publish_health
            }
            /// Publishes the module table (`module_state_<module>`, sync-capable modules
            /// only); false if refused or not sync-capable.
            pub fn publish_table(t: &super::super::supervision::Table, now: ::rtcan::core::Nanos) -> bool {
                #publish_table
            }
            /// Every health received since the last call, with its module.
            pub fn drain_health(f: &mut dyn FnMut(u8, ::rtcan::pubsub::EngineHealth)) {
                let _ = &f;
                #(#health_rx)*
            }
            /// Every module table received since the last call.
            pub fn drain_tables(f: &mut dyn FnMut(super::super::supervision::Table)) {
                let _ = &f;
                #(#table_rx)*
            }
        }
    }
}
