//! Message structs: plain data, fields in robot.toml order, little-endian and packed on
//! the wire (the model's field offsets are exactly the running sum of the field sizes).
use crate::{lit, names};
use proc_macro2::TokenStream;
use quote::quote;
use rtcan_model::{FieldType, MsgType, Prim};

fn rust_type(t: FieldType) -> TokenStream {
    let prim = names::ident(t.prim.name());
    match t.len {
        Some(n) => {
            let n = lit::int(n);
            quote! { [#prim; #n] }
        }
        None => quote! { #prim },
    }
}

/// The struct, its `Default` (all zero) and its `Message` impl.
pub fn message(ty: &MsgType) -> TokenStream {
    let name = names::ident(&ty.name);
    let size = lit::usize(ty.size);
    let fields: Vec<_> = ty.fields.iter().map(|f| names::ident(&f.name)).collect();
    let types: Vec<_> = ty.fields.iter().map(|f| rust_type(f.ty)).collect();
    let docs: Vec<String> = ty
        .fields
        .iter()
        .map(|f| {
            format!(
                "`{}`, bytes {}..{} (little-endian).",
                f.ty.rust(),
                f.offset,
                f.offset + f.ty.size()
            )
        })
        .collect();
    let floats = ty
        .fields
        .iter()
        .any(|f| matches!(f.ty.prim, Prim::F32 | Prim::F64));
    let eq = if floats { quote!() } else { quote!(, Eq, Hash) };
    let doc = format!(
        "Message type `{}` of robot.toml: {} bytes on the wire.",
        ty.name, ty.size
    );
    quote! {
        #[doc = #doc]
        #[derive(Clone, Copy, Debug, PartialEq #eq)]
        pub struct #name {
            #(#[doc = #docs] pub #fields: #types,)*
        }

        impl ::core::default::Default for #name {
            fn default() -> Self {
                #name { #(#fields: <#types as ::rtcan::wire::Field>::ZERO,)* }
            }
        }

        impl ::rtcan::pubsub::Message for #name {
            const SIZE: usize = #size;
            type Wire = [u8; #size];
            fn encode(&self, out: &mut [u8]) {
                let mut w = ::rtcan::wire::Writer::new(out);
                #(::rtcan::wire::Field::put(&self.#fields, &mut w);)*
                let _ = &mut w;
            }
            fn decode(bytes: &[u8]) -> ::core::option::Option<Self> {
                if bytes.len() != #size {
                    return ::core::option::Option::None;
                }
                let mut r = ::rtcan::wire::Reader::new(bytes);
                let _ = &mut r;
                ::core::option::Option::Some(#name {
                    #(#fields: <#types as ::rtcan::wire::Field>::take(&mut r)?,)*
                })
            }
        }
    }
}
