//! Finding records in the byte stream, one byte at a time.
//!
//! A byte with the sync bit starts a record; the 19 after it must not have it. A byte with
//! the sync bit inside a record ends the record being collected (dropped) and starts the next,
//! so garbage costs at most the record it falls into, never a later one. A complete record
//! whose station the tracker does not have is dropped the same way (C++ VRPN flushes the whole
//! input buffer instead). Each record keeps the time the read holding its first byte arrived.

use super::record::{self, Invalid, Model, Pose, RECORD_LEN, SYNC};
use crate::time::Now;

/// A record found in the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// Its values.
    pub pose: Pose,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes dropped since the previous record.
    pub skipped: u32,
    /// Why the last candidate before this record was dropped, if one was.
    pub rejected: Option<Invalid>,
}

/// The byte-wise record finder. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    model: Model,
    buf: [u8; RECORD_LEN],
    len: usize,
    first_byte: Option<Now>,
    skipped: u32,
    rejected: Option<Invalid>,
    total_skipped: u64,
}

impl Framer {
    /// An empty framer for `model`'s records.
    pub fn new(model: Model) -> Framer {
        Framer {
            model,
            buf: [0; RECORD_LEN],
            len: 0,
            first_byte: None,
            skipped: 0,
            rejected: None,
            total_skipped: 0,
        }
    }

    /// Forgets a partial record (after a reset or a reopen).
    pub fn clear(&mut self) {
        self.len = 0;
        self.first_byte = None;
        self.skipped = 0;
        self.rejected = None;
    }

    /// Bytes dropped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn drop_bytes(&mut self, n: usize) {
        self.skipped = self.skipped.saturating_add(n as u32);
        self.total_skipped += n as u64;
    }

    /// Takes one byte that arrived at `arrived`; returns a record when this byte completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        if b & SYNC != 0 {
            // A start: whatever was collected is lost.
            self.drop_bytes(self.len);
            self.buf[0] = b;
            self.len = 1;
            self.first_byte = Some(arrived);
            return None;
        }
        if self.len == 0 {
            self.drop_bytes(1);
            return None;
        }
        self.buf[self.len] = b;
        self.len += 1;
        if self.len < RECORD_LEN {
            return None;
        }
        self.len = 0;
        match record::decode(self.model, &self.buf) {
            Ok(pose) => Some(Framed {
                pose,
                first_byte: self.first_byte.take().unwrap_or(arrived),
                skipped: std::mem::take(&mut self.skipped),
                rejected: self.rejected.take(),
            }),
            Err(why) => {
                self.rejected = Some(why);
                self.drop_bytes(RECORD_LEN);
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::threespace::record::{data, pack};
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(100, 0).plus(Duration::from_millis(ms)),
        }
    }

    fn feed(f: &mut Framer, bytes: &[u8], t: Now, out: &mut Vec<Framed>) {
        for &b in bytes {
            out.extend(f.push(b, t));
        }
    }

    #[test]
    fn garbage_and_broken_records_cost_no_later_record() {
        let base = Instant::now();
        let mut f = Framer::new(Model::Isotrak);
        let mut out = Vec::new();
        let a = pack(&data(1, b'*', [1, 2, 3, 32767, 0, 0, 0]));
        let b = pack(&data(2, b'@', [-1, -2, -3, 0, 32767, 0, 0]));
        feed(&mut f, &[0x01, 0x7F], at(0, base), &mut out);
        feed(&mut f, &a, at(1, base), &mut out);
        // A broken record (cut by the next sync byte), then b in two reads.
        feed(&mut f, &a[..9], at(2, base), &mut out);
        feed(&mut f, &b[..5], at(3, base), &mut out);
        feed(&mut f, &b[5..], at(4, base), &mut out);
        // A record for a station the Isotrak does not have, then a again.
        feed(&mut f, &pack(&data(3, b' ', [0; 7])), at(5, base), &mut out);
        feed(&mut f, &a, at(6, base), &mut out);
        assert_eq!(out.len(), 3);
        assert_eq!((out[0].pose.sensor, out[0].skipped), (0, 2));
        assert_eq!(out[0].first_byte, at(1, base));
        assert_eq!((out[1].pose.sensor, out[1].skipped), (1, 9));
        assert_eq!(out[1].first_byte, at(3, base));
        assert_eq!(out[2].skipped, 20);
        assert_eq!(out[2].rejected, Some(Invalid::Station(b'3')));
        assert_eq!(f.total_skipped(), 31);
    }
}
