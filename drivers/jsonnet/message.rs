//! One datagram of `vrpn_Tracker_JsonNet` read the way C++ VRPN 07.38 reads it (with jsoncpp):
//! the JSON object's fields are kept as values of jsoncpp's kinds and converted with its rules
//! (`isConvertibleTo`, `asInt`, `asDouble`, `asBool`, `asString`). Parsing borrows the datagram
//! and allocates nothing: fields are deserialized (serde_json) into fixed-size values, nested
//! values are skipped, and the one string that matters (a text message's `data`) is copied into
//! a buffer the caller keeps.

use std::fmt::{self, Write as _};

use serde::de::{DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};

/// Message types (the `type` field).
const TRACKER: i32 = 1;
const BUTTON: i32 = 2;
const ANALOG: i32 = 3;
const TEXT: i32 = 4;

/// An array element, as far as `asDouble` tells them apart.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scalar {
    /// `null`: 0.
    Null,
    /// `true` or `false`: 1 or 0.
    Bool(bool),
    /// A number.
    Number(f64),
    /// A string, array or object: jsoncpp throws (C++ VRPN aborts); the message is refused.
    Other,
}

impl Scalar {
    fn as_double(self) -> Option<f64> {
        match self {
            Scalar::Null => Some(0.0),
            Scalar::Bool(b) => Some(if b { 1.0 } else { 0.0 }),
            Scalar::Number(v) => Some(v),
            Scalar::Other => None,
        }
    }
}

/// A field's value, of jsoncpp's kinds: integers that fit 64 bits signed are `Int`, larger
/// ones `UInt`, numbers with a fraction or exponent (or beyond 64 bits) `Real`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// `null`.
    Null,
    /// `true` or `false`.
    Bool(bool),
    /// A signed integer.
    Int(i64),
    /// An integer above `i64::MAX`.
    UInt(u64),
    /// A real number.
    Real(f64),
    /// A string (its text is kept only for the `data` field).
    Str,
    /// An array: its length and its first four elements.
    Array {
        /// Elements.
        len: usize,
        /// The first four.
        items: [Scalar; 4],
    },
    /// An object and its number of members.
    Object {
        /// Members.
        len: usize,
    },
}

impl Value {
    /// jsoncpp `empty()`: null, or an empty array or object (such a field counts as absent).
    fn empty(self) -> bool {
        matches!(
            self,
            Value::Null | Value::Array { len: 0, .. } | Value::Object { len: 0 }
        )
    }

    /// `isConvertibleTo(intValue)` then `asInt()`: integers within 32 bits, reals within
    /// 32 bits (truncated), booleans.
    pub fn as_int(self) -> Option<i32> {
        if self.empty() {
            return None;
        }
        match self {
            Value::Int(i) => i32::try_from(i).ok(),
            Value::UInt(u) => i32::try_from(u).ok(),
            Value::Real(r) if (-2_147_483_648.0..=2_147_483_647.0).contains(&r) => Some(r as i32),
            Value::Bool(b) => Some(i32::from(b)),
            _ => None,
        }
    }

    /// `isConvertibleTo(realValue)` then `asDouble()`: numbers and booleans.
    pub fn as_real(self) -> Option<f64> {
        match self {
            Value::Int(i) => Some(i as f64),
            Value::UInt(u) => Some(u as f64),
            Value::Real(r) => Some(r),
            Value::Bool(b) => Some(if b { 1.0 } else { 0.0 }),
            _ => None,
        }
    }

    /// `isConvertibleTo(booleanValue)` then `asBool()`: a number is true when not zero.
    pub fn as_bool(self) -> Option<bool> {
        match self {
            Value::Int(i) => Some(i != 0),
            Value::UInt(u) => Some(u != 0),
            Value::Real(r) => Some(r != 0.0 && !r.is_nan()),
            Value::Bool(b) => Some(b),
            _ => None,
        }
    }

    /// A fixed-size array of doubles (`quat`, `pos`): `None` when the field is absent or of
    /// another length (the previous values stay), an error when an element is no number.
    fn doubles<const N: usize>(self) -> Result<Option<[f64; N]>, Rejected> {
        match self {
            Value::Array { len, items } if len == N => {
                let mut out = [0.0; N];
                for (o, item) in out.iter_mut().zip(items) {
                    *o = item.as_double().ok_or(Rejected::NotANumber)?;
                }
                Ok(Some(out))
            }
            _ => Ok(None),
        }
    }
}

/// A message C++ VRPN accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Message {
    /// Type 1: a pose for sensor `sensor`; a `quat` or `pos` absent (or of the wrong length)
    /// keeps the previous one.
    Tracker {
        /// Sensor number.
        sensor: i32,
        /// Orientation (x, y, z, w).
        quat: Option<[f64; 4]>,
        /// Position.
        pos: Option<[f64; 3]>,
    },
    /// Type 2: a button's state.
    Button {
        /// Button number (C++ ignores one out of range, and so do we).
        button: i32,
        /// Pressed.
        pressed: bool,
    },
    /// Type 3: an analog channel's value.
    Analog {
        /// Channel number (C++ ignores one out of range, and so do we).
        channel: i32,
        /// Value.
        value: f64,
    },
    /// Type 4: a text (its characters are in the text buffer given to [`parse`]).
    Text,
}

/// Why a datagram gives no message (C++ VRPN prints the reason and skips it too, except where
/// noted).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rejected {
    /// Not JSON (or not UTF-8, which jsoncpp does not check).
    Syntax,
    /// A JSON value other than an object or `null` (jsoncpp throws: C++ VRPN aborts).
    NotAnObject,
    /// No `type` convertible to an integer.
    NoType,
    /// A `type` other than 1 to 4.
    UnknownType,
    /// A required field (`id`, `button`, `state`, `num`, `data`) is absent or of a kind C++
    /// cannot convert.
    MissingField(&'static str),
    /// A `quat` or `pos` element that is a string, array or object (jsoncpp throws: C++ VRPN
    /// aborts).
    NotANumber,
}

impl fmt::Display for Rejected {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Rejected::Syntax => f.write_str("not JSON"),
            Rejected::NotAnObject => f.write_str("not a JSON object"),
            Rejected::NoType => f.write_str("missing message type"),
            Rejected::UnknownType => f.write_str("unknown message type"),
            Rejected::MissingField(name) => write!(f, "missing or unusable '{name}'"),
            Rejected::NotANumber => f.write_str("a 'quat' or 'pos' element is not a number"),
        }
    }
}

/// The fields C++ VRPN reads (the last of a repeated name wins, as in jsoncpp).
#[derive(Clone, Copy, Debug, Default)]
struct Fields {
    kind: Option<Value>,
    id: Option<Value>,
    quat: Option<Value>,
    pos: Option<Value>,
    button: Option<Value>,
    state: Option<Value>,
    num: Option<Value>,
    data: Option<Value>,
}

/// Reads one datagram. A text message's characters (or the number or boolean it holds, as
/// jsoncpp writes them) are left in `text`, which is cleared first and should have room for a
/// datagram so that it never grows. Anything after the JSON value is ignored, as jsoncpp does.
pub fn parse(datagram: &[u8], text: &mut String) -> Result<Message, Rejected> {
    text.clear();
    let mut de = serde_json::Deserializer::from_slice(datagram);
    let root = RootSeed { text }
        .deserialize(&mut de)
        .map_err(|_| Rejected::Syntax)?;
    let fields = match root {
        Root::Object(f) => f,
        // `null`: every field absent.
        Root::Null => return Err(Rejected::NoType),
        Root::Other => return Err(Rejected::NotAnObject),
    };
    let kind = fields
        .kind
        .and_then(Value::as_int)
        .ok_or(Rejected::NoType)?;
    let field = |v: Option<Value>| v.filter(|v| !v.empty());
    match kind {
        TRACKER => {
            let sensor = field(fields.id)
                .and_then(Value::as_int)
                .ok_or(Rejected::MissingField("id"))?;
            let quat = match field(fields.quat) {
                Some(q) => q.doubles::<4>()?,
                None => None,
            };
            let pos = match field(fields.pos) {
                Some(p) => p.doubles::<3>()?,
                None => None,
            };
            Ok(Message::Tracker { sensor, quat, pos })
        }
        BUTTON => {
            let pressed = field(fields.state)
                .and_then(Value::as_bool)
                .ok_or(Rejected::MissingField("state"))?;
            let button = field(fields.button)
                .and_then(Value::as_int)
                .ok_or(Rejected::MissingField("button"))?;
            Ok(Message::Button { button, pressed })
        }
        ANALOG => {
            let value = field(fields.data)
                .and_then(Value::as_real)
                .ok_or(Rejected::MissingField("data"))?;
            let channel = field(fields.num)
                .and_then(Value::as_int)
                .ok_or(Rejected::MissingField("num"))?;
            Ok(Message::Analog { channel, value })
        }
        TEXT => {
            let data = field(fields.data).ok_or(Rejected::MissingField("data"))?;
            if data != Value::Str {
                text.clear();
            }
            match data {
                // The string is in `text` already.
                Value::Str => {}
                Value::Bool(b) => text.push_str(if b { "true" } else { "false" }),
                Value::Int(i) => {
                    let _ = write!(text, "{i}");
                }
                Value::UInt(u) => {
                    let _ = write!(text, "{u}");
                }
                Value::Real(r) => write_real(text, r),
                _ => return Err(Rejected::MissingField("data")),
            }
            Ok(Message::Text)
        }
        _ => Err(Rejected::UnknownType),
    }
}

/// A double as jsoncpp's `asString` writes it: C's `%.17g`, then `.0` when that has neither a
/// point nor an exponent.
pub fn write_real(out: &mut String, v: f64) {
    if !v.is_finite() {
        // JSON has no such numbers; jsoncpp's own spelling.
        out.push_str(if v.is_nan() {
            "null"
        } else if v > 0.0 {
            "1e+9999"
        } else {
            "-1e+9999"
        });
        return;
    }
    // 17 significant digits, correctly rounded, as `d.dddde±x`.
    let mut sci = Buf::default();
    let _ = write!(sci, "{v:.16e}");
    let s = sci.as_str();
    let (mantissa, exp) = s.split_once('e').unwrap_or((s, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let (sign, mantissa) = match mantissa.strip_prefix('-') {
        Some(m) => ("-", m),
        None => ("", mantissa),
    };
    let mut digits = Buf::default();
    for c in mantissa.bytes().filter(u8::is_ascii_digit) {
        digits.push(c);
    }
    // %g drops trailing zeros (no '#' flag).
    let digits = digits.as_str().trim_end_matches('0');
    let digits = if digits.is_empty() { "0" } else { digits };
    out.push_str(sign);
    if (-4..17).contains(&exp) {
        if exp < 0 {
            out.push_str("0.");
            for _ in 0..(-exp - 1) {
                out.push('0');
            }
            out.push_str(digits);
        } else {
            let int_len = exp as usize + 1;
            if digits.len() <= int_len {
                out.push_str(digits);
                for _ in digits.len()..int_len {
                    out.push('0');
                }
                out.push_str(".0");
            } else {
                out.push_str(&digits[..int_len]);
                out.push('.');
                out.push_str(&digits[int_len..]);
            }
        }
    } else {
        out.push_str(&digits[..1]);
        if digits.len() > 1 {
            out.push('.');
            out.push_str(&digits[1..]);
        }
        let _ = write!(out, "e{}{:02}", if exp < 0 { '-' } else { '+' }, exp.abs());
    }
}

/// A small text buffer on the stack, for formatting numbers without allocating.
struct Buf {
    bytes: [u8; 48],
    len: usize,
}

impl Default for Buf {
    fn default() -> Self {
        Buf {
            bytes: [0; 48],
            len: 0,
        }
    }
}

impl Buf {
    fn push(&mut self, b: u8) {
        if self.len < self.bytes.len() {
            self.bytes[self.len] = b;
            self.len += 1;
        }
    }

    fn as_str(&self) -> &str {
        std::str::from_utf8(&self.bytes[..self.len]).unwrap_or("")
    }
}

impl fmt::Write for Buf {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        for b in s.bytes() {
            self.push(b);
        }
        Ok(())
    }
}

/// The field names C++ VRPN reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Key {
    Type,
    Id,
    Quat,
    Pos,
    Button,
    State,
    Num,
    Data,
    Other,
}

impl Key {
    fn of(name: &str) -> Key {
        match name {
            "type" => Key::Type,
            "id" => Key::Id,
            "quat" => Key::Quat,
            "pos" => Key::Pos,
            "button" => Key::Button,
            "state" => Key::State,
            "num" => Key::Num,
            "data" => Key::Data,
            _ => Key::Other,
        }
    }
}

struct KeySeed;

impl<'de> DeserializeSeed<'de> for KeySeed {
    type Value = Key;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Key, D::Error> {
        d.deserialize_str(self)
    }
}

impl<'de> Visitor<'de> for KeySeed {
    type Value = Key;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a member name")
    }
    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Key, E> {
        Ok(Key::of(v))
    }
}

/// What the datagram holds (on the stack: boxing the fields would allocate per datagram).
#[allow(clippy::large_enum_variant)]
enum Root {
    Object(Fields),
    Null,
    Other,
}

/// The root value.
struct RootSeed<'t> {
    text: &'t mut String,
}

impl<'de> DeserializeSeed<'de> for RootSeed<'_> {
    type Value = Root;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Root, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for RootSeed<'_> {
    type Value = Root;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON object")
    }
    fn visit_unit<E: serde::de::Error>(self) -> Result<Root, E> {
        Ok(Root::Null)
    }
    fn visit_bool<E: serde::de::Error>(self, _: bool) -> Result<Root, E> {
        Ok(Root::Other)
    }
    fn visit_i64<E: serde::de::Error>(self, _: i64) -> Result<Root, E> {
        Ok(Root::Other)
    }
    fn visit_u64<E: serde::de::Error>(self, _: u64) -> Result<Root, E> {
        Ok(Root::Other)
    }
    fn visit_f64<E: serde::de::Error>(self, _: f64) -> Result<Root, E> {
        Ok(Root::Other)
    }
    fn visit_str<E: serde::de::Error>(self, _: &str) -> Result<Root, E> {
        Ok(Root::Other)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Root, A::Error> {
        while seq.next_element::<IgnoredAny>()?.is_some() {}
        Ok(Root::Other)
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Root, A::Error> {
        let mut f = Fields::default();
        while let Some(key) = map.next_key_seed(KeySeed)? {
            let slot = match key {
                Key::Type => &mut f.kind,
                Key::Id => &mut f.id,
                Key::Quat => &mut f.quat,
                Key::Pos => &mut f.pos,
                Key::Button => &mut f.button,
                Key::State => &mut f.state,
                Key::Num => &mut f.num,
                Key::Data => {
                    f.data = Some(map.next_value_seed(ValueSeed {
                        text: Some(&mut *self.text),
                    })?);
                    continue;
                }
                Key::Other => {
                    map.next_value::<IgnoredAny>()?;
                    continue;
                }
            };
            *slot = Some(map.next_value_seed(ValueSeed { text: None })?);
        }
        Ok(Root::Object(f))
    }
}

/// A field's value; a string's characters go to `text` when given.
struct ValueSeed<'t> {
    text: Option<&'t mut String>,
}

impl<'de> DeserializeSeed<'de> for ValueSeed<'_> {
    type Value = Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for ValueSeed<'_> {
    type Value = Value;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_unit<E: serde::de::Error>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_bool<E: serde::de::Error>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Value, E> {
        Ok(Value::Int(v))
    }
    fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Value, E> {
        Ok(i64::try_from(v).map_or(Value::UInt(v), Value::Int))
    }
    fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Value, E> {
        Ok(Value::Real(v))
    }
    fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Value, E> {
        if let Some(text) = self.text {
            text.clear();
            text.push_str(v);
        }
        Ok(Value::Str)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = [Scalar::Other; 4];
        let mut len = 0;
        while len < items.len() {
            match seq.next_element_seed(ScalarSeed)? {
                Some(s) => {
                    items[len] = s;
                    len += 1;
                }
                None => return Ok(Value::Array { len, items }),
            }
        }
        while seq.next_element::<IgnoredAny>()?.is_some() {
            len += 1;
        }
        Ok(Value::Array { len, items })
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut len = 0;
        while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {
            len += 1;
        }
        Ok(Value::Object { len })
    }
}

/// An array element.
struct ScalarSeed;

impl<'de> DeserializeSeed<'de> for ScalarSeed {
    type Value = Scalar;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Scalar, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for ScalarSeed {
    type Value = Scalar;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_unit<E: serde::de::Error>(self) -> Result<Scalar, E> {
        Ok(Scalar::Null)
    }
    fn visit_bool<E: serde::de::Error>(self, v: bool) -> Result<Scalar, E> {
        Ok(Scalar::Bool(v))
    }
    fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Scalar, E> {
        Ok(Scalar::Number(v as f64))
    }
    fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Scalar, E> {
        Ok(Scalar::Number(v as f64))
    }
    fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Scalar, E> {
        Ok(Scalar::Number(v))
    }
    fn visit_str<E: serde::de::Error>(self, _: &str) -> Result<Scalar, E> {
        Ok(Scalar::Other)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Scalar, A::Error> {
        while seq.next_element::<IgnoredAny>()?.is_some() {}
        Ok(Scalar::Other)
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Scalar, A::Error> {
        while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
        Ok(Scalar::Other)
    }
}
