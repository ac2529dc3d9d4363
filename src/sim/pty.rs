//! A device simulator on a pseudo-terminal: a [`DeviceModel`] on the master end, the driver
//! (through the serial layer, as for real hardware) on the slave end.
//!
//! A test and simulation tool. It never blocks and never sleeps: the caller runs
//! [`PtyDevice::step`] from its own loop (a test thread, or the `DEVICE_SIM` mode of
//! `benches/first_byte.rs`), waiting on [`PtyDevice::master_fd`] and
//! [`PtyDevice::next_deadline`] in between. The device can be unplugged and plugged back under
//! the same path (a symbolic link that is pointed at a fresh pseudo-terminal), which is how the
//! tests check that a server reopens a port that vanished.

use std::io;
use std::os::fd::{AsRawFd, RawFd};
use std::path::{Path, PathBuf};
use std::time::Instant;

use std::os::unix::fs::OpenOptionsExt;

use nix::fcntl::OFlag;
use nix::pty::{grantpt, posix_openpt, ptsname_r, unlockpt, PtyMaster};
use nix::sys::termios;

use super::line::DeviceModel;
use crate::time::Now;

fn errno(e: nix::errno::Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

struct Pty {
    master: PtyMaster,
    /// Kept open so the master never reads EIO while no driver has the slave open.
    _slave: std::fs::File,
    slave_path: PathBuf,
}

fn open_pty() -> io::Result<Pty> {
    // Both ends are opened close-on-exec in the same call that makes them, so a program a
    // test starts meanwhile (a server, perhaps for another test on another thread) never
    // inherits a copy: a copy of the master would keep the line up after an unplug, and the
    // server would never see it go.
    let master =
        posix_openpt(OFlag::O_RDWR | OFlag::O_NOCTTY | OFlag::O_CLOEXEC | OFlag::O_NONBLOCK)
            .map_err(errno)?;
    grantpt(&master).map_err(errno)?;
    unlockpt(&master).map_err(errno)?;
    let slave_path = PathBuf::from(ptsname_r(&master).map_err(errno)?);
    // std opens files close-on-exec.
    let slave = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(nix::libc::O_NOCTTY)
        .open(&slave_path)?;
    // The slave starts in raw mode, so nothing the simulator writes is changed before a
    // driver opens it (the serial layer sets raw mode again when it does).
    let mut mode = termios::tcgetattr(slave.as_raw_fd()).map_err(errno)?;
    termios::cfmakeraw(&mut mode);
    termios::tcsetattr(slave.as_raw_fd(), termios::SetArg::TCSANOW, &mode).map_err(errno)?;
    Ok(Pty {
        master,
        _slave: slave,
        slave_path,
    })
}

/// The speed set on the slave end (which the driver configures), in bits per second, for
/// the standard rates.
fn line_speed(pty: &Pty) -> Option<u32> {
    use termios::BaudRate as B;
    let mode = termios::tcgetattr(pty._slave.as_raw_fd()).ok()?;
    // nix's cfgetospeed panics on a speed code it has no name for (a line in the middle of
    // being closed or reconfigured can show one): such a speed is simply not a standard rate.
    let speed =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| termios::cfgetospeed(&mode)))
            .ok()?;
    Some(match speed {
        B::B300 => 300,
        B::B1200 => 1200,
        B::B2400 => 2400,
        B::B4800 => 4800,
        B::B9600 => 9600,
        B::B19200 => 19200,
        B::B38400 => 38400,
        B::B57600 => 57600,
        B::B115200 => 115200,
        _ => return None,
    })
}

/// One write to the line: when, where in the stream, how many bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Written {
    /// The `now` of the [`PtyDevice::step`] that wrote (read by the caller just before).
    pub at: Now,
    /// Offset of its first byte in everything the device has written.
    pub offset: u64,
    /// Bytes written.
    pub len: usize,
}

/// A device model on a pseudo-terminal. See the module documentation.
pub struct PtyDevice<M: DeviceModel> {
    /// The simulated device.
    pub model: M,
    pty: Option<Pty>,
    link: PathBuf,
    out: Vec<u8>,
    buf: Vec<u8>,
    /// Every write, in order (for first-byte timing).
    pub writes: Vec<Written>,
    written: u64,
    /// Keep the write log (off by default; on for timing measurements).
    pub log_writes: bool,
    /// The line speed the driver last set on its end, as last told to the model.
    baud: Option<u32>,
}

impl<M: DeviceModel> PtyDevice<M> {
    /// Plugs `model` in: a new pseudo-terminal whose slave is reachable at `link` (a symbolic
    /// link this call creates, replacing any file there).
    pub fn open(model: M, link: &Path) -> io::Result<PtyDevice<M>> {
        let mut d = PtyDevice {
            model,
            pty: None,
            link: link.to_path_buf(),
            out: Vec::with_capacity(4096),
            buf: vec![0; 4096],
            writes: Vec::new(),
            written: 0,
            log_writes: false,
            baud: None,
        };
        d.plug()?;
        Ok(d)
    }

    /// The path a driver opens.
    pub fn path(&self) -> &Path {
        &self.link
    }

    /// True while plugged in.
    pub fn is_plugged(&self) -> bool {
        self.pty.is_some()
    }

    /// The master side's descriptor, to wait for what the driver writes (`None` unplugged).
    pub fn master_fd(&self) -> Option<RawFd> {
        self.pty.as_ref().map(|p| p.master.as_raw_fd())
    }

    /// Unplugs the device: the driver's reads fail (EIO) and the path disappears.
    pub fn unplug(&mut self) {
        self.pty = None;
        let _ = std::fs::remove_file(&self.link);
    }

    /// Plugs the device back in (a new pseudo-terminal under the same path).
    pub fn plug(&mut self) -> io::Result<()> {
        let pty = open_pty()?;
        let _ = std::fs::remove_file(&self.link);
        std::os::unix::fs::symlink(&pty.slave_path, &self.link)?;
        self.baud = line_speed(&pty);
        self.pty = Some(pty);
        Ok(())
    }

    /// When the model next has something to send by itself.
    pub fn next_deadline(&self) -> Option<Instant> {
        self.model.next_deadline()
    }

    /// Hands the model what the driver wrote, and writes what the model sends at `now`.
    /// Returns whether anything moved.
    pub fn step(&mut self, now: Now) -> io::Result<bool> {
        let Some(pty) = self.pty.as_ref() else {
            return Ok(false);
        };
        let fd = pty.master.as_raw_fd();
        let mut moved = false;
        // A speed the driver set since the last step applies to the bytes read now (a driver
        // that switches rates waits for the line to be idle before it does).
        let speed = line_speed(pty);
        if speed.is_some() && speed != self.baud {
            self.baud = speed;
            if let Some(b) = speed {
                self.model.set_baud(b, now);
            }
        }
        loop {
            match nix::unistd::read(fd, &mut self.buf) {
                Ok(0) => break,
                Ok(n) => {
                    moved = true;
                    self.model.receive(&self.buf[..n], now);
                }
                Err(nix::errno::Errno::EAGAIN) => break,
                // No slave open on the other end: nothing to read.
                Err(nix::errno::Errno::EIO) => break,
                Err(e) => return Err(errno(e)),
            }
        }
        self.out.clear();
        self.model.transmit(now, &mut self.out);
        let mut sent = 0;
        while sent < self.out.len() {
            match nix::unistd::write(fd, &self.out[sent..]) {
                Ok(n) => {
                    if self.log_writes {
                        self.writes.push(Written {
                            at: now,
                            offset: self.written,
                            len: n,
                        });
                    }
                    self.written += n as u64;
                    sent += n;
                    moved = true;
                }
                // The line is full (nobody reads the slave): the device's output is lost, as
                // a real device's would be.
                Err(nix::errno::Errno::EAGAIN) => break,
                Err(e) => return Err(errno(e)),
            }
        }
        Ok(moved)
    }

    /// The time a byte at stream `offset` was written (from the write log).
    pub fn write_time(&self, offset: u64) -> Option<Now> {
        let i = self
            .writes
            .partition_point(|w| w.offset + w.len as u64 <= offset);
        self.writes
            .get(i)
            .filter(|w| w.offset <= offset)
            .map(|w| w.at)
    }
}

impl<M: DeviceModel> Drop for PtyDevice<M> {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.link);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nix::fcntl::{fcntl, FcntlArg, FdFlag};

    #[test]
    fn both_ends_are_close_on_exec_and_the_master_never_blocks() {
        let pty = open_pty().unwrap();
        for fd in [pty.master.as_raw_fd(), pty._slave.as_raw_fd()] {
            let flags = FdFlag::from_bits_truncate(fcntl(fd, FcntlArg::F_GETFD).unwrap());
            assert!(flags.contains(FdFlag::FD_CLOEXEC), "fd {fd}: {flags:?}");
        }
        let fl =
            OFlag::from_bits_truncate(fcntl(pty.master.as_raw_fd(), FcntlArg::F_GETFL).unwrap());
        assert!(fl.contains(OFlag::O_NONBLOCK));
        // A byte written on the slave reaches the master unchanged (raw mode).
        nix::unistd::write(pty._slave.as_raw_fd(), b"\r\n\x03").unwrap();
        let mut buf = [0u8; 8];
        let mut got = Vec::new();
        for _ in 0..100 {
            match nix::unistd::read(pty.master.as_raw_fd(), &mut buf) {
                Ok(n) => got.extend_from_slice(&buf[..n]),
                Err(nix::errno::Errno::EAGAIN) => {}
                Err(e) => panic!("{e}"),
            }
            if got.len() >= 3 {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        assert_eq!(got, b"\r\n\x03");
    }

    /// Keeps the speeds it is told.
    struct Speeds(Vec<u32>);

    impl DeviceModel for Speeds {
        fn receive(&mut self, _bytes: &[u8], _now: Now) {}
        fn set_baud(&mut self, baud: u32, _now: Now) {
            self.0.push(baud);
        }
        fn transmit(&mut self, _now: Now, _out: &mut Vec<u8>) {}
        fn next_deadline(&self) -> Option<Instant> {
            None
        }
    }

    #[test]
    fn the_model_hears_of_the_speeds_the_driver_sets() {
        let dir = std::env::temp_dir().join(format!("vrpn-pty-speed-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let link = dir.join("tty");
        let mut d = PtyDevice::open(Speeds(Vec::new()), &link).unwrap();
        let kind = |baud| crate::serial::PortKind::Serial(crate::serial::PortSettings::n81(baud));
        let mut port = crate::serial::Port::open(link.to_str().unwrap(), kind(9600)).unwrap();
        d.step(Now::read()).unwrap();
        port.set_baud(115200).unwrap();
        d.step(Now::read()).unwrap();
        d.step(Now::read()).unwrap();
        assert_eq!(d.model.0, [9600, 115200]);
        drop(d);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
