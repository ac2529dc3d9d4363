//! The joystick's 4-byte messages, byte by byte. Pure.
//!
//! A message is `FF`, two bytes of button bits (high byte first, a button *pressed while its
//! bit is clear*), and a byte no one reads. The eight buttons' bits, in VRPN's button order:
//! bottom `1000`, middle `0100`, top `0001`, trigger `0200`, hat up `0800`, hat right
//! `0002`, hat down `0400`, hat left `0004`.

/// Buttons served.
pub const BUTTONS: usize = 8;
/// Bytes in a message.
pub const MESSAGE_LEN: usize = 4;
/// The byte a message starts with.
pub const SYNC: u8 = 0xFF;
/// Button `i`'s bit in the 16-bit word of bytes 1 and 2.
pub const MASKS: [u16; BUTTONS] = [
    0x1000, 0x0100, 0x0001, 0x0200, 0x0800, 0x0002, 0x0400, 0x0004,
];

/// The buttons a message's two button bytes say are pressed.
pub fn buttons(high: u8, low: u8) -> [bool; BUTTONS] {
    let word = u16::from_be_bytes([high, low]);
    MASKS.map(|m| word & m == 0)
}

/// What a byte did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// It ended a message, whose buttons these are.
    Message([bool; BUTTONS]),
    /// It is part of a message under way.
    Partial,
    /// It is outside any message and not its start: skipped.
    Garbage,
}

/// Finds messages byte by byte: a message starts at an `FF` outside a message (as C++
/// looks for it).
#[derive(Clone, Debug, Default)]
pub struct Framer {
    buf: [u8; MESSAGE_LEN],
    len: usize,
}

impl Framer {
    /// Forgets a message under way.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// True when the next byte would start a message (none is under way).
    pub fn idle(&self) -> bool {
        self.len == 0
    }

    /// Reads byte `b`.
    pub fn push(&mut self, b: u8) -> Step {
        if self.len == 0 && b != SYNC {
            return Step::Garbage;
        }
        self.buf[self.len] = b;
        self.len += 1;
        if self.len < MESSAGE_LEN {
            return Step::Partial;
        }
        self.len = 0;
        Step::Message(buttons(self.buf[1], self.buf[2]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_are_found_after_garbage_and_buttons_are_active_low() {
        let mut f = Framer::default();
        assert_eq!(f.push(0x41), Step::Garbage);
        assert_eq!(f.push(SYNC), Step::Partial);
        assert_eq!(f.push(0x1F), Step::Partial);
        assert_eq!(f.push(0x07), Step::Partial);
        assert_eq!(f.push(0x00), Step::Message([false; BUTTONS]));
        // Trigger (0200) and hat left (0004) pressed.
        let m = [SYNC, 0x1D, 0x03, 0x00].map(|b| f.push(b));
        let mut want = [false; BUTTONS];
        want[3] = true;
        want[7] = true;
        assert_eq!(m[3], Step::Message(want));
        assert_eq!(buttons(0, 0), [true; BUTTONS]);
    }
}
