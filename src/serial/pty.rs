//! A device simulator on a pseudo-terminal: a [`DeviceModel`] on the master end, the driver
//! (through the serial layer, as for real hardware) on the slave end.
//!
//! A test and simulation tool. It never blocks and never sleeps: the caller runs
//! [`PtyDevice::step`] from its own loop (a test thread, the `vrpn_device_sim` program),
//! waiting on [`PtyDevice::master_fd`] and [`PtyDevice::next_deadline`] in between. The
//! device can be unplugged and plugged back under the same path (a symbolic link that is
//! pointed at a fresh pseudo-terminal), which is how the tests check that a server reopens a
//! port that vanished.

use std::io;
use std::os::fd::{AsRawFd, RawFd};
use std::path::{Path, PathBuf};
use std::time::Instant;

use nix::fcntl::{fcntl, FcntlArg, FdFlag, OFlag};
use serialport::{SerialPort, TTYPort};

use super::testing::DeviceModel;
use crate::time::Now;

fn errno(e: nix::errno::Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

struct Pty {
    master: TTYPort,
    /// Kept open so the master never reads EIO while no driver has the slave open.
    _slave: TTYPort,
    slave_path: PathBuf,
}

fn open_pty() -> io::Result<Pty> {
    // The slave starts in raw mode, so nothing the simulator writes is changed before a
    // driver opens it (the serial layer sets raw mode again when it does).
    let (master, slave) = TTYPort::pair().map_err(|e| io::Error::other(e.description))?;
    let slave_path = slave
        .name()
        .map(PathBuf::from)
        .ok_or_else(|| io::Error::other("the pseudo-terminal has no name"))?;
    // Close-on-exec, so a child process started meanwhile (a server under test) does not
    // keep the master open: unplugging must hang up the driver's end.
    for fd in [master.as_raw_fd(), slave.as_raw_fd()] {
        fcntl(fd, FcntlArg::F_SETFD(FdFlag::FD_CLOEXEC)).map_err(errno)?;
    }
    let fd = master.as_raw_fd();
    let flags = fcntl(fd, FcntlArg::F_GETFL).map_err(errno)?;
    fcntl(
        fd,
        FcntlArg::F_SETFL(OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK),
    )
    .map_err(errno)?;
    Ok(Pty {
        master,
        _slave: slave,
        slave_path,
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
