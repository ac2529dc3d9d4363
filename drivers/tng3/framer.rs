//! The TNG-3's records and how they are found (pure code).
//!
//! The box streams records of ten bytes with no gaps it promises: a start byte, eight analog
//! inputs (0-255), one byte of digital inputs (a set bit is an open, unpressed input). The
//! start byte is 0x55 and 0xAA in turn, and that is the only framing there is: data bytes
//! take every value, 0x55 and 0xAA included.
//!
//! In step, the framer expects the complement of the last start byte right after each record,
//! and a record is complete at its tenth byte. Anything else there loses step: then a
//! candidate record (a start byte and nine more) counts only once the byte after it is the
//! complement of its start byte, so a start byte among garbage or data is not taken for a
//! record; a failed candidate gives up its first byte only. The first record found after
//! losing step is therefore reported when the next one starts (with its own first byte's
//! time), and the rest as they complete.

use crate::time::Now;

/// Bytes in a record, the start byte included.
pub const RECORD_LEN: usize = 10;
/// The two start bytes.
pub const STARTS: [u8; 2] = [0x55, 0xAA];

/// A record found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// Its bytes: start byte, eight analogs, the digital byte.
    pub bytes: [u8; RECORD_LEN],
    /// When the read holding its start byte arrived.
    pub first_byte: Now,
    /// Bytes skipped since the previous record.
    pub skipped: u32,
}

/// The framer. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    buf: [u8; RECORD_LEN + 1],
    times: [Option<Now>; RECORD_LEN + 1],
    len: usize,
    /// The start byte expected next, while in step.
    in_step: Option<u8>,
    skipped: u32,
    total_skipped: u64,
}

impl Default for Framer {
    fn default() -> Framer {
        Framer::new()
    }
}

impl Framer {
    /// A framer out of step.
    pub fn new() -> Framer {
        Framer {
            buf: [0; RECORD_LEN + 1],
            times: [None; RECORD_LEN + 1],
            len: 0,
            in_step: None,
            skipped: 0,
            total_skipped: 0,
        }
    }

    /// Forgets everything, step included.
    pub fn clear(&mut self) {
        self.len = 0;
        self.in_step = None;
        self.skipped = 0;
    }

    /// True while in step.
    pub fn in_step(&self) -> bool {
        self.in_step.is_some()
    }

    /// Bytes skipped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn drop_front(&mut self, n: usize) {
        self.skipped = self.skipped.saturating_add(n as u32);
        self.total_skipped += n as u64;
        self.buf.copy_within(n..self.len, 0);
        self.times.copy_within(n..self.len, 0);
        self.len -= n;
    }

    fn take_record(&mut self, arrived: Now) -> Framed {
        let mut bytes = [0; RECORD_LEN];
        bytes.copy_from_slice(&self.buf[..RECORD_LEN]);
        let framed = Framed {
            bytes,
            first_byte: self.times[0].unwrap_or(arrived),
            skipped: std::mem::take(&mut self.skipped),
        };
        self.in_step = Some(!bytes[0]);
        self.buf.copy_within(RECORD_LEN..self.len, 0);
        self.times.copy_within(RECORD_LEN..self.len, 0);
        self.len -= RECORD_LEN;
        framed
    }

    /// Takes one byte that arrived at `arrived`; returns a record when one is found.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        self.buf[self.len] = b;
        self.times[self.len] = Some(arrived);
        self.len += 1;
        if let Some(start) = self.in_step {
            if self.buf[0] != start {
                // Out of step: hunt from here.
                self.in_step = None;
            } else if self.len == RECORD_LEN {
                return Some(self.take_record(arrived));
            } else {
                return None;
            }
        }
        loop {
            let first = (0..self.len)
                .find(|&i| STARTS.contains(&self.buf[i]))
                .unwrap_or(self.len);
            if first > 0 {
                self.drop_front(first);
            }
            if self.len <= RECORD_LEN {
                return None;
            }
            if self.buf[RECORD_LEN] == !self.buf[0] {
                return Some(self.take_record(arrived));
            }
            self.drop_front(1);
        }
    }
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

    fn record(start: u8, fill: u8) -> [u8; RECORD_LEN] {
        let mut r = [fill; RECORD_LEN];
        r[0] = start;
        r
    }

    #[test]
    fn in_step_after_two_records_and_back_after_garbage() {
        let base = Instant::now();
        let mut f = Framer::new();
        let mut got = Vec::new();
        // Data bytes that look like start bytes: a record full of 0xAA after a 0x55.
        let stream = [record(0x55, 0xAA), record(0xAA, 0x55), record(0x55, 0x12)];
        for (i, r) in stream.iter().enumerate() {
            for &b in r {
                got.extend(f.push(b, at(10 * i as u64, base)));
            }
        }
        // The first is found when the second starts; the others as they complete.
        assert_eq!(got.len(), 3);
        assert!(f.in_step());
        assert_eq!(got[0].bytes, stream[0]);
        assert_eq!(got[0].first_byte, at(0, base));
        assert_eq!(got[2].bytes, stream[2]);
        // Garbage, then the next records: nothing lost but the garbage.
        for &b in &[0x01, 0x55, 0x02] {
            assert_eq!(f.push(b, at(35, base)), None);
        }
        assert!(!f.in_step());
        let more = [record(0xAA, 0x33), record(0x55, 0x44)];
        for (i, r) in more.iter().enumerate() {
            for &b in r {
                got.extend(f.push(b, at(40 + 10 * i as u64, base)));
            }
        }
        assert_eq!(got.len(), 5);
        assert_eq!(got[4].bytes, more[1]);
        assert_eq!(got[3].bytes, more[0]);
        assert_eq!(got[3].skipped, 3);
        assert_eq!(got[3].first_byte, at(40, base));
        assert_eq!(f.total_skipped(), 3);
    }
}
