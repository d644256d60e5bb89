//! Topic payloads as JSON objects with robot.toml's field names (arrays as JSON arrays),
//! both ways. Encoding refuses any value that does not fit the field's type exactly
//! (out of range, fractional integer, wrong kind, missing or unknown field), so a command
//! never reaches the bus silently changed.
use rtcan_model::Prim;
use rtcan_sim::decode::{FieldDesc, TopicDesc};
use serde_json::{Map, Number, Value};

fn read_prim(prim: Prim, b: &[u8]) -> Value {
    let mut a = [0u8; 8];
    for (d, s) in a.iter_mut().zip(b) {
        *d = *s;
    }
    let u = u64::from_le_bytes(a);
    match prim {
        Prim::U8 | Prim::U16 | Prim::U32 | Prim::U64 => Value::from(u),
        Prim::I8 => Value::from(u as u8 as i8),
        Prim::I16 => Value::from(u as u16 as i16),
        Prim::I32 => Value::from(u as u32 as i32),
        Prim::I64 => Value::from(u as i64),
        // Non-finite floats have no JSON number: null.
        Prim::F32 => {
            Number::from_f64(f64::from(f32::from_bits(u as u32))).map_or(Value::Null, Value::Number)
        }
        Prim::F64 => Number::from_f64(f64::from_bits(u)).map_or(Value::Null, Value::Number),
        Prim::Bool => Value::Bool(u != 0),
    }
}

/// The payload as a JSON object (fields beyond the payload's end are left out).
pub fn to_json(topic: &TopicDesc, payload: &[u8]) -> Value {
    let mut obj = Map::new();
    for f in &topic.fields {
        let size = f.prim.size();
        let at = |k: usize| payload.get(f.offset + k * size..f.offset + (k + 1) * size);
        let v = match f.len {
            Some(n) => Value::Array(
                (0..usize::from(n))
                    .filter_map(|k| at(k).map(|b| read_prim(f.prim, b)))
                    .collect(),
            ),
            None => match at(0) {
                Some(b) => read_prim(f.prim, b),
                None => continue,
            },
        };
        obj.insert(f.name.clone(), v);
    }
    Value::Object(obj)
}

fn prim_name(p: Prim) -> &'static str {
    match p {
        Prim::U8 => "u8",
        Prim::U16 => "u16",
        Prim::U32 => "u32",
        Prim::U64 => "u64",
        Prim::I8 => "i8",
        Prim::I16 => "i16",
        Prim::I32 => "i32",
        Prim::I64 => "i64",
        Prim::F32 => "f32",
        Prim::F64 => "f64",
        Prim::Bool => "bool",
    }
}

/// Little-endian bytes of one element, or why `v` does not fit `prim`.
fn write_prim(prim: Prim, v: &Value) -> Result<Vec<u8>, String> {
    let int = |min: i128, max: i128| -> Result<i128, String> {
        let n = match v {
            Value::Number(n) => n,
            other => {
                return Err(format!(
                    "expected an integer ({}), got {other}",
                    prim_name(prim)
                ))
            }
        };
        let i = if let Some(u) = n.as_u64() {
            i128::from(u)
        } else if let Some(i) = n.as_i64() {
            i128::from(i)
        } else {
            return Err(format!("{n} is not an integer ({})", prim_name(prim)));
        };
        if i < min || i > max {
            return Err(format!(
                "{i} does not fit {} ({min}..={max})",
                prim_name(prim)
            ));
        }
        Ok(i)
    };
    let float = || -> Result<f64, String> {
        v.as_f64()
            .ok_or_else(|| format!("expected a number ({}), got {v}", prim_name(prim)))
    };
    Ok(match prim {
        Prim::U8 => (int(0, u8::MAX.into())? as u8).to_le_bytes().to_vec(),
        Prim::U16 => (int(0, u16::MAX.into())? as u16).to_le_bytes().to_vec(),
        Prim::U32 => (int(0, u32::MAX.into())? as u32).to_le_bytes().to_vec(),
        Prim::U64 => (int(0, u64::MAX.into())? as u64).to_le_bytes().to_vec(),
        Prim::I8 => (int(i8::MIN.into(), i8::MAX.into())? as i8)
            .to_le_bytes()
            .to_vec(),
        Prim::I16 => (int(i16::MIN.into(), i16::MAX.into())? as i16)
            .to_le_bytes()
            .to_vec(),
        Prim::I32 => (int(i32::MIN.into(), i32::MAX.into())? as i32)
            .to_le_bytes()
            .to_vec(),
        Prim::I64 => (int(i64::MIN.into(), i64::MAX.into())? as i64)
            .to_le_bytes()
            .to_vec(),
        Prim::F32 => {
            let x = float()?;
            let y = x as f32;
            if y.is_infinite() {
                return Err(format!("{x} does not fit f32"));
            }
            y.to_le_bytes().to_vec()
        }
        Prim::F64 => float()?.to_le_bytes().to_vec(),
        Prim::Bool => match v {
            Value::Bool(b) => vec![u8::from(*b)],
            other => return Err(format!("expected true or false (bool), got {other}")),
        },
    })
}

fn write_field(f: &FieldDesc, v: &Value, out: &mut [u8]) -> Result<(), String> {
    let values: Vec<&Value> = match (f.len, v) {
        (Some(n), Value::Array(a)) => {
            if a.len() != usize::from(n) {
                return Err(format!(
                    "field `{}`: expected {n} elements, got {}",
                    f.name,
                    a.len()
                ));
            }
            a.iter().collect()
        }
        (Some(n), other) => {
            return Err(format!(
                "field `{}`: expected an array of {n} {}, got {other}",
                f.name,
                prim_name(f.prim)
            ))
        }
        (None, v) => vec![v],
    };
    for (k, v) in values.into_iter().enumerate() {
        let bytes = write_prim(f.prim, v).map_err(|e| format!("field `{}`: {e}", f.name))?;
        let at = f.offset + k * f.prim.size();
        let dst = out
            .get_mut(at..at + bytes.len())
            .ok_or_else(|| format!("field `{}` lies outside the payload", f.name))?;
        dst.copy_from_slice(&bytes);
    }
    Ok(())
}

/// The payload of `json` (an object naming every field of the topic's type exactly once).
pub fn from_json(topic: &TopicDesc, json: &Value) -> Result<Vec<u8>, String> {
    let obj = json.as_object().ok_or_else(|| {
        format!(
            "`{}` takes a JSON object with the fields {}",
            topic.name,
            field_list(topic)
        )
    })?;
    if let Some(k) = obj
        .keys()
        .find(|k| !topic.fields.iter().any(|f| &f.name == *k))
    {
        return Err(format!(
            "`{}` has no field `{k}`; its fields: {}",
            topic.name,
            field_list(topic)
        ));
    }
    let mut out = vec![0u8; usize::from(topic.size)];
    for f in &topic.fields {
        let v = obj.get(&f.name).ok_or_else(|| {
            format!(
                "missing field `{}`; `{}` needs {}",
                f.name,
                topic.name,
                field_list(topic)
            )
        })?;
        write_field(f, v, &mut out)?;
    }
    Ok(out)
}

/// `vx: f32, vy: f32, text: [u8; 32]`.
pub fn field_list(topic: &TopicDesc) -> String {
    topic
        .fields
        .iter()
        .map(|f| match f.len {
            Some(n) => format!("{}: [{}; {n}]", f.name, prim_name(f.prim)),
            None => format!("{}: {}", f.name, prim_name(f.prim)),
        })
        .collect::<Vec<_>>()
        .join(", ")
}
