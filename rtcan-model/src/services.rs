//! Request/reply services (docs/SERVICES.md §3): `[services.NAME]` tables naming a
//! request and a reply type (a `[types]` name or an inline field table), the server
//! node, the client node, the call timeout and the per-message deadline.
//!
//! A service is carried by two SRT topics appended after the declared ones, so message
//! IDs, filters, tables, pools and the lock all follow from the topic machinery:
//! `NAME_request` (client → server) and `NAME_reply` (server → client). Their message
//! types are frame types `<Name>RequestFrame` / `<Name>ReplyFrame`: the call number
//! (`call: u16`, rtcan_pubsub::service's framing) then the payload's fields.
use crate::diag::{Code, Diagnostic, Span};
use crate::model::{Field, FieldType, Model, MsgType, Prim, Subscriber, Topic, TopicSpans};
use crate::syntax::{Entry, Kind, Node};
use crate::{names, units, validate};
use rtcan_core::fragment::MAX_PAYLOAD;
use rtcan_core::Class;

const SERVICE_KEYS: &[&str] = &[
    "request",
    "reply",
    "server",
    "client",
    "timeout",
    "deadline",
    "rate",
    "in_flight",
];

/// Most calls one client keeps in flight (the server's request queue has as many).
pub const MAX_IN_FLIGHT: i64 = 8;
/// Calls in flight when `in_flight` is not given.
pub const DEFAULT_IN_FLIGHT: u16 = 2;
/// Name of the call-number field every frame type starts with.
pub const CALL_FIELD: &str = "call";

/// One validated service.
#[derive(Clone, Debug, PartialEq)]
pub struct Service {
    /// Name (snake_case).
    pub name: String,
    /// Request payload type (index into the types).
    pub request_ty: usize,
    /// Reply payload type.
    pub reply_ty: usize,
    /// Topic carrying the request frames (index into the topics).
    pub request_topic: usize,
    /// Topic carrying the reply frames.
    pub reply_topic: usize,
    /// Serving node.
    pub server: usize,
    /// Calling node.
    pub client: usize,
    /// A call without a reply this long after it was made times out, ns.
    pub timeout_ns: u64,
    /// SRT deadline of the request and of the reply, each, ns.
    pub deadline_ns: u64,
    /// Declared average call rate (bus-load check), Hz.
    pub rate_hz: Option<f64>,
    /// Calls the client keeps in flight at most.
    pub in_flight: u16,
    /// Where `[services.NAME]` is.
    pub span: Option<Span>,
}

fn err(code: Code, span: Option<Span>, msg: String, help: &str) -> Diagnostic {
    Diagnostic::new(code, span, msg).help(help)
}

/// Reads `[services]` of `root` into `model` (types, topics and `services`); errors go to
/// `items`. A service with an error adds nothing to the model.
pub fn validate(root: &[Entry], model: &mut Model, items: &mut Vec<Diagnostic>) {
    let Some(top) = root.iter().find(|e| e.key == "services") else {
        return;
    };
    let Kind::Table(services) = &top.value.kind else {
        items.push(err(
            Code::WrongType,
            top.value.span.clone(),
            format!(
                "`services` must be a table, found {}",
                top.value.kind.type_name()
            ),
            "write `[services.<name>]` tables",
        ));
        return;
    };
    for s in services {
        if let Some(svc) = service(s, model, items) {
            model.services.push(svc);
        }
    }
}

/// The node named by a string value, or a diagnostic.
fn node_ref(model: &Model, n: &Node, what: &str, items: &mut Vec<Diagnostic>) -> Option<usize> {
    let Kind::Str(name) = &n.kind else {
        items.push(err(
            Code::WrongType,
            n.span.clone(),
            format!("{what} must be a node name (a string)"),
            "e.g. `server = \"ir_ranger\"`",
        ));
        return None;
    };
    let found = model.nodes.iter().position(|x| &x.name == name);
    if found.is_none() {
        let known: Vec<&str> = model
            .nodes
            .iter()
            .map(|x| x.name.as_str())
            .take(12)
            .collect();
        items.push(
            Diagnostic::new(
                Code::UnknownNode,
                n.span.clone(),
                format!("{what}: no node `{name}`"),
            )
            .help(format!("declared nodes: {}", known.join(", "))),
        );
    }
    found
}

fn duration(n: &Node, what: &str, items: &mut Vec<Diagnostic>) -> Option<u64> {
    match &n.kind {
        Kind::Str(s) => match units::duration_ns(s) {
            Ok(v) => Some(v),
            Err(m) => {
                items.push(err(
                    Code::BadValue,
                    n.span.clone(),
                    format!("{what}: {m}"),
                    "e.g. \"20ms\"",
                ));
                None
            }
        },
        _ => {
            items.push(err(
                Code::WrongType,
                n.span.clone(),
                format!("{what} must be a duration string"),
                "e.g. \"20ms\"",
            ));
            None
        }
    }
}

/// Fields of an inline field table (`{ sensor = "u8" }`).
fn inline_fields(keys: &[Entry], what: &str, items: &mut Vec<Diagnostic>) -> Option<Vec<Field>> {
    let before = items.len();
    let mut fields = Vec::new();
    let mut offset = 0;
    for f in keys {
        let ok_name = f.key.chars().next().is_some_and(|c| c.is_ascii_lowercase())
            && f.key
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
            && !names::is_keyword(&f.key);
        if !ok_name {
            items.push(err(
                Code::BadName,
                f.key_span.clone(),
                format!("{what}: field name `{}` is not a valid name", f.key),
                "field names are snake_case, not a Rust keyword; they become Rust identifiers",
            ));
            continue;
        }
        let Kind::Str(text) = &f.value.kind else {
            items.push(err(
                Code::WrongType,
                f.value.span.clone(),
                format!("{what}: field `{}` must be a type string", f.key),
                "e.g. `range_mm = \"u16\"`",
            ));
            continue;
        };
        match validate::field_type(text) {
            Some(ty) => {
                fields.push(Field {
                    name: f.key.clone(),
                    ty,
                    offset,
                });
                offset += ty.size();
            }
            None => items.push(err(
                Code::UnknownType,
                f.value.span.clone(),
                format!("{what}: unknown field type `{text}` for `{}`", f.key),
                "field types are u8, u16, u32, u64, i8, i16, i32, i64, f32, f64, bool, or an array `[T; N]` of one",
            )),
        }
    }
    (items.len() == before).then_some(fields)
}

/// The payload type of `request`/`reply`: an existing type's index, or a new type
/// `<Name><Suffix>` from an inline table (pushed to `model.types`).
fn payload(
    model: &mut Model,
    n: &Node,
    service: &str,
    suffix: &str,
    items: &mut Vec<Diagnostic>,
) -> Option<usize> {
    let what = format!("`services.{service}.{}`", suffix.to_ascii_lowercase());
    let (fields, name) = match &n.kind {
        Kind::Str(t) => {
            let Some(i) = model.types.iter().position(|x| &x.name == t) else {
                let known: Vec<&str> = model
                    .types
                    .iter()
                    .map(|x| x.name.as_str())
                    .take(12)
                    .collect();
                items.push(
                    Diagnostic::new(
                        Code::UnknownType,
                        n.span.clone(),
                        format!("{what}: no message type `{t}`"),
                    )
                    .help(format!(
                        "name a `[types]` entry ({}) or write the fields inline, e.g. `{{ sensor = \"u8\" }}`",
                        known.join(", ")
                    )),
                );
                return None;
            };
            let fields = model.types.get(i).map(|x| x.fields.clone())?;
            (fields, None::<String>)
        }
        Kind::Table(keys) => (
            inline_fields(keys, &what, items)?,
            Some(names::camel(service) + suffix),
        ),
        other => {
            items.push(err(
                Code::WrongType,
                n.span.clone(),
                format!(
                    "{what} must be a type name or a field table, found {}",
                    other.type_name()
                ),
                "e.g. `request = { sensor = \"u8\" }` or `request = \"Proximity\"`",
            ));
            return None;
        }
    };
    if let Some(f) = fields.iter().find(|f| f.name == CALL_FIELD) {
        items.push(err(
            Code::NameCollision,
            n.span.clone(),
            format!(
                "{what}: field `{}` collides with the call number every service frame starts with",
                f.name
            ),
            "rename the field",
        ));
        return None;
    }
    match name {
        None => model
            .types
            .iter()
            .position(|x| matches!(&n.kind, Kind::Str(t) if &x.name == t)),
        Some(name) => new_type(model, name, fields, n.span.clone(), service, items),
    }
}

/// Pushes a generated type unless its name is taken.
fn new_type(
    model: &mut Model,
    name: String,
    fields: Vec<Field>,
    span: Option<Span>,
    service: &str,
    items: &mut Vec<Diagnostic>,
) -> Option<usize> {
    if model.types.iter().any(|t| t.name == name) {
        items.push(err(
            Code::DuplicateName,
            span,
            format!(
                "service `{service}` needs the message type `{name}`, which is already declared"
            ),
            "rename the service or the type",
        ));
        return None;
    }
    let size = fields.iter().map(|f| f.ty.size()).sum();
    model.types.push(MsgType {
        name,
        fields,
        size,
        span,
    });
    Some(model.types.len() - 1)
}

/// The frame type: the call number, then `payload`'s fields shifted by its 2 bytes.
fn frame_type(
    model: &mut Model,
    payload: usize,
    name: String,
    span: Option<Span>,
    service: &str,
    items: &mut Vec<Diagnostic>,
) -> Option<usize> {
    let p = model.types.get(payload)?;
    let call = FieldType {
        prim: Prim::U16,
        len: None,
    };
    let mut fields = vec![Field {
        name: CALL_FIELD.to_string(),
        ty: call,
        offset: 0,
    }];
    fields.extend(p.fields.iter().map(|f| Field {
        offset: f.offset + call.size(),
        ..f.clone()
    }));
    let size = p.size + call.size();
    if size > MAX_PAYLOAD {
        items.push(err(
            Code::PayloadTooLarge,
            span,
            format!("service `{service}`: `{name}` is {size} bytes (2 for the call number); a message carries at most {MAX_PAYLOAD}"),
            "make the request or reply smaller",
        ));
        return None;
    }
    new_type(model, name, fields, span, service, items)
}

fn service(s: &Entry, model: &mut Model, items: &mut Vec<Diagnostic>) -> Option<Service> {
    let name = &s.key;
    let name_ok = name.chars().next().is_some_and(|c| c.is_ascii_lowercase())
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
        && !names::is_keyword(name);
    if !name_ok {
        items.push(err(
            Code::BadName,
            s.key_span.clone(),
            format!("service name `{name}` is not a valid name"),
            "service names are snake_case, e.g. `sonar_read`; they become Rust identifiers",
        ));
        return None;
    }
    let Kind::Table(keys) = &s.value.kind else {
        items.push(err(
            Code::WrongType,
            s.value.span.clone(),
            format!("`services.{name}` must be a table"),
            "e.g. `[services.sonar_read]` with `request`, `reply`, `server`, `client`, `timeout`",
        ));
        return None;
    };
    let before = items.len();
    for e in keys {
        if !SERVICE_KEYS.contains(&e.key.as_str()) {
            items.push(err(
                Code::UnknownKey,
                e.key_span.clone(),
                format!("unknown key `{}` in `services.{name}`", e.key),
                "expected one of `request`, `reply`, `server`, `client`, `timeout`, `deadline`, `rate`, `in_flight`",
            ));
        }
    }
    let get = |k: &str| keys.iter().find(|e| e.key == k);
    let missing = |k: &str, example: &str, items: &mut Vec<Diagnostic>| {
        items.push(err(
            Code::MissingKey,
            s.key_span.clone(),
            format!("`services.{name}` has no `{k}`"),
            example,
        ));
    };
    let server = match get("server") {
        Some(e) => node_ref(model, &e.value, &format!("`services.{name}.server`"), items),
        None => {
            missing(
                "server",
                "add `server = \"<node>\"`: the node that answers",
                items,
            );
            None
        }
    };
    let client = match get("client") {
        Some(e) => node_ref(model, &e.value, &format!("`services.{name}.client`"), items),
        None => {
            missing("client", "add `client = \"<node>\"`: the node that calls (one per service; declare another service for another client)", items);
            None
        }
    };
    let timeout = match get("timeout") {
        Some(e) => duration(&e.value, &format!("`services.{name}.timeout`"), items),
        None => {
            missing(
                "timeout",
                "add `timeout = \"20ms\"`: how long a call waits for its reply",
                items,
            );
            None
        }
    };
    let deadline = match get("deadline") {
        Some(e) => duration(&e.value, &format!("`services.{name}.deadline`"), items).map(Some),
        None => Some(None),
    };
    let rate_hz = match get("rate").map(|e| &e.value) {
        None => None,
        Some(n) => match &n.kind {
            Kind::Str(t) => match units::frequency_hz(t) {
                Ok(v) => Some(v),
                Err(m) => {
                    items.push(err(
                        Code::BadValue,
                        n.span.clone(),
                        format!("`services.{name}.rate`: {m}"),
                        "e.g. \"10Hz\": calls per second, for the bus-load check",
                    ));
                    None
                }
            },
            _ => {
                items.push(err(
                    Code::WrongType,
                    n.span.clone(),
                    format!("`services.{name}.rate` must be a frequency string"),
                    "e.g. \"10Hz\"",
                ));
                None
            }
        },
    };
    let in_flight = match get("in_flight").map(|e| &e.value) {
        None => Some(DEFAULT_IN_FLIGHT),
        Some(n) => match n.kind {
            Kind::Int(k) if (1..=MAX_IN_FLIGHT).contains(&k) => u16::try_from(k).ok(),
            _ => {
                items.push(err(
                    Code::BadValue,
                    n.span.clone(),
                    format!("`services.{name}.in_flight` must be an integer 1..={MAX_IN_FLIGHT}"),
                    "calls one client keeps in flight; the server queues as many requests",
                ));
                None
            }
        },
    };
    let req_payload = match get("request") {
        Some(e) => payload(model, &e.value, name, "Request", items),
        None => {
            missing(
                "request",
                "add `request = { field = \"type\", ... }` or a `[types]` name",
                items,
            );
            None
        }
    };
    let rep_payload = match get("reply") {
        Some(e) => payload(model, &e.value, name, "Reply", items),
        None => {
            missing(
                "reply",
                "add `reply = { field = \"type\", ... }` or a `[types]` name",
                items,
            );
            None
        }
    };
    let (Some(server), Some(client), Some(timeout_ns), Some(deadline), Some(in_flight)) =
        (server, client, timeout, deadline, in_flight)
    else {
        return None;
    };
    // A call is a request and a reply, each allowed up to the deadline: a timeout shorter
    // than both would give up on replies that are still on time.
    let deadline_ns = deadline.unwrap_or(timeout_ns / 2).max(1);
    if timeout_ns < 2 * deadline_ns {
        let span = get("timeout").and_then(|e| e.value.span.clone());
        items.push(
            err(
                Code::BadValue,
                span,
                format!(
                    "`services.{name}`: timeout {} is shorter than a round trip at the deadline ({} for the request and {} for the reply)",
                    units::fmt_ns(timeout_ns as f64),
                    units::fmt_ns(deadline_ns as f64),
                    units::fmt_ns(deadline_ns as f64)
                ),
                "make `timeout` at least twice `deadline`",
            ),
        );
    }
    if server == client {
        items.push(err(
            Code::BadValue,
            get("client").and_then(|e| e.value.span.clone()),
            format!("`services.{name}`: the client is the server"),
            "a node calls another node's service; call the function directly instead",
        ));
    }
    let topic_names = [format!("{name}_request"), format!("{name}_reply")];
    for t in &topic_names {
        let alias = names::topic_alias(t);
        if model
            .topics
            .iter()
            .any(|x| &x.name == t || names::topic_alias(&x.name) == alias)
        {
            items.push(err(
                Code::DuplicateName,
                s.key_span.clone(),
                format!("service `{name}` needs the topic `{t}`, which is already declared"),
                "rename the service or the topic",
            ));
        }
    }
    let (Some(req_payload), Some(rep_payload)) = (req_payload, rep_payload) else {
        return None;
    };
    if items.len() > before {
        return None;
    }
    let camel = names::camel(name);
    let req_frame = frame_type(
        model,
        req_payload,
        camel.clone() + "RequestFrame",
        s.key_span.clone(),
        name,
        items,
    )?;
    let rep_frame = frame_type(
        model,
        rep_payload,
        camel + "ReplyFrame",
        s.key_span.clone(),
        name,
        items,
    )?;
    // Each message must fit its deadline on the wire.
    for fr in [req_frame, rep_frame] {
        let size = model.types.get(fr).map_or(0, |t| t.size);
        let tx = validate::message_ns(size, model.bus.bitrate);
        if deadline_ns < tx {
            items.push(err(
                Code::SrtDeadlineTooShort,
                get("deadline").and_then(|e| e.value.span.clone()),
                format!(
                    "service `{name}`: deadline {} is shorter than a {size}-byte frame's transmission ({} worst case)",
                    units::fmt_ns(deadline_ns as f64),
                    units::fmt_ns(tx as f64)
                ),
                "raise `deadline`",
            ));
            return None;
        }
    }
    let spans = TopicSpans {
        name: s.key_span.clone(),
        timing: get("rate").and_then(|e| e.value.span.clone()),
        deadline: get("deadline").and_then(|e| e.value.span.clone()),
    };
    let topic = |tname: &str, ty: usize, from: usize, to: usize| Topic {
        name: tname.to_string(),
        ty,
        publisher: from,
        class: Class::Srt,
        period_slots: None,
        requested_period_ns: None,
        deadline_ns: Some(deadline_ns),
        rate_hz,
        lead_ns: None,
        subscribers: vec![Subscriber {
            node: to,
            queue: in_flight,
            span: s.key_span.clone(),
        }],
        spans: spans.clone(),
    };
    let [req_name, rep_name] = &topic_names;
    model
        .topics
        .push(topic(req_name, req_frame, client, server));
    let request_topic = model.topics.len() - 1;
    model
        .topics
        .push(topic(rep_name, rep_frame, server, client));
    Some(Service {
        name: name.clone(),
        request_ty: req_payload,
        reply_ty: rep_payload,
        request_topic,
        reply_topic: request_topic + 1,
        server,
        client,
        timeout_ns,
        deadline_ns,
        rate_hz,
        in_flight,
        span: s.key_span.clone(),
    })
}
