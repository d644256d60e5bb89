//! `pub mod nodes`: every node of the robot under its own name, wherever robot.toml
//! places it. `nodes::<node>` re-exports the node's typed handles from
//! `<module>::nodes::<node>` and names its module (`module`, `MODULE`), so node code
//! written against `robot::nodes::<node>` builds unchanged when robot.toml moves the node
//! to another module (R2P §5.2); only the generated layout follows the move.
use crate::{lit, names};
use proc_macro2::TokenStream;
use quote::quote;
use rtcan_model::Plan;

/// The generated `pub mod nodes`.
pub fn placement(plan: &Plan) -> TokenStream {
    let nodes = plan.nodes.iter().filter_map(|n| {
        let m = plan.modules.get(n.module)?;
        let (node, module) = (names::ident(&n.name), names::ident(&m.name));
        let (mname, index) = (&m.name, lit::int(m.index));
        let doc = format!(
            "Node `{}` (priority {}), on module `{}` as robot.toml places it.",
            n.name, n.priority, m.name
        );
        Some(quote! {
            #[doc = #doc]
            pub mod #node {
                pub use super::super::#module::nodes::#node::*;
                /// The module this node runs on (its `STATUS`, tables, engine).
                pub use super::super::#module as module;
                /// Name of the module this node runs on.
                pub const MODULE: &str = #mname;
                /// Index of the module this node runs on.
                pub const MODULE_INDEX: u8 = #index;
            }
        })
    });
    quote! {
        /// Every node under its own name, re-exported from the module robot.toml places it
        /// on: code written against `nodes::<node>` does not name its module.
        pub mod nodes {
            #(#nodes)*
        }
    }
}
