//! Finding CerealBox records in the byte stream, one byte at a time, with the shared framer
//! ([`crate::driver::framing`]).
//!
//! A record starts with `p`, has the layout's length, carries only data characters
//! (`0x21..=0x60`) and ends with LF. A byte that breaks these rules ends the record being
//! collected (which is dropped) and is itself looked at as a possible start, so garbage
//! costs at most the record it hits. The record's time is the arrival of its `p`.

use super::record::{Layout, LF, MAX_DATA, MAX_RECORD, OFFSET, START};
use crate::driver::framing::{self, RecordFormat};

pub use crate::driver::framing::{Problem, Skipped};

/// The shape of a box's records: their length depends on its layout.
#[derive(Clone, Copy, Debug)]
pub struct Format {
    len: usize,
}

impl Format {
    /// Records of `layout`.
    pub fn new(layout: &Layout) -> Format {
        Format {
            len: layout.record_len(),
        }
    }
}

impl RecordFormat for Format {
    fn start(&self, b: u8) -> Option<usize> {
        (b == START).then_some(self.len)
    }
    fn is_data(&self, b: u8) -> bool {
        (OFFSET..=MAX_DATA).contains(&b)
    }
    fn last(&self) -> u8 {
        LF
    }
}

/// One complete record (`p` and LF included) and what was dropped before it.
pub type Framed = framing::Framed<MAX_RECORD>;

/// The box's framer.
pub type Framer = framing::Framer<Format, MAX_RECORD>;

#[cfg(test)]
mod tests {
    use std::time::{Duration, Instant};

    use super::*;
    use crate::time::{Now, TimeVal};

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
        let mut f = Framer::new(Format::new(&LAYOUT));
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
        let mut f = Framer::new(Format::new(&LAYOUT));
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
        assert_eq!(got[2].skipped.unwrap().first, Problem::BadLastByte(b'!'));
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
        let mut f = Framer::new(Format::new(&none));
        let got = frame_all(&mut f, b"p\npp\n", at(0, base));
        assert_eq!(got.len(), 2);
        assert_eq!(f.total_skipped(), 1);
    }
}
