//! Opening a device file the way the drivers need it: a serial line in raw mode at the
//! configured speed and framing (what C++ VRPN sets), or an input device read as it is; both
//! non-blocking, so a read returns what has arrived and never waits.

use std::io;
use std::os::fd::{AsRawFd, RawFd};

use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::sys::termios::{
    self, BaudRate, ControlFlags, InputFlags, SetArg, SpecialCharacterIndices,
};
use serialport::{ClearBuffer, SerialPort, TTYPort};

use super::driver::{Parity, PortKind, PortSettings};

/// An open port.
pub enum Port {
    /// A serial line (real, USB or pseudo-terminal).
    Serial(TTYPort),
    /// An input device (Linux joystick).
    Input(std::fs::File),
}

impl std::fmt::Debug for Port {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Port::Serial(_) => f.write_str("Port::Serial"),
            Port::Input(_) => f.write_str("Port::Input"),
        }
    }
}

fn baud_rate(baud: u32) -> io::Result<BaudRate> {
    Ok(match baud {
        300 => BaudRate::B300,
        1200 => BaudRate::B1200,
        2400 => BaudRate::B2400,
        4800 => BaudRate::B4800,
        9600 => BaudRate::B9600,
        19200 => BaudRate::B19200,
        38400 => BaudRate::B38400,
        57600 => BaudRate::B57600,
        115200 => BaudRate::B115200,
        _ => {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "unsupported baud rate {baud} (300, 1200, 2400, 4800, 9600, 19200, 38400, \
                     57600 or 115200)"
                ),
            ))
        }
    })
}

/// A `serialport` error as the `io::Error` it stands for (its kind kept: a missing file is
/// `NotFound`, a refused open `PermissionDenied`).
fn from_serialport(e: serialport::Error) -> io::Error {
    match e.kind() {
        serialport::ErrorKind::Io(kind) => io::Error::new(kind, e.description),
        serialport::ErrorKind::NoDevice => io::Error::other(format!(
            "{} (is another program using the port?)",
            e.description
        )),
        _ => io::Error::other(e.description),
    }
}

fn errno(e: nix::errno::Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

/// Puts the line in the state C++ VRPN's serial layer leaves it in: raw (no echo, no line
/// editing, no signals, no output processing, breaks and parity errors ignored), the given
/// speed and framing, the receiver on, modem lines ignored, RTS/CTS only when asked for.
///
/// One difference: C++ sets `VMIN = 0`, under which a read with nothing waiting returns 0 —
/// the same as a line that hung up. Here `VMIN = 1` with the descriptor non-blocking: a read
/// still never waits (nothing waiting is `EAGAIN`), and 0 then means the device is gone.
fn configure(fd: RawFd, s: &PortSettings) -> io::Result<()> {
    let mut t = termios::tcgetattr(fd).map_err(errno)?;
    let speed = baud_rate(s.baud)?;
    termios::cfsetispeed(&mut t, speed).map_err(errno)?;
    termios::cfsetospeed(&mut t, speed).map_err(errno)?;
    t.input_flags = InputFlags::IGNBRK | InputFlags::IGNPAR;
    t.output_flags = termios::OutputFlags::empty();
    t.local_flags = termios::LocalFlags::empty();
    let c = &mut t.control_flags;
    c.remove(ControlFlags::CSIZE);
    c.insert(if s.data_bits == 7 {
        ControlFlags::CS7
    } else {
        ControlFlags::CS8
    });
    c.set(ControlFlags::CSTOPB, s.stop_bits == 2);
    match s.parity {
        Parity::None => c.remove(ControlFlags::PARENB),
        Parity::Odd => c.insert(ControlFlags::PARENB | ControlFlags::PARODD),
        Parity::Even => {
            c.insert(ControlFlags::PARENB);
            c.remove(ControlFlags::PARODD);
        }
    }
    c.insert(ControlFlags::CREAD | ControlFlags::CLOCAL);
    c.set(ControlFlags::CRTSCTS, s.rts_cts);
    t.control_chars[SpecialCharacterIndices::VMIN as usize] = 1;
    t.control_chars[SpecialCharacterIndices::VTIME as usize] = 0;
    termios::tcsetattr(fd, SetArg::TCSANOW, &t).map_err(errno)
}

fn set_nonblocking(fd: RawFd) -> io::Result<()> {
    let flags = fcntl(fd, FcntlArg::F_GETFL).map_err(errno)?;
    let flags = OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK;
    fcntl(fd, FcntlArg::F_SETFL(flags)).map_err(errno)?;
    Ok(())
}

/// USB serial adapters (FTDI) hold received bytes for their latency timer, 16 ms by default,
/// before passing them on; 1 ms is what a first-byte timestamp needs. Best effort: the sysfs
/// file exists only for such adapters and may not be writable.
fn lower_usb_latency(path: &str) {
    let Some(name) = std::path::Path::new(path)
        .canonicalize()
        .ok()
        .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
    else {
        return;
    };
    let timer = format!("/sys/bus/usb-serial/devices/{name}/latency_timer");
    if std::path::Path::new(&timer).exists() {
        let _ = std::fs::write(timer, b"1");
    }
}

impl Port {
    /// Opens `path` as `kind` asks, non-blocking.
    pub fn open(path: &str, kind: PortKind) -> io::Result<Port> {
        match kind {
            PortKind::Serial(settings) => {
                let tty = serialport::new(path, settings.baud)
                    .open_native()
                    .map_err(from_serialport)?;
                let fd = tty.as_raw_fd();
                configure(fd, &settings)?;
                set_nonblocking(fd)?;
                lower_usb_latency(path);
                Ok(Port::Serial(tty))
            }
            PortKind::InputDevice => {
                use std::os::unix::fs::OpenOptionsExt;
                // O_NOCTTY: a terminal standing in for the device (a pseudo-terminal in
                // tests) must not become the server's controlling terminal, whose hang-up
                // would kill it.
                let file = std::fs::OpenOptions::new()
                    .read(true)
                    .custom_flags(nix::libc::O_NONBLOCK | nix::libc::O_NOCTTY)
                    .open(path)?;
                Ok(Port::Input(file))
            }
        }
    }

    /// The file descriptor (to wait on it in a poll).
    pub fn fd(&self) -> RawFd {
        match self {
            Port::Serial(t) => t.as_raw_fd(),
            Port::Input(f) => f.as_raw_fd(),
        }
    }

    /// Reads what has arrived. `Ok(0)` means the far end closed (a pseudo-terminal whose
    /// master went away, an unplugged device); `WouldBlock`, that nothing is there yet.
    pub fn read(&self, buf: &mut [u8]) -> io::Result<usize> {
        nix::unistd::read(self.fd(), buf).map_err(errno)
    }

    /// Writes what the line takes now; returns how many bytes that was.
    pub fn write(&self, bytes: &[u8]) -> io::Result<usize> {
        match self {
            Port::Serial(_) => nix::unistd::write(self.fd(), bytes).map_err(errno),
            Port::Input(_) => Ok(bytes.len()),
        }
    }

    /// Discards received, unread input.
    pub fn flush_input(&self) -> io::Result<()> {
        match self {
            Port::Serial(t) => t.clear(ClearBuffer::Input).map_err(from_serialport),
            Port::Input(_) => Ok(()),
        }
    }

    /// Discards written, unsent output.
    pub fn flush_output(&self) -> io::Result<()> {
        match self {
            Port::Serial(t) => t.clear(ClearBuffer::Output).map_err(from_serialport),
            Port::Input(_) => Ok(()),
        }
    }

    /// Sets RTS. On a pseudo-terminal the modem-line calls fail (ENOTTY): not an error here.
    pub fn set_rts(&mut self, on: bool) {
        if let Port::Serial(t) = self {
            let _ = t.write_request_to_send(on);
        }
    }

    /// Changes the line's speed, both directions, at once (`tcsetattr(TCSANOW)`); the framing
    /// and raw mode stay as opened.
    pub fn set_baud(&mut self, baud: u32) -> io::Result<()> {
        let Port::Serial(_) = self else {
            return Ok(());
        };
        let fd = self.fd();
        let speed = baud_rate(baud)?;
        let mut t = termios::tcgetattr(fd).map_err(errno)?;
        termios::cfsetispeed(&mut t, speed).map_err(errno)?;
        termios::cfsetospeed(&mut t, speed).map_err(errno)?;
        termios::tcsetattr(fd, SetArg::TCSANOW, &t).map_err(errno)
    }

    /// Sets DTR (best effort, as [`set_rts`](Self::set_rts)).
    pub fn set_dtr(&mut self, on: bool) {
        if let Port::Serial(t) = self {
            let _ = t.write_data_terminal_ready(on);
        }
    }
}
