//! `rtcan::robot!("robot.toml")`: reads the robot description (path relative to the
//! calling crate's `CARGO_MANIFEST_DIR`), runs the model (parse, validate, plan) and the
//! code generator, and expands to the generated items, or to one `compile_error!` per
//! diagnostic, rendered rustc-style with the robot.toml excerpt.
//!
//! Usage (compiled for real in the root crate's `tests/generated.rs` and `tests/ui/`):
//!
//! ```text
//! rtcan::robot!("robot.toml");
//! rtcan::robot!("robot.toml", kick = crate::pend_can_pump);
//! ```
use proc_macro::TokenStream;
use proc_macro2::Span;
use quote::quote;
use std::path::PathBuf;
use syn::parse::{Parse, ParseStream};
use syn::{LitStr, Path, Token};

struct Input {
    file: LitStr,
    kick: Option<Path>,
}

impl Parse for Input {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        let file: LitStr = input.parse()?;
        let mut kick = None;
        while input.peek(Token![,]) {
            input.parse::<Token![,]>()?;
            if input.is_empty() {
                break;
            }
            let key: syn::Ident = input.parse()?;
            if key != "kick" {
                return Err(syn::Error::new(
                    key.span(),
                    "unknown option; expected `kick = path::to::fn`",
                ));
            }
            input.parse::<Token![=]>()?;
            kick = Some(input.parse()?);
        }
        Ok(Input { file, kick })
    }
}

/// Generates a robot's types, topic constants, per-module tables, filters, pools and
/// typed handles from a robot.toml (see the `rtcan` crate docs and rtcan-codegen/README.md).
#[proc_macro]
pub fn robot(input: TokenStream) -> TokenStream {
    let input = match syn::parse::<Input>(input) {
        Ok(i) => i,
        Err(e) => return e.to_compile_error().into(),
    };
    let caller = proc_macro::Span::call_site().local_file();
    expand(&input, caller).into()
}

/// `rel` under the calling crate's manifest directory; if no such file exists there,
/// under the nearest ancestor directory of the calling source file that has it. The
/// fallback is what lets a crate compiled elsewhere from this crate's sources (trybuild
/// UI tests build `tests/ui/*.rs` in a scratch crate under `target/`) find its robot.
fn resolve(rel: &str, caller: Option<PathBuf>) -> PathBuf {
    let base = std::env::var_os("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .unwrap_or_default();
    let primary = base.join(rel);
    if primary.exists() {
        return primary;
    }
    caller
        .as_deref()
        .and_then(|file| {
            file.ancestors()
                .skip(1)
                .map(|dir| dir.join(rel))
                .find(|p| p.is_file())
        })
        .unwrap_or(primary)
}

fn expand(input: &Input, caller: Option<PathBuf>) -> proc_macro2::TokenStream {
    let span = input.file.span();
    let rel = input.file.value();
    let abs = resolve(&rel, caller);
    // Diagnostics name the file as written, so messages are the same on every machine.
    // With its robot.lock, like build.rs and the CLI (stable allocation).
    let analysis = rtcan_model::read_analysis(&abs, &rel);
    let plan = match analysis.plan {
        Some(p) if analysis.diagnostics.is_empty() => p,
        _ => {
            let d = &analysis.diagnostics;
            let index = d.index();
            let errs = d
                .items
                .iter()
                .take(rtcan_model::diag::MAX_RENDERED)
                .map(|item| error(span, &compile_message(d, &index, item)));
            let rest = d.omitted().map(|n| {
                error(
                    span,
                    &format!(
                        "{n} more error(s) in {} not shown; `rtcan check {}` lists them all",
                        d.file, d.file
                    ),
                )
            });
            return quote! { #(#errs)* #rest };
        }
    };
    let opts = rtcan_codegen::Options {
        kick: input.kick.as_ref().map(|k| quote!(#k)),
    };
    let code = rtcan_codegen::generate(&plan, &opts);
    let abs_str = abs.display().to_string();
    quote! {
        // Rebuild when the robot description changes.
        const _: &[u8] = include_bytes!(#abs_str);
        #code
    }
}

/// The model's rustc-style rendering, with its `error[code]: message` header turned into
/// `message [code]`, because rustc already prints `error: ` before a `compile_error!`.
fn compile_message(
    d: &rtcan_model::Diagnostics,
    index: &rtcan_model::diag::LineIndex,
    item: &rtcan_model::Diagnostic,
) -> String {
    let rendered = d.render_one_with(index, item);
    let body = rendered.split_once('\n').map_or("", |(_, rest)| rest);
    format!(
        "{} [{}]\n{}",
        item.message,
        item.code.name(),
        body.trim_end()
    )
}

fn error(span: Span, msg: &str) -> proc_macro2::TokenStream {
    quote::quote_spanned! { span => ::core::compile_error!(#msg); }
}
