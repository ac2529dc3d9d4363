//! The system calls mio does not offer: receiving several datagrams, with their sources, in
//! one call (`recvmmsg`), sending datagrams to many destinations in one call (`sendmmsg`), and
//! asking how many bytes wait on a descriptor (`FIONREAD`). The crate's only `unsafe` code
//! outside the programs' signal handlers, the C and Python bindings and the drivers' device
//! ioctls lives here.
#![allow(unsafe_code)]

use std::io;
use std::net::{Ipv4Addr, SocketAddrV4};
#[cfg(any(target_os = "linux", target_os = "android"))]
use std::{marker::PhantomData, mem::MaybeUninit};

#[cfg(any(target_os = "linux", target_os = "android"))]
use nix::libc;

use mio::net::UdpSocket;

use crate::proto::buffers::{DatagramInbox, INBOX_SLOT, INBOX_SLOTS};

/// Bytes waiting to be read on `fd` (a terminal, a pipe: `FIONREAD`), or `None` where the
/// descriptor cannot tell.
pub(crate) fn bytes_waiting(fd: std::os::fd::RawFd) -> Option<usize> {
    let mut n: nix::libc::c_int = 0;
    // SAFETY: FIONREAD writes one int through the pointer, which points at `n`; a descriptor
    // that is not open or does not support the request makes it fail with an error code.
    let r = unsafe { nix::libc::ioctl(fd, nix::libc::FIONREAD as _, &mut n) };
    (r == 0).then(|| usize::try_from(n).ok()).flatten()
}

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

/// Datagrams one [`send_datagrams`] call hands the kernel at most.
pub(crate) const SEND_BATCH: usize = 256;

/// Datagrams to send with one system call: each one's destination and bytes, borrowed until
/// [`send`](SendBatch::send). Built on the stack and filled only as far as used, so a pass
/// that sends one datagram pays for one.
#[cfg(any(target_os = "linux", target_os = "android"))]
pub(crate) struct SendBatch<'a> {
    iov: [MaybeUninit<libc::iovec>; SEND_BATCH],
    names: [MaybeUninit<libc::sockaddr_in>; SEND_BATCH],
    len: usize,
    _bytes: PhantomData<&'a [u8]>,
}

#[cfg(any(target_os = "linux", target_os = "android"))]
impl<'a> SendBatch<'a> {
    pub(crate) fn new() -> SendBatch<'a> {
        SendBatch {
            // SAFETY: an array of `MaybeUninit` needs no initialisation.
            iov: unsafe { MaybeUninit::uninit().assume_init() },
            names: unsafe { MaybeUninit::uninit().assume_init() },
            len: 0,
            _bytes: PhantomData,
        }
    }

    /// Adds a datagram for `to` (`None`: the address the socket is connected to, which
    /// spares the kernel a route lookup); false (and nothing added) when the batch is full.
    #[inline]
    pub(crate) fn push(&mut self, to: Option<SocketAddrV4>, bytes: &'a [u8]) -> bool {
        if self.len == SEND_BATCH {
            return false;
        }
        self.iov[self.len].write(libc::iovec {
            iov_base: bytes.as_ptr() as *mut libc::c_void,
            iov_len: bytes.len(),
        });
        // SAFETY: sockaddr_in is plain data; all-zero is a valid value (and zero padding
        // is what the kernel expects in sin_zero). Family 0 marks "no address".
        let mut a: libc::sockaddr_in = unsafe { std::mem::zeroed() };
        if let Some(to) = to {
            a.sin_family = libc::AF_INET as libc::sa_family_t;
            a.sin_port = to.port().to_be();
            a.sin_addr.s_addr = u32::from(*to.ip()).to_be();
        }
        self.names[self.len].write(a);
        self.len += 1;
        true
    }

    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// A batch of one (a reply in a round trip): a plain `send`/`sendto`, which the kernel
    /// takes with less copying in than a one-message `sendmmsg`.
    fn send_one(&mut self, sock: &UdpSocket) -> usize {
        use std::os::fd::AsRawFd;
        loop {
            // SAFETY: `iov[0]` and `names[0]` were initialised by `push` (len is 1); the
            // bytes are borrowed for 'a and outlive the call; the name, when there is one,
            // is a complete sockaddr_in.
            let r = unsafe {
                let iov = self.iov[0].assume_init_ref();
                let name = self.names[0].as_ptr();
                if (*name).sin_family != 0 {
                    libc::sendto(
                        sock.as_raw_fd(),
                        iov.iov_base,
                        iov.iov_len,
                        libc::MSG_DONTWAIT,
                        name.cast(),
                        std::mem::size_of::<libc::sockaddr_in>() as _,
                    )
                } else {
                    libc::send(
                        sock.as_raw_fd(),
                        iov.iov_base,
                        iov.iov_len,
                        libc::MSG_DONTWAIT,
                    )
                }
            };
            if r >= 0 {
                return 1;
            }
            match io::Error::last_os_error().kind() {
                io::ErrorKind::WouldBlock => return 0,
                io::ErrorKind::Interrupted => continue,
                // Lost, as an unreliable datagram may be.
                _ => return 1,
            }
        }
    }

    /// Sends the batch in order with `sendmmsg`; returns how many datagrams the kernel took
    /// (fewer than all when the socket's buffer filled: the rest may be sent later). A
    /// datagram the kernel refused for another reason counts as taken (lost, as unreliable
    /// traffic may be), so one bad destination cannot stall the others.
    pub(crate) fn send(&mut self, sock: &UdpSocket) -> usize {
        use std::os::fd::AsRawFd;
        let mut msgs: [MaybeUninit<libc::mmsghdr>; SEND_BATCH] =
            // SAFETY: an array of `MaybeUninit` needs no initialisation.
            unsafe { MaybeUninit::uninit().assume_init() };
        if self.len == 1 {
            return self.send_one(sock);
        }
        let mut sent = 0;
        while sent < self.len {
            let n = self.len - sent;
            for (k, slot) in msgs.iter_mut().enumerate().take(n) {
                // SAFETY: msghdr is plain data (all-zero is valid: no name, no control);
                // the pointers set point into `self.iov` / `self.names`, initialised up to
                // `self.len`, which outlive the call; the bytes they point at are borrowed
                // for 'a, which outlives `self`.
                let mut h: libc::mmsghdr = unsafe { std::mem::zeroed() };
                let name = self.names[sent + k].as_mut_ptr();
                // SAFETY: initialised by `push` for every index below `self.len`.
                if unsafe { (*name).sin_family } != 0 {
                    h.msg_hdr.msg_name = name.cast();
                    h.msg_hdr.msg_namelen = std::mem::size_of::<libc::sockaddr_in>() as _;
                }
                h.msg_hdr.msg_iov = self.iov[sent + k].as_mut_ptr();
                h.msg_hdr.msg_iovlen = 1;
                slot.write(h);
            }
            // SAFETY: the first `n` headers are initialised (above) and valid for the call.
            let r = unsafe {
                libc::sendmmsg(
                    sock.as_raw_fd(),
                    msgs.as_mut_ptr().cast(),
                    n as _,
                    libc::MSG_DONTWAIT as _,
                )
            };
            if r < 0 {
                let e = io::Error::last_os_error();
                match e.kind() {
                    io::ErrorKind::WouldBlock => break,
                    io::ErrorKind::Interrupted => continue,
                    // The first datagram failed (e.g. no route): it is lost, go on.
                    _ => sent += 1,
                }
            } else {
                // Stopped short: the next call reports why (would block: stop; another
                // error: that datagram is skipped).
                sent += r as usize;
            }
        }
        sent
    }
}

/// Portable fallback: one `send_to` per datagram.
#[cfg(not(any(target_os = "linux", target_os = "android")))]
pub(crate) struct SendBatch<'a> {
    datagrams: Vec<(Option<SocketAddrV4>, &'a [u8])>,
}

#[cfg(not(any(target_os = "linux", target_os = "android")))]
impl<'a> SendBatch<'a> {
    pub(crate) fn new() -> SendBatch<'a> {
        SendBatch {
            datagrams: Vec::new(),
        }
    }

    pub(crate) fn push(&mut self, to: Option<SocketAddrV4>, bytes: &'a [u8]) -> bool {
        if self.datagrams.len() == SEND_BATCH {
            return false;
        }
        self.datagrams.push((to, bytes));
        true
    }

    pub(crate) fn len(&self) -> usize {
        self.datagrams.len()
    }

    pub(crate) fn send(&mut self, sock: &UdpSocket) -> usize {
        let mut sent = 0;
        for (to, bytes) in &self.datagrams {
            let r = match to {
                Some(to) => sock.send_to(bytes, std::net::SocketAddr::V4(*to)),
                None => sock.send(bytes),
            };
            match r {
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                _ => sent += 1,
            }
        }
        sent
    }
}
