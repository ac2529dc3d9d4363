//! Hot-plug without polling sysfs: the kernel's uevent socket waits in the server's reactor,
//! and every `add` or `remove` of a hidraw or evdev node bumps a generation counter that the
//! devices compare with the one they last saw (then read sysfs again).
//!
//! On a real system the socket is a netlink `NETLINK_KOBJECT_UEVENT` socket bound to the
//! kernel's multicast group 1. A fake [`DeviceTree`] (tests, simulators) has no kernel behind
//! it: its watcher binds a Unix datagram socket at the tree's `uevent` path instead, and
//! simulators send it the same messages the kernel would (see [`super::uevent::message`]).
//!
//! One watcher serves every device of a process (clones share it); whichever device asks
//! first drains the socket.

use std::cell::RefCell;
use std::io;
use std::os::fd::{AsRawFd, OwnedFd, RawFd};
use std::rc::Rc;

use nix::sys::socket::{
    bind, recv, setsockopt, socket, sockopt, AddressFamily, MsgFlags, NetlinkAddr, SockFlag,
    SockProtocol, SockType,
};

use super::sysfs::DeviceTree;
use super::uevent::{self, Action};
use crate::net::Reactor;

/// The kernel's uevent multicast group.
const KERNEL_GROUP: u32 = 1;
/// Receive buffer asked for (event storms at boot or on a hub plug fill the default).
const RECEIVE_BUFFER: usize = 1 << 20;

fn errno(e: nix::errno::Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

struct Inner {
    fd: OwnedFd,
    reactor: Option<Reactor>,
    token: Option<mio::Token>,
    generation: u64,
    /// Messages read and parsed, for diagnostics.
    messages: u64,
    buf: Box<[u8; 8192]>,
    /// Kept so the socket file of a fake tree is removed with the watcher.
    path: Option<std::path::PathBuf>,
}

impl Drop for Inner {
    fn drop(&mut self) {
        if let (Some(r), Some(t)) = (&self.reactor, self.token) {
            r.deregister_fd(self.fd.as_raw_fd(), t);
        }
        if let Some(p) = &self.path {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// A shared hot-plug watcher: see the module documentation.
#[derive(Clone)]
pub struct Hotplug {
    inner: Rc<RefCell<Inner>>,
}

impl std::fmt::Debug for Hotplug {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let i = self.inner.borrow();
        f.debug_struct("Hotplug")
            .field("generation", &i.generation)
            .field("messages", &i.messages)
            .finish()
    }
}

/// Opens the kernel's uevent socket, non-blocking and close-on-exec.
pub fn kernel_socket() -> io::Result<OwnedFd> {
    let fd = socket(
        AddressFamily::Netlink,
        SockType::Datagram,
        SockFlag::SOCK_NONBLOCK | SockFlag::SOCK_CLOEXEC,
        SockProtocol::NetlinkKObjectUEvent,
    )
    .map_err(errno)?;
    // SAFETY-free: nix hands back a fresh descriptor we now own.
    let fd = owned(fd);
    let _ = setsockopt(fd.as_raw_fd(), sockopt::RcvBuf, &RECEIVE_BUFFER);
    bind(fd.as_raw_fd(), &NetlinkAddr::new(0, KERNEL_GROUP)).map_err(errno)?;
    Ok(fd)
}

fn owned(fd: RawFd) -> OwnedFd {
    super::ioctl::own_fd(fd)
}

impl Hotplug {
    /// Watches `tree`'s hot-plug events, waiting in `reactor` (without one, every
    /// [`generation`](Self::generation) call reads the socket).
    pub fn open(tree: &DeviceTree, reactor: Option<&Reactor>) -> io::Result<Hotplug> {
        let (fd, path) = match tree.uevent_socket() {
            None => (kernel_socket()?, None),
            Some(p) => {
                let _ = std::fs::remove_file(&p);
                let sock = std::os::unix::net::UnixDatagram::bind(&p)?;
                sock.set_nonblocking(true)?;
                (OwnedFd::from(sock), Some(p))
            }
        };
        let token = match reactor {
            Some(r) => Some(r.register_fd(fd.as_raw_fd(), mio::Interest::READABLE)?),
            None => None,
        };
        Ok(Hotplug {
            inner: Rc::new(RefCell::new(Inner {
                fd,
                reactor: reactor.cloned(),
                token,
                generation: 0,
                messages: 0,
                buf: Box::new([0; 8192]),
                path,
            })),
        })
    }

    /// A watcher on an already open datagram socket (tests hand it one end of a pair).
    pub fn from_socket(fd: OwnedFd, reactor: Option<&Reactor>) -> io::Result<Hotplug> {
        let token = match reactor {
            Some(r) => Some(r.register_fd(fd.as_raw_fd(), mio::Interest::READABLE)?),
            None => None,
        };
        Ok(Hotplug {
            inner: Rc::new(RefCell::new(Inner {
                fd,
                reactor: reactor.cloned(),
                token,
                generation: 0,
                messages: 0,
                buf: Box::new([0; 8192]),
                path: None,
            })),
        })
    }

    /// The socket's descriptor (its netlink port id is what tests send to).
    pub fn raw_fd(&self) -> RawFd {
        self.inner.borrow().fd.as_raw_fd()
    }

    /// Messages read so far.
    pub fn messages(&self) -> u64 {
        self.inner.borrow().messages
    }

    /// Reads what arrived, then returns how many hidraw or evdev nodes came or went since the
    /// watcher opened. A device that saw another number reads sysfs again.
    pub fn generation(&self) -> u64 {
        let mut i = self.inner.borrow_mut();
        let i = &mut *i;
        let readable = match (&i.reactor, i.token) {
            (Some(r), Some(t)) => r.take(t).readable,
            _ => true,
        };
        if readable {
            loop {
                match recv(i.fd.as_raw_fd(), &mut i.buf[..], MsgFlags::MSG_DONTWAIT) {
                    Ok(n) => {
                        i.messages += 1;
                        if let Some(ev) = uevent::parse(&i.buf[..n]) {
                            if ev.is_device_node() && ev.action != Action::Other {
                                i.generation += 1;
                            }
                        }
                    }
                    Err(nix::errno::Errno::EINTR) => {}
                    // Events were lost: assume something changed.
                    Err(nix::errno::Errno::ENOBUFS) => i.generation += 1,
                    Err(_) => break,
                }
            }
        }
        i.generation
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nix::sys::socket::{getsockname, sendto};
    use std::time::{Duration, Instant};

    fn wait_for(h: &Hotplug, r: &Reactor, gen: u64) {
        let start = Instant::now();
        while h.generation() < gen {
            assert!(
                start.elapsed() < Duration::from_secs(5),
                "no uevent arrived"
            );
            r.wait(None, Duration::from_millis(50)).unwrap();
        }
    }

    /// The real kernel socket: messages written to it (by port id, as the kernel's would
    /// arrive) wake the reactor and count when they concern a device node.
    #[test]
    fn the_kernel_socket_hears_uevents_written_to_it() {
        let r = Reactor::new().unwrap();
        let h = match Hotplug::open(&DeviceTree::system(), Some(&r)) {
            Ok(h) => h,
            // A sandbox without netlink: the fake-tree test below covers the parser path.
            Err(e) if e.kind() == io::ErrorKind::PermissionDenied => return,
            Err(e) => panic!("cannot open the uevent socket: {e}"),
        };
        let me: NetlinkAddr = getsockname(h.raw_fd()).unwrap();
        let sender = kernel_socket_unbound();
        let to = NetlinkAddr::new(me.pid(), 0);
        let send = |m: &[u8]| {
            sendto(sender.as_raw_fd(), m, &to, MsgFlags::empty()).unwrap();
        };
        assert_eq!(h.generation(), 0);
        send(&uevent::message("add", "usb", "", "/devices/x"));
        send(&uevent::message(
            "add",
            "hidraw",
            "hidraw4",
            "/devices/x/hidraw/hidraw4",
        ));
        wait_for(&h, &r, 1);
        send(b"libudev\0garbage");
        send(&uevent::message(
            "remove",
            "input",
            "input/event2",
            "/devices/y/event2",
        ));
        wait_for(&h, &r, 2);
        assert_eq!(h.messages(), 4);
    }

    fn kernel_socket_unbound() -> OwnedFd {
        let fd = socket(
            AddressFamily::Netlink,
            SockType::Datagram,
            SockFlag::SOCK_CLOEXEC,
            SockProtocol::NetlinkKObjectUEvent,
        )
        .unwrap();
        let fd = owned(fd);
        bind(fd.as_raw_fd(), &NetlinkAddr::new(0, 0)).unwrap();
        fd
    }

    #[test]
    fn a_fake_tree_takes_uevents_on_its_socket() {
        let root = crate::hid::fake::TempDir::new("hotplug");
        let tree = DeviceTree::under(root.path());
        let r = Reactor::new().unwrap();
        let h = Hotplug::open(&tree, Some(&r)).unwrap();
        let s = std::os::unix::net::UnixDatagram::unbound().unwrap();
        let path = tree.uevent_socket().unwrap();
        s.send_to(
            &uevent::message("add", "hidraw", "hidraw0", "/d/hidraw0"),
            &path,
        )
        .unwrap();
        wait_for(&h, &r, 1);
        // Shared: a clone sees the same count without reading anything.
        assert_eq!(h.clone().generation(), 1);
        drop(h);
        assert!(!path.exists(), "the socket file outlived the watcher");
    }
}
