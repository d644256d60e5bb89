//! `pub mod services` inside a module: a typed client handle per service one of the
//! module's nodes calls, and a server handle per service it serves (robot.toml
//! `[services]`, docs/SERVICES.md §3).
//!
//! Both are plain values the task owns (no static state: a call table is mutable, and
//! firmware code has no `static mut`). They ride on the module's two service topics:
//! the client publishes `<Name>RequestFrame`s (call number + request) and matches the
//! `<Name>ReplyFrame`s it receives with `rtcan::pubsub::service::Client`, which also
//! times the calls out; the server answers each request frame with the same call number.
use crate::{lit, names};
use proc_macro2::TokenStream;
use quote::quote;
use rtcan_model::services::Service;
use rtcan_model::{MsgType, Plan};

/// Subscriber slot of `node` on topic `topic` on module `mi` (the generated topics
/// number their local subscribers in robot.toml order).
fn slot(plan: &Plan, topic: usize, mi: usize, node: usize) -> Option<usize> {
    plan.topics
        .get(topic)?
        .subscribers
        .iter()
        .filter(|s| s.module == mi)
        .position(|s| s.node == node)
}

fn ty(plan: &Plan, i: usize) -> Option<&MsgType> {
    plan.types.get(i)
}

/// `Payload { a: frame.a, b: frame.b }` and `Frame { call, a: payload.a, ... }`.
fn moves(payload: &MsgType, from: &TokenStream) -> Vec<TokenStream> {
    payload
        .fields
        .iter()
        .map(|f| {
            let n = names::ident(&f.name);
            quote! { #n: #from.#n }
        })
        .collect()
}

fn client(plan: &Plan, s: &Service, mi: usize) -> Option<TokenStream> {
    let req = ty(plan, s.request_ty)?;
    let rep = ty(plan, s.reply_ty)?;
    let req_topic = plan.topics.get(s.request_topic)?;
    let rep_topic = plan.topics.get(s.reply_topic)?;
    let req_frame = names::ident(&ty(plan, req_topic.ty)?.name);
    let (req_ty, rep_ty) = (names::ident(&req.name), names::ident(&rep.name));
    let handle = names::camel_suffixed(&s.name, "Client");
    let req_static = names::upper(&req_topic.name);
    let rep_static = names::upper(&rep_topic.name);
    let sub_slot = lit::usize(slot(plan, s.reply_topic, mi, s.client)?);
    let n = lit::usize(usize::from(s.in_flight));
    let timeout = lit::int(s.timeout_ns);
    let req_size = lit::usize(req.size);
    let rep_size = lit::usize(rep.size + 2);
    let fill = moves(req, &quote!(request));
    let take = moves(rep, &quote!(frame));
    let server = plan.nodes.get(s.server).map_or("?", |x| x.name.as_str());
    let client = plan.nodes.get(s.client).map_or("?", |x| x.name.as_str());
    let doc = format!(
        "Client of service `{}` (called by node `{client}`, served by `{server}`): at most {} calls in flight, each timed out {} ns after it was made; request and reply are SRT with a {} ns deadline each. Own it in the calling task.",
        s.name, s.in_flight, s.timeout_ns, s.deadline_ns
    );
    Some(quote! {
        #[doc = #doc]
        pub struct #handle {
            inner: ::rtcan::pubsub::service::Client<#n>,
        }

        impl ::core::default::Default for #handle {
            fn default() -> Self {
                Self::new()
            }
        }

        impl #handle {
            /// Calls one client keeps in flight (robot.toml `in_flight`).
            pub const IN_FLIGHT: usize = #n;
            /// The call timeout, ns (robot.toml `timeout`).
            pub const TIMEOUT_NS: ::rtcan::core::Nanos = #timeout;

            /// No call in flight.
            pub const fn new() -> Self {
                #handle { inner: ::rtcan::pubsub::service::Client::new(#timeout) }
            }

            /// Sends `request` at local time `now`; its reply or its timeout comes out of
            /// [`Self::poll`] with the returned call number. `Busy` with `IN_FLIGHT`
            /// calls in flight; `NotSent` when the request could not be queued.
            pub fn call(
                &mut self,
                now: ::rtcan::core::Nanos,
                request: &super::super::#req_ty,
            ) -> ::core::result::Result<::rtcan::pubsub::service::CallId, ::rtcan::pubsub::service::CallError> {
                let mut body = [0u8; #req_size];
                ::rtcan::pubsub::Message::encode(request, &mut body);
                let mut framed = [0u8; #req_size + 2];
                let (id, _) = self.inner.call(now, &body, &mut framed)?;
                let frame = super::super::#req_frame { call: id.0, #(#fill,)* };
                match super::topics::#req_static.publisher().send(frame, now) {
                    ::core::result::Result::Ok(()) => ::core::result::Result::Ok(id),
                    ::core::result::Result::Err(_) => {
                        self.inner.cancel(id);
                        ::core::result::Result::Err(::rtcan::pubsub::service::CallError::NotSent)
                    }
                }
            }

            /// The next outcome at local time `now`: a reply that arrived before its
            /// call's deadline (late, unknown and duplicate replies are counted and
            /// dropped), else a call whose deadline passed; `None` when neither.
            pub fn poll(
                &mut self,
                now: ::rtcan::core::Nanos,
            ) -> ::core::option::Option<::rtcan::pubsub::service::Event<super::super::#rep_ty>> {
                let sub = super::topics::#rep_static.subscriber::<#sub_slot>();
                while let ::core::option::Option::Some(m) = sub.try_recv() {
                    let (frame, at) = (*m, m.stamp());
                    drop(m);
                    let mut bytes = [0u8; #rep_size];
                    ::rtcan::pubsub::Message::encode(&frame, &mut bytes);
                    if let ::core::option::Option::Some((id, _)) = self.inner.on_reply(at, &bytes) {
                        let reply = super::super::#rep_ty { #(#take,)* };
                        return ::core::option::Option::Some(::rtcan::pubsub::service::Event::Reply(id, reply));
                    }
                }
                self.inner
                    .expire_one(now)
                    .map(::rtcan::pubsub::service::Event::TimedOut)
            }

            /// [`Self::call`], then waits for that call's reply: `Ok(reply)`, or
            /// `Err(CallError::TimedOut)` once its timeout passed. `now` reads the local
            /// clock; `wait(until)` is the caller's sleep until at most `until` (the
            /// call's deadline), e.g. RTIC's `Mono::delay_until`, or a wait on the reply
            /// topic raced against it: after each the client polls again. The call owns
            /// the client while it waits: with another call in flight it returns `Busy`
            /// rather than take that call's outcome.
            pub async fn call_async<W: ::core::future::Future<Output = ()>>(
                &mut self,
                request: &super::super::#req_ty,
                mut now: impl FnMut() -> ::rtcan::core::Nanos,
                mut wait: impl FnMut(::rtcan::core::Nanos) -> W,
            ) -> ::core::result::Result<super::super::#rep_ty, ::rtcan::pubsub::service::CallError> {
                if self.inner.in_flight() > 0 {
                    return ::core::result::Result::Err(::rtcan::pubsub::service::CallError::Busy);
                }
                let id = self.call(now(), request)?;
                loop {
                    let t = now();
                    match self.poll(t) {
                        ::core::option::Option::Some(::rtcan::pubsub::service::Event::Reply(got, reply)) if got == id => {
                            return ::core::result::Result::Ok(reply);
                        }
                        ::core::option::Option::Some(::rtcan::pubsub::service::Event::TimedOut(got)) if got == id => {
                            return ::core::result::Result::Err(::rtcan::pubsub::service::CallError::TimedOut);
                        }
                        // Only this call is in flight: nothing else can come out.
                        _ => {}
                    }
                    wait(self.inner.next_deadline().unwrap_or(t)).await;
                }
            }

            /// Calls, replies, timeouts, late or unknown replies, refusals.
            pub fn counters(&self) -> ::rtcan::pubsub::service::ClientCounters {
                self.inner.counters
            }

            /// Three calls in a row timed out and no reply came since.
            pub fn server_absent(&self) -> bool {
                self.inner.server_absent()
            }

            /// Calls in flight.
            pub fn in_flight(&self) -> usize {
                self.inner.in_flight()
            }

            /// The earliest deadline in flight: when to `poll` at the latest.
            pub fn next_deadline(&self) -> ::core::option::Option<::rtcan::core::Nanos> {
                self.inner.next_deadline()
            }
        }
    })
}

fn server(plan: &Plan, s: &Service, mi: usize) -> Option<TokenStream> {
    let req = ty(plan, s.request_ty)?;
    let rep = ty(plan, s.reply_ty)?;
    let req_topic = plan.topics.get(s.request_topic)?;
    let rep_topic = plan.topics.get(s.reply_topic)?;
    let rep_frame = names::ident(&ty(plan, rep_topic.ty)?.name);
    let (req_ty, rep_ty) = (names::ident(&req.name), names::ident(&rep.name));
    let handle = names::camel_suffixed(&s.name, "Server");
    let req_static = names::upper(&req_topic.name);
    let rep_static = names::upper(&rep_topic.name);
    let sub_slot = lit::usize(slot(plan, s.request_topic, mi, s.server)?);
    let take = moves(req, &quote!(frame));
    let fill = moves(rep, &quote!(reply));
    let server = plan.nodes.get(s.server).map_or("?", |x| x.name.as_str());
    let doc = format!(
        "Server of service `{}` (node `{server}`): answers each queued request with the handler's reply, under the request's call number. Own it in the serving task.",
        s.name
    );
    Some(quote! {
        #[doc = #doc]
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        pub struct #handle {
            /// Requests answered.
            pub served: u32,
            /// Replies that could not be queued for sending (the client times out).
            pub not_sent: u32,
        }

        impl #handle {
            /// Nothing served yet.
            pub const fn new() -> Self {
                #handle { served: 0, not_sent: 0 }
            }

            /// Answers every request received so far with `handler`, at local time
            /// `now`; returns how many replies were queued.
            pub fn serve(
                &mut self,
                now: ::rtcan::core::Nanos,
                mut handler: impl FnMut(&super::super::#req_ty) -> super::super::#rep_ty,
            ) -> usize {
                let sub = super::topics::#req_static.subscriber::<#sub_slot>();
                let publisher = super::topics::#rep_static.publisher();
                let mut queued = 0;
                while let ::core::option::Option::Some(m) = sub.try_recv() {
                    let frame = *m;
                    drop(m);
                    let request = super::super::#req_ty { #(#take,)* };
                    let reply = handler(&request);
                    let out = super::super::#rep_frame { call: frame.call, #(#fill,)* };
                    match publisher.send(out, now) {
                        ::core::result::Result::Ok(()) => {
                            self.served = self.served.wrapping_add(1);
                            queued += 1;
                        }
                        ::core::result::Result::Err(_) => {
                            self.not_sent = self.not_sent.wrapping_add(1);
                        }
                    }
                }
                queued
            }
        }
    })
}

/// `pub mod services` of module `mi` (empty when it has no service).
pub fn module_services(plan: &Plan, mi: usize) -> TokenStream {
    let node_module = |n: usize| plan.nodes.get(n).map(|x| x.module);
    let items = plan.services.iter().flat_map(|s| {
        let mut out = Vec::new();
        if node_module(s.client) == Some(mi) {
            out.extend(client(plan, s, mi));
        }
        if node_module(s.server) == Some(mi) {
            out.extend(server(plan, s, mi));
        }
        out
    });
    quote! {
        /// Request/reply services this module calls or serves (robot.toml `[services]`).
        pub mod services {
            #(#items)*
        }
    }
}
