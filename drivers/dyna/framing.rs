//! Finding records in the byte stream, one byte at a time.
//!
//! A record starts at a byte whose high nibble is `1000`. Eight bytes from such a byte are
//! checked ([`record::validate`]); a failed candidate gives up only its first byte and the
//! search goes on from the second, so a record that follows garbage (or a false start inside
//! garbage) is still found. C++ VRPN drops all eight bytes of a failed candidate instead, and
//! with them the start of the next record.
//!
//! The protocol has no checksum: a header-like byte just before a record can pass, with the
//! record's first seven bytes, for a record (when no coordinate pair looks like a header).
//! That record is then lost and a wrong position reported, as in C++; garbage whose
//! header-like bytes are each followed by another byte costs nothing.
//!
//! Each buffered byte keeps the time its read arrived, so a record found after a rescan still
//! carries the arrival time of its own first byte.

use super::record::{self, Invalid, RECORD_LEN};
use crate::time::Now;

/// A record found in the stream.
#[derive(Clone, Copy, Debug)]
pub struct Framed {
    /// The record's bytes (valid).
    pub bytes: [u8; RECORD_LEN],
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes skipped since the previous record.
    pub skipped: u32,
    /// Why the last candidate before this record failed, if one did.
    pub rejected: Option<Invalid>,
}

/// The byte-wise record finder. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    buf: [u8; RECORD_LEN],
    times: [Option<Now>; RECORD_LEN],
    len: usize,
    skipped: u32,
    rejected: Option<Invalid>,
    total_skipped: u64,
}

impl Default for Framer {
    fn default() -> Framer {
        Framer::new()
    }
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Framer {
        Framer {
            buf: [0; RECORD_LEN],
            times: [None; RECORD_LEN],
            len: 0,
            skipped: 0,
            rejected: None,
            total_skipped: 0,
        }
    }

    /// Forgets a partial record (after a reset or a reopen).
    pub fn clear(&mut self) {
        self.len = 0;
        self.skipped = 0;
        self.rejected = None;
    }

    /// Bytes skipped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn skip(&mut self, n: usize) {
        self.skipped = self.skipped.saturating_add(n as u32);
        self.total_skipped += n as u64;
    }

    /// Takes one byte that arrived at `arrived`; returns a record when this byte completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        if self.len == 0 && !record::is_sync(b) {
            self.skip(1);
            return None;
        }
        self.buf[self.len] = b;
        self.times[self.len] = Some(arrived);
        self.len += 1;
        if self.len < RECORD_LEN {
            return None;
        }
        match record::validate(&self.buf) {
            Ok(()) => {
                let framed = Framed {
                    bytes: self.buf,
                    first_byte: self.times[0].unwrap_or(arrived),
                    skipped: self.skipped,
                    rejected: self.rejected.take(),
                };
                self.len = 0;
                self.skipped = 0;
                Some(framed)
            }
            Err(why) => {
                self.rejected = Some(why);
                // Give up the first byte, then everything up to the next possible start.
                let next = (1..RECORD_LEN)
                    .find(|&i| record::is_sync(self.buf[i]))
                    .unwrap_or(RECORD_LEN);
                self.skip(next);
                self.buf.copy_within(next.., 0);
                self.times.copy_within(next.., 0);
                self.len = RECORD_LEN - next;
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::dyna::record::encode;
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
    fn records_after_garbage_and_false_starts_are_all_found() {
        let base = Instant::now();
        let mut f = Framer::new();
        let mut out = Vec::new();
        let a = encode(0, 1, 0, [10, 20, 30]);
        let b = encode(0, 2, 1, [-10, -20, -30]);
        feed(&mut f, &[0x01, 0x7F], at(0, base), &mut out);
        feed(&mut f, &a, at(1, base), &mut out);
        // A false start (0x85 then a byte without the sync nibble), then a record.
        feed(&mut f, &[0x85, 0x12, 0x33], at(2, base), &mut out);
        feed(&mut f, &b[..3], at(3, base), &mut out);
        feed(&mut f, &b[3..], at(4, base), &mut out);
        assert_eq!(out.len(), 2);
        assert_eq!(out[0].bytes, a);
        assert_eq!(out[0].skipped, 2);
        assert_eq!(out[0].first_byte, at(1, base));
        assert_eq!(out[1].bytes, b);
        assert_eq!(out[1].skipped, 3);
        assert_eq!(out[1].rejected, Some(Invalid::SecondByte(0x12)));
        // The first byte of b arrived at 3 ms, its last at 4 ms.
        assert_eq!(out[1].first_byte, at(3, base));
        assert_eq!(f.total_skipped(), 5);
    }

    #[test]
    fn a_record_straddling_a_failed_candidate_keeps_its_own_time() {
        let base = Instant::now();
        let mut f = Framer::new();
        let mut out = Vec::new();
        // X = 0x8300: its high byte looks like a header byte.
        let a = encode(0, 0, 0, [0x8300u16 as i16, 2, 3]);
        // 0x81 then a: the candidate [81 80 80 83 ..] has a header pair inside.
        feed(&mut f, &[0x81], at(0, base), &mut out);
        feed(&mut f, &a, at(5, base), &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].bytes, a);
        assert_eq!(out[0].first_byte, at(5, base));
        assert_eq!(out[0].rejected, Some(Invalid::HeaderInside));
    }
}
