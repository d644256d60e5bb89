//! Rust names derived from robot.toml names (the model guarantees snake_case, non-keyword
//! names for fields, modules, nodes and topics, and CamelCase-able type names).
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

/// `wheel_setpoints` → `WheelSetpoints`.
pub fn camel(name: &str) -> String {
    name.split('_')
        .filter(|p| !p.is_empty())
        .map(|p| {
            let mut c = p.chars();
            c.next()
                .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
                .unwrap_or_default()
        })
        .collect()
}

/// `wheel_setpoints` + `Topic` → `WheelSetpointsTopic`.
pub fn camel_suffixed(name: &str, suffix: &str) -> Ident {
    ident(&(camel(name) + suffix))
}

/// `topics` is the only name the generated code itself places next to the module modules.
pub const RESERVED_MODULE_NAMES: &[&str] = &["topics"];

/// A `compile_error!` for a module whose name clashes with a generated item (the model's
/// names are valid identifiers; this is a constraint of this generator's layout only).
pub fn reserved_clashes(plan: &Plan) -> TokenStream {
    let errs = plan
        .modules
        .iter()
        .filter(|m| RESERVED_MODULE_NAMES.contains(&m.name.as_str()))
        .map(|m| {
            let msg = format!(
                "{}: module name `{}` is reserved by the generated code (it holds the topic constants); rename the module",
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
