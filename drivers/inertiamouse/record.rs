//! The inertia mouse's records and C++ VRPN's arithmetic on them. Pure.
//!
//! Two records, each ending in LF: `D` and 23 more bytes (25 in all: six channels of four
//! bytes, the last channel's fourth byte being the LF), and `B`, the button byte, one more
//! byte, LF (4 in all). A channel's four bytes carry a 16-bit word in their high nibbles:
//! bits 10-12 the channel number, bits 0-9 the acceleration (`(a − 256) / 256`).
//!
//! Channels 4 and 5 are reported as they come; channels 0 to 3 go through a DC blocker and a
//! Butterworth low-pass, then, while button 0 is held, are integrated twice over a step of
//! 0.25 (the reported value is the displacement of one step), and are 0 otherwise. A record
//! holding channel 4 or 5 stops there (C++ leaves the loop at that channel). These are C++
//! VRPN's formulas, kept to the bit.

use crate::time::Now;

/// Analog channels.
pub const CHANNELS: usize = 6;
/// Buttons.
pub const BUTTONS: usize = 2;
/// Bytes of a `D` record.
pub const DATA_LEN: usize = 25;
/// Bytes of a `B` record.
pub const BUTTON_LEN: usize = 4;

/// The DC blocker (C++'s `dcblocker`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DcBlocker {
    input: f64,
    output: f64,
}

impl DcBlocker {
    /// Filters one sample.
    pub fn filter(&mut self, s: f64) -> f64 {
        self.output = s - self.input + 0.95 * self.output;
        self.input = s;
        self.output
    }
}

/// The Butterworth low-pass (C++'s `lowpass`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LowPass {
    input: [f64; 2],
    output: [f64; 2],
}

impl LowPass {
    /// Filters one sample.
    pub fn filter(&mut self, s: f64) -> f64 {
        self.input[0] = self.input[1];
        self.input[1] = s / 6.242183581;
        self.output[0] = self.output[1];
        self.output[1] = self.input[0] + self.input[1] + 0.6795992982 * self.output[0];
        self.output[1]
    }
}

/// What the device's values are, as C++ keeps them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MouseState {
    /// The analog channels.
    pub channels: [f64; CHANNELS],
    /// The buttons.
    pub buttons: [bool; BUTTONS],
    velocity: [f64; CHANNELS],
    dc: [DcBlocker; CHANNELS],
    lowpass: [LowPass; CHANNELS],
}

/// What a record did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Applied {
    /// The channels or buttons were updated: report.
    Report,
    /// A channel number above 5 (the word's): the record is dropped, the channels before it
    /// stay updated (as in C++).
    BadChannel(u8),
}

impl MouseState {
    /// Applies a whole record (`D…LF` or `B…LF`).
    pub fn apply(&mut self, rec: &[u8]) -> Applied {
        if rec[0] == b'B' {
            self.buttons = [rec[1] & 1 != 0, rec[1] & 2 != 0];
            return Applied::Report;
        }
        for i in 0..CHANNELS {
            let b = &rec[1 + 4 * i..5 + 4 * i];
            let word = (u16::from(b[0] & 0xF0) << 8)
                | (u16::from(b[1] & 0xF0) << 4)
                | u16::from(b[2] & 0xF0)
                | u16::from(b[3] & 0xF0) >> 4;
            let chan = usize::from((word >> 10) & 7);
            if chan >= CHANNELS {
                return Applied::BadChannel(chan as u8);
            }
            let v = (f64::from(word & 0x3FF) - 256.0) / 256.0;
            if chan >= 4 {
                self.channels[chan] = v;
                break;
            }
            let v = self.lowpass[chan].filter(self.dc[chan].filter(v));
            let dt = 0.25;
            if self.buttons[0] {
                let pos = self.velocity[chan] * dt + v * dt * dt / 2.0;
                self.velocity[chan] += v * dt;
                if self.velocity[chan].abs() < dt / 2.0 {
                    self.velocity[chan] *= 0.90;
                }
                self.channels[chan] = pos;
            } else {
                self.velocity[chan] = 0.0;
                self.channels[chan] = 0.0;
            }
        }
        Applied::Report
    }
}

/// A record found in the stream.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed<'a> {
    /// Its bytes, LF included.
    pub bytes: &'a [u8],
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
    /// Bytes dropped since the previous record.
    pub skipped: u32,
}

/// Finds records byte by byte: `D` or `B` starts one, its length is known, its last byte
/// must be LF; a candidate that fails gives up its first byte and the rest is searched
/// again (C++ drops it whole).
pub struct Framer {
    buf: [u8; DATA_LEN],
    times: [Option<Now>; DATA_LEN],
    len: usize,
    skipped: u32,
}

impl Default for Framer {
    fn default() -> Framer {
        Framer::new()
    }
}

fn record_len(first: u8) -> Option<usize> {
    match first {
        b'D' => Some(DATA_LEN),
        b'B' => Some(BUTTON_LEN),
        _ => None,
    }
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Framer {
        Framer {
            buf: [0; DATA_LEN],
            times: [None; DATA_LEN],
            len: 0,
            skipped: 0,
        }
    }

    /// Forgets a partial record.
    pub fn clear(&mut self) {
        self.len = 0;
        self.skipped = 0;
    }

    fn give_up_first(&mut self) {
        let next = (1..self.len)
            .find(|&i| record_len(self.buf[i]).is_some())
            .unwrap_or(self.len);
        self.skipped += next as u32;
        self.buf.copy_within(next..self.len, 0);
        self.times.copy_within(next..self.len, 0);
        self.len -= next;
    }

    /// Takes one byte that arrived at `arrived`; returns a record when this byte completes
    /// one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed<'_>> {
        self.buf[self.len] = b;
        self.times[self.len] = Some(arrived);
        self.len += 1;
        loop {
            if self.len == 0 {
                return None;
            }
            let Some(want) = record_len(self.buf[0]) else {
                self.give_up_first();
                continue;
            };
            if self.len < want {
                return None;
            }
            if self.buf[want - 1] != b'\n' {
                self.give_up_first();
                continue;
            }
            // Nothing follows the completing byte in the buffer.
            self.len = 0;
            return Some(Framed {
                bytes: &self.buf[..want],
                first_byte: self.times[0].unwrap_or(arrived),
                skipped: std::mem::take(&mut self.skipped),
            });
        }
    }
}

/// Encodes a `D` record: channel numbers and 10-bit accelerations, in order (for the
/// simulator and tests). The last channel's lowest nibble is the LF's high nibble, 0.
pub fn encode_data(words: [(u8, u16); CHANNELS]) -> [u8; DATA_LEN] {
    let mut r = [0u8; DATA_LEN];
    r[0] = b'D';
    for (i, (chan, acc)) in words.iter().enumerate() {
        let w = (u16::from(*chan & 7) << 10) | (acc & 0x3FF);
        let nib = [w >> 12, (w >> 8) & 0xF, (w >> 4) & 0xF, w & 0xF];
        for k in 0..4 {
            // High nibble: the data; low nibble: anything (here 0x5).
            r[1 + 4 * i + k] = ((nib[k] as u8) << 4) | 0x5;
        }
    }
    r[DATA_LEN - 1] = b'\n';
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_decode_and_the_last_nibble_is_the_newline_s() {
        let mut s = MouseState::default();
        // Channel 5 cannot carry a low nibble (the LF's is 0): 0x3F0 survives as 0x3F0.
        let rec = encode_data([(0, 512), (1, 256), (2, 0), (3, 1023), (4, 384), (5, 0x3F0)]);
        assert_eq!(s.apply(&rec), Applied::Report);
        // Channels 0-3 are 0 while button 0 is up; channel 4 is read and the loop stops.
        assert_eq!(s.channels, [0.0, 0.0, 0.0, 0.0, 0.5, 0.0]);
        s.apply(b"B\x01\x00\n");
        assert_eq!(s.buttons, [true, false]);
        let rec = encode_data([(0, 512), (1, 256), (2, 0), (3, 1023), (5, 0x3F0), (4, 0)]);
        s.apply(&rec);
        // The filters saw channel 0's 1.0 in both records.
        let v0 = {
            let mut dc = DcBlocker::default();
            let mut lp = LowPass::default();
            lp.filter(dc.filter(1.0));
            lp.filter(dc.filter(1.0))
        };
        assert_eq!(s.channels[0], v0 * 0.25 * 0.25 / 2.0);
        assert_eq!(s.channels[5], (f64::from(0x3F0u16) - 256.0) / 256.0);
        let bad = encode_data([(7, 0); CHANNELS]);
        assert_eq!(s.apply(&bad), Applied::BadChannel(7));
    }
}
