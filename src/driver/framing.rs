//! Finding records in a byte stream, one byte at a time, for the many devices whose records
//! have one shape: a start byte that gives the record's length, data bytes of one class, and a
//! fixed last byte (an ASCII `p` … LF, a letter … CR).
//!
//! A byte that breaks the shape ends the record being collected (which is dropped) and is
//! itself looked at as a possible start, so garbage costs at most the record it hits and never
//! a later one. Each record carries the arrival time of its first byte, whatever read brought
//! the rest. A device with another shape (a checksum, a sync pattern, a variable length) writes
//! its own framer and keeps these two rules.

use crate::time::Now;

/// The shape of a device's records.
pub trait RecordFormat {
    /// The record's whole length (start and last byte included) if `b` can start one.
    fn start(&self, b: u8) -> Option<usize>;
    /// Whether `b` may stand between the start and the last byte.
    fn is_data(&self, b: u8) -> bool;
    /// The byte every record ends with.
    fn last(&self) -> u8;
}

/// Why bytes were dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Problem {
    /// A byte that starts no record where a record should start.
    NotRecordStart(u8),
    /// A byte that is not a data byte inside a record.
    BadCharacter(u8),
    /// The last byte of a record was not the one it must be.
    BadLastByte(u8),
}

/// Bytes dropped before a record, and the first reason.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Skipped {
    /// How many.
    pub bytes: u64,
    /// Why the first of them was dropped.
    pub first: Problem,
}

/// One complete record of at most `N` bytes, and what was dropped before it.
#[derive(Clone, Copy, Debug)]
pub struct Framed<const N: usize> {
    bytes: [u8; N],
    len: usize,
    /// When the poll woke for its first byte.
    pub first_byte: Now,
    /// Garbage dropped between the previous record and this one.
    pub skipped: Option<Skipped>,
}

impl<const N: usize> Framed<N> {
    /// The record, start and last byte included.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }

    /// Its first byte.
    pub fn start(&self) -> u8 {
        self.bytes[0]
    }
}

impl<const N: usize> PartialEq for Framed<N> {
    fn eq(&self, other: &Self) -> bool {
        self.bytes() == other.bytes()
            && self.first_byte == other.first_byte
            && self.skipped == other.skipped
    }
}

impl<const N: usize> Eq for Framed<N> {}

/// The byte-wise record finder for records of format `F` and at most `N` bytes.
#[derive(Debug)]
pub struct Framer<F: RecordFormat, const N: usize> {
    format: F,
    buf: [u8; N],
    len: usize,
    want: usize,
    first_byte: Option<Now>,
    skipped: Option<Skipped>,
    total_skipped: u64,
}

impl<F: RecordFormat, const N: usize> Framer<F, N> {
    /// Waiting for a record start.
    pub fn new(format: F) -> Self {
        Framer {
            format,
            buf: [0; N],
            len: 0,
            want: 0,
            first_byte: None,
            skipped: None,
            total_skipped: 0,
        }
    }

    /// Forgets any partial record and the garbage count not reported yet (after a flush or a
    /// reopen).
    pub fn clear(&mut self) {
        self.len = 0;
        self.want = 0;
        self.first_byte = None;
        self.skipped = None;
    }

    /// Bytes dropped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    /// True while part of a record has been read.
    pub fn in_record(&self) -> bool {
        self.len > 0
    }

    /// Takes one byte that arrived at `arrived`; returns a record when this byte completes
    /// one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed<N>> {
        if self.want == 0 {
            self.start(b, arrived);
            return None;
        }
        if self.len + 1 < self.want {
            if !self.format.is_data(b) {
                self.drop_partial(Problem::BadCharacter(b));
                self.start(b, arrived);
                return None;
            }
            self.buf[self.len] = b;
            self.len += 1;
            return None;
        }
        if b != self.format.last() {
            self.drop_partial(Problem::BadLastByte(b));
            self.start(b, arrived);
            return None;
        }
        self.buf[self.len] = b;
        let framed = Framed {
            bytes: self.buf,
            len: self.want,
            first_byte: self.first_byte.unwrap_or(arrived),
            skipped: self.skipped.take(),
        };
        self.len = 0;
        self.want = 0;
        self.first_byte = None;
        Some(framed)
    }

    fn start(&mut self, b: u8, arrived: Now) {
        match self.format.start(b).filter(|&n| (2..=N).contains(&n)) {
            Some(n) => {
                self.buf[0] = b;
                self.len = 1;
                self.want = n;
                self.first_byte = Some(arrived);
            }
            None => self.skip(1, Problem::NotRecordStart(b)),
        }
    }

    fn drop_partial(&mut self, why: Problem) {
        let n = self.len as u64;
        self.len = 0;
        self.want = 0;
        self.first_byte = None;
        self.skip(n, why);
    }

    fn skip(&mut self, n: u64, why: Problem) {
        self.total_skipped += n;
        match &mut self.skipped {
            Some(s) => s.bytes += n,
            None => {
                self.skipped = Some(Skipped {
                    bytes: n,
                    first: why,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::time::{Duration, Instant};

    use super::*;
    use crate::time::TimeVal;

    /// `a` + 2 digits + `.`, or `b` + `.`.
    struct Toy;

    impl RecordFormat for Toy {
        fn start(&self, b: u8) -> Option<usize> {
            match b {
                b'a' => Some(4),
                b'b' => Some(2),
                _ => None,
            }
        }
        fn is_data(&self, b: u8) -> bool {
            b.is_ascii_digit()
        }
        fn last(&self) -> u8 {
            b'.'
        }
    }

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(1000, 0).plus(Duration::from_millis(ms)),
        }
    }

    fn frame(f: &mut Framer<Toy, 8>, bytes: &[u8], t: Now) -> Vec<Framed<8>> {
        bytes.iter().filter_map(|&b| f.push(b, t)).collect()
    }

    #[test]
    fn records_in_pieces_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut f = Framer::new(Toy);
        assert!(frame(&mut f, b"a1", at(1, base)).is_empty());
        assert!(f.in_record());
        let got = frame(&mut f, b"2.b.", at(5, base));
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].bytes(), b"a12.");
        assert_eq!(got[0].first_byte, at(1, base));
        assert_eq!(got[1].bytes(), b"b.");
        assert_eq!(got[1].first_byte, at(5, base));
        assert_eq!(got[1].start(), b'b');
    }

    #[test]
    fn garbage_costs_only_the_record_it_hits() {
        let base = Instant::now();
        let mut f = Framer::new(Toy);
        // Noise; a record cut by a start; a bad data byte; a bad last byte; then good ones.
        let got = frame(&mut f, b"xy\x00a1b.a1z9a12!a34.", at(0, base));
        let recs: Vec<&[u8]> = got.iter().map(|g| g.bytes()).collect();
        assert_eq!(recs, vec![&b"b."[..], &b"a34."[..]]);
        assert_eq!(
            got[0].skipped,
            Some(Skipped {
                bytes: 5,
                first: Problem::NotRecordStart(b'x')
            })
        );
        let s = got[1].skipped.unwrap();
        assert_eq!(s.first, Problem::BadCharacter(b'z'));
        // "a1", 'z', '9', then "a12" cut by '!', and '!' itself.
        assert_eq!(s.bytes, 2 + 1 + 1 + 3 + 1);
        assert_eq!(f.total_skipped(), 5 + 8);
        f.clear();
        assert!(!f.in_record());
    }
}
