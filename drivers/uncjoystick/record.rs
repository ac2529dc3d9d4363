//! The UNC joystick box's two-byte records and how they are found (pure code).
//!
//! ```text
//! first byte:   0 . C2 C1 C0 V9 V8 V7     C = channel 0-7, V9-V7 the value's high bits
//! second byte:  1 V6 V5 V4 V3 V2 V1 V0
//! ```
//!
//! Channels 0-6 are the slider and the two three-axis sticks (10-bit values); channel 7
//! holds the two buttons in the value's low bits, a clear bit meaning pressed.

use crate::time::Now;

/// Analog channels: 0 the slider, 1-3 and 4-6 the two sticks.
pub const CHANNELS: usize = 7;
/// Buttons: one on top of each stick.
pub const BUTTONS: usize = 2;
/// The channel that carries the buttons.
pub const BUTTON_CHANNEL: u8 = 7;
/// Divisors from raw counts to the channels (C++'s `JoyScale`).
pub const SCALE: [f64; CHANNELS] = [1019.0, 200.0, 200.0, 350.0, 200.0, 200.0, 350.0];
/// The slider's rest value (it does not centre itself).
pub const SLIDER_REST: u16 = 512;

/// One decoded record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pair {
    /// Channel 0-7.
    pub channel: u8,
    /// The 10-bit value.
    pub value: u16,
}

impl Pair {
    /// The record's two bytes.
    pub fn encode(self) -> [u8; 2] {
        [
            ((self.channel & 7) << 3) | ((self.value >> 7) & 7) as u8,
            0x80 | (self.value & 0x7F) as u8,
        ]
    }

    /// The buttons of a channel-7 record: bit 0 clear is button 0 pressed, bit 1 button 1.
    pub fn buttons(self) -> [bool; BUTTONS] {
        [self.value & 1 == 0, self.value & 2 == 0]
    }
}

/// Channel `c`'s value for raw `value` against its rest value: (rest − value) / scale,
/// clamped to ±0.5; the slider's sign is flipped.
pub fn channel_value(c: usize, rest: u16, value: u16) -> f64 {
    let v = ((f64::from(rest) - f64::from(value)) / SCALE[c]).clamp(-0.5, 0.5);
    if c == 0 {
        -v
    } else {
        v
    }
}

/// A record found, with the arrival of its first byte and the bytes skipped before it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// The record.
    pub pair: Pair,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes skipped since the previous record.
    pub skipped: u32,
}

/// Finds records byte by byte: a byte with bit 7 clear starts one (replacing a first byte
/// still waiting for its second, as C++ does), a byte with bit 7 set completes it; a second
/// byte with no first is skipped.
#[derive(Clone, Debug, Default)]
pub struct Framer {
    first: Option<(u8, Now)>,
    skipped: u32,
    total_skipped: u64,
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Framer {
        Framer::default()
    }

    /// Forgets a partial record.
    pub fn clear(&mut self) {
        self.first = None;
        self.skipped = 0;
    }

    /// Bytes skipped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    fn skip(&mut self) {
        self.skipped = self.skipped.saturating_add(1);
        self.total_skipped += 1;
    }

    /// Takes one byte that arrived at `arrived`.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        if b & 0x80 == 0 {
            if self.first.is_some() {
                self.skip();
            }
            self.first = Some((b, arrived));
            return None;
        }
        let Some((f, first_byte)) = self.first.take() else {
            self.skip();
            return None;
        };
        Some(Framed {
            pair: Pair {
                channel: (f >> 3) & 7,
                value: (u16::from(f & 7) << 7) | u16::from(b & 0x7F),
            },
            first_byte,
            skipped: std::mem::take(&mut self.skipped),
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
    fn pairs_round_trip_and_scale() {
        for channel in 0..8 {
            for value in [0u16, 1, 127, 128, 511, 512, 1023] {
                let p = Pair { channel, value };
                let mut f = Framer::new();
                let base = Instant::now();
                let [a, b] = p.encode();
                assert_eq!(f.push(a, at(0, base)), None);
                assert_eq!(f.push(b, at(1, base)).unwrap().pair, p);
            }
        }
        assert_eq!(channel_value(1, 512, 412), 0.5);
        assert_eq!(channel_value(1, 512, 462), 0.25);
        assert_eq!(channel_value(0, 512, 0), -0.5);
        assert_eq!(channel_value(3, 500, 535), -0.1);
        assert_eq!(
            Pair {
                channel: 7,
                value: 0b10
            }
            .buttons(),
            [true, false]
        );
    }

    #[test]
    fn resynchronises_as_cplusplus() {
        let base = Instant::now();
        let mut f = Framer::new();
        let p = Pair {
            channel: 3,
            value: 700,
        };
        let [a, b] = p.encode();
        // A stray second byte, then a doubled first byte: both skipped, the record kept.
        assert_eq!(f.push(0x95, at(0, base)), None);
        assert_eq!(f.push(a, at(1, base)), None);
        assert_eq!(f.push(a, at(2, base)), None);
        let got = f.push(b, at(3, base)).unwrap();
        assert_eq!(got.pair, p);
        assert_eq!(got.first_byte, at(2, base));
        assert_eq!(got.skipped, 2);
    }
}
