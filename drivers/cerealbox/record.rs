//! CerealBox records and the configuration command: which inputs are on, how long a record
//! is, and how its characters decode (with the encoding the simulator needs).
//!
//! Data characters carry six bits (four for buttons) plus [`OFFSET`], so every one of them is
//! in `0x21..=0x60`: neither the record's start `p` nor its final LF can hide inside one.
//! A record is `p`, two characters per bank of eight buttons (highest nibble first), two per
//! analog (high six bits first, twelve bits in all), four per encoder (six bits each, least
//! significant first, a 24-bit two's complement count of ticks), then LF.

/// Added to data characters to keep them printable.
pub const OFFSET: u8 = 0x21;
/// Highest data character.
pub const MAX_DATA: u8 = OFFSET + 0x3F;
/// Starts a record; also the first byte of the request for one.
pub const START: u8 = b'p';
/// Ends a record and the configuration command.
pub const LF: u8 = b'\n';
/// Asks the box for one record.
pub const REQUEST: &[u8] = b"pE";
/// Asks the box for its banner (and lets it detect the baud rate).
pub const BANNER_REQUEST: &[u8] = b"T";
/// Length of the banner.
pub const BANNER_LEN: usize = 44;
/// How the banner starts.
pub const BANNER_PREFIX: &[u8] = b"Copyright (c), BG Systems";
/// Encoder ticks per revolution.
pub const TICKS_PER_REV: f64 = 4096.0;
/// Longest record: 24 buttons, 8 analogs, 8 encoders.
pub const MAX_RECORD: usize = 2 + 6 + 16 + 32;

/// Which inputs are used: counts from the configuration line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Buttons, 0..=24 (read in banks of eight).
    pub buttons: usize,
    /// Analogs (sliders), 0..=8.
    pub analogs: usize,
    /// Encoders (dials), 0..=8.
    pub encoders: usize,
}

/// Bits `0..n` of a four-channel group starting at channel `from`.
fn group_bits(n: usize, from: usize) -> u8 {
    (0..4)
        .filter(|i| from + i < n)
        .fold(0, |bits, i| bits | 1 << i)
}

impl Layout {
    /// Banks of eight buttons.
    pub fn banks(&self) -> usize {
        self.buttons.div_ceil(8)
    }

    /// Characters that carry buttons (two per bank).
    pub fn button_chars(&self) -> usize {
        2 * self.banks()
    }

    /// Length of a record, `p` and LF included.
    pub fn record_len(&self) -> usize {
        2 + self.button_chars() + 2 * self.analogs + 4 * self.encoders
    }

    /// The command that switches on these inputs, encoders counting increments.
    pub fn config_command(&self) -> [u8; 10] {
        let digital = (1u8 << self.banks()) - 1;
        let enc_low = group_bits(self.encoders, 0);
        let enc_high = group_bits(self.encoders, 4);
        [
            b'c',
            OFFSET + group_bits(self.analogs, 0),
            OFFSET + (group_bits(self.analogs, 4) | digital << 4),
            OFFSET,
            OFFSET,
            OFFSET + enc_low,
            OFFSET + enc_low,
            OFFSET + enc_high,
            OFFSET + enc_high,
            LF,
        ]
    }

    /// The layout a configuration command asks for (what the simulated box does with it).
    pub fn from_config_command(cmd: &[u8; 10]) -> Layout {
        let v = |i: usize| cmd[i].wrapping_sub(OFFSET);
        let (a1, a2, e1, e2) = (v(1) & 0x0F, v(2) & 0x0F, v(5) & 0x0F, v(7) & 0x0F);
        Layout {
            buttons: 8 * (v(2) >> 4).count_ones() as usize,
            analogs: (a1.count_ones() + a2.count_ones()) as usize,
            encoders: (e1.count_ones() + e2.count_ones()) as usize,
        }
    }

    /// The button states in `record` as a mask (bit `i` = button `i`; whole banks).
    pub fn buttons_of(&self, record: &[u8]) -> u32 {
        let k = self.button_chars();
        record[1..1 + k]
            .iter()
            .enumerate()
            .fold(0, |mask, (j, &c)| {
                let nibble = u32::from(c.wrapping_sub(OFFSET) & 0x0F);
                mask | nibble << (4 * (k - 1 - j))
            })
    }

    /// Analog `i` of `record`, from -1 to 1.
    pub fn analog_of(&self, record: &[u8], i: usize) -> f64 {
        -1.0 + 2.0 * f64::from(analog_raw(record, 1 + self.button_chars() + 2 * i)) / 4095.0
    }

    /// Ticks encoder `i` turned, from `record`.
    pub fn encoder_of(&self, record: &[u8], i: usize) -> i32 {
        let at = 1 + self.button_chars() + 2 * self.analogs + 4 * i;
        let v = record[at..at + 4].iter().rev().fold(0i32, |v, &c| {
            v << 6 | i32::from(c.wrapping_sub(OFFSET) & 0x3F)
        });
        // Sign-extend from bit 23.
        (v << 8) >> 8
    }

    /// A record with these values: `buttons` mask, analog raw values (0..=4095), encoder
    /// ticks (24-bit two's complement). Returns the buffer and its length.
    pub fn encode(
        &self,
        buttons: u32,
        analogs: &[u16],
        encoders: &[i32],
    ) -> ([u8; MAX_RECORD], usize) {
        let mut r = [0u8; MAX_RECORD];
        let k = self.button_chars();
        r[0] = START;
        for j in 0..k {
            r[1 + j] = OFFSET + ((buttons >> (4 * (k - 1 - j))) & 0x0F) as u8;
        }
        let mut at = 1 + k;
        for &a in &analogs[..self.analogs] {
            r[at] = OFFSET + ((a >> 6) & 0x3F) as u8;
            r[at + 1] = OFFSET + (a & 0x3F) as u8;
            at += 2;
        }
        for &e in &encoders[..self.encoders] {
            let u = (e as u32) & 0xFF_FFFF;
            for g in 0..4 {
                r[at + g] = OFFSET + ((u >> (6 * g)) & 0x3F) as u8;
            }
            at += 4;
        }
        r[at] = LF;
        (r, at + 1)
    }
}

/// The twelve-bit value of the two characters at `at`.
fn analog_raw(record: &[u8], at: usize) -> u16 {
    u16::from(record[at].wrapping_sub(OFFSET) & 0x3F) << 6
        | u16::from(record[at + 1].wrapping_sub(OFFSET) & 0x3F)
}

/// Revolutions of `ticks` encoder ticks.
pub fn revolutions(ticks: i32) -> f64 {
    f64::from(ticks) / TICKS_PER_REV
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_configuration_command_for_every_count() {
        let full = Layout {
            buttons: 24,
            analogs: 8,
            encoders: 8,
        };
        assert_eq!(&full.config_command(), b"c0\xa0!!0000\n");
        assert_eq!(full.record_len(), MAX_RECORD);
        let l = Layout {
            buttons: 9,
            analogs: 5,
            encoders: 2,
        };
        // Analogs 0-3 and 4; banks 0 and 1; encoders 0 and 1, incremental.
        assert_eq!(
            l.config_command(),
            [
                b'c',
                0x21 + 0xF,
                0x21 + 0x31,
                0x21,
                0x21,
                0x24,
                0x24,
                0x21,
                0x21,
                b'\n'
            ]
        );
        assert_eq!(l.record_len(), 2 + 4 + 10 + 8);
        for buttons in 0..=24 {
            for analogs in 0..=8 {
                for encoders in 0..=8 {
                    let l = Layout {
                        buttons,
                        analogs,
                        encoders,
                    };
                    let back = Layout::from_config_command(&l.config_command());
                    assert_eq!(back.buttons, 8 * l.banks());
                    assert_eq!((back.analogs, back.encoders), (analogs, encoders));
                }
            }
        }
        let none = Layout {
            buttons: 0,
            analogs: 0,
            encoders: 0,
        };
        assert_eq!(none.record_len(), 2);
        assert_eq!(&none.config_command(), b"c!!!!!!!!\n");
    }

    #[test]
    fn records_round_trip_and_stay_printable() {
        let l = Layout {
            buttons: 20,
            analogs: 3,
            encoders: 3,
        };
        let analogs = [0u16, 4095, 2048];
        let encoders = [-1, 8_388_607, -8_388_608];
        let (r, n) = l.encode(0xA_5F3C, &analogs, &encoders);
        assert_eq!(n, l.record_len());
        assert_eq!((r[0], r[n - 1]), (START, LF));
        assert!(r[1..n - 1]
            .iter()
            .all(|&c| (OFFSET..=MAX_DATA).contains(&c)));
        assert_eq!(l.buttons_of(&r), 0xA_5F3C);
        assert_eq!(l.analog_of(&r, 0), -1.0);
        assert_eq!(l.analog_of(&r, 1), 1.0);
        assert_eq!(l.analog_of(&r, 2), -1.0 + 4096.0 / 4095.0);
        let ticks: Vec<i32> = (0..3).map(|i| l.encoder_of(&r, i)).collect();
        assert_eq!(ticks, encoders);
        assert_eq!(revolutions(-4096), -1.0);
        // The first button character holds the highest nibble.
        assert_eq!(r[1] - OFFSET, 0x00);
        assert_eq!(r[2] - OFFSET, 0x0A);
        assert_eq!(r[6] - OFFSET, 0x0C);
    }
}
