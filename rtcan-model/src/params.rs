//! Typed parameters (docs/SERVICES.md §2): `[params.<node or module>]` tables whose
//! entries are inline tables `{ type, default, min, max, unit, persist }`, e.g.
//! `kp = { type = "f32", default = 0.5, min = 0.0, max = 10.0, persist = true }`.
//! Validated with the rest of robot.toml (`analyze`): every error has a span and a hint.
use crate::diag::{Code, Diagnostic, Diagnostics};
use crate::model::Model;
use crate::syntax::{Entry, Kind, Node};

/// A parameter's type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamTy {
    F32,
    I32,
    U32,
    Bool,
}

impl ParamTy {
    fn parse(s: &str) -> Option<ParamTy> {
        Some(match s {
            "f32" => ParamTy::F32,
            "i32" => ParamTy::I32,
            "u32" => ParamTy::U32,
            "bool" => ParamTy::Bool,
            _ => return None,
        })
    }

    /// The robot.toml spelling.
    pub fn name(self) -> &'static str {
        match self {
            ParamTy::F32 => "f32",
            ParamTy::I32 => "i32",
            ParamTy::U32 => "u32",
            ParamTy::Bool => "bool",
        }
    }

    /// Whether `v` is representable (integers exactly, f32 finite).
    pub fn holds(self, v: f64) -> bool {
        match self {
            ParamTy::F32 => v.is_finite() && v.abs() <= f64::from(f32::MAX),
            ParamTy::I32 => v.fract() == 0.0 && (-2_147_483_648.0..=2_147_483_647.0).contains(&v),
            ParamTy::U32 => v.fract() == 0.0 && (0.0..=4_294_967_295.0).contains(&v),
            ParamTy::Bool => v == 0.0 || v == 1.0,
        }
    }
}

/// One declared parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamDecl {
    /// `owner.name` (owner: the node or module of the table).
    pub name: String,
    /// Module serving it.
    pub module: usize,
    /// Index among its module's parameters (declaration order: the wire index).
    pub index: u16,
    pub ty: ParamTy,
    /// Values as f64 (exact for every declared type; bool 0/1).
    pub default: f64,
    pub min: f64,
    pub max: f64,
    pub unit: String,
    pub persist: bool,
}

const PARAM_KEYS: &[&str] = &["type", "default", "min", "max", "unit", "persist"];

fn number(n: &Node, ty: ParamTy) -> Option<f64> {
    match (&n.kind, ty) {
        (Kind::Bool(b), ParamTy::Bool) => Some(f64::from(u8::from(*b))),
        (Kind::Int(i), ParamTy::F32 | ParamTy::I32 | ParamTy::U32) => Some(*i as f64),
        (Kind::Float(f), ParamTy::F32) => Some(*f),
        _ => None,
    }
}

fn err(code: Code, n: &Node, msg: String, help: &str) -> Diagnostic {
    Diagnostic::new(code, n.span.clone(), msg).help(help)
}

/// Reads `[params]` of `root`; errors go to `items`.
pub fn validate(root: &[Entry], model: &Model, items: &mut Vec<Diagnostic>) -> Vec<ParamDecl> {
    let mut out = Vec::new();
    let Some(top) = root.iter().find(|e| e.key == "params") else {
        return out;
    };
    let Kind::Table(owners) = &top.value.kind else {
        items.push(err(
            Code::WrongType,
            &top.value,
            format!(
                "`params` must be a table, found {}",
                top.value.kind.type_name()
            ),
            "write `[params.<node>]` tables",
        ));
        return out;
    };
    let mut per_module: Vec<u16> = vec![0; model.modules.len()];
    for owner in owners {
        let module = model
            .nodes
            .iter()
            .find(|n| n.name == owner.key)
            .map(|n| n.module)
            .or_else(|| model.modules.iter().position(|m| m.name == owner.key));
        let Some(module) = module else {
            items.push(
                Diagnostic::new(
                    Code::UnknownNode,
                    owner.key_span.clone(),
                    format!("`params.{}`: no node or module of that name", owner.key),
                )
                .help("parameters belong to a node (`[nodes.x]`) or a module (`[modules.x]`)"),
            );
            continue;
        };
        let Kind::Table(params) = &owner.value.kind else {
            items.push(err(
                Code::WrongType,
                &owner.value,
                format!("`params.{}` must be a table", owner.key),
                "e.g. `[params.pid1]` then `kp = { type = \"f32\", default = 0.5, min = 0.0, max = 10.0 }`",
            ));
            continue;
        };
        for p in params {
            let what = format!("`params.{}.{}`", owner.key, p.key);
            if let Some(d) = decl(p, &what, items) {
                let Some(idx) = per_module.get_mut(module) else {
                    continue;
                };
                out.push(ParamDecl {
                    name: format!("{}.{}", owner.key, p.key),
                    module,
                    index: *idx,
                    ..d
                });
                *idx = idx.saturating_add(1);
            }
        }
    }
    out
}

fn decl(p: &Entry, what: &str, items: &mut Vec<Diagnostic>) -> Option<ParamDecl> {
    let Kind::Table(keys) = &p.value.kind else {
        items.push(err(
            Code::WrongType,
            &p.value,
            format!("{what} must be a table, found {}", p.value.kind.type_name()),
            "e.g. `kp = { type = \"f32\", default = 0.5, min = 0.0, max = 10.0 }`",
        ));
        return None;
    };
    let before = items.len();
    for e in keys {
        if !PARAM_KEYS.contains(&e.key.as_str()) {
            items.push(
                Diagnostic::new(
                    Code::UnknownKey,
                    e.key_span.clone(),
                    format!("unknown key `{}` in {what}", e.key),
                )
                .help("expected one of `type`, `default`, `min`, `max`, `unit`, `persist`"),
            );
        }
    }
    let get = |k: &str| keys.iter().find(|e| e.key == k).map(|e| &e.value);
    let ty = match get("type") {
        Some(n) => match &n.kind {
            Kind::Str(s) => match ParamTy::parse(s) {
                Some(t) => Some(t),
                None => {
                    items.push(err(
                        Code::BadValue,
                        n,
                        format!("{what}: unknown parameter type `{s}`"),
                        "expected one of `f32`, `i32`, `u32`, `bool`",
                    ));
                    None
                }
            },
            _ => {
                items.push(err(
                    Code::WrongType,
                    n,
                    format!("{what}: `type` must be a string"),
                    "e.g. `type = \"f32\"`",
                ));
                None
            }
        },
        None => {
            items.push(err(
                Code::MissingKey,
                &p.value,
                format!("{what} has no `type`"),
                "add `type = \"f32\"` (or i32, u32, bool)",
            ));
            None
        }
    }?;
    let mut val = |k: &str, fallback: Option<f64>| -> Option<f64> {
        match get(k) {
            Some(n) => match number(n, ty) {
                Some(v) if ty.holds(v) => Some(v),
                _ => {
                    items.push(err(
                        Code::BadValue,
                        n,
                        format!("{what}: `{k}` is not a {} value", ty.name()),
                        "integers for i32/u32 (in their range), a number for f32, true/false for bool",
                    ));
                    None
                }
            },
            None => match fallback {
                Some(v) => Some(v),
                None => {
                    items.push(err(
                        Code::MissingKey,
                        &p.value,
                        format!("{what} has no `{k}`"),
                        "every parameter declares its default",
                    ));
                    None
                }
            },
        }
    };
    let (lo, hi) = match ty {
        ParamTy::F32 => (-f64::from(f32::MAX), f64::from(f32::MAX)),
        ParamTy::I32 => (-2_147_483_648.0, 2_147_483_647.0),
        ParamTy::U32 => (0.0, 4_294_967_295.0),
        ParamTy::Bool => (0.0, 1.0),
    };
    let default = val("default", None);
    let min = val("min", Some(lo));
    let max = val("max", Some(hi));
    let unit = match get("unit").map(|n| (&n.kind, n)) {
        None => String::new(),
        Some((Kind::Str(s), _)) => s.clone(),
        Some((_, n)) => {
            items.push(err(
                Code::WrongType,
                n,
                format!("{what}: `unit` must be a string"),
                "e.g. `unit = \"rad/s\"`",
            ));
            String::new()
        }
    };
    let persist = match get("persist").map(|n| (&n.kind, n)) {
        None => false,
        Some((Kind::Bool(b), _)) => *b,
        Some((_, n)) => {
            items.push(err(
                Code::WrongType,
                n,
                format!("{what}: `persist` must be true or false"),
                "persisted parameters survive a reset (flash)",
            ));
            false
        }
    };
    let (default, min, max) = (default?, min?, max?);
    if !(min <= default && default <= max) {
        items.push(err(
            Code::BadValue,
            get("default").unwrap_or(&p.value),
            format!("{what}: default {default} outside [{min}, {max}]"),
            "the default must lie within `min` ..= `max`",
        ));
    }
    if items.len() > before {
        return None;
    }
    Some(ParamDecl {
        name: String::new(),
        module: 0,
        index: 0,
        ty,
        default,
        min,
        max,
        unit,
        persist,
    })
}

/// Parses and validates `source` and returns its plan and parameters (for `rtcan param`):
/// the parameters are the plan's (`Plan::params`, read once by `analyze`).
pub fn load(file: &str, source: &str) -> Result<(crate::Plan, Vec<ParamDecl>), Diagnostics> {
    let a = crate::analyze(file, source);
    let (Some(_), Some(plan)) = (a.model, a.plan) else {
        return Err(a.diagnostics);
    };
    if !a.diagnostics.items.is_empty() {
        return Err(a.diagnostics);
    }
    let params = plan.params.clone();
    Ok((plan, params))
}
