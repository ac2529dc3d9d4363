//! A fake device tree in a temporary folder, for simulators and tests: sysfs entries for
//! hidraw and evdev nodes written as the kernel lays them out, device nodes that are
//! simulator sockets (hidraw) or named pipes (evdev), and uevent messages sent to the tree's
//! hot-plug socket. See [`DeviceTree::under`].

use std::io;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use std::os::fd::{AsRawFd, OwnedFd, RawFd};

use nix::sys::socket::{recv, send, socket, AddressFamily, MsgFlags, SockFlag, SockType, UnixAddr};

use super::ioctl;
use super::source::{wait_readable, ReportSource, FEATURE_TIMEOUT};
use super::sysfs::DeviceTree;
use super::uevent;

fn errno(e: nix::errno::Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

/// A folder removed (with everything in it) when dropped.
#[derive(Debug)]
pub struct TempDir(PathBuf);

impl TempDir {
    /// A new, empty folder under the system's temporary folder.
    pub fn new(tag: &str) -> TempDir {
        static N: AtomicU64 = AtomicU64::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0);
        let p = std::env::temp_dir().join(format!(
            "vrpn-{tag}-{}-{}-{nanos}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&p).expect("cannot create a temporary folder");
        TempDir(p)
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fake `/sys` and `/dev`: see the module documentation.
#[derive(Debug)]
pub struct FakeTree {
    dir: TempDir,
}

impl Default for FakeTree {
    fn default() -> Self {
        FakeTree::new()
    }
}

fn write(path: &Path, contents: impl AsRef<[u8]>) {
    if let Some(p) = path.parent() {
        std::fs::create_dir_all(p).expect("cannot create a fake sysfs folder");
    }
    std::fs::write(path, contents).expect("cannot write a fake sysfs file");
}

impl FakeTree {
    /// An empty tree.
    pub fn new() -> FakeTree {
        let dir = TempDir::new("devtree");
        std::fs::create_dir_all(dir.path().join("sys/class/hidraw")).expect("fake sysfs");
        std::fs::create_dir_all(dir.path().join("sys/class/input")).expect("fake sysfs");
        std::fs::create_dir_all(dir.path().join("dev/input")).expect("fake dev");
        FakeTree { dir }
    }

    /// The folder holding `sys/`, `dev/` and `uevent`.
    pub fn root(&self) -> &Path {
        self.dir.path()
    }

    /// The tree, as the device layer sees it.
    pub fn tree(&self) -> DeviceTree {
        DeviceTree::under(self.dir.path())
    }

    /// Describes hidraw node `n` in sysfs (no device node yet: see
    /// [`listen_hidraw`](Self::listen_hidraw)).
    pub fn add_hidraw(
        &self,
        n: u32,
        vendor: u16,
        product: u16,
        interface: i32,
        name: &str,
        serial: &str,
    ) {
        let class = self.root().join(format!("sys/class/hidraw/hidraw{n}"));
        write(
            &class.join("uevent"),
            format!("MAJOR=241\nMINOR={n}\nDEVNAME=hidraw{n}\n"),
        );
        write(
            &class.join("device/uevent"),
            format!(
                "DRIVER=hid-generic\nHID_ID=0003:{vendor:08X}:{product:08X}\nHID_NAME={name}\n\
                 HID_PHYS=usb-0000:00:14.0-{n}/input{interface}\nHID_UNIQ={serial}\n\
                 MODALIAS=hid:b0003g0001v{vendor:08X}p{product:08X}\n"
            ),
        );
        write(&class.join("device/report_descriptor"), []);
    }

    /// Sets hidraw node `n`'s report descriptor.
    pub fn set_report_descriptor(&self, n: u32, descriptor: &[u8]) {
        write(
            &self.root().join(format!(
                "sys/class/hidraw/hidraw{n}/device/report_descriptor"
            )),
            descriptor,
        );
    }

    /// A simulator's socket at hidraw node `n`'s device file.
    pub fn listen_hidraw(&self, n: u32) -> io::Result<NodeListener> {
        NodeListener::bind(&self.root().join(format!("dev/hidraw{n}")))
    }

    /// Removes hidraw node `n` from sysfs and its device file.
    pub fn remove_hidraw(&self, n: u32) {
        let _ = std::fs::remove_dir_all(self.root().join(format!("sys/class/hidraw/hidraw{n}")));
        let _ = std::fs::remove_file(self.root().join(format!("dev/hidraw{n}")));
    }

    /// Describes evdev node `n` in sysfs; capabilities are sysfs's hex words.
    #[allow(clippy::too_many_arguments)]
    pub fn add_input(
        &self,
        n: u32,
        name: &str,
        vendor: u16,
        product: u16,
        ev: &str,
        key: &str,
        rel: &str,
        abs: &str,
    ) {
        let class = self.root().join(format!("sys/class/input/event{n}"));
        write(
            &class.join("uevent"),
            format!("MAJOR=13\nMINOR={}\nDEVNAME=input/event{n}\n", 64 + n),
        );
        let dev = class.join("device");
        write(&dev.join("name"), format!("{name}\n"));
        write(&dev.join("phys"), format!("usb-0000:00:14.0-{n}/input0\n"));
        write(&dev.join("id/bustype"), "0003\n");
        write(&dev.join("id/vendor"), format!("{vendor:04x}\n"));
        write(&dev.join("id/product"), format!("{product:04x}\n"));
        for (f, v) in [("ev", ev), ("key", key), ("rel", rel), ("abs", abs)] {
            write(&dev.join("capabilities").join(f), format!("{v}\n"));
        }
    }

    /// Makes evdev node `n`'s device file a named pipe; returns its path.
    pub fn fifo_input(&self, n: u32) -> io::Result<PathBuf> {
        let p = self.root().join(format!("dev/input/event{n}"));
        let _ = std::fs::remove_file(&p);
        nix::unistd::mkfifo(&p, nix::sys::stat::Mode::from_bits_truncate(0o600))
            .map_err(|e| io::Error::from_raw_os_error(e as i32))?;
        Ok(p)
    }

    /// Removes evdev node `n` from sysfs and its device file.
    pub fn remove_input(&self, n: u32) {
        let _ = std::fs::remove_dir_all(self.root().join(format!("sys/class/input/event{n}")));
        let _ = std::fs::remove_file(self.root().join(format!("dev/input/event{n}")));
    }

    /// Sends the tree's watcher the uevent the kernel would (`"add"`/`"remove"`,
    /// `"hidraw"`/`"input"`, `"hidraw0"`/`"input/event3"`). Fails when nothing listens yet.
    pub fn uevent(&self, action: &str, subsystem: &str, devname: &str) -> io::Result<()> {
        let path = self
            .tree()
            .uevent_socket()
            .expect("a fake tree has a uevent socket");
        let msg = uevent::message(
            action,
            subsystem,
            devname,
            &format!("/devices/fake/{subsystem}/{devname}"),
        );
        std::os::unix::net::UnixDatagram::unbound()?.send_to(&msg, path)?;
        Ok(())
    }
}

/// The device half of a stand-in: what a simulator holds. Made by a listener at the node's
/// path ([`NodeListener::accept`]) or from `socketpair`s.
#[derive(Debug)]
pub struct DeviceEnd {
    /// Input reports go out here; output reports come in.
    pub data: OwnedFd,
    /// Feature requests come in here.
    pub control: OwnedFd,
}

/// One request the host made of a simulated device.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum HostRequest {
    /// An output report.
    Output(Vec<u8>),
    /// A feature report to set.
    SetFeature(Vec<u8>),
    /// A feature report asked for: its id and the most bytes wanted.
    GetFeature {
        /// Report id.
        id: u8,
        /// Buffer length.
        len: u16,
    },
}

impl DeviceEnd {
    /// A connected pair: the host's [`ReportSource`] and the simulator's end.
    pub fn pair() -> io::Result<(ReportSource, DeviceEnd)> {
        use nix::sys::socket::socketpair;
        let pair = || -> io::Result<(OwnedFd, OwnedFd)> {
            let (a, b) = socketpair(
                AddressFamily::Unix,
                SockType::SeqPacket,
                None,
                SockFlag::SOCK_CLOEXEC,
            )
            .map_err(errno)?;
            Ok((ioctl::own_fd(a), ioctl::own_fd(b)))
        };
        let (host_data, dev_data) = pair()?;
        let (host_control, dev_control) = pair()?;
        Ok((
            ReportSource::from_sockets(host_data, host_control)?,
            DeviceEnd {
                data: dev_data,
                control: dev_control,
            },
        ))
    }

    /// Sends one input report.
    pub fn send_report(&self, report: &[u8]) -> io::Result<()> {
        send(self.data.as_raw_fd(), report, MsgFlags::MSG_NOSIGNAL).map_err(errno)?;
        Ok(())
    }

    /// The next request from the host, if one is waiting (non-blocking). The host having
    /// closed the device is `UnexpectedEof`.
    pub fn try_request(&self) -> io::Result<Option<HostRequest>> {
        let mut buf = [0u8; 4096];
        // Feature requests first: a host that sends one and closes must not lose it behind
        // the end of the data socket.
        match recv(self.control.as_raw_fd(), &mut buf, MsgFlags::MSG_DONTWAIT) {
            Ok(0) | Err(nix::errno::Errno::EAGAIN) => {}
            Ok(n) => {
                return Ok(match buf[0] {
                    b'S' => Some(HostRequest::SetFeature(buf[1..n].to_vec())),
                    b'G' if n >= 4 => Some(HostRequest::GetFeature {
                        id: buf[1],
                        len: u16::from_le_bytes([buf[2], buf[3]]),
                    }),
                    _ => None,
                })
            }
            Err(e) => return Err(errno(e)),
        }
        match recv(self.data.as_raw_fd(), &mut buf, MsgFlags::MSG_DONTWAIT) {
            Ok(0) => Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                "the host closed the device",
            )),
            Ok(n) => Ok(Some(HostRequest::Output(buf[..n].to_vec()))),
            Err(nix::errno::Errno::EAGAIN) => Ok(None),
            Err(e) => Err(errno(e)),
        }
    }

    /// Answers a get-feature request.
    pub fn answer_feature(&self, report: &[u8]) -> io::Result<()> {
        send(self.control.as_raw_fd(), report, MsgFlags::MSG_NOSIGNAL).map_err(errno)?;
        Ok(())
    }
}

/// A simulator's listening socket at a device node's path.
#[derive(Debug)]
pub struct NodeListener {
    fd: OwnedFd,
    path: std::path::PathBuf,
}

impl NodeListener {
    /// Listens at `path` (replacing a stale socket file).
    pub fn bind(path: &Path) -> io::Result<NodeListener> {
        use nix::sys::socket::{bind, listen};
        let _ = std::fs::remove_file(path);
        let fd = socket(
            AddressFamily::Unix,
            SockType::SeqPacket,
            SockFlag::SOCK_CLOEXEC | SockFlag::SOCK_NONBLOCK,
            None,
        )
        .map_err(errno)?;
        let fd = ioctl::own_fd(fd);
        bind(fd.as_raw_fd(), &UnixAddr::new(path).map_err(errno)?).map_err(errno)?;
        listen(fd.as_raw_fd(), 4).map_err(errno)?;
        Ok(NodeListener {
            fd,
            path: path.to_path_buf(),
        })
    }

    /// The host connected (both sockets): its device end, or `None` if it has not yet.
    pub fn accept(&self) -> io::Result<Option<DeviceEnd>> {
        use nix::sys::socket::accept;
        let take = |fd: RawFd| -> io::Result<Option<OwnedFd>> {
            match accept(fd) {
                Ok(c) => Ok(Some(ioctl::own_fd(c))),
                Err(nix::errno::Errno::EAGAIN) => Ok(None),
                Err(e) => Err(errno(e)),
            }
        };
        let Some(data) = take(self.fd.as_raw_fd())? else {
            return Ok(None);
        };
        // The host connects its control socket right after the data socket.
        wait_readable(self.fd.as_raw_fd(), FEATURE_TIMEOUT)?;
        let control = take(self.fd.as_raw_fd())?
            .ok_or_else(|| io::Error::new(io::ErrorKind::TimedOut, "no control connection"))?;
        Ok(Some(DeviceEnd { data, control }))
    }

    /// The listening descriptor (readable when the host connects).
    pub fn raw_fd(&self) -> RawFd {
        self.fd.as_raw_fd()
    }
}

impl Drop for NodeListener {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}
