//! Rust names derived from robot.toml names (the model guarantees snake_case, non-keyword
//! names for fields, modules, nodes and topics, CamelCase non-keyword type names, and no
//! collisions between the derived names: `rtcan_model::names`).
use proc_macro2::{Ident, Span, TokenStream};
use quote::quote;
use rtcan_model::Plan;

/// `name` as an identifier.
pub fn ident(name: &str) -> Ident {
    Ident::new(name, Span::call_site())
}

/// `wheel_setpoints` → `WHEEL_SETPOINTS`.
pub fn upper(name: &str) -> Ident {
    ident(&name.to_ascii_uppercase())
}

/// `wheel_setpoints` → `WheelSetpoints` (the model's conversion, whose collisions
/// `rtcan check` refuses).
pub fn camel(name: &str) -> String {
    rtcan_model::names::camel(name)
}

/// `wheel_setpoints` + `Topic` → `WheelSetpointsTopic`.
pub fn camel_suffixed(name: &str, suffix: &str) -> Ident {
    ident(&(camel(name) + suffix))
}

/// Module names the generated code cannot use (the model refuses them first; this stays
/// as the generator's own guard).
pub use rtcan_model::names::RESERVED_MODULE_NAMES;

/// A `compile_error!` for a module whose name clashes with a generated item (the model's
/// names are valid identifiers; this is a constraint of this generator's layout only).
pub fn reserved_clashes(plan: &Plan) -> TokenStream {
    let errs = plan
        .modules
        .iter()
        .filter(|m| RESERVED_MODULE_NAMES.contains(&m.name.as_str()))
        .map(|m| {
            let msg = format!(
                "{}: module name `{}` is reserved by the generated code; rename the module",
                plan.file, m.name
            );
            quote! { ::core::compile_error!(#msg); }
        });
    quote! { #(#errs)* }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_case() {
        assert_eq!(camel("wheel_setpoints"), "WheelSetpoints");
        assert_eq!(camel("enc1"), "Enc1");
        assert_eq!(upper("enc1").to_string(), "ENC1");
    }
}
