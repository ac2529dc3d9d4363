//! The Data Glove 16's packets: finding them byte by byte and decoding them.
//!
//! Two kinds, both starting with `<`: data, `<D`, 36 bytes (sixteen sensors, each a
//! big-endian 16-bit value, then two bytes C++ ignores); information, `<I`, 7 bytes (hardware
//! version major and minor, a byte whose bit 0 says right hand, a byte whose bit 0 says wired,
//! one more byte). The glove puts information packets among its data packets.
//!
//! The [`Framer`] starts a candidate at `<` followed by `D` or `I`; any other byte is skipped,
//! so garbage costs no packet after it. Each buffered byte keeps the arrival time of its read.

use crate::time::Now;

/// First byte of every packet.
pub const START: u8 = b'<';
/// Length of a data packet.
pub const DATA_LEN: usize = 36;
/// Length of an information packet.
pub const INFO_LEN: usize = 7;
/// Sensors in a data packet.
pub const SENSORS: usize = 16;
/// Channels served: C++'s seventeen (channel 16 is never set).
pub const CHANNELS: usize = 17;

/// What a packet is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `<D`: sensor values.
    Data,
    /// `<I`: hardware version, hand, wired or wireless.
    Info,
}

impl Kind {
    fn of(b: u8) -> Option<Kind> {
        match b {
            b'D' => Some(Kind::Data),
            b'I' => Some(Kind::Info),
            _ => None,
        }
    }

    fn len(self) -> usize {
        match self {
            Kind::Data => DATA_LEN,
            Kind::Info => INFO_LEN,
        }
    }
}

/// The seventeen channels of a data packet, as C++ reports them: sensor `i` is
/// `256 × byte[2 + 2i] + byte[3 + 2i]`; channel 16 stays 0.
pub fn channels(p: &[u8]) -> [f64; CHANNELS] {
    let mut c = [0.0; CHANNELS];
    for (i, v) in c.iter_mut().take(SENSORS).enumerate() {
        *v = f64::from(p[2 + 2 * i]) * 256.0 + f64::from(p[3 + 2 * i]);
    }
    c
}

/// A packet found in the stream.
#[derive(Clone, Copy, Debug)]
pub struct Packet {
    /// Its kind.
    pub kind: Kind,
    bytes: [u8; DATA_LEN],
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
}

impl Packet {
    /// The packet's bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..self.kind.len()]
    }
}

/// Finds packets byte by byte. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    buf: [u8; DATA_LEN],
    first: Option<Now>,
    len: usize,
    skipped: u64,
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
            buf: [0; DATA_LEN],
            first: None,
            len: 0,
            skipped: 0,
            total_skipped: 0,
        }
    }

    /// Forgets a partial packet.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Bytes skipped since the last call (and forgets them).
    pub fn take_skipped(&mut self) -> u64 {
        std::mem::take(&mut self.skipped)
    }

    /// Bytes skipped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn skip(&mut self, n: usize) {
        self.skipped += n as u64;
        self.total_skipped += n as u64;
    }

    /// Takes one byte that arrived at `arrived`; returns a packet when it completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Packet> {
        match self.len {
            0 if b != START => {
                self.skip(1);
                return None;
            }
            0 => self.first = Some(arrived),
            1 if Kind::of(b).is_none() => {
                // Not a packet: the `<` was noise; this byte may start one.
                self.skip(1);
                self.len = 0;
                return self.push(b, arrived);
            }
            _ => {}
        }
        self.buf[self.len] = b;
        self.len += 1;
        let kind = Kind::of(self.buf[1]).filter(|_| self.len >= 2)?;
        if self.len < kind.len() {
            return None;
        }
        self.len = 0;
        Some(Packet {
            kind,
            bytes: self.buf,
            first_byte: self.first.unwrap_or(arrived),
        })
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

    #[test]
    fn packets_after_garbage_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut f = Framer::new();
        let mut data = vec![b'<', b'D'];
        for i in 0..16u16 {
            data.extend_from_slice(&(i * 257).to_be_bytes());
        }
        data.extend_from_slice(&[0, b'>']);
        let info = b"<I\x02\x01\x01\x01>";
        let mut got = Vec::new();
        for (i, chunk) in [&b"<<x"[..], &data[..5], &data[5..], info, b"\x00<"]
            .iter()
            .enumerate()
        {
            for &b in chunk.iter() {
                got.extend(f.push(b, at(i as u64, base)));
            }
        }
        let kinds: Vec<_> = got.iter().map(|p| p.kind).collect();
        assert_eq!(kinds, [Kind::Data, Kind::Info]);
        assert_eq!(got[0].first_byte, at(1, base));
        assert_eq!(got[1].first_byte, at(3, base));
        assert_eq!(got[0].bytes(), &data[..]);
        assert_eq!(f.total_skipped(), 4);
        let c = channels(got[0].bytes());
        assert_eq!(c[1], 257.0);
        assert_eq!(c[15], 15.0 * 257.0);
        assert_eq!(c[16], 0.0);
    }
}
