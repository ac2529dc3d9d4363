//! Zaber's binary protocol: six-byte commands and replies, `[device, command, data LE i32]`,
//! and finding replies byte by byte.
//!
//! The [`Framer`] takes six bytes as a reply when the device number is one of the chain's and
//! the command is one the driver knows ([`Command::of`]); otherwise it gives up one byte and
//! tries again from the next, so garbage costs no reply after it. Each buffered byte keeps the
//! arrival time of its read.

use crate::time::Now;

/// Length of every command and reply.
pub const LEN: usize = 6;

/// Renumber the chain (sent to device 0, every device answers with its new number).
pub const RENUMBER: u8 = 2;
/// Return the current position.
pub const POSITION: u8 = 23;
/// Move to an absolute position (answered with the position reached).
pub const MOVE_ABSOLUTE: u8 = 20;
/// Set the device mode (C++ sets 16).
pub const SET_MODE: u8 = 40;
/// Set the target speed (C++ sets 128).
pub const SET_SPEED: u8 = 41;
/// Set the acceleration (C++ sets 128).
pub const SET_ACCELERATION: u8 = 42;
/// Home (answered with the position, 0).
pub const HOME: u8 = 1;
/// Manual move tracking (the knob turned: the position now).
pub const MANUAL_MOVE: u8 = 10;
/// An error reply (data: the error code).
pub const ERROR: u8 = 255;

/// A command's six bytes.
pub fn command(device: u8, cmd: u8, data: i32) -> [u8; LEN] {
    let d = data.to_le_bytes();
    [device, cmd, d[0], d[1], d[2], d[3]]
}

/// What a reply means to the driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// A position (home, manual move, move done, position query).
    Position,
    /// An error code.
    Error,
    /// An answer to a set-up command: nothing to report.
    SetUp,
}

impl Command {
    /// What command byte `c` is, if the driver knows it.
    pub fn of(c: u8) -> Option<Command> {
        match c {
            HOME | MANUAL_MOVE | MOVE_ABSOLUTE | POSITION => Some(Command::Position),
            ERROR => Some(Command::Error),
            RENUMBER | SET_MODE | SET_SPEED | SET_ACCELERATION => Some(Command::SetUp),
            _ => None,
        }
    }
}

/// A reply found in the stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reply {
    /// The device (1..).
    pub device: u8,
    /// Its command byte.
    pub command: u8,
    /// Its data.
    pub data: i32,
    /// When the read holding its first byte arrived.
    pub first_byte: Now,
}

impl Reply {
    /// Decodes six bytes.
    pub fn decode(b: &[u8], first_byte: Now) -> Reply {
        Reply {
            device: b[0],
            command: b[1],
            data: i32::from_le_bytes([b[2], b[3], b[4], b[5]]),
            first_byte,
        }
    }
}

/// Finds replies of a chain of `devices` devices. See the module documentation.
#[derive(Clone, Debug)]
pub struct Framer {
    devices: u8,
    buf: [u8; LEN],
    times: [Option<Now>; LEN],
    len: usize,
    skipped: u64,
}

impl Framer {
    /// A framer for a chain of `devices` devices.
    pub fn new(devices: u8) -> Framer {
        Framer {
            devices,
            buf: [0; LEN],
            times: [None; LEN],
            len: 0,
            skipped: 0,
        }
    }

    /// Forgets a partial reply and sets the chain's length.
    pub fn reset(&mut self, devices: u8) {
        self.devices = devices;
        self.len = 0;
    }

    /// Bytes skipped since the last call (and forgets them).
    pub fn take_skipped(&mut self) -> u64 {
        std::mem::take(&mut self.skipped)
    }

    fn plausible(&self, i: usize) -> bool {
        let ok_device = |d: u8| d >= 1 && d <= self.devices;
        match self.len - i {
            0 => true,
            1 => ok_device(self.buf[i]),
            _ => ok_device(self.buf[i]) && Command::of(self.buf[i + 1]).is_some(),
        }
    }

    /// Takes one byte that arrived at `arrived`; returns a reply when it completes one.
    pub fn push(&mut self, b: u8, arrived: Now) -> Option<Reply> {
        self.buf[self.len] = b;
        self.times[self.len] = Some(arrived);
        self.len += 1;
        // Drop bytes from the front until what is buffered may start a reply.
        let start = (0..=self.len)
            .find(|&i| self.plausible(i))
            .unwrap_or(self.len);
        if start > 0 {
            self.skipped += start as u64;
            self.buf.copy_within(start..self.len, 0);
            self.times.copy_within(start..self.len, 0);
            self.len -= start;
        }
        if self.len < LEN {
            return None;
        }
        self.len = 0;
        Some(Reply::decode(&self.buf, self.times[0].unwrap_or(arrived)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::TimeVal;
    use std::time::{Duration, Instant};

    fn at(ms: u64, base: Instant) -> Now {
        Now {
            mono: base + Duration::from_millis(ms),
            wall: TimeVal::new(100, 0).plus(Duration::from_millis(ms)),
        }
    }

    #[test]
    fn commands_are_little_endian() {
        assert_eq!(command(2, 20, -2), [2, 20, 0xFE, 0xFF, 0xFF, 0xFF]);
        assert_eq!(command(0, 2, 0), [0, 2, 0, 0, 0, 0]);
    }

    #[test]
    fn replies_after_garbage_keep_their_first_byte_time() {
        let base = Instant::now();
        let mut f = Framer::new(2);
        let r1 = command(2, 20, 123_456);
        let r2 = command(1, 255, 21);
        let mut got = Vec::new();
        for (i, chunk) in [&[9u8, 1, 99, 0][..], &r1[..3], &r1[3..], &r2]
            .iter()
            .enumerate()
        {
            for &b in chunk.iter() {
                got.extend(f.push(b, at(i as u64, base)));
            }
        }
        assert_eq!(got.len(), 2);
        assert_eq!(
            (got[0].device, got[0].command, got[0].data),
            (2, 20, 123_456)
        );
        assert_eq!(got[0].first_byte, at(1, base));
        assert_eq!((got[1].device, got[1].command, got[1].data), (1, 255, 21));
        assert_eq!(f.take_skipped(), 4);
    }
}
