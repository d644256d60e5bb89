//! `pub mod link`: the gateway's serial link topics robot.toml declares (`link = "in" |
//! "out"`), numbered 1.. in file order by rtcan-model. The firmware's gateway and the
//! host take the numbers from here / from the same plan, never from a hand list.
use crate::{lit, names};
use proc_macro2::TokenStream;
use quote::quote;
use rtcan_model::bridge_keys::LinkDir;
use rtcan_model::Plan;

/// `pub mod link { pub mod number { pub const NAME: u8 = n; } pub const TOPICS: ...; }`
/// (the numbers in their own module: a topic named `topics` or `in_count` cannot clash).
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
            /// Link topic number of each link topic.
            pub mod number {
                #(#consts)*
            }
            /// Every link topic: (number, topic name, payload bytes, host → robot).
            pub const TOPICS: [(u8, &str, usize, bool); #count] = [#(#rows),*];
            /// How many link topics go host → robot.
            pub const IN_COUNT: usize = #ins;
            /// How many link topics go robot → host.
            pub const OUT_COUNT: usize = #outs;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(src: &str) -> Plan {
        rtcan_model::Robot::parse("robot.toml", src).unwrap()
    }

    fn robot() -> String {
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../robot.toml")).unwrap()
    }

    #[test]
    fn triskar2_link_numbers_and_table_come_from_robot_toml() {
        let code = link(&plan(&robot())).to_string();
        for want in [
            "pub const TELEOP : u8 = 1 ;",
            "pub const ODOMETRY : u8 = 2 ;",
            "pub const PROXIMITY : u8 = 3 ;",
            "pub const BATTERY : u8 = 4 ;",
            "pub const LOG : u8 = 5 ;",
            "pub const TOPICS : [(u8 , & str , usize , bool) ; 5] = [(1 , \"teleop\" , 12 , true) , (2 , \"odometry\" , 24 , false) , (3 , \"proximity\" , 8 , false) , (4 , \"battery\" , 5 , false) , (5 , \"log\" , 32 , false)] ;",
            "pub const IN_COUNT : usize = 1 ;",
            "pub const OUT_COUNT : usize = 4 ;",
        ] {
            assert!(code.contains(want), "`{want}` not in {code}");
        }
        assert!(!code.contains("ENCODER1"));
        // The numbers live in their own module (no clash with TOPICS / IN_COUNT).
        assert!(code.contains("pub mod number {"), "{code}");
    }

    #[test]
    fn a_robot_without_link_topics_gets_an_empty_table() {
        let src: String = robot()
            .lines()
            .filter(|l| !l.starts_with("link"))
            .map(|l| format!("{l}\n"))
            .collect();
        let code = link(&plan(&src)).to_string();
        assert!(
            code.contains("pub const TOPICS : [(u8 , & str , usize , bool) ; 0] = [] ;"),
            "{code}"
        );
        assert!(code.contains("pub const OUT_COUNT : usize = 0 ;"));
    }
}
