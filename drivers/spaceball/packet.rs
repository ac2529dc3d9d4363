//! The Spaceball's packets: escapes, finding packets byte by byte, decoding them.
//!
//! The device escapes the bytes that would upset a serial line inside its packets: `^Q`,
//! `^S` and `^M` stand for XON (0x11), XOFF (0x13) and CR (0x0D), `^^` for `^` itself
//! ([`Unescape`]). After unescaping, a packet starts with a letter that gives its kind and
//! length ([`kind`]) and ends with a carriage return; reset (`@`) and error (`E`) packets run
//! to the first carriage return. A carriage return that did not come escaped therefore ends a
//! packet: a data or key candidate with one before its end, or without one at its end, is not
//! a packet.
//!
//! The [`Framer`] keeps each buffered byte with the arrival time of its read, so a packet found
//! after a rescan still carries the time of its own first byte. A data, key or 4000-key packet
//! that does not end in a carriage return gives up its first byte only, and the search goes on
//! from the second: garbage costs no packet after it.

use crate::time::Now;

/// The escape byte.
pub const ESCAPE: u8 = b'^';
/// The longest packet: a reset banner (`@...`), as C++ bounds it.
pub const MAX_PACKET: usize = 62;

/// Removes the device's escapes, one byte at a time.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unescape {
    escaped: bool,
}

impl Unescape {
    /// The byte `b` stands for and whether it came escaped, or `None` when `b` is an escape
    /// to be eaten.
    pub fn push(&mut self, b: u8) -> Option<(u8, bool)> {
        if self.escaped {
            self.escaped = false;
            return Some(match b {
                b'Q' | b'S' | b'M' => (b & 0x1F, true),
                ESCAPE => (b, true),
                // The device escapes nothing else: the `^` was noise, the byte is as it came
                // (C++ keeps it too).
                _ => (b, false),
            });
        }
        if b == ESCAPE {
            self.escaped = true;
            return None;
        }
        Some((b, false))
    }

    /// Forgets a pending escape.
    pub fn clear(&mut self) {
        self.escaped = false;
    }
}

/// How long a packet of some kind is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Length {
    /// Exactly this many bytes, the final carriage return included.
    Fixed(usize),
    /// Up to and including the first carriage return, at most this many bytes.
    ToCr(usize),
}

/// What a packet is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `D`: ball displacement (six axes).
    Displacement,
    /// `K`: keys of the 2003/3003 (and, for compatibility, the 4000).
    Keys,
    /// `.`: the 4000 FLX's twelve keys and handedness.
    Keys4000,
    /// `@`: the device reset itself (power-on or hard reset banner).
    ResetBanner,
    /// `E`: the device reports an error.
    Error,
    /// Answers to the set-up commands, power-on XON and carriage returns: ignored.
    Other,
}

/// The kind and length of a packet starting with `b`, or `None` for a byte that starts none
/// (C++'s list and lengths).
pub fn kind(b: u8) -> Option<(Kind, Length)> {
    Some(match b {
        b'D' => (Kind::Displacement, Length::Fixed(16)),
        b'K' => (Kind::Keys, Length::Fixed(4)),
        b'.' => (Kind::Keys4000, Length::Fixed(4)),
        b'C' | b'F' => (Kind::Other, Length::Fixed(4)),
        b'M' => (Kind::Other, Length::Fixed(5)),
        b'N' => (Kind::Other, Length::Fixed(3)),
        b'P' => (Kind::Other, Length::Fixed(6)),
        b'Z' => (Kind::Other, Length::Fixed(14)),
        0x0B | b'\r' | b'\n' => (Kind::Other, Length::Fixed(1)),
        b'@' => (Kind::ResetBanner, Length::ToCr(MAX_PACKET)),
        b'E' => (Kind::Error, Length::ToCr(8)),
        _ => return None,
    })
}

/// Whether a candidate of `kind` must end exactly at its length with a plain carriage
/// return: the reported kinds (the others are ignored, so nothing is lost by taking them as
/// they come).
fn checked(kind: Kind) -> bool {
    matches!(kind, Kind::Displacement | Kind::Keys | Kind::Keys4000)
}

/// A packet found in the stream (unescaped).
#[derive(Clone, Copy, Debug)]
pub struct Packet {
    /// Its kind.
    pub kind: Kind,
    bytes: [u8; MAX_PACKET],
    len: usize,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
}

impl Packet {
    /// The packet's bytes, from its letter to its carriage return.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

/// Finds packets in the unescaped byte stream. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    buf: [u8; MAX_PACKET],
    /// Whether each buffered byte came escaped.
    escaped: [bool; MAX_PACKET],
    times: [Option<Now>; MAX_PACKET],
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
            buf: [0; MAX_PACKET],
            escaped: [false; MAX_PACKET],
            times: [None; MAX_PACKET],
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

    /// Takes one unescaped byte (`escaped`: it came escaped) that arrived at `arrived`;
    /// calls `found` for each packet this byte completes (more than one only after a rescan).
    pub fn push(&mut self, b: u8, escaped: bool, arrived: Now, found: &mut impl FnMut(Packet)) {
        if self.len == 0 && (escaped || kind(b).is_none()) {
            self.skip(1);
            return;
        }
        self.buf[self.len] = b;
        self.escaped[self.len] = escaped;
        self.times[self.len] = Some(arrived);
        self.len += 1;
        while let Some(done) = self.complete(arrived) {
            match done {
                Ok(p) => {
                    self.len = 0;
                    found(p);
                }
                Err(()) => self.rescan(found),
            }
        }
    }

    /// The buffered candidate, once it is complete (`arrived`: the time of its last byte):
    /// a packet, or `Err` for a bad one.
    fn complete(&self, arrived: Now) -> Option<Result<Packet, ()>> {
        if self.len == 0 {
            return None;
        }
        let (k, length) = kind(self.buf[0])?;
        let ended = self.buf[self.len - 1] == b'\r' && !self.escaped[self.len - 1];
        let done = match length {
            Length::Fixed(n) => self.len >= n || (ended && checked(k)),
            Length::ToCr(max) => ended || self.len >= max,
        };
        if !done {
            return None;
        }
        if checked(k) && !(ended && matches!(length, Length::Fixed(n) if n == self.len)) {
            return Some(Err(()));
        }
        Some(Ok(Packet {
            kind: k,
            bytes: self.buf,
            len: self.len,
            first_byte: self.times[0].unwrap_or(arrived),
        }))
    }

    /// Gives up the candidate's first byte and feeds the rest through again.
    fn rescan(&mut self, found: &mut impl FnMut(Packet)) {
        let n = self.len;
        let (bytes, escaped, times) = (self.buf, self.escaped, self.times);
        self.skip(1);
        self.len = 0;
        for i in 1..n {
            if let Some(t) = times[i] {
                self.push(bytes[i], escaped[i], t, found);
            }
        }
    }
}

/// Raw axis values within this of zero read as zero (C++'s null radius after its reset).
pub const NULL_RADIUS: i16 = 8;
/// Axes of a displacement packet.
pub const AXES: usize = 6;
/// Buttons served (the 4000 FLX's twelve; the 2003/3003 use the first nine).
pub const BUTTONS: usize = 12;

/// The six axis values of a displacement packet, as C++ reports them: translations X, Y, Z
/// and rotations X, Y, Z, raw / 32768, zero within [`NULL_RADIUS`], Z axes negated.
pub fn axes(p: &[u8]) -> [f64; AXES] {
    let mut out = [0.0; AXES];
    for (i, v) in out.iter_mut().enumerate() {
        let raw = i16::from_be_bytes([p[3 + 2 * i], p[4 + 2 * i]]);
        let raw = if (-NULL_RADIUS..=NULL_RADIUS).contains(&raw) {
            0
        } else {
            raw
        };
        *v = f64::from(raw) / 32768.0;
    }
    out[2] = -out[2];
    out[5] = -out[5];
    out
}

/// The nine buttons of a `K` packet (2003/3003 layout, as C++ maps it: the 3003's two
/// rezero bits are or-ed into buttons 0 and 1, button 7 is the 2003's pick button).
pub fn keys(p: &[u8]) -> [bool; 9] {
    let (hi, lo) = (p[1], p[2]);
    [
        lo & 0x11 != 0,
        lo & 0x22 != 0,
        lo & 0x04 != 0,
        lo & 0x08 != 0,
        hi & 0x01 != 0,
        hi & 0x02 != 0,
        hi & 0x04 != 0,
        hi & 0x28 != 0,
        hi & 0x10 != 0,
    ]
}

/// The twelve buttons of a 4000 FLX `.` packet, and whether it is in left-handed mode.
pub fn keys_4000(p: &[u8]) -> ([bool; BUTTONS], bool) {
    let (hi, lo) = (p[1], p[2]);
    let mut b = [false; BUTTONS];
    for (i, bit) in [0x01u8, 0x02, 0x04, 0x08, 0x10, 0x20, 0x80]
        .iter()
        .enumerate()
    {
        b[i] = lo & bit != 0;
    }
    for i in 0..5 {
        b[7 + i] = hi & (1 << i) != 0;
    }
    (b, hi & 0x20 == 0)
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

    fn feed(f: &mut Framer, u: &mut Unescape, bytes: &[u8], t: Now) -> Vec<Packet> {
        let mut out = Vec::new();
        for &b in bytes {
            if let Some((b, esc)) = u.push(b) {
                f.push(b, esc, t, &mut |p| out.push(p));
            }
        }
        out
    }

    #[test]
    fn escapes_are_undone() {
        let mut u = Unescape::default();
        let got: Vec<u8> = b"a^Q^S^M^^^x"
            .iter()
            .filter_map(|&b| u.push(b).map(|(b, _)| b))
            .collect();
        assert_eq!(got, [b'a', 0x11, 0x13, 0x0D, b'^', b'x']);
    }

    #[test]
    fn packets_keep_their_own_first_byte_time_across_garbage_and_rescans() {
        let base = Instant::now();
        let (mut f, mut u) = (Framer::new(), Unescape::default());
        let mut d = vec![b'D', 0, 1];
        d.extend_from_slice(&[0x10, 0, 0, 5, 0x80, 0, 0, 0, 0x7F, 0xFF, 0xFF, 0xF0]);
        d.push(b'\r');
        // Garbage, then a 'D' that is not a packet (no CR where it must end), then a K.
        let mut first = feed(&mut f, &mut u, &[0xFF, 0x01], at(0, base));
        first.extend(feed(&mut f, &mut u, b"Dxx", at(1, base)));
        first.extend(feed(&mut f, &mut u, b"K\x00\x01\r", at(2, base)));
        first.extend(feed(&mut f, &mut u, &d, at(3, base)));
        // The bogus D swallowed the K; it is found again when the D fails.
        assert!(first.is_empty() || first[0].kind == Kind::Keys);
        let more = feed(&mut f, &mut u, b"N\x08\r", at(4, base));
        let all: Vec<_> = first.into_iter().chain(more).collect();
        let kinds: Vec<_> = all.iter().map(|p| p.kind).collect();
        assert_eq!(kinds, [Kind::Keys, Kind::Displacement, Kind::Other]);
        assert_eq!(all[0].first_byte, at(2, base));
        assert_eq!(all[1].first_byte, at(3, base));
        assert_eq!(all[1].bytes(), &d[..]);
        assert!(f.total_skipped() >= 2 + 3);
        let a = axes(all[1].bytes());
        assert_eq!(a[0], 4096.0 / 32768.0);
        assert_eq!(a[1], 0.0, "within the null radius");
        assert_eq!(a[2], 32768.0 / 32768.0, "negated");
        assert_eq!(a[4], 32767.0 / 32768.0);
        assert_eq!(a[5], 16.0 / 32768.0, "negated");
    }

    #[test]
    fn reset_and_error_packets_run_to_their_carriage_return() {
        let base = Instant::now();
        let (mut f, mut u) = (Framer::new(), Unescape::default());
        let got = feed(
            &mut f,
            &mut u,
            b"@1 Spaceball alive\rE\x01\x02\r",
            at(0, base),
        );
        let kinds: Vec<_> = got.iter().map(|p| p.kind).collect();
        assert_eq!(kinds, [Kind::ResetBanner, Kind::Error]);
        assert_eq!(got[0].bytes(), b"@1 Spaceball alive\r");
    }

    #[test]
    fn key_layouts() {
        assert_eq!(
            keys(b"K\x10\x11\r"),
            [true, false, false, false, false, false, false, false, true]
        );
        let (b, lefty) = keys_4000(b".\x21\x80\r");
        assert!(b[6] && b[7] && !lefty);
        assert_eq!(b.iter().filter(|&&x| x).count(), 2);
        assert!(keys_4000(b".\x00\x00\r").1);
    }
}
