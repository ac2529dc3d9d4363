//! Finding records in the byte stream, one byte at a time.
//!
//! A record starts at a byte with the phasing bit (bit 7) set, and no other byte of a record
//! has it. So a byte with bit 7 clear while no record is open is garbage and is skipped, and
//! a byte with bit 7 set always opens a new record, abandoning a partial one: garbage never
//! costs more than the record it landed in, and the record after it is read whole.

use super::record::{GROUP_RECORD_LEN, PHASING_BIT};
use crate::time::Now;

/// A complete record, with the time its first byte arrived.
#[derive(Clone, Copy, Debug)]
pub struct Framed {
    /// The record's bytes (the first `len` are valid).
    pub bytes: [u8; GROUP_RECORD_LEN],
    /// When the read that carried the record's first byte woke.
    pub first_byte: Now,
    /// Bytes thrown away since the previous complete record (garbage and abandoned parts).
    pub skipped: u32,
}

/// Cuts a byte stream into records of one length.
#[derive(Clone, Debug)]
pub struct Framer {
    len: usize,
    buf: [u8; GROUP_RECORD_LEN],
    fill: usize,
    first_byte: Option<Now>,
    skipped: u32,
}

impl Framer {
    /// A framer for records of `len` bytes (at most the group-mode length).
    pub fn new(len: usize) -> Framer {
        assert!((1..=GROUP_RECORD_LEN).contains(&len));
        Framer {
            len,
            buf: [0; GROUP_RECORD_LEN],
            fill: 0,
            first_byte: None,
            skipped: 0,
        }
    }

    /// Record length.
    pub fn record_len(&self) -> usize {
        self.len
    }

    /// Takes one byte that arrived at `arrived`; returns the record it completes.
    pub fn push(&mut self, byte: u8, arrived: Now) -> Option<Framed> {
        if byte & PHASING_BIT != 0 {
            // A record starts here, whatever was open.
            self.skipped += self.fill as u32;
            self.buf[0] = byte;
            self.fill = 1;
            self.first_byte = Some(arrived);
        } else if self.fill == 0 {
            self.skipped += 1;
            return None;
        } else {
            self.buf[self.fill] = byte;
            self.fill += 1;
        }
        if self.fill < self.len {
            return None;
        }
        self.fill = 0;
        Some(Framed {
            bytes: self.buf,
            first_byte: self.first_byte.take().unwrap_or(arrived),
            skipped: std::mem::take(&mut self.skipped),
        })
    }

    /// Counts a complete record the caller rejected (a bad address) as skipped bytes.
    pub fn reject(&mut self, framed: &Framed) {
        self.skipped += framed.skipped + self.len as u32;
    }

    /// Forgets a partial record and the skip count (after a reset or reopen).
    pub fn clear(&mut self) {
        self.fill = 0;
        self.first_byte = None;
        self.skipped = 0;
    }

    /// True while a record is partly read.
    pub fn in_record(&self) -> bool {
        self.fill > 0
    }
}

#[cfg(test)]
mod tests {
    use std::time::{Duration, Instant};

    use super::*;
    use crate::time::TimeVal;

    fn at(ms: u64, base: Now) -> Now {
        base.plus(Duration::from_millis(ms))
    }

    fn base() -> Now {
        Now {
            mono: Instant::now(),
            wall: TimeVal::new(1000, 0),
        }
    }

    #[test]
    fn record_carries_its_first_byte_time() {
        let b = base();
        let mut f = Framer::new(4);
        assert!(f.push(0x81, at(1, b)).is_none());
        assert!(f.push(0x01, at(2, b)).is_none());
        assert!(f.push(0x02, at(3, b)).is_none());
        let r = f.push(0x03, at(4, b)).unwrap();
        assert_eq!(&r.bytes[..4], &[0x81, 1, 2, 3]);
        assert_eq!(r.first_byte, at(1, b));
        assert_eq!(r.skipped, 0);
    }

    #[test]
    fn garbage_is_skipped_and_a_phasing_byte_restarts() {
        let b = base();
        let mut f = Framer::new(3);
        let mut out = Vec::new();
        // Two garbage bytes, a partial record cut by a new one, then two whole records.
        for (i, byte) in [0x11u8, 0x12, 0x80, 0x01, 0x85, 0x05, 0x06, 0x87, 0x07, 0x08]
            .into_iter()
            .enumerate()
        {
            if let Some(r) = f.push(byte, at(i as u64, b)) {
                out.push(r);
            }
        }
        assert_eq!(out.len(), 2);
        assert_eq!(&out[0].bytes[..3], &[0x85, 5, 6]);
        assert_eq!(out[0].skipped, 4);
        assert_eq!(out[0].first_byte, at(4, b));
        assert_eq!(&out[1].bytes[..3], &[0x87, 7, 8]);
        assert_eq!(out[1].skipped, 0);
        assert_eq!(out[1].first_byte, at(7, b));
    }

    #[test]
    fn rejected_records_count_as_skipped() {
        let b = base();
        let mut f = Framer::new(2);
        f.push(0x80, b);
        let r = f.push(0x01, b).unwrap();
        f.reject(&r);
        f.push(0x81, b);
        assert!(f.in_record());
        let r = f.push(0x02, b).unwrap();
        assert_eq!(r.skipped, 2);
    }
}
