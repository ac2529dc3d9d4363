//! The Wanda's records and how they are found in the byte stream (pure code).
//!
//! The Wanda speaks the three-button Logitech serial-mouse protocol: seven data bits at 1200
//! baud. A record is three bytes, the first marked by bit 6:
//!
//! ```text
//! byte 0:  0 1 R B Y7 Y6 X7 X6     R = red button, B = blue button
//! byte 1:  0 0 X5 X4 X3 X2 X1 X0
//! byte 2:  0 0 Y5 Y4 Y3 Y2 Y1 Y0
//! byte 3:  0 0 M . . . . .         optional: the yellow (middle) button
//! ```
//!
//! X and Y are signed 8-bit values. The optional fourth byte follows a record while the
//! yellow button is down and once more when it is released; any non-zero value means
//! pressed. Nothing else marks a record: the sync bit is the only check the protocol has.

use crate::time::Now;

/// Bytes in a record (without the optional yellow-button byte).
pub const RECORD_LEN: usize = 3;
/// The bit that marks a record's first byte.
pub const SYNC: u8 = 1 << 6;
/// Red button bit of the first byte.
pub const RED: u8 = 1 << 5;
/// Blue button bit of the first byte.
pub const BLUE: u8 = 1 << 4;
/// The value of the yellow-button byte while it is pressed (any non-zero value counts).
pub const YELLOW_DOWN: u8 = 0x20;
/// Divisor from the raw ball value to the channel (C++'s "max range" guess).
pub const SCALE: f64 = 34.0;
/// The two bytes a Wanda sends when it powers up.
pub const INIT_MESSAGE: [u8; 2] = *b"M3";

/// Buttons: 0 blue, 1 yellow, 2 red (C++'s numbering).
pub const BUTTONS: usize = 3;
/// Channels: 0 left/right (right is negative, as C++), 1 forward/back.
pub const CHANNELS: usize = 2;

/// The raw X and Y of a record, signed.
pub fn raw_xy(r: [u8; RECORD_LEN]) -> (i8, i8) {
    let x = (r[1] & 0x3F) | ((r[0] & 0x03) << 6);
    let y = (r[2] & 0x3F) | ((r[0] & 0x0C) << 4);
    (x as i8, y as i8)
}

/// The two channels a record sets: −X/34 and Y/34, each clamped to −1..1.
pub fn channels(r: [u8; RECORD_LEN]) -> [f64; CHANNELS] {
    let (x, y) = raw_xy(r);
    [
        (-f64::from(x) / SCALE).clamp(-1.0, 1.0),
        (f64::from(y) / SCALE).clamp(-1.0, 1.0),
    ]
}

/// Blue (button 0) and red (button 2) of a record.
pub fn blue_red(r: [u8; RECORD_LEN]) -> (bool, bool) {
    (r[0] & BLUE != 0, r[0] & RED != 0)
}

/// The bytes of a record for raw `x`, `y` and the blue and red buttons.
pub fn encode(x: i8, y: i8, blue: bool, red: bool) -> [u8; RECORD_LEN] {
    let (x, y) = (x as u8, y as u8);
    let mut b0 = SYNC | ((y >> 6) << 2) | (x >> 6);
    if blue {
        b0 |= BLUE;
    }
    if red {
        b0 |= RED;
    }
    [b0, x & 0x3F, y & 0x3F]
}

/// What the framer found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Found {
    /// A complete three-byte record.
    Record {
        /// Its bytes.
        bytes: [u8; RECORD_LEN],
        /// When the read holding its first byte arrived.
        first_byte: Now,
        /// Bytes skipped since the previous record.
        skipped: u32,
    },
    /// The yellow-button byte after the last record.
    Yellow {
        /// Pressed (any non-zero value).
        pressed: bool,
        /// The record's first-byte time.
        first_byte: Now,
    },
}

/// Finds records byte by byte. A byte with bit 7 set cannot come from a seven-bit line: it is
/// skipped, and so is a partial record it interrupts. A sync byte before a record is complete
/// starts a new one (the partial one is skipped); data bytes with no record open are skipped.
#[derive(Clone, Debug, Default)]
pub struct Framer {
    buf: [u8; RECORD_LEN],
    /// Bytes of the current record; `RECORD_LEN` once complete (a yellow byte may follow).
    len: usize,
    first_byte: Option<Now>,
    skipped: u32,
    total_skipped: u64,
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Framer {
        Framer::default()
    }

    /// Forgets a partial record (the port closed).
    pub fn clear(&mut self) {
        self.len = 0;
        self.skipped = 0;
        self.first_byte = None;
    }

    /// Bytes skipped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn skip(&mut self, n: usize) {
        self.skipped = self.skipped.saturating_add(n as u32);
        self.total_skipped += n as u64;
    }

    /// Takes one byte that arrived at `arrived`.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Found> {
        if b & 0x80 != 0 {
            if self.len < RECORD_LEN {
                self.skip(self.len);
            }
            self.len = 0;
            self.skip(1);
            return None;
        }
        if b & SYNC != 0 {
            if self.len < RECORD_LEN {
                self.skip(self.len);
            }
            self.buf[0] = b;
            self.len = 1;
            self.first_byte = Some(arrived);
            return None;
        }
        match self.len {
            0 => {
                self.skip(1);
                None
            }
            1 | 2 => {
                self.buf[self.len] = b;
                self.len += 1;
                if self.len < RECORD_LEN {
                    return None;
                }
                let skipped = std::mem::take(&mut self.skipped);
                Some(Found::Record {
                    bytes: self.buf,
                    first_byte: self.first_byte.unwrap_or(arrived),
                    skipped,
                })
            }
            _ => {
                // The optional fourth byte; after it, only a sync byte may follow.
                self.len = 0;
                Some(Found::Yellow {
                    pressed: b != 0,
                    first_byte: self.first_byte.unwrap_or(arrived),
                })
            }
        }
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
    fn encoding_round_trips_every_value_and_button() {
        for x in i8::MIN..=i8::MAX {
            for (y, blue, red) in [(0, false, false), (-128, true, false), (127, false, true)] {
                let r = encode(x, y, blue, red);
                assert_eq!(raw_xy(r), (x, y));
                assert_eq!(blue_red(r), (blue, red));
                assert!(r[0] & SYNC != 0 && r[1] & SYNC == 0 && r[2] & SYNC == 0);
            }
        }
        assert_eq!(channels(encode(34, -17, false, false)), [-1.0, -0.5]);
        assert_eq!(channels(encode(-128, 127, false, false)), [1.0, 1.0]);
    }

    #[test]
    fn records_yellow_bytes_and_garbage() {
        let base = Instant::now();
        let mut f = Framer::new();
        let a = encode(5, -5, true, false);
        let b = encode(-20, 30, false, true);
        let mut out = Vec::new();
        // Garbage: a data byte with no record, a byte with bit 7, a false start.
        for (i, &byte) in [0x05u8, 0xC1, 0x41].iter().enumerate() {
            out.extend(f.push(byte, at(i as u64, base)));
        }
        for &byte in &a {
            out.extend(f.push(byte, at(10, base)));
        }
        out.extend(f.push(YELLOW_DOWN, at(11, base)));
        for (i, &byte) in b.iter().enumerate() {
            out.extend(f.push(byte, at(20 + i as u64, base)));
        }
        assert_eq!(
            out,
            vec![
                Found::Record {
                    bytes: a,
                    first_byte: at(10, base),
                    skipped: 3
                },
                Found::Yellow {
                    pressed: true,
                    first_byte: at(10, base)
                },
                Found::Record {
                    bytes: b,
                    first_byte: at(20, base),
                    skipped: 0
                },
            ]
        );
        // A record cut by a byte with bit 7 set is dropped.
        f.push(a[0], at(30, base));
        f.push(0x90, at(31, base));
        assert_eq!(f.push(a[1], at(32, base)), None);
        assert_eq!(f.total_skipped(), 3 + 2 + 1);
    }
}
