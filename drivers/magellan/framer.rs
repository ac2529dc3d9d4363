//! Finding Magellan records in the byte stream, one byte at a time, with the shared framer
//! ([`crate::driver::framing`]).
//!
//! A record starts with a known letter, has the length that letter gives, carries only
//! nibble characters, and ends with CR. A byte that breaks these rules ends the record being
//! collected (which is dropped), and is itself looked at as a possible record start, so
//! garbage costs at most the record it hits and never a later one. The record's time is the
//! arrival of its letter.

use super::record::{is_nibble_char, record_len, CR, MAX_RECORD};
use crate::driver::framing::{self, RecordFormat};

pub use crate::driver::framing::{Problem, Skipped};

/// The Magellan's record shape.
#[derive(Clone, Copy, Debug, Default)]
pub struct Format;

impl RecordFormat for Format {
    fn start(&self, b: u8) -> Option<usize> {
        record_len(b)
    }
    fn is_data(&self, b: u8) -> bool {
        is_nibble_char(b)
    }
    fn last(&self) -> u8 {
        CR
    }
}

/// One complete record: its letter is [`Record::start`](framing::Framed::start).
pub type Record = framing::Framed<MAX_RECORD>;

/// The Magellan's framer.
pub type Framer = framing::Framer<Format, MAX_RECORD>;

#[cfg(test)]
mod tests {
    use std::time::{Duration, Instant};

    use super::super::record::{encode_axes, encode_keys};
    use super::*;
    use crate::time::{Now, TimeVal};

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(1000, 0).plus(Duration::from_millis(ms)),
        }
    }

    fn frame_all(f: &mut Framer, bytes: &[u8], t: Now) -> Vec<Record> {
        bytes.iter().filter_map(|&b| f.push(b, t)).collect()
    }

    #[test]
    fn records_in_pieces_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut f = Framer::new(Format);
        let d = encode_axes(&[1, 2, 3, 4, 5, 6]);
        assert!(frame_all(&mut f, &d[..10], at(1, base)).is_empty());
        let got = frame_all(&mut f, &d[10..], at(7, base));
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].bytes(), &d[..]);
        assert_eq!(got[0].first_byte, at(1, base));
        assert!(got[0].skipped.is_none());
        let got = frame_all(&mut f, b"z\rb\rnH\r", at(9, base));
        let letters: Vec<u8> = got.iter().map(|g| g.start()).collect();
        assert_eq!(letters, b"zbn");
    }

    #[test]
    fn garbage_costs_only_the_record_it_hits() {
        let base = Instant::now();
        let mut f = Framer::new(Format);
        let k = encode_keys(0x155);
        let d = encode_axes(&[-7000, 0, 9, 100, -100, 7000]);
        let mut stream = Vec::new();
        stream.extend_from_slice(b"\x00xy");
        // A key record cut short by an axis record: the key record is lost, the axis kept.
        stream.extend_from_slice(&k[..3]);
        stream.extend_from_slice(&d);
        // An axis record with a bad character, then a key record.
        let mut bad = d;
        bad[9] = b'1';
        stream.extend_from_slice(&bad);
        stream.extend_from_slice(&k);
        // No CR where it belongs, then a good key record right after.
        stream.extend_from_slice(&k[..4]);
        stream.push(b'A');
        stream.extend_from_slice(&k);
        let got = frame_all(&mut f, &stream, at(0, base));
        let recs: Vec<&[u8]> = got.iter().map(|g| g.bytes()).collect();
        assert_eq!(recs, vec![&d[..], &k[..], &k[..]]);
        assert_eq!(
            got[0].skipped,
            Some(Skipped {
                bytes: 6,
                first: Problem::NotRecordStart(0)
            })
        );
        // The bad axis record's 9 bytes, the '1', and the following data characters up to
        // the key record's letter.
        let s1 = got[1].skipped.unwrap();
        assert_eq!(s1.first, Problem::BadCharacter(b'1'));
        assert_eq!(s1.bytes, 26);
        let s2 = got[2].skipped.unwrap();
        assert_eq!(s2.first, Problem::BadLastByte(b'A'));
        assert_eq!(s2.bytes, 5);
        assert_eq!(f.total_skipped(), 6 + 26 + 5);
    }
}
