//! The Linux joystick interface's event record (`struct js_event`, 8 bytes in host byte
//! order), and finding whole events in a byte stream.
//!
//! | Offset | Size | Field |
//! |---|---|---|
//! | 0 | 4 | time, ms (the driver's clock; not used) |
//! | 4 | 2 | value, signed |
//! | 6 | 1 | type: 1 button, 2 axis, + 0x80 for the initial state sent after open |
//! | 7 | 1 | number (axis or button index) |
//!
//! A joystick device hands over whole events; a stand-in (a pipe, a pseudo-terminal) may
//! split them, and a damaged stream has no sync marker. The [`Framer`] collects eight bytes,
//! and when they are not a plausible event (an unknown type, a button value other than 0 or
//! 1, a number the caller knows the device does not have) gives up one byte and tries again
//! from the next. Damage can still pass for an event now and then: there is no checksum.

use crate::time::Now;

/// Bytes in one event.
pub const EVENT_LEN: usize = 8;
/// Type: a button.
pub const JS_EVENT_BUTTON: u8 = 0x01;
/// Type: an axis.
pub const JS_EVENT_AXIS: u8 = 0x02;
/// Type flag: the initial state, sent for every button and axis after the device opens.
pub const JS_EVENT_INIT: u8 = 0x80;

/// What an event is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A button; value 0 (released) or 1 (pressed).
    Button,
    /// An axis; value −32767..=32767.
    Axis,
}

/// One decoded event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JsEvent {
    /// The driver's time stamp, ms.
    pub time_ms: u32,
    /// The value.
    pub value: i16,
    /// Button or axis.
    pub kind: Kind,
    /// Part of the initial state after open.
    pub init: bool,
    /// Button or axis index.
    pub number: u8,
}

impl JsEvent {
    /// Decodes an event; `None` when it is not a plausible one.
    pub fn decode(b: &[u8; EVENT_LEN]) -> Option<JsEvent> {
        let value = i16::from_ne_bytes([b[4], b[5]]);
        let kind = match b[6] & !JS_EVENT_INIT {
            JS_EVENT_BUTTON if value == 0 || value == 1 => Kind::Button,
            JS_EVENT_AXIS => Kind::Axis,
            _ => return None,
        };
        Some(JsEvent {
            time_ms: u32::from_ne_bytes([b[0], b[1], b[2], b[3]]),
            value,
            kind,
            init: b[6] & JS_EVENT_INIT != 0,
            number: b[7],
        })
    }

    /// The event's bytes, as the kernel writes them.
    pub fn encode(&self) -> [u8; EVENT_LEN] {
        let mut b = [0u8; EVENT_LEN];
        b[..4].copy_from_slice(&self.time_ms.to_ne_bytes());
        b[4..6].copy_from_slice(&self.value.to_ne_bytes());
        b[6] = match self.kind {
            Kind::Button => JS_EVENT_BUTTON,
            Kind::Axis => JS_EVENT_AXIS,
        } | if self.init { JS_EVENT_INIT } else { 0 };
        b[7] = self.number;
        b
    }
}

/// Collects whole events from a byte stream. See the module documentation.
#[derive(Clone, Debug, Default)]
pub struct Framer {
    buf: [u8; EVENT_LEN],
    times: [Option<Now>; EVENT_LEN],
    len: usize,
    skipped: u64,
}

impl Framer {
    /// An empty framer.
    pub fn new() -> Framer {
        Framer::default()
    }

    /// Forgets a partial event (after a reopen).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Bytes given up since construction.
    pub fn total_skipped(&self) -> u64 {
        self.skipped
    }

    /// Takes one byte that arrived at `arrived`; returns an event (with the arrival of its
    /// first byte) when this byte completes one that is plausible and that `accept` takes.
    pub fn push(
        &mut self,
        b: u8,
        arrived: Now,
        accept: impl Fn(&JsEvent) -> bool,
    ) -> Option<(JsEvent, Now)> {
        self.buf[self.len] = b;
        self.times[self.len] = Some(arrived);
        self.len += 1;
        if self.len < EVENT_LEN {
            return None;
        }
        if let Some(ev) = JsEvent::decode(&self.buf).filter(|e| accept(e)) {
            self.len = 0;
            return Some((ev, self.times[0].unwrap_or(arrived)));
        }
        // Give up the first byte; the search goes on from the second.
        self.skipped += 1;
        self.buf.copy_within(1.., 0);
        self.times.copy_within(1.., 0);
        self.len = EVENT_LEN - 1;
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use std::time::Instant;

    fn ev(kind: Kind, number: u8, value: i16, init: bool) -> JsEvent {
        JsEvent {
            time_ms: 123_456,
            value,
            kind,
            init,
            number,
        }
    }

    #[test]
    fn events_round_trip_and_implausible_ones_are_refused() {
        for e in [
            ev(Kind::Axis, 3, -32767, false),
            ev(Kind::Button, 11, 1, true),
            ev(Kind::Axis, 0, 0, true),
        ] {
            assert_eq!(JsEvent::decode(&e.encode()), Some(e));
        }
        let mut b = ev(Kind::Button, 0, 1, false).encode();
        b[4] = 7;
        assert_eq!(JsEvent::decode(&b), None);
        b[6] = 0x04;
        assert_eq!(JsEvent::decode(&b), None);
    }

    #[test]
    fn garbage_before_an_event_costs_only_itself() {
        let now = Now {
            mono: Instant::now(),
            wall: TimeVal::new(5, 0),
        };
        let mut f = Framer::new();
        let a = ev(Kind::Axis, 1, 1000, false);
        let b = ev(Kind::Button, 2, 1, false);
        let mut got = Vec::new();
        // Garbage whose type byte position holds 0x33, then two events.
        for &x in [0x10, 0x20, 0x30]
            .iter()
            .chain(&a.encode())
            .chain(&b.encode())
        {
            got.extend(f.push(x, now, |_| true).map(|(e, _)| e));
        }
        assert_eq!(got, vec![a, b]);
        assert_eq!(f.total_skipped(), 3);
    }
}
