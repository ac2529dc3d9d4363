//! The JSON rendering of a record (feature `json`), as `vrpn_log dump --json` prints it: one
//! object per entry, written with serde.

use std::io::Write as _;

use serde::ser::{Serialize, SerializeMap, Serializer};

use super::decode::Field;
use super::text::Hex;
use super::walk::Record;
use crate::time::TimeVal;

/// A float as JSON can carry it: non-finite values become `null`.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// The `f64` nearest to the decimal `sec.usec`, so that a JSON writer prints that decimal (less
/// trailing zeros) and a reader gets back exactly what parsing the decimal gives.
fn seconds(t: TimeVal) -> f64 {
    let mut digits = [0u8; 48];
    let mut cursor = std::io::Cursor::new(&mut digits[..]);
    // An i64 and six digits fit in 48 bytes.
    let _ = write!(cursor, "{t}");
    let len = cursor.position() as usize;
    std::str::from_utf8(&digits[..len])
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| t.as_secs_f64())
}

impl Serialize for Field<'_> {
    /// Integers and floats as numbers (non-finite floats as `null`), lists as arrays, text as
    /// strings (bytes as lossy UTF-8), [`Field::Hex`] as a string of hex digits.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Field::Int(i) => s.serialize_i64(*i),
            Field::Num(v) => finite(*v).serialize(s),
            Field::Nums(vs) => s.collect_seq(vs.iter().map(|v| finite(*v))),
            Field::Ints(vs) => s.collect_seq(vs.iter()),
            Field::Str(t) => s.serialize_str(t),
            Field::String(t) => s.serialize_str(t),
            Field::Bytes(b) => s.serialize_str(&String::from_utf8_lossy(b)),
            Field::Hex(b) => s.collect_str(&Hex(b)),
        }
    }
}

impl Serialize for Record<'_, '_> {
    /// An object with the keys `offset`, `time` (seconds, the number `sec.usec`), `sec`,
    /// `usec`, `sender` (null when unnamed), `sender_id`, `type` (null when undescribed),
    /// `type_id`, `kind` ([`super::Decoded::kind`]), then the decoded fields of
    /// [`super::Decoded::fields`], in that order.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let e = &self.entry;
        let t = e.time();
        let mut map = s.serialize_map(None)?;
        map.serialize_entry("offset", &e.offset)?;
        map.serialize_entry("time", &seconds(t))?;
        map.serialize_entry("sec", &t.sec)?;
        map.serialize_entry("usec", &t.usec)?;
        map.serialize_entry("sender", &self.sender)?;
        map.serialize_entry("sender_id", &e.sender())?;
        map.serialize_entry("type", &self.type_name)?;
        map.serialize_entry("type_id", &e.type_id())?;
        map.serialize_entry("kind", self.decoded.kind())?;
        for (key, field) in self.decoded.fields() {
            map.serialize_entry(key, &field)?;
        }
        map.end()
    }
}

/// Appends the one-line JSON form of a record (no newline); see [`Record`]'s `Serialize` for
/// the keys. To write straight to a stream, use `serde_json::to_writer(out, rec)`.
pub fn format_json(out: &mut String, rec: &Record<'_, '_>) {
    let mut bytes = std::mem::take(out).into_bytes();
    // Into memory, from numbers and strings: cannot fail.
    serde_json::to_writer(&mut bytes, rec).expect("JSON into memory");
    *out = String::from_utf8(bytes).expect("serde_json writes UTF-8");
}

#[cfg(test)]
mod tests {
    use super::super::test_log::sample;
    use super::super::{Decoded, Walk};
    use super::*;

    /// The JSON lines of the sample log.
    fn lines() -> Vec<String> {
        let r = sample().reader();
        let mut w = Walk::new(&r);
        let mut lines = Vec::new();
        while let Some(rec) = w.next_record() {
            let mut line = String::new();
            format_json(&mut line, &rec.unwrap());
            lines.push(line);
        }
        lines
    }

    #[test]
    fn json_lines() {
        let lines = lines();
        assert!(
            lines[5].contains(
                "\"time\":10.0,\"sec\":10,\"usec\":0,\"sender\":\"Tracker0\",\"sender_id\":1,\
                 \"type\":\"vrpn_Tracker Pos_Quat\",\"type_id\":4,\"kind\":\"pose\",\"sensor\":0,\
                 \"pos\":[0.1,0.5,-1.0],\"quat\":[0.0,0.0,0.0,1.0]}"
            ),
            "{}",
            lines[5]
        );
        assert!(lines[0].ends_with(
            "\"sender\":null,\"sender_id\":1,\"type\":\"SENDER_DESCRIPTION\",\"type_id\":-1,\
             \"kind\":\"system\",\"system\":\"sender_description\",\"id\":1,\"name\":\"Tracker0\"}"
        ));
        assert!(lines[9].ends_with("\"kind\":\"analog\",\"channels\":[0.25,-0.5,0.001]}"));
        assert!(lines[11].ends_with("\"kind\":\"raw\",\"len\":2,\"hex\":\"dead\"}"));
    }

    #[test]
    fn fields_escape_text_and_null_non_finite_floats() {
        let json = |f: Field<'_>| serde_json::to_string(&f).unwrap();
        assert_eq!(
            json(Field::Str("a\"b\\c\nd\u{1}")),
            "\"a\\\"b\\\\c\\nd\\u0001\""
        );
        assert_eq!(json(Field::Bytes(b"ok\xff")), "\"ok\u{fffd}\"");
        assert_eq!(json(Field::Num(f64::NAN)), "null");
        assert_eq!(json(Field::Nums(&[1.5, f64::INFINITY])), "[1.5,null]");
        assert_eq!(json(Field::Ints(&[1, -2])), "[1,-2]");
        assert_eq!(json(Field::Hex(&[0xde, 0xad])), "\"dead\"");
        assert_eq!(
            json(Decoded::Raw(&[1]).fields().remove(0).1),
            "1",
            "len of a raw payload"
        );
    }

    #[test]
    fn time_is_the_decimal_sec_usec() {
        for (sec, usec) in [
            (1_795_309_401, 663_779),
            (10, 1),
            (0, 0),
            (4_294_967_295, 999_999),
        ] {
            let decimal = format!("{sec}.{usec:06}");
            let t = seconds(TimeVal::new(sec, usec));
            assert_eq!(t.to_bits(), decimal.parse::<f64>().unwrap().to_bits());
            let printed = serde_json::to_string(&t).unwrap();
            assert_eq!(printed.parse::<f64>().unwrap().to_bits(), t.to_bits());
        }
        assert_eq!(
            serde_json::to_string(&seconds(TimeVal::new(1_795_309_401, 663_779))).unwrap(),
            "1795309401.663779"
        );
    }

    #[test]
    fn format_json_appends() {
        let r = sample().reader();
        let mut w = Walk::new(&r);
        let rec = w.next_record().unwrap().unwrap();
        let mut s = String::from("x");
        format_json(&mut s, &rec);
        assert!(s.starts_with("x{\"offset\":24,\"time\":1.0,"), "{s}");
    }
}
