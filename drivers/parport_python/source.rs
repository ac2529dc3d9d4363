//! Where the parallel port's status register is read: [`StatusSource`], with the Linux
//! `ppdev` implementation ([`Ppdev`]: `/dev/parportN`, ioctls, no port I/O privileges).
//! Tests stand in with a fake (`sim::FakeParport`).
//!
//! The ioctls are the only `unsafe` code of the driver; each call says why it is sound.
#![allow(unsafe_code)]

use std::io;
use std::os::fd::AsRawFd;

/// A parallel port whose status register can be read.
pub trait StatusSource {
    /// Opens the port and claims it.
    fn open(&mut self) -> io::Result<()>;
    /// Reads the status register (bits 3-7: ERROR, SELECT, PAPER-OUT, ACK, BUSY).
    fn read_status(&mut self) -> io::Result<u8>;
    /// Releases the port and closes it.
    fn close(&mut self);
    /// The port's path, for messages.
    fn path(&self) -> &str;
}

mod ioctls {
    // From <linux/ppdev.h>.
    nix::ioctl_none!(claim, b'p', 0x8b);
    nix::ioctl_none!(release, b'p', 0x8c);
    nix::ioctl_read!(read_status, b'p', 0x81, u8);
    nix::ioctl_write_ptr!(write_data, b'p', 0x86, u8);
}

/// The value written to the data register after claiming the port: bits 0 and 1 high, which
/// powers the UNC button box on some ports (C++ writes it on Windows; on Linux it could not).
pub const POWER_DATA: u8 = 3;

fn errno(e: nix::errno::Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

/// A parallel port through the Linux `ppdev` driver: opened read-write, claimed (`PPCLAIM`),
/// the data register set to [`POWER_DATA`] (`PPWDATA`), the status register read with
/// `PPRSTATUS`, released (`PPRELEASE`) when closed.
///
/// Not exercised against real hardware: the tests use a fake port.
#[derive(Debug)]
pub struct Ppdev {
    path: String,
    file: Option<std::fs::File>,
}

impl Ppdev {
    /// The port at `path` (`/dev/parport0` …), not opened yet.
    pub fn new(path: &str) -> Ppdev {
        Ppdev {
            path: path.to_owned(),
            file: None,
        }
    }
}

impl StatusSource for Ppdev {
    fn open(&mut self) -> io::Result<()> {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&self.path)?;
        let fd = file.as_raw_fd();
        // SAFETY: `fd` is an open descriptor for the whole call; PPCLAIM takes no argument.
        unsafe { ioctls::claim(fd) }.map_err(errno)?;
        // SAFETY: as above; PPWDATA reads one byte from the pointer, which lives on the stack
        // for the call.
        unsafe { ioctls::write_data(fd, &POWER_DATA) }.map_err(errno)?;
        self.file = Some(file);
        Ok(())
    }

    fn read_status(&mut self) -> io::Result<u8> {
        let Some(file) = &self.file else {
            return Err(io::Error::new(io::ErrorKind::NotConnected, "not open"));
        };
        let mut status = 0u8;
        // SAFETY: the descriptor is open; PPRSTATUS writes one byte to `status`.
        unsafe { ioctls::read_status(file.as_raw_fd(), &mut status) }.map_err(errno)?;
        Ok(status)
    }

    fn close(&mut self) {
        if let Some(file) = self.file.take() {
            // SAFETY: the descriptor is open until `file` drops below; failure is harmless.
            let _ = unsafe { ioctls::release(file.as_raw_fd()) };
        }
    }

    fn path(&self) -> &str {
        &self.path
    }
}

impl Drop for Ppdev {
    fn drop(&mut self) {
        self.close();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_port_is_an_error_naming_it_and_nothing_is_claimed() {
        let mut p = Ppdev::new("/nonexistent/parport9");
        let e = p.open().unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::NotFound);
        assert_eq!(
            p.read_status().unwrap_err().kind(),
            io::ErrorKind::NotConnected
        );
        p.close();
    }

    #[test]
    fn a_file_that_is_no_parallel_port_refuses_the_claim() {
        // /dev/null opens read-write but does not know the ppdev ioctls.
        let mut p = Ppdev::new("/dev/null");
        let e = p.open().unwrap_err();
        assert_eq!(e.raw_os_error(), Some(nix::libc::ENOTTY));
    }
}
