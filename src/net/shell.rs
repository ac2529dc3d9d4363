//! The sockets of one connection, and the byte movement between them and its session.
//!
//! The shell decides nothing: it accepts, connects, binds, reads, writes and closes when the
//! [`Session`] says so or when a socket is ready, and reports every outcome back.

use std::io::{self, Read, Write};
use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4};

use mio::net::{TcpListener, TcpStream, UdpSocket};
use mio::{Interest, Token};

use super::reactor::{DeadlineTimer, Reactor, Ready};
use super::sys::recv_datagrams;
use crate::error::Error;
use crate::proto::buffers::INBOX_SLOTS;
use crate::proto::{IoRequest, PeerId, Session};
use crate::time::TimeSource;

/// Whether a TCP read that leaves part of the buffer unfilled proves the socket empty, so the
/// read that would only return `WouldBlock` can be skipped (one system call per pass saved).
///
/// True for epoll, where mio registers sockets edge-triggered and the kernel raises a new
/// event for every later arrival (epoll(7), Q9; netty's epoll transport and tokio do the
/// same). Not after the poller reported the peer's close, which must be read to the end.
const SHORT_READ_DRAINS: bool = cfg!(any(target_os = "linux", target_os = "android"));

/// Connection requests read from the server's UDP port per pass: a flood of them must not
/// starve the peers' traffic.
const REQUESTS_PER_PASS: usize = 256;
/// TCP connections accepted per pass.
const ACCEPTS_PER_PASS: usize = 64;

/// A socket with the readiness the shell knows about (sticky until a read proves it empty).
struct Sock<S> {
    sock: S,
    token: Token,
    ready: Ready,
}

impl<S: mio::event::Source> Sock<S> {
    fn register(reactor: &Reactor, sock: S, interest: Interest) -> io::Result<Sock<S>> {
        Self::register_as(reactor, sock, interest, false)
    }

    /// A listener: its readiness is not activity (see [`Reactor::register_quiet`]).
    fn register_listener(reactor: &Reactor, sock: S) -> io::Result<Sock<S>> {
        Self::register_as(reactor, sock, Interest::READABLE, true)
    }

    fn register_as(
        reactor: &Reactor,
        mut sock: S,
        interest: Interest,
        quiet: bool,
    ) -> io::Result<Sock<S>> {
        let token = if quiet {
            reactor.register_quiet(&mut sock, interest)?
        } else {
            reactor.register(&mut sock, interest)?
        };
        Ok(Sock {
            sock,
            token,
            ready: Ready {
                readable: true,
                writable: true,
                ..Ready::default()
            },
        })
    }

    /// Merges what the polls saw since the last look.
    fn refresh(&mut self, reactor: &Reactor) {
        let r = reactor.take(self.token);
        self.ready.readable |= r.readable;
        self.ready.writable |= r.writable;
        self.ready.read_closed |= r.read_closed;
        self.ready.error |= r.error;
    }

    fn close(mut self, reactor: &Reactor) {
        reactor.deregister(&mut self.sock, self.token);
    }
}

/// Sockets of one peer.
struct PeerIo {
    id: PeerId,
    tcp: Sock<TcpStream>,
    connecting: bool,
    udp_in: Option<Sock<UdpSocket>>,
    udp_out: Option<UdpSocket>,
}

enum Listeners {
    None,
    Server {
        tcp: Sock<TcpListener>,
        udp: Sock<UdpSocket>,
        nic: Option<Ipv4Addr>,
        port: u16,
    },
    Client {
        /// Where the server calls back (default path only).
        listener: Option<Sock<TcpListener>>,
        /// The socket of the last connection request (reports ICMP errors).
        request: Option<Sock<UdpSocket>>,
    },
}

/// Every socket of one connection.
pub(crate) struct Shell {
    reactor: Option<Reactor>,
    /// Watches the session's next deadline in the poll (made when first needed).
    deadline: Option<DeadlineTimer>,
    /// The reactor's epoch when this shell last took its sockets' readiness.
    seen_epoch: u64,
    listeners: Listeners,
    peers: Vec<Option<PeerIo>>,
    request_buf: [u8; 256],
}

fn v4(a: SocketAddr) -> SocketAddrV4 {
    match a {
        SocketAddr::V4(a) => a,
        SocketAddr::V6(_) => SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0),
    }
}

fn would_block(e: &io::Error) -> bool {
    e.kind() == io::ErrorKind::WouldBlock
}

fn interrupted(e: &io::Error) -> bool {
    e.kind() == io::ErrorKind::Interrupted
}

/// The local address that routes to `server`, found the way C++ does: connect a throw-away
/// UDP socket towards the server and read its local name.
fn local_ip_towards(server: Ipv4Addr) -> Ipv4Addr {
    let probe = std::net::UdpSocket::bind((Ipv4Addr::UNSPECIFIED, 0))
        .and_then(|s| s.connect((server, crate::wire::DEFAULT_PORT)).map(|_| s))
        .and_then(|s| s.local_addr());
    match probe {
        Ok(SocketAddr::V4(a)) if !a.ip().is_unspecified() => *a.ip(),
        _ => Ipv4Addr::UNSPECIFIED,
    }
}

/// Stores the sockets of a new peer at its slot (closing whatever a stale peer left there).
fn put_peer(
    peers: &mut Vec<Option<PeerIo>>,
    reactor: &Reactor,
    id: PeerId,
    tcp: Sock<TcpStream>,
    connecting: bool,
) {
    let slot = id.slot;
    if peers.len() <= slot {
        peers.resize_with(slot + 1, || None);
    }
    if let Some(old) = peers[slot].take() {
        Shell::close_io(old, reactor);
    }
    peers[slot] = Some(PeerIo {
        id,
        tcp,
        connecting,
        udp_in: None,
        udp_out: None,
    });
}

impl Shell {
    /// A connection without sockets (loopback, replay).
    pub(crate) fn none() -> Shell {
        Shell {
            reactor: None,
            deadline: None,
            seen_epoch: 0,
            listeners: Listeners::None,
            peers: Vec::new(),
            request_buf: [0; 256],
        }
    }

    /// A server listening on UDP and TCP at `nic:port` (every interface without a NIC).
    pub(crate) fn server(
        reactor: &Reactor,
        nic: Option<Ipv4Addr>,
        port: u16,
    ) -> Result<Shell, Error> {
        let ip = nic.unwrap_or(Ipv4Addr::UNSPECIFIED);
        // Bind TCP first so port 0 picks a number that UDP then shares.
        let tcp = TcpListener::bind(SocketAddr::V4(SocketAddrV4::new(ip, port)))
            .map_err(|e| Error::io(format!("listening on TCP {ip}:{port}"), e))?;
        let port = tcp
            .local_addr()
            .map_err(|e| Error::io("reading the TCP listener address", e))?
            .port();
        let udp = UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(ip, port)))
            .map_err(|e| Error::io(format!("listening on UDP {ip}:{port}"), e))?;
        let tcp = Sock::register_listener(reactor, tcp)
            .map_err(|e| Error::io("registering listeners", e))?;
        let udp = Sock::register_listener(reactor, udp)
            .map_err(|e| Error::io("registering listeners", e))?;
        Ok(Shell {
            reactor: Some(reactor.clone()),
            deadline: None,
            seen_epoch: 0,
            listeners: Listeners::Server {
                tcp,
                udp,
                nic,
                port,
            },
            peers: Vec::new(),
            request_buf: [0; 256],
        })
    }

    /// A client of `server`; on the default path, also the call-back listener, whose
    /// announced address is returned.
    pub(crate) fn client(
        reactor: &Reactor,
        server: SocketAddrV4,
        tcp_only: bool,
    ) -> Result<(Shell, Option<SocketAddrV4>), Error> {
        let mut listener = None;
        let mut announced = None;
        if !tcp_only {
            let ip = local_ip_towards(*server.ip());
            let l = TcpListener::bind(SocketAddr::V4(SocketAddrV4::new(ip, 0)))
                .map_err(|e| Error::io("opening the TCP call-back listener", e))?;
            let port = l
                .local_addr()
                .map_err(|e| Error::io("reading the call-back listener address", e))?
                .port();
            let shown = if ip.is_unspecified() {
                Ipv4Addr::LOCALHOST
            } else {
                ip
            };
            announced = Some(SocketAddrV4::new(shown, port));
            listener = Some(
                Sock::register_listener(reactor, l)
                    .map_err(|e| Error::io("registering the call-back listener", e))?,
            );
        }
        let shell = Shell {
            reactor: Some(reactor.clone()),
            deadline: None,
            seen_epoch: 0,
            listeners: Listeners::Client {
                listener,
                request: None,
            },
            peers: Vec::new(),
            request_buf: [0; 256],
        };
        Ok((shell, announced))
    }

    /// The reactor the sockets wait in.
    pub(crate) fn reactor(&self) -> Option<&Reactor> {
        self.reactor.as_ref()
    }

    /// Whether the session's next deadline (`Session::poll_timeout`) has passed. With a
    /// reactor a timer in the poll answers, so a pass reads the clock only when the deadline
    /// changes or passes; without one the clock is compared.
    pub(crate) fn deadline_passed(
        &mut self,
        deadline: Option<std::time::Instant>,
        clock: &dyn TimeSource,
    ) -> bool {
        let Some(deadline) = deadline else {
            return false;
        };
        if self.deadline.is_none() {
            self.deadline = self.reactor.as_ref().and_then(DeadlineTimer::new);
        }
        match &mut self.deadline {
            Some(timer) => timer.passed(deadline, clock),
            None => clock.now().mono >= deadline,
        }
    }

    /// The server's port (after binding port 0, the one the OS chose).
    pub(crate) fn server_port(&self) -> Option<u16> {
        match &self.listeners {
            Listeners::Server { port, .. } => Some(*port),
            _ => None,
        }
    }

    fn close_io(io: PeerIo, reactor: &Reactor) {
        io.tcp.close(reactor);
        if let Some(u) = io.udp_in {
            u.close(reactor);
        }
    }

    fn peer_io(&mut self, id: PeerId) -> Option<&mut PeerIo> {
        self.peers
            .get_mut(id.slot)
            .and_then(Option::as_mut)
            .filter(|p| p.id == id)
    }

    // ------------------------------------------------------------------ set-up

    /// Takes what the listeners and connecting sockets are ready for to the session, then
    /// carries out what the session asks.
    pub(crate) fn service(&mut self, clock: &dyn TimeSource, session: &mut Session) {
        let Some(reactor) = self.reactor.clone() else {
            return;
        };
        // Nothing new since the last look (no poll brought events): the sticky flags hold.
        let epoch = reactor.epoch();
        let fresh = epoch != self.seen_epoch;
        self.seen_epoch = epoch;
        let Shell {
            listeners,
            peers,
            request_buf,
            ..
        } = self;
        match listeners {
            Listeners::Server { tcp, udp, .. } => {
                if fresh {
                    tcp.refresh(&reactor);
                    udp.refresh(&reactor);
                }
                for _ in 0..REQUESTS_PER_PASS {
                    if !udp.ready.readable {
                        break;
                    }
                    match udp.sock.recv_from(request_buf) {
                        Ok((n, from)) => {
                            session.handle_request(clock.now(), v4(from), &request_buf[..n]);
                        }
                        Err(e) if would_block(&e) => udp.ready.readable = false,
                        Err(e) if interrupted(&e) => {}
                        Err(_) => {}
                    }
                }
                for _ in 0..ACCEPTS_PER_PASS {
                    if !tcp.ready.readable {
                        break;
                    }
                    match tcp.sock.accept() {
                        Ok((stream, from)) => {
                            let local = stream.local_addr().map(v4).unwrap_or(v4(from));
                            if let Some(id) = session.handle_accept(clock.now(), v4(from), local) {
                                let _ = stream.set_nodelay(true);
                                match Sock::register(
                                    &reactor,
                                    stream,
                                    Interest::READABLE | Interest::WRITABLE,
                                ) {
                                    Ok(tcp) => put_peer(peers, &reactor, id, tcp, false),
                                    Err(e) => session.handle_closed(clock.now(), id, Some(&e)),
                                }
                            }
                        }
                        Err(e) if would_block(&e) => tcp.ready.readable = false,
                        Err(e) if interrupted(&e) => {}
                        Err(_) => tcp.ready.readable = false,
                    }
                }
            }
            Listeners::Client { listener, request } => {
                if let Some(l) = listener.as_mut() {
                    if fresh {
                        l.refresh(&reactor);
                    }
                    while l.ready.readable {
                        match l.sock.accept() {
                            Ok((stream, from)) => {
                                let local = stream.local_addr().map(v4).unwrap_or(v4(from));
                                if let Some(id) =
                                    session.handle_callback(clock.now(), v4(from), local)
                                {
                                    let _ = stream.set_nodelay(true);
                                    match Sock::register(
                                        &reactor,
                                        stream,
                                        Interest::READABLE | Interest::WRITABLE,
                                    ) {
                                        Ok(tcp) => {
                                            if let Some(r) = request.take() {
                                                r.close(&reactor);
                                            }
                                            put_peer(peers, &reactor, id, tcp, false);
                                            break;
                                        }
                                        Err(e) => session.handle_closed(clock.now(), id, Some(&e)),
                                    }
                                }
                                // Further call-backs while one is live are closed on drop.
                            }
                            Err(e) if would_block(&e) => l.ready.readable = false,
                            Err(e) if interrupted(&e) => {}
                            Err(_) => l.ready.readable = false,
                        }
                    }
                }
                if let Some(r) = request.as_mut() {
                    if fresh {
                        r.refresh(&reactor);
                    }
                    if std::mem::take(&mut r.ready.readable) {
                        let mut b = [0u8; 16];
                        if let Err(e) = r.sock.recv(&mut b) {
                            if e.kind() == io::ErrorKind::ConnectionRefused {
                                session.handle_request_refused(clock.now());
                            }
                        }
                    }
                }
            }
            Listeners::None => {}
        }
        // What the poll saw for each peer's sockets (read and flush rely on it for the rest
        // of the pass: only a poll changes it), and connects in progress.
        for slot in 0..self.peers.len() {
            let Some(p) = self.peers[slot].as_mut() else {
                continue;
            };
            if fresh {
                p.tcp.refresh(&reactor);
                if let Some(u) = p.udp_in.as_mut() {
                    u.refresh(&reactor);
                }
            }
            if !p.connecting {
                continue;
            }
            if !p.tcp.ready.writable {
                continue;
            }
            let id = p.id;
            match p.tcp.sock.take_error() {
                Ok(Some(e)) | Err(e) => {
                    session.handle_connect_failed(clock.now(), id, &e);
                    continue;
                }
                Ok(None) => {}
            }
            match p.tcp.sock.peer_addr() {
                Ok(_) => {
                    p.connecting = false;
                    let local = p
                        .tcp
                        .sock
                        .local_addr()
                        .map(v4)
                        .unwrap_or(SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0));
                    session.handle_connected(clock.now(), id, local);
                }
                Err(e) if e.kind() == io::ErrorKind::NotConnected => {
                    p.tcp.ready.writable = false;
                }
                Err(e) => session.handle_connect_failed(clock.now(), id, &e),
            }
        }
        if session.has_io() {
            self.carry_out(clock, session);
        }
    }

    /// Carries out every request the session has queued, reporting each outcome.
    pub(crate) fn carry_out(&mut self, clock: &dyn TimeSource, session: &mut Session) {
        while let Some(req) = session.poll_io() {
            let Some(reactor) = self.reactor.clone() else {
                // No sockets here (loopback, replay): nothing to connect or bind.
                continue;
            };
            match req {
                IoRequest::Connect { peer, addr } => {
                    let started = TcpStream::connect(SocketAddr::V4(addr)).and_then(|s| {
                        let _ = s.set_nodelay(true);
                        Sock::register(&reactor, s, Interest::READABLE | Interest::WRITABLE)
                    });
                    match started {
                        Ok(mut tcp) => {
                            tcp.ready.writable = false;
                            put_peer(&mut self.peers, &reactor, peer, tcp, true);
                        }
                        Err(e) => session.handle_connect_failed(clock.now(), peer, &e),
                    }
                }
                IoRequest::BindUdp { peer } => {
                    let nic = match &self.listeners {
                        Listeners::Server { nic, .. } => *nic,
                        _ => None,
                    };
                    let ip = nic.unwrap_or(Ipv4Addr::UNSPECIFIED);
                    let bound =
                        UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(ip, 0))).and_then(|u| {
                            let port = u.local_addr()?.port();
                            Ok((Sock::register(&reactor, u, Interest::READABLE)?, port))
                        });
                    match (bound, self.peer_io(peer)) {
                        (Ok((sock, port)), Some(p)) => {
                            p.udp_in = Some(sock);
                            session.handle_udp_bound(clock.now(), peer, Some(port));
                        }
                        (Ok((sock, _)), None) => sock.close(&reactor),
                        (Err(_), _) => session.handle_udp_bound(clock.now(), peer, None),
                    }
                }
                IoRequest::OpenUdpOut { peer, addr } => {
                    let sock = UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(
                        Ipv4Addr::UNSPECIFIED,
                        0,
                    )))
                    .and_then(|s| s.connect(SocketAddr::V4(addr)).map(|_| s));
                    let ok = match (sock, self.peer_io(peer)) {
                        (Ok(s), Some(p)) => {
                            p.udp_out = Some(s);
                            true
                        }
                        _ => false,
                    };
                    session.handle_udp_out(clock.now(), peer, ok);
                }
                IoRequest::Close { peer } => {
                    if let Some(io) = self
                        .peers
                        .get_mut(peer.slot)
                        .and_then(|s| s.take_if(|p| p.id == peer))
                    {
                        Self::close_io(io, &reactor);
                    }
                }
                IoRequest::SendRequest { to } => {
                    let Listeners::Client { request, .. } = &mut self.listeners else {
                        continue;
                    };
                    if let Some(old) = request.take() {
                        old.close(&reactor);
                    }
                    let sent = UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(
                        Ipv4Addr::UNSPECIFIED,
                        0,
                    )))
                    .and_then(|s| s.connect(SocketAddr::V4(to)).map(|_| s))
                    .and_then(|s| {
                        s.send(session.request_text())?;
                        Sock::register(&reactor, s, Interest::READABLE)
                    });
                    match sent {
                        Ok(mut s) => {
                            s.ready.readable = false;
                            *request = Some(s);
                        }
                        Err(e) => session.report_request_error(clock.now(), to, &e),
                    }
                }
            }
        }
    }

    // ------------------------------------------------------------------ bytes

    /// Reads once from every socket whose peer wants input. Returns whether bytes came.
    pub(crate) fn read(&mut self, clock: &dyn TimeSource, session: &mut Session) -> bool {
        let mut got = false;
        for slot in 0..self.peers.len() {
            let Some(p) = self.peers[slot].as_mut() else {
                continue;
            };
            if p.connecting {
                continue;
            }
            let id = p.id;
            if p.tcp.ready.readable {
                let spare = session.rx_spare(id);
                let spare_len = spare.len();
                if spare_len > 0 {
                    match p.tcp.sock.read(spare) {
                        Ok(0) => {
                            session.handle_closed(clock.now(), id, None);
                            continue;
                        }
                        Ok(n) => {
                            session.handle_tcp_data(id, n);
                            got = true;
                            if SHORT_READ_DRAINS && n < spare_len && !p.tcp.ready.read_closed {
                                p.tcp.ready.readable = false;
                            }
                        }
                        Err(e) if would_block(&e) => p.tcp.ready.readable = false,
                        Err(e) if interrupted(&e) => {}
                        Err(e) => {
                            session.handle_closed(clock.now(), id, Some(&e));
                            continue;
                        }
                    }
                }
            }
            let Some(u) = p.udp_in.as_mut() else {
                continue;
            };
            if !u.ready.readable {
                continue;
            }
            let Some(inbox) = session.udp_inbox(id) else {
                continue;
            };
            match recv_datagrams(&u.sock, inbox) {
                Ok(n) => {
                    session.handle_datagrams(id, n);
                    got = true;
                    // A short batch proves the queue empty (edge-triggered epoll raises a new
                    // event for the next arrival): no WouldBlock call needed.
                    if n < INBOX_SLOTS && SHORT_READ_DRAINS {
                        u.ready.readable = false;
                    }
                }
                Err(e) if would_block(&e) => u.ready.readable = false,
                Err(_) => u.ready.readable = false,
            }
        }
        if got {
            if let Some(r) = &self.reactor {
                r.note_activity();
            }
        }
        got
    }

    /// Writes what the session queued, as far as the sockets take it.
    pub(crate) fn flush(&mut self, clock: &dyn TimeSource, session: &mut Session) {
        for slot in 0..self.peers.len() {
            let Some(p) = self.peers[slot].as_mut() else {
                continue;
            };
            if p.connecting {
                continue;
            }
            let id = p.id;
            // After a WouldBlock, wait for the writable event (taken from the poll at the start
            // of the pass) instead of retrying every pass: a stalled peer would otherwise cost
            // a failing write per pass.
            let mut failed = None;
            while p.tcp.ready.writable {
                let pending = session.tcp_pending(id);
                if pending.is_empty() {
                    break;
                }
                match p.tcp.sock.write(pending) {
                    Ok(0) => break,
                    Ok(n) => session.tcp_sent(id, n),
                    Err(e) if would_block(&e) => p.tcp.ready.writable = false,
                    Err(e) if interrupted(&e) => {}
                    Err(e) => {
                        failed = Some(e);
                        break;
                    }
                }
            }
            if let Some(e) = failed {
                session.handle_send_failed(clock.now(), id, &e);
                continue;
            }
            match &p.udp_out {
                Some(sock) => {
                    while let Some(dg) = session.udp_front(id) {
                        match sock.send(dg) {
                            Err(e) if would_block(&e) => break,
                            // Unreliable: a refused or failed datagram is simply lost.
                            _ => session.udp_sent(id),
                        }
                    }
                }
                None => {
                    while session.udp_front(id).is_some() {
                        session.udp_sent(id);
                    }
                }
            }
        }
        if session.has_io() {
            self.carry_out(clock, session);
        }
    }
}

impl Drop for Shell {
    fn drop(&mut self) {
        if let Some(r) = self.reactor.clone() {
            for io in self.peers.drain(..).flatten() {
                Shell::close_io(io, &r);
            }
            match std::mem::replace(&mut self.listeners, Listeners::None) {
                Listeners::Server { tcp, udp, .. } => {
                    tcp.close(&r);
                    udp.close(&r);
                }
                Listeners::Client { listener, request } => {
                    if let Some(l) = listener {
                        l.close(&r);
                    }
                    if let Some(q) = request {
                        q.close(&r);
                    }
                }
                Listeners::None => {}
            }
        }
    }
}
