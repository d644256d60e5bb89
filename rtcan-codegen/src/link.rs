//! `pub mod link`: the gateway's serial link topics robot.toml declares (`link = "in" |
//! "out"`), numbered 1.. in file order by rtcan-model. The firmware's gateway and the
//! host take the numbers from here / from the same plan, never from a hand list.
use crate::{lit, names};
use proc_macro2::TokenStream;
use quote::quote;
use rtcan_model::bridge_keys::LinkDir;
use rtcan_model::Plan;

/// `pub mod link { pub const NAME: u8 = n; pub const TOPICS: [LinkTopic; N] = ...; }`.
pub fn link(plan: &Plan) -> TokenStream {
    let topics = &plan.bridge.link;
    let consts = topics.iter().map(|l| {
        let c = names::upper(&l.name);
        let n = lit::int(l.number);
        let doc = format!(
            "Link topic number of `{}` ({}, {} B).",
            l.name,
            match l.dir {
                LinkDir::In => "host → robot",
                LinkDir::Out => "robot → host",
            },
            l.size
        );
        quote! {
            #[doc = #doc]
            pub const #c: u8 = #n;
        }
    });
    let rows = topics.iter().map(|l| {
        let n = lit::int(l.number);
        let name = &l.name;
        let size = lit::usize(l.size);
        let to_robot = l.dir == LinkDir::In;
        quote!((#n, #name, #size, #to_robot))
    });
    let count = lit::usize(topics.len());
    let ins = lit::usize(topics.iter().filter(|l| l.dir == LinkDir::In).count());
    let outs = lit::usize(topics.iter().filter(|l| l.dir == LinkDir::Out).count());
    quote! {
        /// The gateway's serial link topics (robot.toml `link`).
        pub mod link {
            #(#consts)*
            /// Every link topic: (number, topic name, payload bytes, host → robot).
            pub const TOPICS: [(u8, &str, usize, bool); #count] = [#(#rows),*];
            /// How many link topics go host → robot.
            pub const IN_COUNT: usize = #ins;
            /// How many link topics go robot → host.
            pub const OUT_COUNT: usize = #outs;
        }
    }
}
