//! Typed parameters of a module (docs/SERVICES.md §2): their declaration, the range check
//! the module applies before any value is taken (a refused value is never applied), and
//! the get/set/list protocol carried over NRT. Names live on the host (robot.toml); the
//! wire carries parameter indices in declaration order. [`bus`] carries the protocol as
//! NRT frames on the reserved parameter channel.

pub mod bus;

/// A parameter's type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParamType {
    F32,
    I32,
    U32,
    Bool,
}

/// A typed value (stored and sent as 32 bits: f32 bits, two's complement, 0/1).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Value {
    F32(f32),
    I32(i32),
    U32(u32),
    Bool(bool),
}

impl Value {
    /// The 32 wire/flash bits.
    pub fn bits(self) -> u32 {
        match self {
            Value::F32(v) => v.to_bits(),
            Value::I32(v) => u32::from_le_bytes(v.to_le_bytes()),
            Value::U32(v) => v,
            Value::Bool(v) => u32::from(v),
        }
    }

    /// The value of type `ty` from its 32 bits; `None` for a bool other than 0/1.
    pub fn from_bits(ty: ParamType, bits: u32) -> Option<Value> {
        Some(match ty {
            ParamType::F32 => Value::F32(f32::from_bits(bits)),
            ParamType::I32 => Value::I32(i32::from_le_bytes(bits.to_le_bytes())),
            ParamType::U32 => Value::U32(bits),
            ParamType::Bool => match bits {
                0 => Value::Bool(false),
                1 => Value::Bool(true),
                _ => return None,
            },
        })
    }

    /// The type of this value.
    pub fn ty(self) -> ParamType {
        match self {
            Value::F32(_) => ParamType::F32,
            Value::I32(_) => ParamType::I32,
            Value::U32(_) => ParamType::U32,
            Value::Bool(_) => ParamType::Bool,
        }
    }
}

/// One parameter as declared in robot.toml.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    /// `node.name`, as `rtcan param` shows it.
    pub name: &'static str,
    pub default: Value,
    /// Inclusive range (same type as `default`; ignored for bool).
    pub min: Value,
    pub max: Value,
    /// Unit, for display.
    pub unit: &'static str,
    /// Kept in flash across resets.
    pub persist: bool,
}

/// Why a value was refused (the wire status byte).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Refused {
    /// No parameter with this index.
    Unknown = 1,
    /// Below `min` or above `max`.
    OutOfRange = 2,
    /// Not a value of the parameter's type (NaN, a bool other than 0/1).
    BadValue = 3,
    /// The request was malformed.
    BadRequest = 4,
    /// Applied, but could not be persisted (flash error): the value is live until reset.
    NotPersisted = 5,
}

impl Refused {
    /// Human-readable reason (`rtcan param set` prints it).
    pub fn reason(self) -> &'static str {
        match self {
            Refused::Unknown => "no such parameter",
            Refused::OutOfRange => "value outside the declared range",
            Refused::BadValue => "not a value of the parameter's type",
            Refused::BadRequest => "malformed request",
            Refused::NotPersisted => "applied, but the flash write failed",
        }
    }

    fn from_u8(b: u8) -> Option<Refused> {
        Some(match b {
            1 => Refused::Unknown,
            2 => Refused::OutOfRange,
            3 => Refused::BadValue,
            4 => Refused::BadRequest,
            5 => Refused::NotPersisted,
            _ => return None,
        })
    }
}

impl ParamSpec {
    /// The value if acceptable for this parameter, else why not.
    pub fn check(&self, bits: u32) -> Result<Value, Refused> {
        let v = Value::from_bits(self.default.ty(), bits).ok_or(Refused::BadValue)?;
        let ok = match (v, self.min, self.max) {
            (Value::F32(x), Value::F32(lo), Value::F32(hi)) => {
                if x.is_nan() {
                    return Err(Refused::BadValue);
                }
                lo <= x && x <= hi
            }
            (Value::I32(x), Value::I32(lo), Value::I32(hi)) => lo <= x && x <= hi,
            (Value::U32(x), Value::U32(lo), Value::U32(hi)) => lo <= x && x <= hi,
            (Value::Bool(_), _, _) => true,
            // A spec whose range has another type: the model rejects it; refuse.
            _ => false,
        };
        if ok {
            Ok(v)
        } else {
            Err(Refused::OutOfRange)
        }
    }
}

/// A Rust type a parameter can have (`f32`, `i32`, `u32`, `bool`).
pub trait ParamValue: Copy {
    /// The value if `v` has this type.
    fn of(v: Value) -> Option<Self>;
    /// As a [`Value`].
    fn value(self) -> Value;
}

impl ParamValue for f32 {
    fn of(v: Value) -> Option<Self> {
        match v {
            Value::F32(x) => Some(x),
            _ => None,
        }
    }
    fn value(self) -> Value {
        Value::F32(self)
    }
}

impl ParamValue for i32 {
    fn of(v: Value) -> Option<Self> {
        match v {
            Value::I32(x) => Some(x),
            _ => None,
        }
    }
    fn value(self) -> Value {
        Value::I32(self)
    }
}

impl ParamValue for u32 {
    fn of(v: Value) -> Option<Self> {
        match v {
            Value::U32(x) => Some(x),
            _ => None,
        }
    }
    fn value(self) -> Value {
        Value::U32(self)
    }
}

impl ParamValue for bool {
    fn of(v: Value) -> Option<Self> {
        match v {
            Value::Bool(x) => Some(x),
            _ => None,
        }
    }
    fn value(self) -> Value {
        Value::Bool(self)
    }
}

/// A typed handle on one declared parameter (generated per parameter as
/// `<module>::params::<NAME>`): its wire index and its default. Node code reads the live
/// value of its module's table with it, so a value set over the bus takes effect at the
/// next read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Param<T> {
    index: u16,
    default: T,
}

impl<T: ParamValue> Param<T> {
    /// The handle of parameter `index` (declaration order in its module).
    pub const fn new(index: u16, default: T) -> Self {
        Param { index, default }
    }

    /// The wire index.
    pub const fn index(self) -> u16 {
        self.index
    }

    /// The declared default.
    pub const fn default_value(self) -> T {
        self.default
    }

    /// The live value in `table`; the default if `table` has no parameter of this type at
    /// this index (not with the generated table of the same module).
    pub fn get<const N: usize>(self, table: &Params<N>) -> T {
        table
            .get(usize::from(self.index))
            .and_then(T::of)
            .unwrap_or(self.default)
    }

    /// Sets the value in `table` after the declared range check, as a `set` over the bus
    /// does (a refused value changes nothing and is counted).
    pub fn set<const N: usize>(self, table: &mut Params<N>, v: T) -> Result<T, Refused> {
        table
            .set(usize::from(self.index), v.value().bits())
            .map(|_| v)
    }
}

/// The live parameters of one module: `N` values in declaration order.
#[derive(Clone, Debug, PartialEq)]
pub struct Params<const N: usize> {
    specs: &'static [ParamSpec; N],
    values: [u32; N],
    /// Sets refused so far (counted, nothing is lost silently).
    pub refused: u32,
}

impl<const N: usize> Params<N> {
    /// Every parameter at its default.
    pub fn new(specs: &'static [ParamSpec; N]) -> Self {
        let mut values = [0; N];
        for (v, s) in values.iter_mut().zip(specs.iter()) {
            *v = s.default.bits();
        }
        Params {
            specs,
            values,
            refused: 0,
        }
    }

    /// The declarations.
    pub fn specs(&self) -> &'static [ParamSpec; N] {
        self.specs
    }

    /// Current value of parameter `i`.
    pub fn get(&self, i: usize) -> Option<Value> {
        let spec = self.specs.get(i)?;
        Value::from_bits(spec.default.ty(), *self.values.get(i)?)
    }

    /// Current f32 value of parameter `i` (generated accessors use this); the default
    /// type is checked by the model, so a mismatch returns `None`.
    pub fn f32(&self, i: usize) -> Option<f32> {
        match self.get(i)? {
            Value::F32(v) => Some(v),
            _ => None,
        }
    }

    /// Sets parameter `i` to `bits` after the range check; a refused value changes
    /// nothing.
    pub fn set(&mut self, i: usize, bits: u32) -> Result<Value, Refused> {
        let r = self
            .specs
            .get(i)
            .ok_or(Refused::Unknown)
            .and_then(|s| s.check(bits));
        match r {
            Ok(v) => {
                if let Some(slot) = self.values.get_mut(i) {
                    *slot = v.bits();
                }
                Ok(v)
            }
            Err(e) => {
                self.refused = self.refused.saturating_add(1);
                Err(e)
            }
        }
    }

    /// Loads persisted values (index, bits) as a store returns them; each is range
    /// checked again (a value from an older robot.toml out of the new range stays at
    /// the default). Returns how many were taken.
    pub fn load(&mut self, stored: impl IntoIterator<Item = (u16, u32)>) -> usize {
        let mut n = 0;
        for (i, bits) in stored {
            let i = usize::from(i);
            if self
                .specs
                .get(i)
                .is_some_and(|s| s.persist && s.check(bits).is_ok())
            {
                if let Some(slot) = self.values.get_mut(i) {
                    *slot = bits;
                    n += 1;
                }
            }
        }
        n
    }

    /// Serves one request: the reply to send back (see [`serve`]).
    pub fn serve(&mut self, request: &[u8], persist: &mut dyn FnMut(u16, u32) -> bool) -> Reply {
        serve(
            self.specs,
            &mut self.values,
            &mut self.refused,
            request,
            persist,
        )
    }
}

/// The module side of the protocol over any parameter set (`values` in `specs` order):
/// decodes `request`, range-checks a set (a refused value changes nothing; `refused`
/// counts it), writes a set of a persisted parameter through `persist` after applying
/// it, and returns the reply.
pub fn serve(
    specs: &[ParamSpec],
    values: &mut [u32],
    refused: &mut u32,
    request: &[u8],
    persist: &mut dyn FnMut(u16, u32) -> bool,
) -> Reply {
    let Some(req) = Request::decode(request) else {
        *refused = refused.saturating_add(1);
        return Reply::Refused {
            index: 0,
            why: Refused::BadRequest,
        };
    };
    let index = req.index();
    let i = usize::from(index);
    let count = u16::try_from(specs.len()).unwrap_or(u16::MAX);
    let (Some(spec), Some(slot)) = (specs.get(i), values.get_mut(i)) else {
        *refused = refused.saturating_add(1);
        return Reply::Refused {
            index,
            why: Refused::Unknown,
        };
    };
    match req {
        Request::Get { .. } | Request::List { .. } => Reply::Value {
            index,
            bits: *slot,
            count,
        },
        Request::Set { bits, .. } => match spec.check(bits) {
            Ok(v) => {
                *slot = v.bits();
                if spec.persist && !persist(index, v.bits()) {
                    return Reply::Refused {
                        index,
                        why: Refused::NotPersisted,
                    };
                }
                Reply::Value {
                    index,
                    bits: v.bits(),
                    count,
                }
            }
            Err(why) => {
                *refused = refused.saturating_add(1);
                Reply::Refused { index, why }
            }
        },
    }
}

/// A parameter request (8 bytes: op, pad, index u16 LE, value u32 LE).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Request {
    Get {
        index: u16,
    },
    Set {
        index: u16,
        bits: u32,
    },
    /// The `index`-th parameter (the host lists 0.. until `count`).
    List {
        index: u16,
    },
}

/// Bytes of a request and of a reply.
pub const REQUEST_BYTES: usize = 8;
pub const REPLY_BYTES: usize = 8;

impl Request {
    /// The parameter index the request is about.
    pub fn index(self) -> u16 {
        match self {
            Request::Get { index } | Request::Set { index, .. } | Request::List { index } => index,
        }
    }

    pub fn encode(self) -> [u8; REQUEST_BYTES] {
        let (op, index, bits) = match self {
            Request::Get { index } => (1, index, 0),
            Request::Set { index, bits } => (2, index, bits),
            Request::List { index } => (3, index, 0),
        };
        let [i0, i1] = index.to_le_bytes();
        let [b0, b1, b2, b3] = bits.to_le_bytes();
        [op, 0, i0, i1, b0, b1, b2, b3]
    }

    /// `None` for a wrong length, an unknown op or a non-zero pad.
    pub fn decode(b: &[u8]) -> Option<Request> {
        let &[op, 0, i0, i1, b0, b1, b2, b3] = b else {
            return None;
        };
        let index = u16::from_le_bytes([i0, i1]);
        let bits = u32::from_le_bytes([b0, b1, b2, b3]);
        match op {
            1 if bits == 0 => Some(Request::Get { index }),
            2 => Some(Request::Set { index, bits }),
            3 if bits == 0 => Some(Request::List { index }),
            _ => None,
        }
    }
}

/// A parameter reply (8 bytes: status (0 ok, else `Refused`), count u8, index u16 LE,
/// value u32 LE).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reply {
    /// The (new) value; `count` is the module's number of parameters.
    Value {
        index: u16,
        bits: u32,
        count: u16,
    },
    Refused {
        index: u16,
        why: Refused,
    },
}

impl Reply {
    pub fn encode(self) -> [u8; REPLY_BYTES] {
        let (status, count, index, bits) = match self {
            Reply::Value { index, bits, count } => {
                (0, u8::try_from(count).unwrap_or(u8::MAX), index, bits)
            }
            Reply::Refused { index, why } => (why as u8, 0, index, 0),
        };
        let [i0, i1] = index.to_le_bytes();
        let [b0, b1, b2, b3] = bits.to_le_bytes();
        [status, count, i0, i1, b0, b1, b2, b3]
    }

    pub fn decode(b: &[u8]) -> Option<Reply> {
        let &[status, count, i0, i1, b0, b1, b2, b3] = b else {
            return None;
        };
        let index = u16::from_le_bytes([i0, i1]);
        let bits = u32::from_le_bytes([b0, b1, b2, b3]);
        if status == 0 {
            return Some(Reply::Value {
                index,
                bits,
                count: u16::from(count),
            });
        }
        Some(Reply::Refused {
            index,
            why: Refused::from_u8(status)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    static SPECS: [ParamSpec; 3] = [
        ParamSpec {
            name: "pid1.kp",
            default: Value::F32(0.5),
            min: Value::F32(0.0),
            max: Value::F32(10.0),
            unit: "",
            persist: true,
        },
        ParamSpec {
            name: "pid1.limit",
            default: Value::I32(-5),
            min: Value::I32(-100),
            max: Value::I32(100),
            unit: "mA",
            persist: false,
        },
        ParamSpec {
            name: "pid1.enabled",
            default: Value::Bool(true),
            min: Value::Bool(false),
            max: Value::Bool(true),
            unit: "",
            persist: true,
        },
    ];

    fn no_flash() -> impl FnMut(u16, u32) -> bool {
        |_, _| panic!("not persisted")
    }

    #[test]
    fn set_in_range_applies_out_of_range_never_does() {
        let mut p = Params::new(&SPECS);
        assert_eq!(p.get(0), Some(Value::F32(0.5)));
        assert_eq!(p.set(0, 0.8f32.to_bits()), Ok(Value::F32(0.8)));
        assert_eq!(p.f32(0), Some(0.8));
        assert_eq!(p.set(0, 10.5f32.to_bits()), Err(Refused::OutOfRange));
        assert_eq!(p.set(0, (-0.1f32).to_bits()), Err(Refused::OutOfRange));
        assert_eq!(p.set(0, f32::NAN.to_bits()), Err(Refused::BadValue));
        assert_eq!(p.f32(0), Some(0.8), "refused values are never applied");
        assert_eq!(p.set(1, (-101i32) as u32), Err(Refused::OutOfRange));
        assert_eq!(p.set(1, (-100i32) as u32), Ok(Value::I32(-100)));
        assert_eq!(p.set(2, 2), Err(Refused::BadValue));
        assert_eq!(p.set(3, 0), Err(Refused::Unknown));
        assert_eq!(p.refused, 6);
    }

    #[test]
    fn protocol_exact_bytes() {
        let r = Request::Set {
            index: 0x0102,
            bits: 0.8f32.to_bits(),
        };
        assert_eq!(r.encode(), [2, 0, 2, 1, 0xCD, 0xCC, 0x4C, 0x3F]);
        assert_eq!(Request::decode(&r.encode()), Some(r));
        assert_eq!(Request::decode(&[1, 0, 0, 0, 0, 0, 0]), None, "short");
        assert_eq!(Request::decode(&[9, 0, 0, 0, 0, 0, 0, 0]), None, "op");
        assert_eq!(Request::decode(&[1, 1, 0, 0, 0, 0, 0, 0]), None, "pad");
        assert_eq!(
            Request::decode(&[1, 0, 0, 0, 1, 0, 0, 0]),
            None,
            "get value"
        );
        let rep = Reply::Refused {
            index: 3,
            why: Refused::OutOfRange,
        };
        assert_eq!(rep.encode(), [2, 0, 3, 0, 0, 0, 0, 0]);
        assert_eq!(Reply::decode(&rep.encode()), Some(rep));
        assert_eq!(Reply::decode(&[6, 0, 0, 0, 0, 0, 0, 0]), None);
    }

    #[test]
    fn serve_get_set_list_and_persist() {
        let mut p = Params::new(&SPECS);
        let mut written = Vec::new();
        let mut flash = |i: u16, b: u32| {
            written.push((i, b));
            true
        };
        let set = Request::Set {
            index: 0,
            bits: 2.0f32.to_bits(),
        };
        assert_eq!(
            p.serve(&set.encode(), &mut flash),
            Reply::Value {
                index: 0,
                bits: 2.0f32.to_bits(),
                count: 3
            }
        );
        // Not persisted: limit.
        let set1 = Request::Set { index: 1, bits: 7 };
        assert!(matches!(
            p.serve(&set1.encode(), &mut flash),
            Reply::Value { .. }
        ));
        assert_eq!(written, [(0, 2.0f32.to_bits())]);
        let bad = Request::Set {
            index: 0,
            bits: 99.0f32.to_bits(),
        };
        assert_eq!(
            p.serve(&bad.encode(), &mut no_flash()),
            Reply::Refused {
                index: 0,
                why: Refused::OutOfRange
            }
        );
        assert_eq!(p.f32(0), Some(2.0));
        assert_eq!(
            p.serve(&Request::List { index: 2 }.encode(), &mut no_flash()),
            Reply::Value {
                index: 2,
                bits: 1,
                count: 3
            }
        );
        assert_eq!(
            p.serve(&Request::Get { index: 3 }.encode(), &mut no_flash()),
            Reply::Refused {
                index: 3,
                why: Refused::Unknown
            }
        );
        assert_eq!(
            p.serve(&[0; 3], &mut no_flash()),
            Reply::Refused {
                index: 0,
                why: Refused::BadRequest
            }
        );
        // A flash failure is reported, the value is live.
        let mut failing = |_: u16, _: u32| false;
        assert_eq!(
            p.serve(&Request::Set { index: 2, bits: 0 }.encode(), &mut failing),
            Reply::Refused {
                index: 2,
                why: Refused::NotPersisted
            }
        );
        assert_eq!(p.get(2), Some(Value::Bool(false)));
    }

    #[test]
    fn load_rechecks_ranges_and_persistence() {
        let mut p = Params::new(&SPECS);
        let n = p.load([
            (0, 3.0f32.to_bits()),
            (0, 50.0f32.to_bits()),
            (1, 9),
            (7, 0),
            (2, 0),
        ]);
        assert_eq!(n, 2);
        assert_eq!(p.f32(0), Some(3.0));
        assert_eq!(p.get(1), Some(Value::I32(-5)), "not a persisted parameter");
        assert_eq!(p.get(2), Some(Value::Bool(false)));
    }
}
