//! TOML → a small tree where every key and value keeps its byte span. Validation walks
//! this tree, so it never depends on toml_edit's API beyond this file.
use crate::diag::Span;
use toml_edit::{ImDocument, Item, Table, Value};

/// A value with its location.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// Where the value is (for implicit tables: where their key is).
    pub span: Option<Span>,
    /// The value.
    pub kind: Kind,
}

/// TOML value kinds the schema uses (datetimes are kept only to be rejected).
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// String.
    Str(String),
    /// Integer.
    Int(i64),
    /// Float.
    Float(f64),
    /// Boolean.
    Bool(bool),
    /// Array (of values or of tables).
    Array(Vec<Node>),
    /// Table or inline table, in file order.
    Table(Vec<Entry>),
    /// A date/time.
    Datetime,
}

impl Kind {
    /// TOML type name for messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            Kind::Str(_) => "a string",
            Kind::Int(_) => "an integer",
            Kind::Float(_) => "a float",
            Kind::Bool(_) => "a boolean",
            Kind::Array(_) => "an array",
            Kind::Table(_) => "a table",
            Kind::Datetime => "a datetime",
        }
    }
}

/// A key and its value.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// The key.
    pub key: String,
    /// Where the key is.
    pub key_span: Option<Span>,
    /// The value.
    pub value: Node,
}

impl SyntaxError {
    /// The first line of the message.
    pub fn first_line(&self) -> String {
        self.message
            .lines()
            .next()
            .unwrap_or("invalid TOML")
            .trim()
            .to_string()
    }
}

/// A TOML syntax error.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SyntaxError {
    /// toml_edit's message (may span several lines).
    pub message: String,
    /// Where.
    pub span: Option<Span>,
}

/// Parses a whole document; the root is a `Kind::Table`.
pub fn parse(source: &str) -> Result<Node, SyntaxError> {
    let doc = ImDocument::parse(source).map_err(|e| SyntaxError {
        message: e.message().trim().to_string(),
        span: e.span(),
    })?;
    Ok(Node {
        span: Some(0..source.len()),
        kind: Kind::Table(table_entries(doc.as_table())),
    })
}

fn table_entries(t: &Table) -> Vec<Entry> {
    t.iter()
        .map(|(k, item)| {
            let key_span = t.get_key_value(k).and_then(|(key, _)| key.span());
            let mut value = item_node(item);
            if value.span.is_none() {
                value.span.clone_from(&key_span);
            }
            Entry {
                key: k.to_string(),
                key_span,
                value,
            }
        })
        .collect()
}

fn item_node(item: &Item) -> Node {
    match item {
        Item::Value(v) => value_node(v),
        Item::Table(t) => Node {
            span: t.span(),
            kind: Kind::Table(table_entries(t)),
        },
        Item::ArrayOfTables(a) => Node {
            span: a.span(),
            kind: Kind::Array(
                a.iter()
                    .map(|t| Node {
                        span: t.span(),
                        kind: Kind::Table(table_entries(t)),
                    })
                    .collect(),
            ),
        },
        Item::None => Node {
            span: None,
            kind: Kind::Table(Vec::new()),
        },
    }
}

fn value_node(v: &Value) -> Node {
    let kind = match v {
        Value::String(s) => Kind::Str(s.value().clone()),
        Value::Integer(i) => Kind::Int(*i.value()),
        Value::Float(f) => Kind::Float(*f.value()),
        Value::Boolean(b) => Kind::Bool(*b.value()),
        Value::Datetime(_) => Kind::Datetime,
        Value::Array(a) => Kind::Array(a.iter().map(value_node).collect()),
        Value::InlineTable(t) => Kind::Table(
            t.iter()
                .map(|(k, val)| {
                    let key_span = t.get_key_value(k).and_then(|(key, _)| key.span());
                    let mut value = value_node(val);
                    if value.span.is_none() {
                        value.span.clone_from(&key_span);
                    }
                    Entry {
                        key: k.to_string(),
                        key_span,
                        value,
                    }
                })
                .collect(),
        ),
    };
    Node {
        span: v.span(),
        kind,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_key_and_value_spans() {
        let src = "[topics.speed]\nrate = \"200Hz\"\nsubs = [{ node = \"a\" }]\n";
        let root = parse(src).unwrap();
        let Kind::Table(top) = &root.kind else {
            panic!()
        };
        let Kind::Table(topics) = &top[0].value.kind else {
            panic!()
        };
        assert_eq!(topics[0].key, "speed");
        let Kind::Table(speed) = &topics[0].value.kind else {
            panic!()
        };
        assert_eq!(&src[speed[0].key_span.clone().unwrap()], "rate");
        assert_eq!(&src[speed[0].value.span.clone().unwrap()], "\"200Hz\"");
        let Kind::Array(subs) = &speed[1].value.kind else {
            panic!()
        };
        let Kind::Table(sub) = &subs[0].kind else {
            panic!()
        };
        assert_eq!(&src[sub[0].value.span.clone().unwrap()], "\"a\"");
    }

    #[test]
    fn syntax_error_has_span() {
        let e = parse("[bus\nx = 1").unwrap_err();
        assert!(e.span.is_some());
    }
}
