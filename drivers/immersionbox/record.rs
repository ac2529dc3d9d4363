//! The Immersion box's configuration byte and its records (pure code).
//!
//! The configuration byte asks for time stamps (0x20, never asked for here), analog inputs
//! (0x04 two, 0x08 four, 0x0C eight) and encoders (0x01 two, 0x02 four, 0x03 six). A record
//! is a header (the configuration byte with bit 7 set), the button byte (bit *i* is button
//! *i*), then the analog bytes (one per input and one more for their extra bits: 3, 5 or 9)
//! and two bytes per encoder. How the analog and encoder bytes encode values is not in the
//! public C++ source, which reads them and discards them; so does this driver.

use crate::time::Now;

/// Most buttons, analog inputs and encoders C++ opens.
pub const MAX_BUTTONS: u32 = 7;
/// Most analog inputs.
pub const MAX_ANALOGS: u32 = 8;
/// Most encoders.
pub const MAX_ENCODERS: u32 = 6;
/// Longest record (header, buttons, 9 analog bytes, 12 encoder bytes).
pub const MAX_RECORD: usize = 1 + 1 + 9 + 12;

/// The configuration byte for `analogs` inputs and `encoders` encoders, as C++ computes it
/// (more than 4 analogs asks for 8, more than 2 for 4, any for 2; more than 3 encoders asks
/// for 6, more than 2 for 4, any for 2).
pub fn config_byte(analogs: u32, encoders: u32) -> u8 {
    let a = match analogs {
        0 => 0,
        1..=2 => 0x04,
        3..=4 => 0x08,
        _ => 0x0C,
    };
    let e = match encoders {
        0 => 0,
        1..=2 => 0x01,
        3 => 0x02,
        _ => 0x03,
    };
    a | e
}

/// A record's header for a configuration byte.
pub fn header(config: u8) -> u8 {
    config | 0x80
}

/// A record's length, header included, for a configuration byte: what the configuration
/// asks the box to send.
pub fn record_len(config: u8) -> usize {
    let analog = [0, 3, 5, 9][usize::from((config >> 2) & 3)];
    let encoders = [0, 4, 8, 12][usize::from(config & 3)];
    2 + analog + encoders
}

/// A record found: its button byte and the arrival of its header.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framed {
    /// The button byte.
    pub buttons: u8,
    /// When the read holding its header arrived.
    pub first_byte: Now,
    /// Bytes skipped since the previous record.
    pub skipped: u32,
}

/// Finds records: bytes other than the header are skipped until one is seen, then the
/// record's length is taken. The protocol has no check, so a stray byte equal to the header
/// starts a false record (as in C++).
#[derive(Clone, Debug)]
pub struct Framer {
    header: u8,
    len: usize,
    got: usize,
    buttons: u8,
    first: Option<Now>,
    skipped: u32,
    total_skipped: u64,
}

impl Framer {
    /// A framer for records of configuration byte `config`.
    pub fn new(config: u8) -> Framer {
        Framer {
            header: header(config),
            len: record_len(config),
            got: 0,
            buttons: 0,
            first: None,
            skipped: 0,
            total_skipped: 0,
        }
    }

    /// Forgets a partial record.
    pub fn clear(&mut self) {
        self.got = 0;
        self.skipped = 0;
    }

    /// Bytes skipped since construction.
    pub fn total_skipped(&self) -> u64 {
        self.total_skipped
    }

    /// Takes one byte that arrived at `arrived`.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Framed> {
        if self.got == 0 {
            if b != self.header {
                self.skipped = self.skipped.saturating_add(1);
                self.total_skipped += 1;
                return None;
            }
            self.first = Some(arrived);
        } else if self.got == 1 {
            self.buttons = b;
        }
        self.got += 1;
        if self.got < self.len {
            return None;
        }
        self.got = 0;
        Some(Framed {
            buttons: self.buttons,
            first_byte: self.first.unwrap_or(arrived),
            skipped: std::mem::take(&mut self.skipped),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use std::time::Instant;

    #[test]
    fn configuration_bytes_and_lengths() {
        assert_eq!(config_byte(0, 0), 0);
        assert_eq!(record_len(0), 2);
        assert_eq!(config_byte(2, 1), 0x05);
        assert_eq!(record_len(0x05), 2 + 3 + 4);
        assert_eq!(config_byte(4, 3), 0x0A);
        assert_eq!(record_len(0x0A), 2 + 5 + 8);
        assert_eq!(config_byte(8, 4), 0x0F);
        assert_eq!(record_len(0x0F), MAX_RECORD);
        assert_eq!(header(0x0F), 0x8F);
    }

    #[test]
    fn records_after_garbage() {
        let t = Now {
            mono: Instant::now(),
            wall: TimeVal::new(1, 0),
        };
        let mut f = Framer::new(0x05);
        let mut out = Vec::new();
        for b in [0x01, 0x02, 0x85, 0x0A, 0, 0, 0, 0, 0, 0, 0] {
            out.extend(f.push(b, t));
        }
        assert_eq!(
            out,
            vec![Framed {
                buttons: 0x0A,
                first_byte: t,
                skipped: 2
            }]
        );
    }
}
