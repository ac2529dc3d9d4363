//! Finding CerealBox records in the byte stream, one byte at a time.
//!
//! A record starts with `p`, has the layout's length, carries only data characters
//! (`0x21..=0x60`) and ends with LF. A byte that breaks these rules ends the record being
//! collected (which is dropped) and is itself looked at as a possible start, so garbage
//! costs at most the record it hits. The record's time is the arrival of its `p`.

use super::record::{Layout, LF, MAX_DATA, MAX_RECORD, OFFSET, START};
use crate::time::Now;

/// Why bytes were dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Problem {
    /// A byte other than `p` where a record should start.
    NotRecordStart(u8),
    /// A byte that is not a data character inside a record.
    BadCharacter(u8),
    /// The last byte of a record was not LF.
    NoLineFeed(u8),
}

/// Bytes dropped before a record, and the first reason.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Skipped {
    /// How many.
    pub bytes: u64,
    /// Why the first of them was dropped.
    pub first: Problem,
}

/// One complete record and what was dropped before it.
#[derive(Clone, Copy, Debug)]
pub struct Framed {
    bytes: [u8; MAX_RECORD],
    len: usize,
    /// When the poll woke for its `p`.
    pub first_byte: Now,
    /// Garbage dropped between the previous record and this one.
    pub skipped: Option<Skipped>,
}

impl Framed {
    /// The record, `p` and LF included.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

/// The framing state.
#[derive(Debug)]
pub struct Framer {
    want: usize,
    buf: [u8; MAX_RECORD],
    len: usize,
    first_byte: Option<Now>,
    skipped: Option<Skipped>,
    total_skipped: u64,
}

impl Framer {
    /// Looking for records of `layout`.
    pub fn new(layout: &Layout) -> Framer {
        Framer {
            want: layout.record_len(),
            buf: [0; MAX_RECORD],
            len: 0,
            first_byte: None,
            skipped: None,
            total_skipped: 0,
        }
    }

    /// Forgets any partial record and pending garbage count.
    pub fn clear(&mut self) {
        self.len = 0;
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

    /// Takes one byte that arrived at `arrived`; returns a record when this byte completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        if self.len == 0 {
            self.start(b, arrived);
        } else if self.len + 1 == self.want {
            if b != LF {
                self.drop_partial(Problem::NoLineFeed(b));
                self.start(b, arrived);
                return None;
            }
            self.buf[self.len] = b;
            self.len += 1;
        } else if (OFFSET..=MAX_DATA).contains(&b) {
            self.buf[self.len] = b;
            self.len += 1;
            return None;
        } else {
            self.drop_partial(Problem::BadCharacter(b));
            self.start(b, arrived);
            return None;
        }
        // Only the final LF completes a record (with no inputs a record is just `p` LF).
        if self.len < self.want {
            return None;
        }
        let framed = Framed {
            bytes: self.buf,
            len: self.want,
            first_byte: self.first_byte.unwrap_or(arrived),
            skipped: self.skipped.take(),
        };
        self.len = 0;
        self.first_byte = None;
        Some(framed)
    }

    fn start(&mut self, b: u8, arrived: Now) {
        if b == START {
            self.buf[0] = b;
            self.len = 1;
            self.first_byte = Some(arrived);
        } else {
            self.skip(1, Problem::NotRecordStart(b));
        }
    }

    fn drop_partial(&mut self, why: Problem) {
        let n = self.len as u64;
        self.len = 0;
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

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(1000, 0).plus(Duration::from_millis(ms)),
        }
    }

    const LAYOUT: Layout = Layout {
        buttons: 8,
        analogs: 2,
        encoders: 1,
    };

    fn frame_all(f: &mut Framer, bytes: &[u8], t: Now) -> Vec<Framed> {
        bytes.iter().filter_map(|&b| f.push(b, t)).collect()
    }

    #[test]
    fn records_in_pieces_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut f = Framer::new(&LAYOUT);
        let (r, n) = LAYOUT.encode(0x5A, &[100, 4000], &[-3]);
        assert!(frame_all(&mut f, &r[..3], at(1, base)).is_empty());
        let got = frame_all(&mut f, &r[3..n], at(4, base));
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].bytes(), &r[..n]);
        assert_eq!(got[0].first_byte, at(1, base));
        assert!(got[0].skipped.is_none());
    }

    #[test]
    fn garbage_costs_only_the_record_it_hits() {
        let base = Instant::now();
        let mut f = Framer::new(&LAYOUT);
        let (r, n) = LAYOUT.encode(0xFF, &[0, 4095], &[77]);
        let rec = &r[..n];
        let mut stream = b"xx\n".to_vec();
        // Cut short by the next record.
        stream.extend_from_slice(&rec[..5]);
        stream.extend_from_slice(rec);
        // A control character inside.
        let mut bad = rec.to_vec();
        bad[4] = 0x07;
        stream.extend_from_slice(&bad);
        stream.extend_from_slice(rec);
        // No LF at the end.
        stream.extend_from_slice(&rec[..n - 1]);
        stream.push(b'!');
        stream.extend_from_slice(rec);
        let got = frame_all(&mut f, &stream, at(0, base));
        assert_eq!(got.len(), 3);
        assert!(got.iter().all(|g| g.bytes() == rec));
        assert_eq!(
            got[0].skipped,
            Some(Skipped {
                bytes: 8,
                first: Problem::NotRecordStart(b'x')
            })
        );
        assert_eq!(got[1].skipped.unwrap().first, Problem::BadCharacter(0x07));
        assert_eq!(got[1].skipped.unwrap().bytes, n as u64);
        assert_eq!(got[2].skipped.unwrap().first, Problem::NoLineFeed(b'!'));
        assert_eq!(got[2].skipped.unwrap().bytes, n as u64);
    }

    #[test]
    fn a_box_with_no_inputs_sends_p_lf() {
        let base = Instant::now();
        let none = Layout {
            buttons: 0,
            analogs: 0,
            encoders: 0,
        };
        let mut f = Framer::new(&none);
        let got = frame_all(&mut f, b"p\npp\n", at(0, base));
        assert_eq!(got.len(), 2);
        assert_eq!(f.total_skipped(), 1);
    }
}
