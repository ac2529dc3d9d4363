//! The Radamec Serial Position Interface's records and how they are found (pure code).
//!
//! Every block starts with a type byte from 0xA0 to 0xA6, then the camera's id, then fields
//! that depend on the type (most significant byte first), and ends with a check byte: 0x40
//! minus the sum of all the block's other bytes (modulo 256). Commands to the device are
//! blocks too.
//!
//! | Type | Length | Fields after the id |
//! |---|---|---|
//! | 0xA0 | 15 | pan, tilt, zoom, focus (24 bits each) |
//! | 0xA1 | 18 | pan, tilt, zoom, focus, height |
//! | 0xA2 | 30 | pan, tilt, zoom, focus, height; X fraction, X mm, Y fraction, Y mm, orientation (16 bits each), two more bytes |
//! | 0xA3 | 18 | (not decoded) |
//! | 0xA4 | 4 | a command or its echo: one byte |
//! | 0xA5 | 5 | (not decoded) |
//! | 0xA6 | 26 | pan, tilt, zoom, focus, height; X mm, Y mm, orientation (16 bits each), two more bytes |
//!
//! Pan and tilt count 900 a degree around 0x7FFFF; zoom, focus and height are raw encoder
//! counts (their calibration depends on the lens and the rig); X and Y are millimetres plus
//! a fraction in 1/65536 mm; orientation is in hundredths of a degree.

use crate::time::Now;

/// Longest block.
pub const MAX_LEN: usize = 30;
/// Most channels a record sets.
pub const MAX_CHANNELS: usize = 8;
/// The command block type (and its echo).
pub const COMMAND: u8 = 0xA4;

/// A block's length from its type byte, or `None` for a byte that starts no block.
pub fn block_len(kind: u8) -> Option<usize> {
    Some(match kind {
        0xA0 => 15,
        0xA1 => 18,
        0xA2 => 30,
        0xA3 => 18,
        0xA4 => 4,
        0xA5 => 5,
        0xA6 => 26,
        _ => return None,
    })
}

/// The check byte of `bytes`: 0x40 minus their sum, modulo 256.
pub fn check_byte(bytes: &[u8]) -> u8 {
    let sum = bytes.iter().fold(0u8, |s, &b| s.wrapping_add(b));
    0x40u8.wrapping_sub(sum)
}

/// A command block with its check byte: `A4`, the camera id, the command.
pub fn command(camera: u8, what: u8) -> [u8; 4] {
    let b = [COMMAND, camera, what];
    [b[0], b[1], b[2], check_byte(&b)]
}

/// The "which camera are you?" command, sent to every camera (0xFF).
pub const ASK_CAMERA: [u8; 4] = [
    COMMAND,
    0xFF,
    0x02,
    0x40u8.wrapping_sub(0xA4u8.wrapping_add(0xFF).wrapping_add(0x02)),
];
/// The "stream mode" command's code.
pub const STREAM: u8 = 0x01;

fn u24(b: &[u8]) -> u32 {
    u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2])
}

fn u16_at(b: &[u8]) -> u32 {
    u32::from(b[0]) << 8 | u32::from(b[1])
}

/// Pan or tilt in degrees: 900 counts a degree around 0x7FFFF.
pub fn angle(raw: u32) -> f64 {
    f64::from(raw as i32 - 0x7FFFF) / 900.0
}

/// Millimetres and a fraction in 1/65536 mm, in metres.
pub fn metres(mm: u32, frac: u32) -> f64 {
    0.001 * (f64::from(mm) + f64::from(frac) / 65536.0)
}

/// The channels a data block sets, and how many; `None` for the types that set none.
pub fn channels(block: &[u8]) -> Option<([f64; MAX_CHANNELS], usize)> {
    let mut c = [0.0; MAX_CHANNELS];
    let n = match block[0] {
        0xA0 => 4,
        0xA1 => 5,
        0xA2 | 0xA6 => 8,
        _ => return None,
    };
    c[0] = angle(u24(&block[2..]));
    c[1] = angle(u24(&block[5..]));
    c[2] = f64::from(u24(&block[8..]));
    c[3] = f64::from(u24(&block[11..]));
    if n > 4 {
        c[4] = f64::from(u24(&block[14..]));
    }
    if block[0] == 0xA2 {
        c[5] = metres(u16_at(&block[19..]), u16_at(&block[17..]));
        c[6] = metres(u16_at(&block[23..]), u16_at(&block[21..]));
        c[7] = 0.01 * f64::from(u16_at(&block[25..]));
    } else if block[0] == 0xA6 {
        c[5] = metres(u16_at(&block[17..]), 0);
        c[6] = metres(u16_at(&block[19..]), 0);
        c[7] = 0.01 * f64::from(u16_at(&block[21..]));
    }
    Some((c, n))
}

/// A block found in the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// Its bytes (the first `len`).
    pub bytes: [u8; MAX_LEN],
    /// Its length.
    pub len: usize,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes skipped since the previous block.
    pub skipped: u32,
    /// Candidates dropped for a wrong check byte since the previous block.
    pub bad_checks: u32,
}

impl Framed {
    /// The block's bytes.
    pub fn block(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

/// Finds blocks byte by byte: a type byte starts a candidate of its type's length, which is
/// a block if its check byte is right. A failed candidate gives up only its first byte: the
/// search goes on from the second, so a block right after a stray type byte is still found.
#[derive(Clone, Debug)]
pub struct Framer {
    buf: [u8; MAX_LEN],
    times: [Option<Now>; MAX_LEN],
    len: usize,
    skipped: u32,
    bad_checks: u32,
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
            buf: [0; MAX_LEN],
            times: [None; MAX_LEN],
            len: 0,
            skipped: 0,
            bad_checks: 0,
            total_skipped: 0,
        }
    }

    /// Forgets a partial block.
    pub fn clear(&mut self) {
        self.len = 0;
        self.skipped = 0;
        self.bad_checks = 0;
    }

    /// Bytes skipped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    /// Takes one byte that arrived at `arrived`, and hands every block it completes to
    /// `found` (more than one when a failed candidate held whole blocks).
    pub fn push(&mut self, b: u8, arrived: Now, mut found: impl FnMut(Framed)) {
        self.buf[self.len] = b;
        self.times[self.len] = Some(arrived);
        self.len += 1;
        loop {
            // Drop bytes that start no block.
            let drop = (0..self.len)
                .find(|&i| block_len(self.buf[i]).is_some())
                .unwrap_or(self.len);
            self.take(drop, drop as u32);
            let Some(want) = self.buf[..self.len].first().and_then(|&k| block_len(k)) else {
                return;
            };
            if self.len < want {
                return;
            }
            if self.buf[want - 1] == check_byte(&self.buf[..want - 1]) {
                found(Framed {
                    bytes: self.buf,
                    len: want,
                    first_byte: self.times[0].unwrap_or(arrived),
                    skipped: std::mem::take(&mut self.skipped),
                    bad_checks: std::mem::take(&mut self.bad_checks),
                });
                self.take(want, 0);
            } else {
                // A wrong check byte: give up the candidate's first byte and look again.
                self.bad_checks = self.bad_checks.saturating_add(1);
                self.take(1, 1);
            }
        }
    }

    /// Removes the first `n` buffered bytes, `skipped` of them counted as skipped.
    fn take(&mut self, n: usize, skipped: u32) {
        if n == 0 {
            return;
        }
        self.skipped = self.skipped.saturating_add(skipped);
        self.total_skipped += u64::from(skipped);
        self.buf.copy_within(n..self.len, 0);
        self.times.copy_within(n..self.len, 0);
        self.len -= n;
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

    fn block(kind: u8, fill: u8) -> Vec<u8> {
        let n = block_len(kind).unwrap();
        let mut b: Vec<u8> = (0..n - 1)
            .map(|i| fill.wrapping_add(i as u8) & 0x7F)
            .collect();
        b[0] = kind;
        b[1] = 3;
        b.push(check_byte(&b));
        b
    }

    #[test]
    fn commands_and_values() {
        assert_eq!(command(0xFF, 0x02), ASK_CAMERA);
        assert_eq!(check_byte(&[0xA4, 0xFF, 0x02]), 0x40u8.wrapping_sub(0xA5));
        assert_eq!(angle(0x7FFFF), 0.0);
        assert_eq!(angle(0x7FFFF + 900), 1.0);
        assert_eq!(angle(0x7FFFF - 450), -0.5);
        assert!((metres(1500, 32768) - 1.5005).abs() < 1e-12);
        let mut b = block(0xA2, 0x10);
        b[17..27].copy_from_slice(&[0x80, 0x00, 0x05, 0xDC, 0x00, 0x00, 0x00, 0x02, 0x23, 0x28]);
        let n = b.len();
        b[n - 1] = check_byte(&b[..n - 1]);
        let (c, n) = channels(&b).unwrap();
        assert_eq!(n, 8);
        for (v, want) in c[5..].iter().zip([1.5005, 0.002, 90.0]) {
            assert!((v - want).abs() < 1e-12, "{v} {want}");
        }
    }

    #[test]
    fn blocks_after_garbage_and_false_starts() {
        let base = Instant::now();
        let mut f = Framer::new();
        let a = block(0xA0, 0x20);
        let b = block(0xA6, 0x30);
        let mut got = Vec::new();
        // Noise, then a stray type byte right before a block.
        for &x in &[0x01, 0x55, 0xA1] {
            f.push(x, at(0, base), |g| got.push(g));
        }
        for (i, &x) in a.iter().enumerate() {
            f.push(x, at(1 + i as u64, base), |g| got.push(g));
        }
        for &x in &b {
            f.push(x, at(50, base), |g| got.push(g));
        }
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].block(), a.as_slice());
        assert_eq!(got[0].first_byte, at(1, base));
        assert_eq!(got[0].skipped, 3);
        assert_eq!(got[0].bad_checks, 1);
        assert_eq!(got[1].block(), b.as_slice());
        assert_eq!(got[1].skipped, 0);
    }
}
