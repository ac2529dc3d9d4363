//! The plotter's bytes, free of I/O: the commands the driver writes, the 7-byte GIN answer
//! that tells the pen's position, the framer that finds answers byte by byte, and the
//! plotter's units.
//!
//! Coordinates are 12-bit counts: 4095 counts span 15 inches (0.381 m) in x, and the same
//! scale gives 0.254 m (10 inches) in y.

use crate::time::Now;

/// ASCII escape: starts a device command (`ESC A x`, `A` being the plotter's address).
pub const ESC: u8 = 27;
/// ASCII group separator: enters graphics mode; the next address moves the pen (pen up).
pub const GS: u8 = 29;

/// What a reset writes: 17 NULs (to clear a half-received command), "plotter on"
/// (`ESC A E`), "reset" (`ESC A N`), then a position request ([`GIN`]).
pub const RESET_SEQUENCE: [u8; 26] = [
    0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, //
    ESC, b'A', b'E', //
    ESC, b'A', b'N', //
    ESC, b'A', b'M',
];

/// The graphic-input request: the plotter answers with its pen position ([`ANSWER_LEN`]
/// bytes) once any move before it is done.
pub const GIN: [u8; 3] = [ESC, b'A', b'M'];

/// The length of a GIN answer.
pub const ANSWER_LEN: usize = 7;

/// Counts per metre: 4095 counts per 15 inches (the expression C++ VRPN uses, so that
/// positions convert to the same bits).
pub const COUNTS_PER_METER: f64 = 1.0 / ((15.0 / 4095.0) * (0.0254 / 1.0));

/// The workspace: x from 0 to 15 inches, y from 0 to 10 inches, no z (metres).
pub const WORKSPACE_MAX: [f64; 3] = [0.381, 0.254, 0.0];

/// The position a client sees for a count, in metres: the count over [`COUNTS_PER_METER`],
/// rounded to single precision (as C++ VRPN reports it).
pub fn metres(counts: u16) -> f64 {
    f64::from((f64::from(counts) / COUNTS_PER_METER) as f32)
}

/// The count the pen is sent to for a position in metres (already in the workspace):
/// rounded down, as C++ VRPN does.
pub fn counts(m: f64) -> u16 {
    // In the workspace the product is at most about 4095; `as` saturates anyway.
    (m * COUNTS_PER_METER).floor() as u16
}

/// A requested position clamped to the workspace, or `None` when a coordinate is not a
/// number (C++ would send the pen to an undefined place).
pub fn clamp_to_workspace(pos: [f64; 3]) -> Option<[f64; 3]> {
    if pos.iter().any(|p| p.is_nan()) {
        return None;
    }
    let mut p = pos;
    for (v, max) in p.iter_mut().zip(WORKSPACE_MAX) {
        *v = v.clamp(0.0, max);
    }
    Some(p)
}

/// The move command for the pen to go to (`x`, `y`) counts: [`GS`] then a 12-bit address in
/// five bytes (high y, extra, low y, high x, low x, each with its tag bits).
pub fn move_command(x: u16, y: u16) -> [u8; 6] {
    let (x, y) = (x & 0x0fff, y & 0x0fff);
    [
        GS,
        0x20 | (y >> 7) as u8,
        0x60 | (x & 3) as u8 | ((y & 3) << 2) as u8,
        0x60 | ((y >> 2) & 0x1f) as u8,
        0x20 | (x >> 7) as u8,
        0x40 | ((x >> 2) & 0x1f) as u8,
    ]
}

/// A decoded GIN answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Gin {
    /// The pen's x in counts (0–4095).
    pub x: u16,
    /// The pen's y in counts.
    pub y: u16,
    /// The pen is down (status byte, bit 2).
    pub pen_down: bool,
}

/// Whether byte `b` may stand at position `i` of an answer: bytes 0–5 carry the tag 0x20
/// under the mask 0x60, the status byte (6) the tag 0x40.
pub fn tag_ok(i: usize, b: u8) -> bool {
    let tag = if i < ANSWER_LEN - 1 { 0x20 } else { 0x40 };
    b & 0x60 == tag
}

/// Decodes an answer: x from bytes 0, 2 and 4, y from 1, 3 and 5 (five, five and two bits);
/// `None` when a tag is wrong.
pub fn decode(b: &[u8; ANSWER_LEN]) -> Option<Gin> {
    if !b.iter().enumerate().all(|(i, &v)| tag_ok(i, v)) {
        return None;
    }
    let coord = |hi: u8, mid: u8, lo: u8| {
        (u16::from(hi & 0x1f) << 7) | (u16::from(mid & 0x1f) << 2) | (u16::from(lo & 0x1f) >> 3)
    };
    Some(Gin {
        x: coord(b[0], b[2], b[4]),
        y: coord(b[1], b[3], b[5]),
        pen_down: b[6] & 0x04 != 0,
    })
}

/// Finds answers in the byte stream, one byte at a time. A byte whose tag cannot stand where
/// it would fall costs the oldest buffered byte (counted in [`take_skipped`]), so garbage is
/// given up byte by byte and the answer after it is found whole. Each answer carries the
/// arrival time of its first byte.
///
/// [`take_skipped`]: Framer::take_skipped
#[derive(Debug, Default)]
pub struct Framer {
    bytes: [u8; ANSWER_LEN],
    stamps: [Option<Now>; ANSWER_LEN],
    len: usize,
    skipped: u64,
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Framer {
        Framer::default()
    }

    /// Forgets a partial answer.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Bytes buffered towards the next answer.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Bytes given up since the last call.
    pub fn take_skipped(&mut self) -> u64 {
        std::mem::take(&mut self.skipped)
    }

    /// Takes byte `b`, which arrived at `at`: an answer and its first byte's arrival when `b`
    /// completes one.
    pub fn push(&mut self, b: u8, at: Now) -> Option<(Gin, Now)> {
        self.bytes[self.len] = b;
        self.stamps[self.len] = Some(at);
        self.len += 1;
        // Drop the oldest byte until what is buffered can begin an answer.
        while self.len > 0 && !(0..self.len).all(|i| tag_ok(i, self.bytes[i])) {
            self.bytes.copy_within(1..self.len, 0);
            self.stamps.copy_within(1..self.len, 0);
            self.len -= 1;
            self.skipped += 1;
        }
        if self.len < ANSWER_LEN {
            return None;
        }
        self.len = 0;
        let gin = decode(&self.bytes)?;
        Some((gin, self.stamps[0].unwrap_or(at)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TimeVal;
    use std::time::{Duration, Instant};

    /// An answer for (`x`, `y`) as the plotter sends it, with `noise` in the bits the driver
    /// ignores.
    fn answer(x: u16, y: u16, pen: bool, noise: u8) -> [u8; 7] {
        [
            0x20 | (x >> 7) as u8,
            0x20 | (y >> 7) as u8,
            0x20 | ((x >> 2) & 31) as u8,
            0x20 | ((y >> 2) & 31) as u8,
            0x20 | ((x & 3) << 3) as u8 | (noise & 7),
            0x20 | ((y & 3) << 3) as u8 | ((noise >> 3) & 7),
            0x40 | if pen { 4 } else { 0 } | (noise & 0x1b),
        ]
    }

    #[test]
    fn units_are_those_of_cpp() {
        // 4095 counts span 15 inches.
        assert!((COUNTS_PER_METER - 4095.0 / 0.381).abs() < 1e-9);
        assert_eq!(metres(4095), f64::from(0.381f32));
        assert_eq!(metres(0), 0.0);
        assert_eq!(counts(0.0), 0);
        assert_eq!(counts(0.254), 2730);
        // Whatever the rounding of the product, the far edge is the last count or the one
        // before it, as in C++.
        assert!(counts(0.381) >= 4094);
        for k in [0u16, 1, 17, 2048, 2730, 4095] {
            let m = (f64::from(k) + 0.5) / COUNTS_PER_METER;
            assert_eq!(counts(m), k);
        }
    }

    #[test]
    fn requests_are_clamped_to_the_workspace() {
        assert_eq!(clamp_to_workspace([-1.0, 0.1, 0.3]), Some([0.0, 0.1, 0.0]));
        assert_eq!(
            clamp_to_workspace([2.0, 2.0, -0.5]),
            Some([0.381, 0.254, 0.0])
        );
        assert_eq!(
            clamp_to_workspace([f64::INFINITY, f64::NEG_INFINITY, 0.0]),
            Some([0.381, 0.0, 0.0])
        );
        assert_eq!(clamp_to_workspace([0.1, f64::NAN, 0.0]), None);
    }

    #[test]
    fn moves_carry_twelve_bit_addresses_in_tek_order() {
        assert_eq!(move_command(0, 0), [GS, 0x20, 0x60, 0x60, 0x20, 0x40]);
        // x = 0b1010_1100_1011, y = 0b0110_0101_1110.
        let (x, y) = (0xACB, 0x65E);
        let m = move_command(x, y);
        assert_eq!(m[1], 0x20 | 0b01100); // high y: y >> 7
        assert_eq!(m[2], 0x60 | 0b11 | (0b10 << 2)); // extra: low bits of x and y
        assert_eq!(m[3], 0x60 | 0b10111); // low y: (y >> 2) & 31
        assert_eq!(m[4], 0x20 | 0b10101); // high x
        assert_eq!(m[5], 0x40 | 0b10010); // low x
        assert_eq!(
            move_command(4095, 4095)[1..],
            [0x3f, 0x6f, 0x7f, 0x3f, 0x5f]
        );
    }

    #[test]
    fn answers_decode_every_count_and_the_pen() {
        for (x, y, pen, noise) in [
            (0, 0, false, 0),
            (4095, 2730, true, 63),
            (1234, 567, false, 21),
        ] {
            assert_eq!(
                decode(&answer(x, y, pen, noise)),
                Some(Gin {
                    x,
                    y,
                    pen_down: pen
                })
            );
        }
        for x in 0..4096 {
            assert_eq!(decode(&answer(x, 4095 - x, false, 5)).unwrap().x, x);
        }
        let mut bad = answer(1, 2, false, 0);
        bad[6] = 0x20;
        assert_eq!(decode(&bad), None);
        bad[6] = 0x40;
        bad[3] = 0x60;
        assert_eq!(decode(&bad), None);
    }

    #[test]
    fn the_framer_gives_up_garbage_byte_by_byte_and_keeps_first_byte_stamps() {
        let t0 = Instant::now();
        let at = |ms: u64| Now {
            mono: t0 + Duration::from_millis(ms),
            wall: TimeVal::new(100, ms as i64 * 1000),
        };
        let mut f = Framer::new();
        let mut got = Vec::new();
        let mut feed = |f: &mut Framer, bytes: &[u8], ms: u64| {
            for &b in bytes {
                if let Some((g, t)) = f.push(b, at(ms)) {
                    got.push((g.x, g.y, t.mono - t0));
                }
            }
        };
        feed(&mut f, &answer(10, 20, false, 1)[..3], 0);
        feed(&mut f, &answer(10, 20, false, 1)[3..], 5);
        // Garbage of every kind: wrong tags, a status byte alone, bytes that look like the
        // start of an answer.
        feed(&mut f, b"zz\x00\xff@A12", 10);
        feed(&mut f, &answer(30, 40, true, 2), 20);
        feed(&mut f, b"123456", 30);
        feed(&mut f, &answer(4095, 2730, false, 3), 40);
        assert_eq!(
            got,
            [
                (10, 20, Duration::ZERO),
                (30, 40, Duration::from_millis(20)),
                (4095, 2730, Duration::from_millis(40)),
            ]
        );
        assert_eq!(f.take_skipped(), 8 + 6);
        assert_eq!(f.take_skipped(), 0);
        assert_eq!(f.pending(), 0);
    }
}
