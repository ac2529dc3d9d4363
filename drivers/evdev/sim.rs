//! Input-event sequences as the kernel writes them, for simulators and tests.

use crate::hid::input_event::{InputEvent, EV_ABS, EV_KEY, EV_REL, EV_SYN};

/// One event.
pub const fn ev(kind: u16, code: u16, value: i32) -> InputEvent {
    InputEvent { kind, code, value }
}

/// A key or button event.
pub const fn key(code: u16, value: i32) -> InputEvent {
    ev(EV_KEY, code, value)
}

/// A relative axis event.
pub const fn rel(code: u16, value: i32) -> InputEvent {
    ev(EV_REL, code, value)
}

/// An absolute axis event.
pub const fn abs(code: u16, value: i32) -> InputEvent {
    ev(EV_ABS, code, value)
}

/// The end of a frame.
pub const fn syn() -> InputEvent {
    ev(EV_SYN, 0, 0)
}

/// The bytes of `events`, as one `read` of the node would return them.
pub fn bytes(events: &[InputEvent]) -> Vec<u8> {
    let mut b = Vec::new();
    for (i, e) in events.iter().enumerate() {
        b.extend_from_slice(&e.encode(1_700_000_000, i as i64));
    }
    b
}
