//! The controller's answers to a temperature request, read byte by byte: a decimal number, a
//! unit letter (`C`, or `E` on some channels) and a carriage return, e.g. `37.1C\r`.
//!
//! As C++ reads them: a leading `-` is dropped, the number is read as C's `%f` reads it, and
//! the character after it must be `C`, `E` or the carriage return. Bytes that cannot start an
//! answer (anything but a digit, a sign or a point) are skipped before it, so garbage without
//! digits costs no answer. Each answer carries the arrival time of the read holding its first
//! byte.

use crate::time::Now;

/// Longest answer kept.
const MAX: usize = 32;

/// What a carriage return ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Answer {
    /// A reading, °C, and when its first byte arrived.
    Reading(f64, Now),
    /// Something else (its length in bytes, carriage return included).
    Bad(usize),
}

/// Reads answers byte by byte. See the module documentation.
#[derive(Clone, Debug)]
pub struct Reader {
    buf: [u8; MAX],
    len: usize,
    total: usize,
    first: Option<Now>,
    skipped: u64,
}

impl Default for Reader {
    fn default() -> Reader {
        Reader::new()
    }
}

impl Reader {
    /// A reader between answers.
    pub fn new() -> Reader {
        Reader {
            buf: [0; MAX],
            len: 0,
            total: 0,
            first: None,
            skipped: 0,
        }
    }

    /// Forgets a partial answer.
    pub fn clear(&mut self) {
        self.first = None;
        self.len = 0;
        self.total = 0;
    }

    /// Bytes skipped between answers since the last call (and forgets them).
    pub fn take_skipped(&mut self) -> u64 {
        std::mem::take(&mut self.skipped)
    }

    /// Takes one byte that arrived at `arrived`; returns what a carriage return ended.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Answer> {
        if self.first.is_none() {
            if !(b.is_ascii_digit() || b == b'-' || b == b'+' || b == b'.') {
                self.skipped += 1;
                return None;
            }
            self.first = Some(arrived);
        }
        self.total += 1;
        if b != b'\r' {
            if self.len < MAX {
                self.buf[self.len] = b;
                self.len += 1;
            }
            return None;
        }
        let first = self.first.unwrap_or(arrived);
        let answer = match parse(&self.buf[..self.len]) {
            Some(v) if self.total <= MAX => Answer::Reading(v, first),
            _ => Answer::Bad(self.total),
        };
        self.clear();
        Some(answer)
    }
}

/// The reading in an answer (without its carriage return), as C++ reads it.
pub fn parse(text: &[u8]) -> Option<f64> {
    let text = text.strip_prefix(b"-").unwrap_or(text);
    // The longest prefix that is a number: sign, digits, point, digits.
    let mut end = usize::from(matches!(text.first(), Some(b'+' | b'-')));
    let digits_start = end;
    while text.get(end).is_some_and(u8::is_ascii_digit) {
        end += 1;
    }
    let mut digits = end - digits_start;
    if text.get(end) == Some(&b'.') {
        end += 1;
        let frac = end;
        while text.get(end).is_some_and(u8::is_ascii_digit) {
            end += 1;
        }
        digits += end - frac;
    }
    if digits == 0 {
        return None;
    }
    match &text[end..] {
        [] | [b'C'] | [b'E'] => {}
        [b'C' | b'E', ..] => {}
        _ => return None,
    }
    std::str::from_utf8(&text[..end]).ok()?.parse::<f64>().ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(100, 0).plus(Duration::from_millis(ms)),
        }
    }

    #[test]
    fn readings_as_cpp_reads_them() {
        assert_eq!(parse(b"37.1C"), Some(37.1));
        assert_eq!(parse(b"36.9E"), Some(36.9));
        assert_eq!(parse(b"37"), Some(37.0));
        assert_eq!(parse(b"-5.5C"), Some(5.5), "C++ drops a leading minus");
        assert_eq!(parse(b"37.1 C"), None);
        assert_eq!(parse(b"C"), None);
        assert_eq!(parse(b"37.1X"), None);
    }

    #[test]
    fn answers_after_garbage_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut r = Reader::new();
        let mut got = Vec::new();
        for (i, chunk) in [&b"xy\r"[..], b"3", b"7.5C\r", b"bad!\r", b"2X\r"]
            .iter()
            .enumerate()
        {
            for &b in chunk.iter() {
                got.extend(r.push(b, at(i as u64, base)));
            }
        }
        assert_eq!(got, [Answer::Reading(37.5, at(1, base)), Answer::Bad(3),]);
        // "bad!\r": b, a, d, ! skipped, then the CR alone is skipped as well.
        assert_eq!(r.take_skipped(), 3 + 5);
    }
}
