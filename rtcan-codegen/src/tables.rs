//! Robot-wide constants and the `rtcan_core::tables` values of each module.
use crate::{lit, names};
use proc_macro2::TokenStream;
use quote::quote;
use rtcan_core::laxity::LaxityEncoding;
use rtcan_core::tables::{BusConfig, CalEntry, RxTopic, TxTopic};
use rtcan_core::Class;
use rtcan_model::Plan;

pub fn class(c: Class) -> TokenStream {
    match c {
        Class::Hrt => quote!(::rtcan::core::Class::Hrt),
        Class::Srt => quote!(::rtcan::core::Class::Srt),
        Class::Nrt => quote!(::rtcan::core::Class::Nrt),
    }
}

fn option<T>(v: Option<T>, f: impl FnOnce(T) -> TokenStream) -> TokenStream {
    match v {
        Some(x) => {
            let x = f(x);
            quote!(::core::option::Option::Some(#x))
        }
        None => quote!(::core::option::Option::None),
    }
}

/// `pub mod topics { pub const NAME: ::rtcan::TopicInfo = ...; }`.
pub fn topic_infos(plan: &Plan) -> TokenStream {
    let items = plan.topics.iter().map(|t| {
        let c = names::upper(&t.name);
        let name = &t.name;
        let msg_id = lit::hex(u64::from(t.msg_id.0));
        let class = class(t.class);
        let size = lit::int(t.size);
        let fragments = lit::int(t.fragments);
        let on_bus = t.on_bus;
        let module = lit::usize(t.module);
        let period = option(t.period_slots, |p| tok(lit::int(p)));
        let phase = option(t.phase_slot, |p| tok(lit::int(p)));
        let deadline = option(t.deadline_ns, |d| tok(lit::int(d)));
        let doc = format!(
            "Topic `{name}` ({:?}, {} B in {} frame(s), message ID {:#06x}).",
            t.class, t.size, t.fragments, t.msg_id.0
        );
        quote! {
            #[doc = #doc]
            pub const #c: ::rtcan::TopicInfo = ::rtcan::TopicInfo {
                name: #name,
                msg_id: ::rtcan::core::MsgId(#msg_id),
                class: #class,
                size: #size,
                fragments: #fragments,
                on_bus: #on_bus,
                module: #module,
                period_slots: #period,
                phase_slot: #phase,
                deadline_ns: #deadline,
            };
        }
    });
    let all: Vec<_> = plan.topics.iter().map(|t| names::upper(&t.name)).collect();
    quote! {
        /// Every topic's planned constants (message ID, class, period, phase, deadline,
        /// fragments, size).
        pub mod topics {
            #(#items)*
            /// All topics, in robot.toml order (a function: no topic constant can be
            /// named in lowercase).
            pub fn all() -> &'static [::rtcan::TopicInfo] {
                &[#(#all),*]
            }
        }
    }
}

fn tok(l: proc_macro2::Literal) -> TokenStream {
    quote!(#l)
}

fn laxity(l: LaxityEncoding) -> TokenStream {
    match l {
        LaxityEncoding::Linear { unit_ns } => {
            let u = lit::int(unit_ns);
            quote!(::rtcan::core::laxity::LaxityEncoding::Linear { unit_ns: #u })
        }
        LaxityEncoding::Log { unit_ns } => {
            let u = lit::int(unit_ns);
            quote!(::rtcan::core::laxity::LaxityEncoding::Log { unit_ns: #u })
        }
    }
}

pub fn bus_config(b: &BusConfig) -> TokenStream {
    let bitrate = lit::int(b.bitrate);
    let slots = lit::int(b.slots_per_cycle);
    let slot_ns = lit::int(b.slot_ns);
    let hyper = lit::int(b.hyperperiod_cycles);
    let wrap = lit::int(b.cycle_counter_wrap);
    let lax = laxity(b.laxity);
    let guard = lit::int(b.guard_ns);
    let fp = lit::hex(u64::from(b.fingerprint));
    quote! {
        ::rtcan::core::BusConfig {
            bitrate: #bitrate,
            slots_per_cycle: #slots,
            slot_ns: #slot_ns,
            hyperperiod_cycles: #hyper,
            cycle_counter_wrap: #wrap,
            laxity: #lax,
            guard_ns: #guard,
            fingerprint: #fp,
        }
    }
}

/// `BUS`, `FINGERPRINT`, `MASTER`, `MASTER_MASKS`.
pub fn bus(plan: &Plan) -> TokenStream {
    let cfg = bus_config(&plan.bus.config(plan.fingerprint));
    let fp = lit::hex(u64::from(plan.fingerprint));
    let master = lit::usize(plan.bus.master);
    let masks = plan.master_masks.iter().map(|m| lit::hex(*m));
    let n = lit::usize(plan.master_masks.len());
    let fp_doc = format!(
        "Robot fingerprint (FNV-1a of the canonical plan of {}), carried in heartbeats.",
        plan.file
    );
    quote! {
        /// Bus parameters shared by every module.
        pub const BUS: ::rtcan::core::BusConfig = #cfg;
        #[doc = #fp_doc]
        pub const FINGERPRINT: u32 = #fp;
        /// Index of the master module.
        pub const MASTER: u8 = #master;
        /// The master's reservation mask of every cycle of the hyperperiod (bit k = slot k,
        /// bit 0 = the sync slot).
        pub const MASTER_MASKS: [u64; #n] = [#(#masks),*];
    }
}

pub fn tx(t: &TxTopic) -> TokenStream {
    let id = lit::hex(u64::from(t.msg_id.0));
    let class = class(t.class);
    let size = lit::int(t.size);
    let deadline = lit::int(t.deadline_ns);
    quote! {
        ::rtcan::core::TxTopic {
            msg_id: ::rtcan::core::MsgId(#id),
            class: #class,
            size: #size,
            deadline_ns: #deadline,
        }
    }
}

pub fn rx(t: &RxTopic) -> TokenStream {
    let id = lit::hex(u64::from(t.msg_id.0));
    let size = lit::int(t.size);
    let off = lit::int(t.arena_offset);
    quote! {
        ::rtcan::core::RxTopic { msg_id: ::rtcan::core::MsgId(#id), size: #size, arena_offset: #off }
    }
}

pub fn cal(c: &CalEntry) -> TokenStream {
    let slot = lit::int(c.slot);
    let tx = lit::int(c.tx);
    let frag = lit::int(c.fragment);
    quote! { ::rtcan::core::CalEntry { slot: #slot, tx: #tx, fragment: #frag } }
}
