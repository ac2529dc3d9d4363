//! A UDP socket as a device's input, waiting in the server's one reactor: the source of
//! trackers that stream datagrams to the server (optical tracking controllers, JSON senders).
//!
//! The socket is bound to a port on every interface (optionally joined to a multicast group)
//! and registered with the reactor so that readiness carries the time the poll woke for it:
//! each datagram read in one pass is stamped with that time, the arrival of the first of them.
//! Each datagram is handed to the device whole (its boundaries are the protocol's frames);
//! a datagram longer than the receive buffer is reported as such, never cut into a frame.
//!
//! Unsafe code here: taking ownership of the descriptor `socket(2)` returned (the address
//! must be reusable *before* `bind`, which the standard library cannot do), and setting the
//! multicast interface of a sending socket, for which nix has no option.
#![allow(unsafe_code)]

use std::io;
use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4, UdpSocket};
use std::os::fd::{AsRawFd, FromRawFd};

use nix::sys::socket::{
    bind, setsockopt, socket, sockopt, AddressFamily, IpMembershipRequest, SockFlag, SockType,
    SockaddrIn,
};

use crate::net::Reactor;
use crate::time::Now;

/// One datagram as [`UdpSource::drain`] hands it over.
#[derive(Debug)]
pub struct Datagram<'a> {
    /// Its bytes; empty when it was too long (see [`too_long`](Self::too_long)).
    pub bytes: &'a [u8],
    /// It did not fit the buffer: its bytes are not given (a cut frame is no frame).
    pub too_long: bool,
    /// When the poll woke for it (or the pass's time without a reactor).
    pub arrived: Now,
    /// Who sent it.
    pub from: SocketAddr,
}

/// A bound, non-blocking UDP socket registered with the server's reactor. See the module
/// documentation.
#[derive(Debug)]
pub struct UdpSource {
    sock: UdpSocket,
    reactor: Option<Reactor>,
    token: Option<mio::Token>,
    group: Option<Ipv4Addr>,
}

fn errno(e: nix::errno::Errno) -> io::Error {
    io::Error::from_raw_os_error(e as i32)
}

impl UdpSource {
    /// Binds `port` (0: any free port) on every IPv4 interface, joins `group` if given (with
    /// the address reusable, so that several receivers of one group can share the port), and
    /// waits in `reactor` (without one, [`drain`](Self::drain) reads on every call).
    pub fn bind(
        port: u16,
        group: Option<Ipv4Addr>,
        reactor: Option<&Reactor>,
    ) -> io::Result<UdpSource> {
        let fd = socket(
            AddressFamily::Inet,
            SockType::Datagram,
            SockFlag::SOCK_NONBLOCK | SockFlag::SOCK_CLOEXEC,
            None,
        )
        .map_err(errno)?;
        // SAFETY: `fd` was just returned by socket(2) and is owned by nothing else; from here
        // on the UdpSocket owns it and closes it on every path.
        let sock = unsafe { UdpSocket::from_raw_fd(fd) };
        if group.is_some() {
            setsockopt(sock.as_raw_fd(), sockopt::ReuseAddr, &true).map_err(errno)?;
        }
        let addr = SockaddrIn::from(SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, port));
        bind(sock.as_raw_fd(), &addr).map_err(errno)?;
        if let Some(g) = group {
            join(&sock, g)?;
        }
        let token = match reactor {
            Some(r) => Some(r.register_fd(sock.as_raw_fd(), mio::Interest::READABLE)?),
            None => None,
        };
        Ok(UdpSource {
            sock,
            reactor: reactor.cloned(),
            token,
            group,
        })
    }

    /// The local port (the one asked for, or the one the system chose for 0).
    pub fn local_port(&self) -> u16 {
        self.sock.local_addr().map(|a| a.port()).unwrap_or(0)
    }

    /// The multicast group joined, if any.
    pub fn group(&self) -> Option<Ipv4Addr> {
        self.group
    }

    /// Sends `bytes` to `to` from the bound port (so a stateful firewall lets the peer's
    /// answers to that port through).
    pub fn send_to(&self, bytes: &[u8], to: SocketAddr) -> io::Result<usize> {
        self.sock.send_to(bytes, to)
    }

    /// Reads every datagram waiting, in order, handing each to `f` with `buf` as its storage.
    /// `now` is the pass's time (the stamp when no reactor says better). Returns how many
    /// were read; a socket error other than "nothing waiting" is returned after the
    /// datagrams before it were handed over.
    pub fn drain(
        &mut self,
        buf: &mut [u8],
        now: Now,
        mut f: impl FnMut(Datagram<'_>),
    ) -> io::Result<usize> {
        let arrived = match (&self.reactor, self.token) {
            (Some(r), Some(t)) => {
                let ready = r.take(t);
                if !ready.readable && !ready.error {
                    return Ok(0);
                }
                ready.woke.unwrap_or(now)
            }
            _ => now,
        };
        let mut count = 0;
        loop {
            match self.sock.recv_from(buf) {
                Ok((n, from)) => {
                    count += 1;
                    // A datagram that fills the buffer may have been cut.
                    let too_long = n >= buf.len();
                    f(Datagram {
                        bytes: if too_long { &[] } else { &buf[..n] },
                        too_long,
                        arrived,
                        from,
                    });
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(count),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                // An ICMP error from an earlier send (the firewall message to a closed port)
                // surfaces on the next receive: it is no reason to stop reading.
                Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => {}
                Err(e) => return Err(e),
            }
        }
    }
}

/// Joins `group` on the interface the routing table gives (as C++ does, `INADDR_ANY`) and
/// on the loopback interface, so that a sender on the same machine reaches it too (multicast
/// sent through 127.0.0.1 is delivered only to members on the loopback interface). Either
/// join may fail (no route to multicast addresses, loopback chosen by the routing table
/// already); one must succeed.
fn join(sock: &UdpSocket, group: Ipv4Addr) -> io::Result<()> {
    let fd = sock.as_raw_fd();
    let any = setsockopt(
        fd,
        sockopt::IpAddMembership,
        &IpMembershipRequest::new(group, None),
    );
    let lo = setsockopt(
        fd,
        sockopt::IpAddMembership,
        &IpMembershipRequest::new(group, Some(Ipv4Addr::LOCALHOST)),
    );
    match (any, lo) {
        (Err(e), Err(_)) => Err(errno(e)),
        _ => Ok(()),
    }
}

impl Drop for UdpSource {
    fn drop(&mut self) {
        if let (Some(r), Some(t)) = (&self.reactor, self.token) {
            r.deregister_fd(self.sock.as_raw_fd(), t);
        }
        if let Some(g) = self.group {
            for interface in [None, Some(Ipv4Addr::LOCALHOST)] {
                let _ = setsockopt(
                    self.sock.as_raw_fd(),
                    sockopt::IpDropMembership,
                    &IpMembershipRequest::new(g, interface),
                );
            }
        }
    }
}

/// A UDP socket sending to a multicast group on the loopback interface (what a test's
/// controller simulator sends from): multicast leaves through 127.0.0.1 and loops back.
pub fn loopback_multicast_sender() -> io::Result<UdpSocket> {
    let sock = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0))?;
    let fd = sock.as_raw_fd();
    setsockopt(fd, sockopt::IpMulticastLoop, &true).map_err(errno)?;
    // IP_MULTICAST_IF with the loopback address.
    let addr = nix::libc::in_addr {
        s_addr: u32::from(Ipv4Addr::LOCALHOST).to_be(),
    };
    // SAFETY: `addr` is a valid in_addr that outlives the call, and its size is passed.
    let rc = unsafe {
        nix::libc::setsockopt(
            fd,
            nix::libc::IPPROTO_IP,
            nix::libc::IP_MULTICAST_IF,
            &addr as *const _ as *const nix::libc::c_void,
            std::mem::size_of::<nix::libc::in_addr>() as nix::libc::socklen_t,
        )
    };
    if rc != 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(sock)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn now() -> Now {
        crate::net::clock()
    }

    #[test]
    fn datagrams_arrive_whole_and_in_order() {
        let reactor = Reactor::new().unwrap();
        let mut src = UdpSource::bind(0, None, Some(&reactor)).unwrap();
        let port = src.local_port();
        let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
        tx.send_to(b"one", ("127.0.0.1", port)).unwrap();
        tx.send_to(b"two two", ("127.0.0.1", port)).unwrap();
        tx.send_to(&[7u8; 64], ("127.0.0.1", port)).unwrap();
        let mut got: Vec<(Vec<u8>, bool)> = Vec::new();
        let mut buf = [0u8; 32];
        let start = std::time::Instant::now();
        while got.len() < 3 && start.elapsed() < std::time::Duration::from_secs(5) {
            reactor
                .wait(None, std::time::Duration::from_millis(50))
                .unwrap();
            src.drain(&mut buf, now(), |d| {
                got.push((d.bytes.to_vec(), d.too_long))
            })
            .unwrap();
        }
        assert_eq!(
            got,
            vec![
                (b"one".to_vec(), false),
                (b"two two".to_vec(), false),
                (Vec::new(), true)
            ]
        );
    }

    #[test]
    fn multicast_on_loopback() {
        let group = Ipv4Addr::new(225, 1, 1, 1);
        let mut src = UdpSource::bind(0, Some(group), None).unwrap();
        let port = src.local_port();
        let tx = loopback_multicast_sender().unwrap();
        let mut got = Vec::new();
        let mut buf = [0u8; 64];
        let start = std::time::Instant::now();
        while got.is_empty() && start.elapsed() < std::time::Duration::from_secs(5) {
            tx.send_to(b"fr 1\n", (group, port)).unwrap();
            std::thread::sleep(std::time::Duration::from_millis(20));
            src.drain(&mut buf, now(), |d| got.push(d.bytes.to_vec()))
                .unwrap();
        }
        assert_eq!(got.first().map(Vec::as_slice), Some(&b"fr 1\n"[..]));
    }
}
