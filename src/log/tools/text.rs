//! The one-line text rendering of a record, as `vrpn_log dump` prints it.

use std::fmt::Write as _;

use super::decode::{Field, TEXT_HEX_LIMIT};
use super::walk::Record;

/// Bytes as lower-case hex digits, two per byte.
pub(super) struct Hex<'a>(pub(super) &'a [u8]);

impl std::fmt::Display for Hex<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.iter().try_for_each(|b| write!(f, "{b:02x}"))
    }
}

fn text_field(out: &mut String, f: &Field<'_>) {
    match f {
        Field::Int(i) => {
            let _ = write!(out, "{i}");
        }
        Field::Num(v) => {
            let _ = write!(out, "{v}");
        }
        Field::Nums(vs) => {
            out.push('(');
            for (i, v) in vs.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                let _ = write!(out, "{v}");
            }
            out.push(')');
        }
        Field::Ints(vs) => {
            out.push('(');
            for (i, v) in vs.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                let _ = write!(out, "{v}");
            }
            out.push(')');
        }
        Field::Str(s) => {
            let _ = write!(out, "{s:?}");
        }
        Field::String(s) => out.push_str(s),
        Field::Bytes(b) => {
            let _ = write!(out, "{:?}", String::from_utf8_lossy(b));
        }
        Field::Hex(b) => {
            let _ = write!(out, "{}", Hex(&b[..b.len().min(TEXT_HEX_LIMIT)]));
            if b.len() > TEXT_HEX_LIMIT {
                out.push_str("...");
            }
        }
    }
}

/// Appends the one-line text form of a record (no newline):
/// `OFFSET  SEC.USEC  SENDER  TYPE  field value …`.
pub fn format_text(out: &mut String, rec: &Record<'_, '_>) {
    let _ = write!(
        out,
        "{:>8}  {}  {}  {}",
        rec.entry.offset,
        rec.entry.time(),
        rec.sender_label(),
        rec.type_label()
    );
    for (key, field) in rec.decoded.fields() {
        if key == "system" {
            continue; // the type column already says which
        }
        let _ = write!(out, "  {key} ");
        text_field(out, &field);
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_log::sample;
    use super::super::{Decoded, Walk};
    use super::*;

    #[test]
    fn text_lines() {
        let r = sample().reader();
        let mut w = Walk::new(&r);
        let mut lines = Vec::new();
        while let Some(rec) = w.next_record() {
            let mut line = String::new();
            format_text(&mut line, &rec.unwrap());
            lines.push(line);
        }
        assert_eq!(
            lines[5],
            format!(
                "{:>8}  10.000000  Tracker0  vrpn_Tracker Pos_Quat  sensor 0  pos (0.1, 0.5, -1)  quat (0, 0, 0, 1)",
                {
                    let mut it = r.entries();
                    for _ in 0..5 {
                        it.next_entry();
                    }
                    it.offset()
                }
            )
        );
        assert!(lines[11].ends_with("<type 99>  len 2  hex dead"));
        let long = Decoded::Raw(&[0xab; 40]);
        let mut s = String::new();
        text_field(&mut s, &long.fields()[1].1);
        assert_eq!(s, format!("{}...", "ab".repeat(TEXT_HEX_LIMIT)));
    }
}
