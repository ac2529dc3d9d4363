//! Linux input event devices (`/dev/input/eventN`): the `input_event` record and a source
//! that reads whole records from the node, or from a pipe standing in for it.
//!
//! | Offset (64-bit) | Size | Field |
//! |---|---|---|
//! | 0 | 16 | time (`struct timeval`; the kernel's, not used) |
//! | 16 | 2 | type (`EV_KEY`, `EV_REL`, `EV_ABS`, `EV_SYN`, …) |
//! | 18 | 2 | code (`KEY_A`, `BTN_LEFT`, `REL_X`, `ABS_X`, …) |
//! | 20 | 4 | value, signed |
//!
//! On a 32-bit system the time is 8 bytes and the record 16; [`EVENT_LEN`] is the host's.
//! An evdev node returns whole records; a pipe may split them, so the source keeps the tail
//! of a read until the rest arrives.

use std::io;
use std::os::fd::{AsRawFd, RawFd};
use std::path::Path;

/// Bytes in one `struct input_event` on this host.
pub const EVENT_LEN: usize = std::mem::size_of::<nix::libc::input_event>();

/// Synchronisation: the end of one frame of events.
pub const EV_SYN: u16 = 0x00;
/// Keys and buttons.
pub const EV_KEY: u16 = 0x01;
/// Relative axes.
pub const EV_REL: u16 = 0x02;
/// Absolute axes.
pub const EV_ABS: u16 = 0x03;
/// Miscellaneous (scan codes).
pub const EV_MSC: u16 = 0x04;
/// LEDs.
pub const EV_LED: u16 = 0x11;

/// First mouse button (`BTN_LEFT`).
pub const BTN_MOUSE: u16 = 0x110;
/// Left mouse button.
pub const BTN_LEFT: u16 = 0x110;
/// Right mouse button.
pub const BTN_RIGHT: u16 = 0x111;
/// Middle mouse button.
pub const BTN_MIDDLE: u16 = 0x112;
/// First joystick button (`BTN_TRIGGER`).
pub const BTN_JOYSTICK: u16 = 0x120;
/// First gamepad button (`BTN_SOUTH`).
pub const BTN_GAMEPAD: u16 = 0x130;
/// Highest key or button code.
pub const KEY_MAX: u16 = 0x2ff;

/// Relative X.
pub const REL_X: u16 = 0x00;
/// Relative Y.
pub const REL_Y: u16 = 0x01;
/// The scroll wheel.
pub const REL_WHEEL: u16 = 0x08;
/// Highest relative axis code (C++ `REL_MAX`).
pub const REL_MAX: u16 = 0x0f;
/// Highest absolute axis code (C++ `ABS_MAX`).
pub const ABS_MAX: u16 = 0x3f;

/// One decoded event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputEvent {
    /// Event type.
    pub kind: u16,
    /// Event code.
    pub code: u16,
    /// Value.
    pub value: i32,
}

impl InputEvent {
    /// Decodes one record (host byte order, the host's layout).
    pub fn decode(b: &[u8]) -> Option<InputEvent> {
        if b.len() != EVENT_LEN {
            return None;
        }
        let t = EVENT_LEN - 8;
        Some(InputEvent {
            kind: u16::from_ne_bytes([b[t], b[t + 1]]),
            code: u16::from_ne_bytes([b[t + 2], b[t + 3]]),
            value: i32::from_ne_bytes([b[t + 4], b[t + 5], b[t + 6], b[t + 7]]),
        })
    }

    /// The record the kernel would write for this event at time `sec`.`usec`.
    pub fn encode(&self, sec: i64, usec: i64) -> [u8; EVENT_LEN] {
        let mut b = [0u8; EVENT_LEN];
        let half = (EVENT_LEN - 8) / 2;
        if half == 8 {
            b[..8].copy_from_slice(&sec.to_ne_bytes());
            b[8..16].copy_from_slice(&usec.to_ne_bytes());
        } else {
            b[..4].copy_from_slice(&(sec as i32).to_ne_bytes());
            b[4..8].copy_from_slice(&(usec as i32).to_ne_bytes());
        }
        let t = EVENT_LEN - 8;
        b[t..t + 2].copy_from_slice(&self.kind.to_ne_bytes());
        b[t + 2..t + 4].copy_from_slice(&self.code.to_ne_bytes());
        b[t + 4..].copy_from_slice(&self.value.to_ne_bytes());
        b
    }

    /// A synchronisation event (end of frame).
    pub const fn syn() -> InputEvent {
        InputEvent {
            kind: EV_SYN,
            code: 0,
            value: 0,
        }
    }
}

/// An open evdev node (or a pipe): whole records out of a byte stream.
#[derive(Debug)]
pub struct EventSource {
    file: std::fs::File,
    /// Bytes of a record a read split.
    partial: [u8; EVENT_LEN],
    have: usize,
}

impl EventSource {
    /// Opens `path` read-only and non-blocking.
    pub fn open(path: &Path) -> io::Result<EventSource> {
        use std::os::unix::fs::OpenOptionsExt;
        let file = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(nix::libc::O_NONBLOCK | nix::libc::O_CLOEXEC | nix::libc::O_NOCTTY)
            .open(path)?;
        Ok(EventSource {
            file,
            partial: [0; EVENT_LEN],
            have: 0,
        })
    }

    /// The descriptor to wait on.
    pub fn fd(&self) -> RawFd {
        self.file.as_raw_fd()
    }

    /// Reads what is waiting into `buf` (a multiple of [`EVENT_LEN`] long) and returns how
    /// many whole records it now starts with. `Ok(0)` with nothing kept means end of file
    /// (the pipe's writer left); `WouldBlock`, nothing waiting.
    pub fn read_records(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        debug_assert!(buf.len() >= 2 * EVENT_LEN && buf.len() % EVENT_LEN == 0);
        let keep = self.have;
        buf[..keep].copy_from_slice(&self.partial[..keep]);
        let n = nix::unistd::read(self.file.as_raw_fd(), &mut buf[keep..])
            .map_err(|e| io::Error::from_raw_os_error(e as i32))?;
        if n == 0 {
            self.have = 0;
            return Err(io::Error::new(io::ErrorKind::UnexpectedEof, "end of file"));
        }
        let total = keep + n;
        let whole = total / EVENT_LEN;
        self.have = total % EVENT_LEN;
        self.partial[..self.have].copy_from_slice(&buf[whole * EVENT_LEN..total]);
        Ok(whole)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn records_round_trip() {
        let e = InputEvent {
            kind: EV_REL,
            code: REL_WHEEL,
            value: -3,
        };
        let b = e.encode(5, 6);
        assert_eq!(InputEvent::decode(&b), Some(e));
        assert_eq!(InputEvent::decode(&b[1..]), None);
        assert_eq!(
            EVENT_LEN,
            if cfg!(target_pointer_width = "64") {
                24
            } else {
                16
            }
        );
    }

    #[test]
    fn a_pipe_split_anywhere_gives_whole_records() {
        let dir = crate::hid::fake::TempDir::new("evdev");
        let path = dir.path().join("event0");
        nix::unistd::mkfifo(&path, nix::sys::stat::Mode::from_bits_truncate(0o600)).unwrap();
        let mut src = EventSource::open(&path).unwrap();
        let mut w = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
        let mut bytes = Vec::new();
        for i in 0..3 {
            let e = InputEvent {
                kind: EV_KEY,
                code: BTN_LEFT,
                value: i,
            };
            bytes.extend_from_slice(&e.encode(0, 0));
        }
        let mut buf = [0u8; EVENT_LEN * 8];
        assert_eq!(
            src.read_records(&mut buf).unwrap_err().kind(),
            io::ErrorKind::WouldBlock
        );
        w.write_all(&bytes[..EVENT_LEN + 5]).unwrap();
        assert_eq!(src.read_records(&mut buf).unwrap(), 1);
        assert_eq!(InputEvent::decode(&buf[..EVENT_LEN]).unwrap().value, 0);
        w.write_all(&bytes[EVENT_LEN + 5..]).unwrap();
        assert_eq!(src.read_records(&mut buf).unwrap(), 2);
        assert_eq!(
            InputEvent::decode(&buf[EVENT_LEN..2 * EVENT_LEN])
                .unwrap()
                .value,
            2
        );
        drop(w);
        assert_eq!(
            src.read_records(&mut buf).unwrap_err().kind(),
            io::ErrorKind::UnexpectedEof
        );
    }
}
