//! The interface between a device driver (sans-IO) and the serial layer that owns its port.

use std::time::Instant;

use crate::time::Now;

/// Parity of a serial line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parity {
    /// No parity bit.
    None,
    /// Odd parity.
    Odd,
    /// Even parity.
    Even,
}

/// How a serial port is configured when opened (raw mode always).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PortSettings {
    /// Bits per second: 300, 1200, 2400, 4800, 9600, 19200, 38400, 57600 or 115200.
    pub baud: u32,
    /// 7 or 8.
    pub data_bits: u8,
    /// Parity.
    pub parity: Parity,
    /// 1 or 2.
    pub stop_bits: u8,
    /// Hardware (RTS/CTS) flow control.
    pub rts_cts: bool,
}

impl PortSettings {
    /// 8 data bits, no parity, 1 stop bit, no flow control: what every supported device uses.
    pub const fn n81(baud: u32) -> PortSettings {
        PortSettings {
            baud,
            data_bits: 8,
            parity: Parity::None,
            stop_bits: 1,
            rts_cts: false,
        }
    }
}

/// What kind of file a driver reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PortKind {
    /// A serial line, configured with termios.
    Serial(PortSettings),
    /// A character device read as it is, without termios (the Linux joystick `/dev/input/js*`).
    /// Opened read-only.
    InputDevice,
}

/// One request a driver makes of its port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PortOp {
    /// Write the bytes at `start..start + len` of [`PortOps::bytes`].
    Write {
        /// Offset in the byte buffer.
        start: usize,
        /// Number of bytes.
        len: usize,
    },
    /// Discard everything received but not yet read (`tcflush(TCIFLUSH)`).
    FlushInput,
    /// Discard everything written but not yet sent (`tcflush(TCOFLUSH)`).
    FlushOutput,
    /// Raise (true) or drop (false) RTS. Fails harmlessly on a pseudo-terminal.
    SetRts(bool),
    /// Raise (true) or drop (false) DTR. Fails harmlessly on a pseudo-terminal.
    SetDtr(bool),
    /// Close the port and open it again (the driver's [`SerialDriver::opened`] runs again).
    Reopen,
    /// Change the line's speed (both directions) on the open port, at once: for a device told
    /// to switch its own rate (NDI Polaris `COMM`). Ask for it when nothing is being sent.
    SetBaud(u32),
}

/// The requests a driver makes during one call, carried out in order by the serial layer right
/// after the call returns. Reused between calls: no allocation once warmed up.
#[derive(Debug, Default)]
pub struct PortOps {
    ops: Vec<PortOp>,
    bytes: Vec<u8>,
}

impl PortOps {
    /// An empty request list.
    pub fn new() -> PortOps {
        PortOps {
            ops: Vec::with_capacity(16),
            bytes: Vec::with_capacity(256),
        }
    }

    /// Writes `bytes` to the port.
    pub fn write(&mut self, bytes: &[u8]) {
        let start = self.bytes.len();
        self.bytes.extend_from_slice(bytes);
        self.ops.push(PortOp::Write {
            start,
            len: bytes.len(),
        });
    }

    /// Discards received, unread input.
    pub fn flush_input(&mut self) {
        self.ops.push(PortOp::FlushInput);
    }

    /// Discards written, unsent output.
    pub fn flush_output(&mut self) {
        self.ops.push(PortOp::FlushOutput);
    }

    /// Sets the RTS line.
    pub fn set_rts(&mut self, on: bool) {
        self.ops.push(PortOp::SetRts(on));
    }

    /// Sets the DTR line.
    pub fn set_dtr(&mut self, on: bool) {
        self.ops.push(PortOp::SetDtr(on));
    }

    /// Closes and reopens the port.
    pub fn reopen(&mut self) {
        self.ops.push(PortOp::Reopen);
    }

    /// Changes the line's speed on the open port (see [`PortOp::SetBaud`]).
    pub fn set_baud(&mut self, baud: u32) {
        self.ops.push(PortOp::SetBaud(baud));
    }

    /// The requests, in order.
    pub fn ops(&self) -> &[PortOp] {
        &self.ops
    }

    /// The bytes [`PortOp::Write`] refers to.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The bytes of one write request.
    pub fn write_bytes(&self, start: usize, len: usize) -> &[u8] {
        &self.bytes[start..start + len]
    }

    /// True when nothing was requested.
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// Forgets every request (after they were carried out). Keeps the capacity.
    pub fn clear(&mut self) {
        self.ops.clear();
        self.bytes.clear();
    }
}

/// A device driver, free of I/O and of clocks.
///
/// The serial layer opens the port with [`port_kind`](Self::port_kind), calls
/// [`opened`](Self::opened), then feeds every byte read to [`received`](Self::received) and calls
/// [`poll`](Self::poll) whenever [`next_deadline`](Self::next_deadline) passes. Reset sequences
/// with delays are state machines over deadlines: a driver never sleeps and never blocks.
///
/// Drivers own the device servers they report through (a
/// [`TrackerServer`](crate::TrackerServer), [`ButtonServer`](crate::ButtonServer), …) and send
/// their reports and VRPN text warnings from inside these calls.
pub trait SerialDriver {
    /// The device's name (its VRPN sender), for messages.
    fn name(&self) -> &str;

    /// How to open the port.
    fn port_kind(&self) -> PortKind;

    /// The port was opened, at start and after every reopen: begin the reset sequence.
    fn opened(&mut self, now: Now, port: &mut PortOps);

    /// Bytes arrived. `arrived` is when the first of them came, as well as the serial layer
    /// can tell: the time the poll woke for them, or, for bytes that came after that wake and
    /// before a late read, the time of that read. Any record whose first byte is in `bytes`
    /// carries this time, even if it completes in a later call.
    /// Parse byte by byte: `bytes` may hold part of a record, several records, or garbage.
    fn received(&mut self, bytes: &[u8], arrived: Now, port: &mut PortOps);

    /// Time-driven work: the next step of a reset sequence, the watchdog. Called at or after
    /// [`next_deadline`](Self::next_deadline) (and possibly earlier: check the time).
    fn poll(&mut self, now: Now, port: &mut PortOps);

    /// When [`poll`](Self::poll) is next needed, if ever.
    fn next_deadline(&self) -> Option<Instant>;

    /// The port failed or vanished (unplugged device, closed pty). The serial layer reports it
    /// as a VRPN text error and reopens the port when it can; [`opened`](Self::opened) follows.
    fn closed(&mut self, now: Now);
}
