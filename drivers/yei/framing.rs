//! Finding the wired unit's records in its byte stream, one byte at a time.
//!
//! Records come back to back with no header: once [`RECORD_LEN`] bytes are buffered they are
//! a record if [`decode`] accepts them; if not, the oldest byte is dropped and the window
//! slides on. Garbage therefore costs its own bytes and no record (C++ resets the unit
//! instead, when the confidence is out of range). Each record keeps the time the read
//! holding its first byte arrived.

use super::record::{decode, Invalid, Record, RECORD_LEN};
use crate::time::Now;

/// A record found in the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// Its values.
    pub record: Record,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes dropped before it since the previous record.
    pub skipped: u32,
    /// Why the last window dropped was not a record, if one was.
    pub rejected: Option<Invalid>,
}

/// The sliding-window record finder. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    buf: [u8; RECORD_LEN],
    at: [Option<Now>; RECORD_LEN],
    len: usize,
    skipped: u32,
    rejected: Option<Invalid>,
}

impl Default for Framer {
    fn default() -> Framer {
        Framer {
            buf: [0; RECORD_LEN],
            at: [None; RECORD_LEN],
            len: 0,
            skipped: 0,
            rejected: None,
        }
    }
}

impl Framer {
    /// Forgets a partial record (after a reset or a reopen).
    pub fn clear(&mut self) {
        *self = Framer::default();
    }

    /// Bytes held towards the next record.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Takes one byte that arrived at `arrived`; returns a record when this byte completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        self.buf[self.len] = b;
        self.at[self.len] = Some(arrived);
        self.len += 1;
        if self.len < RECORD_LEN {
            return None;
        }
        match decode(&self.buf) {
            Ok(record) => {
                self.len = 0;
                Some(Framed {
                    record,
                    first_byte: self.at[0].unwrap_or(arrived),
                    skipped: std::mem::take(&mut self.skipped),
                    rejected: self.rejected.take(),
                })
            }
            Err(why) => {
                self.rejected = Some(why);
                self.skipped = self.skipped.saturating_add(1);
                self.buf.copy_within(1.., 0);
                self.at.copy_within(1.., 0);
                self.len -= 1;
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::yei::record::encode;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(100, 0).plus(Duration::from_millis(ms)),
        }
    }

    fn rec(k: u8) -> Record {
        let (s, c) = (f64::from(k) * 0.01).sin_cos();
        Record {
            untared: [0.0, 0.0, s, c],
            tared: [s, 0.0, 0.0, c],
            accel_g: [0.01 * f64::from(k), 0.0, 0.0],
            channels: [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.2, 0.3, 0.4, 25.0, 0.5],
            buttons: k,
        }
    }

    #[test]
    fn garbage_costs_its_own_bytes_and_stamps_are_first_bytes() {
        let base = Instant::now();
        let mut f = Framer::default();
        let mut out = Vec::new();
        let a = encode(&rec(1));
        let b = encode(&rec(2));
        for (i, &x) in a.iter().enumerate() {
            out.extend(f.push(x, at(i as u64 / 40, base)));
        }
        for &x in b"junk!" {
            out.extend(f.push(x, at(10, base)));
        }
        out.extend(b.iter().flat_map(|&x| f.push(x, at(11, base))));
        for &x in &a[..30] {
            assert!(f.push(x, at(12, base)).is_none());
        }
        out.extend(a[30..].iter().flat_map(|&x| f.push(x, at(13, base))));
        assert_eq!(out.len(), 3);
        assert_eq!((out[0].record.buttons, out[0].skipped), (1, 0));
        assert_eq!(out[0].first_byte, at(0, base));
        assert_eq!((out[1].record.buttons, out[1].skipped), (2, 5));
        assert!(out[1].rejected.is_some());
        assert_eq!(out[1].first_byte, at(11, base));
        assert_eq!(out[2].first_byte, at(12, base));
        assert_eq!(out[2].skipped, 0);
    }
}
