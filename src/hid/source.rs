//! Where a HID device's reports come from: a hidraw node, or a stand-in that behaves like one.
//!
//! A hidraw node hands over exactly one report per `read` (with the report id first when the
//! device numbers its reports), takes an output report per `write`, and feature reports
//! through ioctls. The stand-in is a pair of `SOCK_SEQPACKET` Unix sockets, which keep message
//! boundaries the same way, so a device simulator can sit behind a fake device tree
//! (its side is `fake::DeviceEnd`, with the `sim` feature):
//!
//! - the *data* socket carries input reports from the device (one datagram per report, the
//!   bytes hidraw would return) and output reports to it (one datagram per `write`);
//! - the *control* socket carries feature reports: `S` followed by the report (set feature),
//!   `G`, the report id and the length as a little-endian `u16` (get feature), answered by
//!   one datagram with the report.
//!
//! When a node's path is a listening Unix socket, [`ReportSource::open`] connects to it twice:
//! first the data socket, then the control socket. Tests can also hand over the ends of two
//! `socketpair`s directly ([`ReportSource::from_sockets`]).

use std::io;
use std::os::fd::{AsRawFd, OwnedFd, RawFd};
use std::os::unix::fs::FileTypeExt;
use std::path::Path;
use std::time::Duration;

use nix::sys::socket::{
    connect, recv, send, socket, AddressFamily, MsgFlags, SockFlag, SockType, UnixAddr,
};

use super::ioctl;

/// How long a stand-in device has to answer a get-feature request (a real one is bounded by
/// the kernel's USB control timeout, 5 s; simulators answer at once).
pub const FEATURE_TIMEOUT: Duration = Duration::from_millis(500);

fn errno(e: nix::errno::Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

/// An open HID device: see the module documentation.
#[derive(Debug)]
pub enum ReportSource {
    /// A hidraw character device.
    Hidraw(std::fs::File),
    /// A simulator's pair of sequenced-packet sockets.
    Sockets {
        /// Input and output reports.
        data: OwnedFd,
        /// Feature reports.
        control: OwnedFd,
    },
}

fn connect_seqpacket(path: &Path) -> io::Result<OwnedFd> {
    let fd = socket(
        AddressFamily::Unix,
        SockType::SeqPacket,
        SockFlag::SOCK_CLOEXEC,
        None,
    )
    .map_err(errno)?;
    let fd = ioctl::own_fd(fd);
    connect(fd.as_raw_fd(), &UnixAddr::new(path).map_err(errno)?).map_err(errno)?;
    Ok(fd)
}

fn set_nonblocking(fd: RawFd) -> io::Result<()> {
    use nix::fcntl::{fcntl, FcntlArg, OFlag};
    let flags = OFlag::from_bits_truncate(fcntl(fd, FcntlArg::F_GETFL).map_err(errno)?);
    fcntl(fd, FcntlArg::F_SETFL(flags | OFlag::O_NONBLOCK)).map_err(errno)?;
    Ok(())
}

impl ReportSource {
    /// Opens the node at `path`, non-blocking: a hidraw device read-write, or a listening
    /// simulator socket (connected twice, see the module documentation).
    pub fn open(path: &Path) -> io::Result<ReportSource> {
        let meta = std::fs::metadata(path)?;
        if meta.file_type().is_socket() {
            let data = connect_seqpacket(path)?;
            let control = connect_seqpacket(path)?;
            return Self::from_sockets(data, control);
        }
        use std::os::unix::fs::OpenOptionsExt;
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(nix::libc::O_NONBLOCK | nix::libc::O_CLOEXEC | nix::libc::O_NOCTTY)
            .open(path)?;
        Ok(ReportSource::Hidraw(file))
    }

    /// A stand-in made of two connected `SOCK_SEQPACKET` sockets (made non-blocking here).
    pub fn from_sockets(data: OwnedFd, control: OwnedFd) -> io::Result<ReportSource> {
        set_nonblocking(data.as_raw_fd())?;
        Ok(ReportSource::Sockets { data, control })
    }

    /// The descriptor to wait on for input reports.
    pub fn fd(&self) -> RawFd {
        match self {
            ReportSource::Hidraw(f) => f.as_raw_fd(),
            ReportSource::Sockets { data, .. } => data.as_raw_fd(),
        }
    }

    /// Reads one input report into `buf`. `Ok(0)` means the device is gone (a simulator
    /// closed its end); `WouldBlock`, that no report is waiting. An unplugged hidraw device
    /// fails with `EIO` or `ENODEV`.
    pub fn read(&self, buf: &mut [u8]) -> io::Result<usize> {
        match self {
            ReportSource::Hidraw(f) => nix::unistd::read(f.as_raw_fd(), buf).map_err(errno),
            ReportSource::Sockets { data, .. } => {
                recv(data.as_raw_fd(), buf, MsgFlags::MSG_DONTWAIT).map_err(errno)
            }
        }
    }

    /// Writes an output report (`report[0]` is the report id, 0 when the device has none).
    pub fn write_output(&self, report: &[u8]) -> io::Result<usize> {
        match self {
            ReportSource::Hidraw(f) => nix::unistd::write(f.as_raw_fd(), report).map_err(errno),
            ReportSource::Sockets { data, .. } => {
                send(data.as_raw_fd(), report, MsgFlags::MSG_NOSIGNAL).map_err(errno)
            }
        }
    }

    /// Sends a feature report (`report[0]` is the report id).
    pub fn set_feature(&self, report: &[u8]) -> io::Result<usize> {
        match self {
            ReportSource::Hidraw(f) => ioctl::set_feature(f.as_raw_fd(), report),
            ReportSource::Sockets { control, .. } => {
                let mut msg = Vec::with_capacity(report.len() + 1);
                msg.push(b'S');
                msg.extend_from_slice(report);
                send(control.as_raw_fd(), &msg, MsgFlags::MSG_NOSIGNAL)
                    .map(|n| n.saturating_sub(1))
                    .map_err(errno)
            }
        }
    }

    /// Reads feature report `buf[0]` into `buf`; returns its length. Blocks until the device
    /// answers, as the ioctl does (a stand-in has [`FEATURE_TIMEOUT`]).
    pub fn get_feature(&self, buf: &mut [u8]) -> io::Result<usize> {
        match self {
            ReportSource::Hidraw(f) => ioctl::get_feature(f.as_raw_fd(), buf),
            ReportSource::Sockets { control, .. } => {
                let len = u16::try_from(buf.len()).unwrap_or(u16::MAX).to_le_bytes();
                let id = buf.first().copied().unwrap_or(0);
                send(
                    control.as_raw_fd(),
                    &[b'G', id, len[0], len[1]],
                    MsgFlags::MSG_NOSIGNAL,
                )
                .map_err(errno)?;
                wait_readable(control.as_raw_fd(), FEATURE_TIMEOUT)?;
                recv(control.as_raw_fd(), buf, MsgFlags::MSG_DONTWAIT).map_err(errno)
            }
        }
    }

    /// The report descriptor, from the device (`HIDIOCGRDESC`); a stand-in has none to give.
    pub fn report_descriptor(&self) -> io::Result<Vec<u8>> {
        match self {
            ReportSource::Hidraw(f) => ioctl::report_descriptor(f.as_raw_fd()),
            ReportSource::Sockets { .. } => Err(io::Error::new(
                io::ErrorKind::Unsupported,
                "a simulated device has no HIDIOCGRDESC (its descriptor is in sysfs)",
            )),
        }
    }
}

/// Waits until `fd` is readable, at most `timeout`.
pub(crate) fn wait_readable(fd: RawFd, timeout: Duration) -> io::Result<()> {
    use nix::poll::{poll, PollFd, PollFlags};
    let mut fds = [PollFd::new(fd, PollFlags::POLLIN)];
    let ms = timeout.as_millis().min(i32::MAX as u128) as i32;
    match poll(&mut fds, ms).map_err(errno)? {
        0 => Err(io::Error::new(
            io::ErrorKind::TimedOut,
            "the device did not answer the feature request",
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hid::fake::{DeviceEnd, HostRequest, NodeListener};

    #[test]
    fn one_report_per_read_and_requests_reach_the_device() {
        let (host, dev) = DeviceEnd::pair().unwrap();
        let mut buf = [0u8; 64];
        assert_eq!(
            host.read(&mut buf).unwrap_err().kind(),
            io::ErrorKind::WouldBlock
        );
        dev.send_report(&[1, 2, 3]).unwrap();
        dev.send_report(&[4, 5]).unwrap();
        assert_eq!(host.read(&mut buf).unwrap(), 3);
        assert_eq!(&buf[..3], &[1, 2, 3]);
        assert_eq!(host.read(&mut buf).unwrap(), 2);
        host.write_output(&[0, 0xb3, 7, 1]).unwrap();
        host.set_feature(&[0x11, 0, 0, 0x0b, 0x10, 0x27]).unwrap();
        // Feature requests come first (they travel on their own socket).
        assert_eq!(
            dev.try_request().unwrap(),
            Some(HostRequest::SetFeature(vec![0x11, 0, 0, 0x0b, 0x10, 0x27]))
        );
        assert_eq!(
            dev.try_request().unwrap(),
            Some(HostRequest::Output(vec![0, 0xb3, 7, 1]))
        );
        assert_eq!(dev.try_request().unwrap(), None);
        drop(dev);
        assert_eq!(
            host.read(&mut buf).unwrap(),
            0,
            "a closed device reads as gone"
        );
    }

    #[test]
    fn get_feature_waits_for_the_answer() {
        let (host, dev) = DeviceEnd::pair().unwrap();
        let t = std::thread::spawn(move || loop {
            if let Some(HostRequest::GetFeature { id, len }) = dev.try_request().unwrap() {
                assert_eq!((id, len), (0, 91));
                dev.answer_feature(&[0, 9, 8, 7]).unwrap();
                return dev;
            }
            std::thread::sleep(Duration::from_millis(1));
        });
        let mut buf = [0u8; 91];
        assert_eq!(host.get_feature(&mut buf).unwrap(), 4);
        assert_eq!(&buf[..4], &[0, 9, 8, 7]);
        let dev = t.join().unwrap();
        drop(dev);
        // Nobody answers: a clean time-out, not a hang.
        let (host, _dev) = DeviceEnd::pair().unwrap();
        assert_eq!(
            host.get_feature(&mut buf).unwrap_err().kind(),
            io::ErrorKind::TimedOut
        );
    }

    #[test]
    fn a_listening_node_is_opened_as_a_device() {
        let dir = crate::hid::fake::TempDir::new("node");
        let path = dir.path().join("hidraw0");
        let l = NodeListener::bind(&path).unwrap();
        assert!(l.accept().unwrap().is_none());
        let host = ReportSource::open(&path).unwrap();
        let dev = l.accept().unwrap().expect("connected");
        dev.send_report(&[7; 7]).unwrap();
        let mut buf = [0u8; 16];
        // The data socket is non-blocking: wait for the datagram.
        wait_readable(host.fd(), Duration::from_secs(5)).unwrap();
        assert_eq!(host.read(&mut buf).unwrap(), 7);
        host.set_feature(&[1, 2]).unwrap();
        wait_readable(dev.control.as_raw_fd(), Duration::from_secs(5)).unwrap();
        assert_eq!(
            dev.try_request().unwrap(),
            Some(HostRequest::SetFeature(vec![1, 2]))
        );
        assert!(host.report_descriptor().is_err());
        drop(l);
        assert!(!path.exists());
        assert!(ReportSource::open(&path).is_err());
    }
}
