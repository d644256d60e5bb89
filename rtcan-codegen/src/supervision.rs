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
            /// What a missing module means, per module that declares it.
            pub const RULES: &[::rtcan::pubsub::ModuleRule] = &[#(#rules),*];
            /// The module table as this robot has it.
            pub type Table = ::rtcan::pubsub::ModuleTable<MODULES>;
        }
    }
}
