//! The Orb's one-byte events. Pure.
//!
//! Each button has a press byte and a release byte (30 buttons); the thumbwheel and the
//! trackball send one byte per encoder tick and direction; a few bytes are status the Orb
//! sends (its `FC` answers the reset byte `81`) and mean nothing here.

/// Buttons.
pub const BUTTONS: usize = 30;
/// Dials (and analog channels): the thumbwheel, the ball's two axes.
pub const DIALS: usize = 3;
/// Revolutions per thumbwheel tick (C++'s constant, "checked").
pub const REV_PER_TICK_WHEEL: f64 = 1.0 / 15.0;
/// Revolutions per trackball tick (C++'s constant, "guess").
pub const REV_PER_TICK_BALL: f64 = 1.0 / 164.0;
/// The byte that resets the Orb (and asks it to answer).
pub const RESET: u8 = 0x81;
/// The Orb's answer to it.
pub const RESET_ANSWER: u8 = 0xFC;

/// Button `i`'s press byte; its release byte is [`RELEASE`]`[i]`.
pub const PRESS: [u8; BUTTONS] = [
    0x89, 0x88, 0x90, 0x8e, 0x8d, 0x8c, 0x8b, 0x8a, 0x9b, 0x9a, 0x99, 0x98, 0x9f, 0x9e, 0x9d, 0x9c,
    0x81, 0x80, 0x8f, 0x86, 0x85, 0x84, 0x83, 0x82, 0xa0, 0x87, 0xa1, 0xa2, 0x92, 0x91,
];
/// Button `i`'s release byte.
pub const RELEASE: [u8; BUTTONS] = [
    0xb9, 0xb8, 0xc0, 0xbe, 0xbd, 0xbc, 0xbb, 0xba, 0xcb, 0xca, 0xc9, 0xc8, 0xcf, 0xce, 0xcd, 0xcc,
    0xb1, 0xb0, 0xbf, 0xb6, 0xb5, 0xb4, 0xb3, 0xb2, 0xd0, 0xb7, 0xd1, 0xd2, 0xc2, 0xc1,
];

/// What a byte means.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A button pressed or released.
    Button(usize, bool),
    /// A dial turned by this many revolutions.
    Turn(usize, f64),
    /// Status the Orb sends; nothing to report.
    Status,
}

/// The event of byte `b`, if it is one.
pub fn decode(b: u8) -> Option<Event> {
    if let Some(i) = PRESS.iter().position(|&p| p == b) {
        return Some(Event::Button(i, true));
    }
    if let Some(i) = RELEASE.iter().position(|&p| p == b) {
        return Some(Event::Button(i, false));
    }
    Some(match b {
        0xE1 => Event::Turn(0, -REV_PER_TICK_WHEEL),
        0xE0 => Event::Turn(0, REV_PER_TICK_WHEEL),
        0xF2 => Event::Turn(1, REV_PER_TICK_BALL),
        0xF3 => Event::Turn(1, -REV_PER_TICK_BALL),
        0xF0 => Event::Turn(2, REV_PER_TICK_BALL),
        0xF1 => Event::Turn(2, -REV_PER_TICK_BALL),
        0xFD | 0x00 | 0xFE | 0x10 | 0xFB | 0xFC => Event::Status,
        _ => return None,
    })
}

/// The analog channel after a turn: the sum of the turns, held within −1…1 (as C++ does).
pub fn channel_after(value: f64, turn: f64) -> f64 {
    (value + turn).clamp(-1.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_byte_means_one_thing() {
        let mut seen = std::collections::HashSet::new();
        for b in PRESS.iter().chain(&RELEASE) {
            assert!(seen.insert(*b), "{b:02x} twice");
        }
        assert_eq!(decode(0x89), Some(Event::Button(0, true)));
        assert_eq!(decode(0xc1), Some(Event::Button(29, false)));
        assert_eq!(decode(RESET), Some(Event::Button(16, true)));
        assert_eq!(decode(0xF3), Some(Event::Turn(1, -1.0 / 164.0)));
        assert_eq!(decode(RESET_ANSWER), Some(Event::Status));
        assert_eq!(decode(0x41), None);
        assert_eq!(channel_after(0.99, 1.0 / 15.0), 1.0);
    }
}
