//! The SGI dial and button boxes' serial protocol (pure code).
//!
//! The two boxes share one line at 9600 baud. `0x20` resets both; each answers `0x20`.
//! The dial box is enabled with `50 xx FF`; the button box with `71 FF FF FF FF` (enable) and
//! `73 FF FF FF FF` (activate), which it sometimes needs twice. `75 b0 b1 b2 b3` sets the 32
//! button lights (bit *i* of byte *k* is light 8*k* + *i*).
//!
//! From the boxes: a button press or release is one byte (≥ 0xC0, [`button_event`]); a dial
//! turn is three, `3d HH LL`: dial *d* (0-7) and its 16-bit signed position counter, 200
//! counts a revolution.

/// The reset command, and the boxes' answer to it.
pub const RESET: u8 = 0x20;
/// Enable every dial (the dial box; sent first, since enabling the dials disables the
/// buttons).
pub const ENABLE_DIALS: [u8; 3] = [0x50, 0xFF, 0xFF];
/// Enable every button.
pub const ENABLE_BUTTONS: [u8; 5] = [0x71, 0xFF, 0xFF, 0xFF, 0xFF];
/// Activate every button.
pub const ACTIVATE_BUTTONS: [u8; 5] = [0x73, 0xFF, 0xFF, 0xFF, 0xFF];
/// The light command's first byte.
pub const LIGHTS: u8 = 0x75;
/// Buttons on the button box.
pub const BUTTONS: usize = 32;
/// Dials on the dial box.
pub const DIALS: usize = 8;
/// Counts a revolution.
pub const COUNTS_PER_TURN: i32 = 200;

/// The light command for lights `on` (bit *i* is light *i*).
pub fn lights(on: u32) -> [u8; 5] {
    let b = on.to_le_bytes();
    [LIGHTS, b[0], b[1], b[2], b[3]]
}

/// A button byte: (button, pressed). Presses are 0xD8-0xDF for buttons 0-7, 0xD0-0xD7 for
/// 8-15, 0xC8-0xCF for 16-23, 0xC0-0xC7 for 24-31; releases the same plus 0x20.
pub fn button_event(b: u8) -> Option<(usize, bool)> {
    if b < 0xC0 {
        return None;
    }
    let bank = match b & 0x18 {
        0x18 => 0,
        0x10 => 8,
        0x08 => 16,
        _ => 24,
    };
    Some((bank + usize::from(b & 7), b < 0xE0))
}

/// The byte for button `button` pressed or released.
pub fn button_byte(button: usize, pressed: bool) -> u8 {
    let bank = [0x18u8, 0x10, 0x08, 0x00][button / 8 % 4];
    0xC0 | bank | (button % 8) as u8 | if pressed { 0 } else { 0x20 }
}

/// A dial's state between turns: its last position and the middle of its saturating range.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DialState {
    last: i16,
    mid: i32,
}

impl DialState {
    /// The dial moved to `position`: its channel (−0.5…0.5 around a middle that follows the
    /// dial past either end, as C++) and the revolutions turned since the last position.
    pub fn turn(&mut self, position: i16) -> (f64, f64) {
        let p = i32::from(position);
        let from_mid = p - self.mid;
        let channel = if from_mid > COUNTS_PER_TURN {
            self.mid = p - COUNTS_PER_TURN;
            0.5
        } else if from_mid < -COUNTS_PER_TURN {
            self.mid = p + COUNTS_PER_TURN;
            -0.5
        } else {
            f64::from(from_mid) / f64::from(2 * COUNTS_PER_TURN)
        };
        let turned = f64::from(position.wrapping_sub(self.last)) / f64::from(COUNTS_PER_TURN);
        self.last = position;
        (channel, turned)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn button_bytes_round_trip() {
        for button in 0..BUTTONS {
            for pressed in [true, false] {
                let b = button_byte(button, pressed);
                assert_eq!(button_event(b), Some((button, pressed)), "{b:02X}");
            }
        }
        assert_eq!(button_event(0xD8), Some((0, true)));
        assert_eq!(button_event(0xC7), Some((31, true)));
        assert_eq!(button_event(0xF0), Some((8, false)));
        assert_eq!(button_event(0xBF), None);
        assert_eq!(lights(1 << 9 | 1), [LIGHTS, 1, 2, 0, 0]);
    }

    #[test]
    fn dials_saturate_and_back_off() {
        let mut d = DialState::default();
        assert_eq!(d.turn(100), (0.25, 0.5));
        assert_eq!(d.turn(300), (0.5, 1.0));
        // Past the end the middle follows: turning back lowers the value at once.
        assert_eq!(d.turn(250), (0.375, -0.25));
        assert_eq!(d.turn(-300), (-0.5, -2.75));
        // The counter wraps: a small turn, not a full range.
        let mut w = DialState::default();
        w.turn(i16::MAX);
        assert_eq!(w.turn(i16::MIN).1, 1.0 / 200.0);
    }
}
