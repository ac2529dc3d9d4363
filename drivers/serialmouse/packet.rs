//! The mouse's packets, byte by byte, and what they say about its three buttons. Pure.
//!
//! * **Mouse Systems** (`mousesystems`): a 5-byte packet; its first byte is `1000 0LMR`
//!   (`80`-`87`) with the buttons *pressed while clear*, then four motion bytes.
//! * **Microsoft with 3-button emulation** (`3button`): a 3-byte packet whose first byte,
//!   read as 8N1 (the stop bit lands in bit 7), is `11LR YYXX` (the top motion bits in
//!   `YYXX`). Only first bytes without motion bits (`C0`, `D0`, `E0`, `F0`) are read, as in
//!   C++; every other byte is motion and ignored. Such a packet whose left and right buttons
//!   are as in the packet before toggles the middle button (the mouse moved, or the middle
//!   button was pressed), except the very first one, which only clears it.

/// The buttons a serial mouse has.
pub const BUTTONS: usize = 3;
/// Bytes in a Mouse Systems packet.
pub const MOUSESYSTEMS_LEN: usize = 5;

/// The mouse's protocol (the `vrpn.cfg` line's type).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MouseType {
    /// `mousesystems`: 5-byte packets, buttons in the first byte (active low).
    MouseSystems,
    /// `3button`: Microsoft 3-byte packets; middle button toggled by packets without a
    /// left/right change.
    ThreeButton,
}

/// What a byte did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// It began a packet that sets the buttons (left, middle, right).
    Buttons([bool; BUTTONS]),
    /// It belongs to a packet (motion) and says nothing about the buttons.
    Motion,
    /// It belongs to no packet (Mouse Systems only: a byte outside a packet that is not a
    /// first byte).
    Garbage,
}

/// Reads packets byte by byte, keeping the button state the packets build up.
#[derive(Clone, Debug)]
pub struct Decoder {
    kind: MouseType,
    /// Motion bytes still expected in the current Mouse Systems packet.
    motion_left: usize,
    buttons: [bool; BUTTONS],
    /// What the middle button was after the last packet (starts `true` in `3button`, so the
    /// first packet without a change clears it rather than pressing it, as C++ does).
    last_middle: bool,
}

impl Decoder {
    /// A decoder for `kind`, all buttons released.
    pub fn new(kind: MouseType) -> Decoder {
        Decoder {
            kind,
            motion_left: 0,
            buttons: [false; BUTTONS],
            last_middle: kind == MouseType::ThreeButton,
        }
    }

    /// Forgets the packet under way (the port closed); the buttons keep their state.
    pub fn clear_packet(&mut self) {
        self.motion_left = 0;
    }

    /// Reads byte `b`.
    pub fn push(&mut self, b: u8) -> Step {
        match self.kind {
            MouseType::MouseSystems => {
                if self.motion_left > 0 {
                    self.motion_left -= 1;
                    Step::Motion
                } else if b & 0xF8 == 0x80 {
                    self.motion_left = MOUSESYSTEMS_LEN - 1;
                    self.buttons = [b & 4 == 0, b & 2 == 0, b & 1 == 0];
                    Step::Buttons(self.buttons)
                } else {
                    Step::Garbage
                }
            }
            MouseType::ThreeButton => {
                if !matches!(b, 0xC0 | 0xD0 | 0xE0 | 0xF0) {
                    return Step::Motion;
                }
                let (left, right) = (b & 0x20 != 0, b & 0x10 != 0);
                if left == self.buttons[0] && right == self.buttons[2] {
                    self.buttons[1] = !self.last_middle;
                }
                self.buttons[0] = left;
                self.buttons[2] = right;
                self.last_middle = self.buttons[1];
                Step::Buttons(self.buttons)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mouse_systems_buttons_are_active_low_and_motion_is_not_a_first_byte() {
        let mut d = Decoder::new(MouseType::MouseSystems);
        assert_eq!(d.push(0x41), Step::Garbage);
        assert_eq!(d.push(0x83), Step::Buttons([true, false, false]));
        // A motion byte of 0x80-0x87 inside a packet is motion (C++ would read it as
        // buttons).
        for b in [0x85, 0x01, 0xFF, 0x86] {
            assert_eq!(d.push(b), Step::Motion);
        }
        assert_eq!(d.push(0x20), Step::Garbage);
        assert_eq!(d.push(0x80), Step::Buttons([true, true, true]));
        for b in [0, 0, 0, 0] {
            assert_eq!(d.push(b), Step::Motion);
        }
        assert_eq!(d.push(0x87), Step::Buttons([false, false, false]));
    }

    #[test]
    fn three_button_middle_toggles_on_packets_without_a_change() {
        let mut d = Decoder::new(MouseType::ThreeButton);
        // The first packet without a change only clears the middle button.
        assert_eq!(d.push(0xC0), Step::Buttons([false, false, false]));
        assert_eq!(d.push(0x85), Step::Motion);
        assert_eq!(d.push(0xC1), Step::Motion);
        assert_eq!(d.push(0xC0), Step::Buttons([false, true, false]));
        assert_eq!(d.push(0xE0), Step::Buttons([true, true, false]));
        assert_eq!(d.push(0xE0), Step::Buttons([true, false, false]));
        assert_eq!(d.push(0xD0), Step::Buttons([false, false, true]));
        assert_eq!(d.push(0xF0), Step::Buttons([true, false, true]));
        assert_eq!(d.push(0xF0), Step::Buttons([true, true, true]));
    }
}
