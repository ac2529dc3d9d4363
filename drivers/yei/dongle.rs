//! Finding the wireless units' records in what the dongle sends, one byte at a time.
//!
//! A record released by the dongle comes framed: status `00`, the unit's logical id, the
//! length `59` (89) and the record. A frame whose status is not 0, whose id is not a
//! configured unit's, whose length is not a record's or whose record [`decode`] refuses
//! gives up its first byte and the search goes on from the next, so garbage (or a failure
//! answer, `status id`) costs its own bytes and no record (the first reason of a run of
//! dropped bytes is kept, for the note). Each frame keeps the time the read holding its first
//! byte arrived.

use super::record::{decode, Invalid, Record, RECORD_LEN};
use crate::time::Now;

/// Bytes in a framed record.
pub const FRAME_LEN: usize = 3 + RECORD_LEN;

/// Why bytes were dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reject {
    /// A status byte other than 0 (a failure, or garbage).
    Status(u8),
    /// A logical id no configured unit has.
    Id(u8),
    /// A length other than a record's.
    Length(u8),
    /// A record that is not one.
    Record(Invalid),
}

impl std::fmt::Display for Reject {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Reject::Status(s) => write!(f, "status byte {s} where 0 was due"),
            Reject::Id(i) => write!(f, "logical id {i}, which no configured unit has"),
            Reject::Length(n) => write!(f, "length {n} where {RECORD_LEN} was due"),
            Reject::Record(why) => write!(f, "{why}"),
        }
    }
}

/// A record found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// The unit's logical id.
    pub id: u8,
    /// Its values.
    pub record: Record,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes dropped before it since the previous record.
    pub skipped: u32,
    /// Why the last bytes were dropped, if some were.
    pub rejected: Option<Reject>,
}

/// The frame finder. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    ids: u16,
    buf: [u8; FRAME_LEN],
    at: [Option<Now>; FRAME_LEN],
    len: usize,
    skipped: u32,
    rejected: Option<Reject>,
}

impl Framer {
    /// A framer for units at logical `ids` (0–14).
    pub fn new(ids: impl IntoIterator<Item = u8>) -> Framer {
        Framer {
            ids: ids.into_iter().fold(0, |m, id| m | 1 << id),
            buf: [0; FRAME_LEN],
            at: [None; FRAME_LEN],
            len: 0,
            skipped: 0,
            rejected: None,
        }
    }

    /// Forgets a partial frame.
    pub fn clear(&mut self) {
        self.len = 0;
        self.skipped = 0;
        self.rejected = None;
    }

    /// Takes one byte that arrived at `arrived`; call [`next_frame`](Self::next_frame) until
    /// it returns `None`.
    pub fn push(&mut self, b: u8, arrived: Now) {
        if self.len == FRAME_LEN {
            self.drop_one(Reject::Length(self.buf[2]));
        }
        self.buf[self.len] = b;
        self.at[self.len] = Some(arrived);
        self.len += 1;
    }

    fn drop_one(&mut self, why: Reject) {
        // The first reason of a run of dropped bytes tells most.
        self.rejected.get_or_insert(why);
        self.skipped = self.skipped.saturating_add(1);
        self.buf.copy_within(1..self.len, 0);
        self.at.copy_within(1..self.len, 0);
        self.len -= 1;
    }

    fn known(&self, id: u8) -> bool {
        id < 16 && self.ids & (1 << id) != 0
    }

    /// The next record the bytes so far hold, if any.
    pub fn next_frame(&mut self) -> Option<Framed> {
        loop {
            if self.len == 0 {
                return None;
            }
            if self.buf[0] != 0 {
                self.drop_one(Reject::Status(self.buf[0]));
                continue;
            }
            if self.len < 2 {
                return None;
            }
            if !self.known(self.buf[1]) {
                self.drop_one(Reject::Id(self.buf[1]));
                continue;
            }
            if self.len < 3 {
                return None;
            }
            if usize::from(self.buf[2]) != RECORD_LEN {
                self.drop_one(Reject::Length(self.buf[2]));
                continue;
            }
            if self.len < FRAME_LEN {
                return None;
            }
            let body: &[u8; RECORD_LEN] = self.buf[3..].try_into().ok()?;
            match decode(body) {
                Ok(record) => {
                    self.len = 0;
                    return Some(Framed {
                        id: self.buf[1],
                        record,
                        first_byte: self.at[0]?,
                        skipped: std::mem::take(&mut self.skipped),
                        rejected: self.rejected.take(),
                    });
                }
                Err(why) => self.drop_one(Reject::Record(why)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drivers::yei::record::encode;
    use crate::drivers::yei::sim::record_of;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(100, 0).plus(Duration::from_millis(ms)),
        }
    }

    fn frame(id: u8, k: u64) -> Vec<u8> {
        let mut f = vec![0, id, RECORD_LEN as u8];
        f.extend_from_slice(&encode(&record_of(usize::from(id), k)));
        f
    }

    #[test]
    fn frames_of_several_units_and_garbage_between_them() {
        let base = Instant::now();
        let mut f = Framer::new([0, 3]);
        let mut out = Vec::new();
        let mut feed = |f: &mut Framer, bytes: &[u8], t: u64| {
            for &b in bytes {
                f.push(b, at(t, base));
                while let Some(r) = f.next_frame() {
                    out.push(r);
                }
            }
        };
        feed(&mut f, &frame(0, 1), 0);
        // A failure answer, garbage, a unit nobody configured, then unit 3 in two reads.
        feed(&mut f, &[1, 3, b'x', 0, 5, 89], 1);
        let b = frame(3, 2);
        feed(&mut f, &b[..40], 2);
        feed(&mut f, &b[40..], 3);
        // A frame with a wrong length, then unit 0 again.
        feed(&mut f, &[0, 0, 12], 4);
        feed(&mut f, &frame(0, 3), 5);
        assert_eq!(out.len(), 3, "{out:?}");
        assert_eq!(
            (out[0].id, out[0].skipped, out[0].first_byte),
            (0, 0, at(0, base))
        );
        assert_eq!(
            (out[1].id, out[1].skipped, out[1].first_byte),
            (3, 6, at(2, base))
        );
        assert_eq!(out[1].record.buttons, record_of(3, 2).buttons);
        assert_eq!((out[2].id, out[2].skipped), (0, 3));
        assert_eq!(out[2].rejected, Some(Reject::Length(12)));
    }
}
