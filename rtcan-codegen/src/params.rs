//! `<module>::params`: the module's declared parameters (robot.toml `[params]`,
//! docs/SERVICES.md §2) as a table of `ParamSpec`s in wire-index order and one typed
//! handle (`rtcan::pubsub::param::Param<T>`) per parameter.
use proc_macro2::{Ident, Span, TokenStream};
use quote::quote;
use rtcan_model::params::{ParamDecl, ParamTy};
use rtcan_model::Plan;

use crate::lit;

/// `value` as a `Value` constructor of `ty`, and as a plain literal of the Rust type.
fn literal(ty: ParamTy, value: f64) -> (TokenStream, TokenStream) {
    match ty {
        ParamTy::F32 => {
            let f = value as f32;
            // TOML allows inf and nan, and a large f64 overflows f32: spell those out.
            let v = if f.is_nan() {
                quote!(f32::NAN)
            } else if f == f32::INFINITY {
                quote!(f32::INFINITY)
            } else if f == f32::NEG_INFINITY {
                quote!(f32::NEG_INFINITY)
            } else {
                let l = proc_macro2::Literal::f32_suffixed(f);
                quote!(#l)
            };
            (quote!(::rtcan::pubsub::param::Value::F32(#v)), v)
        }
        ParamTy::I32 => {
            let v = proc_macro2::Literal::i32_suffixed(value as i32);
            (quote!(::rtcan::pubsub::param::Value::I32(#v)), quote!(#v))
        }
        ParamTy::U32 => {
            let v = proc_macro2::Literal::u32_suffixed(value as u32);
            (quote!(::rtcan::pubsub::param::Value::U32(#v)), quote!(#v))
        }
        ParamTy::Bool => {
            let v = value != 0.0;
            (quote!(::rtcan::pubsub::param::Value::Bool(#v)), quote!(#v))
        }
    }
}

fn rust_type(ty: ParamTy) -> TokenStream {
    match ty {
        ParamTy::F32 => quote!(f32),
        ParamTy::I32 => quote!(i32),
        ParamTy::U32 => quote!(u32),
        ParamTy::Bool => quote!(bool),
    }
}

/// The handle's name: the parameter's name upper-cased, prefixed by its owner when the
/// owner is a node (`motor1.kp` on module motor1 → `KP`; `pid1.kp` → `PID1_KP`). Every
/// character that cannot be in an identifier becomes `_` (robot.toml keys may be any
/// string: a name `check` admits must build), and names that still clash get their
/// index appended.
fn const_names(decls: &[&ParamDecl], module: &str) -> Vec<Ident> {
    let raw: Vec<String> = decls
        .iter()
        .map(|d| {
            let (owner, name) = d.name.split_once('.').unwrap_or(("", d.name.as_str()));
            let full = if owner == module {
                name.to_string()
            } else {
                format!("{owner}_{name}")
            };
            let mut s: String = full
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() {
                        c.to_ascii_uppercase()
                    } else {
                        '_'
                    }
                })
                .collect();
            if !s.starts_with(|c: char| c.is_ascii_uppercase()) {
                s.insert_str(0, "P_");
            }
            s
        })
        .collect();
    raw.iter()
        .zip(decls)
        .map(|(s, d)| {
            let clash = raw.iter().filter(|o| *o == s).count() > 1 || s == "SPECS" || s == "COUNT";
            let s = if clash {
                format!("{s}_{}", d.index)
            } else {
                s.clone()
            };
            Ident::new(&s, Span::call_site())
        })
        .collect()
}

/// `pub mod params` of module `mi`.
pub fn params(plan: &Plan, mi: usize) -> TokenStream {
    let module = plan.modules.get(mi).map_or("", |m| m.name.as_str());
    let mut decls: Vec<&ParamDecl> = plan.params.iter().filter(|p| p.module == mi).collect();
    decls.sort_by_key(|p| p.index);
    let n = lit::usize(decls.len());
    let names = const_names(&decls, module);
    let specs = decls.iter().map(|d| {
        let (default, _) = literal(d.ty, d.default);
        let (min, _) = literal(d.ty, d.min);
        let (max, _) = literal(d.ty, d.max);
        let (name, unit, persist) = (&d.name, &d.unit, d.persist);
        quote! {
            ::rtcan::pubsub::param::ParamSpec {
                name: #name,
                default: #default,
                min: #min,
                max: #max,
                unit: #unit,
                persist: #persist,
            }
        }
    });
    let handles = decls.iter().zip(&names).map(|(d, c)| {
        let ty = rust_type(d.ty);
        let (_, default) = literal(d.ty, d.default);
        let index = lit::int(d.index);
        let doc = format!(
            "`{}`: {} in {} … {}{}, default {}{}.",
            d.name,
            d.ty.name(),
            d.min,
            d.max,
            if d.unit.is_empty() {
                String::new()
            } else {
                format!(" {}", d.unit)
            },
            d.default,
            if d.persist { ", kept in flash" } else { "" }
        );
        quote! {
            #[doc = #doc]
            pub const #c: ::rtcan::pubsub::param::Param<#ty> =
                ::rtcan::pubsub::param::Param::new(#index, #default);
        }
    });
    quote! {
        /// This module's parameters (robot.toml `[params]`): the declarations in wire-index
        /// order and a typed handle per parameter (`KP.get(&table)`).
        pub mod params {
            /// How many.
            pub const COUNT: usize = #n;
            /// The declarations, in wire-index order.
            pub static SPECS: [::rtcan::pubsub::param::ParamSpec; COUNT] = [#(#specs),*];
            /// A live table at the defaults (what the module's parameter server serves).
            pub fn table() -> ::rtcan::pubsub::param::Params<COUNT> {
                ::rtcan::pubsub::param::Params::new(&SPECS)
            }
            #(#handles)*
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decl(name: &str, index: u16) -> ParamDecl {
        ParamDecl {
            name: name.to_string(),
            module: 0,
            index,
            ty: ParamTy::F32,
            default: 0.0,
            min: 0.0,
            max: 1.0,
            unit: String::new(),
            persist: false,
        }
    }

    /// Any key robot.toml admits gives an identifier (Ident::new panics on a bad one,
    /// which would break a build `check` admitted); clashes get their index.
    #[test]
    fn handle_names_are_identifiers_and_unique() {
        let ds = [
            decl("m.kp", 0),
            decl("pid1.kp", 1),
            decl("m.k-p", 2),
            decl("m.k_p", 3),
            decl("m.9lives", 4),
            decl("m.ünits", 5),
            decl("m.specs", 6),
        ];
        let refs: Vec<&ParamDecl> = ds.iter().collect();
        let names: Vec<String> = const_names(&refs, "m")
            .iter()
            .map(|i| i.to_string())
            .collect();
        assert_eq!(
            names,
            ["KP", "PID1_KP", "K_P_2", "K_P_3", "P_9LIVES", "P__NITS", "SPECS_6"]
        );
    }

    #[test]
    fn non_finite_and_overflowing_f32_values_are_spelled_out() {
        assert_eq!(
            literal(ParamTy::F32, f64::INFINITY).1.to_string(),
            "f32 :: INFINITY"
        );
        assert_eq!(
            literal(ParamTy::F32, 1e300).1.to_string(),
            "f32 :: INFINITY"
        );
        assert_eq!(
            literal(ParamTy::F32, -1e300).1.to_string(),
            "f32 :: NEG_INFINITY"
        );
        assert_eq!(literal(ParamTy::F32, f64::NAN).1.to_string(), "f32 :: NAN");
        assert_eq!(literal(ParamTy::F32, 0.25).1.to_string(), "0.25f32");
        assert_eq!(literal(ParamTy::U32, 10.0).1.to_string(), "10u32");
        assert_eq!(literal(ParamTy::Bool, 1.0).1.to_string(), "true");
    }
}
