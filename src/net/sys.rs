//! The one system call mio does not offer: receiving several datagrams, with their sources,
//! in one call (`recvmmsg`). The crate's only `unsafe` code outside the programs' signal
//! handlers, the C and Python bindings and the drivers' device ioctls lives here.
#![allow(unsafe_code)]

use std::io;
use std::net::{Ipv4Addr, SocketAddrV4};

use mio::net::UdpSocket;

use crate::proto::buffers::{DatagramInbox, INBOX_SLOT, INBOX_SLOTS};

/// Receives up to [`INBOX_SLOTS`] datagrams with one `recvmmsg` call, recording each one's
/// length and source. Returns how many arrived.
///
/// `known_source`: the socket is connected to that address, so every datagram comes from it
/// and the kernel is not asked for sources (copying them out costs about 1 % of a UDP round
/// trip).
#[cfg(any(target_os = "linux", target_os = "android"))]
pub(crate) fn recv_datagrams(
    sock: &UdpSocket,
    inbox: &mut DatagramInbox,
    known_source: Option<SocketAddrV4>,
) -> io::Result<usize> {
    use nix::libc;
    use std::os::fd::AsRawFd;
    let base = inbox.buf.as_mut_ptr();
    // SAFETY: every iovec points into `inbox.buf`, which holds INBOX_SLOTS slots of INBOX_SLOT
    // bytes and outlives the call; every msg_name (set only when sources are wanted) points
    // into `names`, which holds one `sockaddr_in` per message and outlives the call; the
    // mmsghdr array is zero-initialised (a valid empty header for recvmmsg) and only its iov
    // and name fields are set; the kernel writes at most iov_len bytes per slot, at most
    // msg_namelen bytes per name, and the message lengths into `msg_len`.
    unsafe {
        let mut iov: [libc::iovec; INBOX_SLOTS] = std::mem::zeroed();
        let mut names: [libc::sockaddr_in; INBOX_SLOTS] = std::mem::zeroed();
        let mut msgs: [libc::mmsghdr; INBOX_SLOTS] = std::mem::zeroed();
        for k in 0..INBOX_SLOTS {
            iov[k].iov_base = base.add(k * INBOX_SLOT).cast();
            iov[k].iov_len = INBOX_SLOT;
            msgs[k].msg_hdr.msg_iov = &mut iov[k];
            msgs[k].msg_hdr.msg_iovlen = 1;
            if known_source.is_none() {
                msgs[k].msg_hdr.msg_name = (&mut names[k] as *mut libc::sockaddr_in).cast();
                msgs[k].msg_hdr.msg_namelen = std::mem::size_of::<libc::sockaddr_in>() as _;
            }
        }
        let n = libc::recvmmsg(
            sock.as_raw_fd(),
            msgs.as_mut_ptr(),
            INBOX_SLOTS as _,
            libc::MSG_DONTWAIT as _,
            std::ptr::null_mut(),
        );
        if n < 0 {
            return Err(io::Error::last_os_error());
        }
        let n = n as usize;
        for k in 0..n {
            inbox.lens[k] = msgs[k].msg_len as usize;
            let a = &names[k];
            inbox.from[k] = match known_source {
                Some(source) => source,
                None if a.sin_family == libc::AF_INET as libc::sa_family_t => SocketAddrV4::new(
                    Ipv4Addr::from(u32::from_be(a.sin_addr.s_addr)),
                    u16::from_be(a.sin_port),
                ),
                None => SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0),
            };
        }
        Ok(n)
    }
}

/// Portable fallback: one datagram per call.
#[cfg(not(any(target_os = "linux", target_os = "android")))]
pub(crate) fn recv_datagrams(
    sock: &UdpSocket,
    inbox: &mut DatagramInbox,
    known_source: Option<SocketAddrV4>,
) -> io::Result<usize> {
    let (n, from) = match known_source {
        Some(source) => (sock.recv(&mut inbox.buf[..INBOX_SLOT])?, source),
        None => match sock.recv_from(&mut inbox.buf[..INBOX_SLOT])? {
            (n, std::net::SocketAddr::V4(a)) => (n, a),
            (n, _) => (n, SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0)),
        },
    };
    inbox.lens[0] = n;
    inbox.from[0] = from;
    Ok(1)
}
