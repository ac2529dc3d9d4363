//! The sockets of one connection, and the byte movement between them and its session.
//!
//! The shell decides nothing: it accepts, connects, binds, reads, writes and closes when the
//! [`Session`] says so or when a socket is ready, and reports every outcome back.

use std::io::{self, Read, Write};
use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4};

use mio::net::{TcpListener, TcpStream, UdpSocket};
use mio::{Interest, Token};

use super::reactor::{DeadlineTimer, Reactor, ReadyBits};
use super::sys::{recv_datagrams, SendBatch, SEND_BATCH};
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

/// A socket and its readiness: set by the reactor's polls, sticky until a call on the socket
/// proves it stale.
struct Sock<S> {
    sock: S,
    token: Token,
    ready: ReadyBits,
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
        // Ready until a call says otherwise: an event may have come before registration.
        let ready = ReadyBits::new(ReadyBits::READABLE | ReadyBits::WRITABLE);
        let token = reactor.register_shared(&mut sock, interest, quiet, &ready)?;
        Ok(Sock { sock, token, ready })
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
    /// The address `udp_in` is connected to (`IoRequest::PinUdpSource`): every datagram comes
    /// from there, and receiving need not ask the kernel for sources.
    udp_source: Option<SocketAddrV4>,
    /// Where this peer's datagrams go (through the shell's one outbound socket).
    udp_dest: Option<SocketAddrV4>,
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
    /// A peer's TCP connect may be in progress (cleared by the pass that finds none).
    any_connecting: bool,
    listeners: Listeners,
    peers: Vec<Option<PeerIo>>,
    request_buf: [u8; 256],
    /// The one outbound UDP socket of every peer (unconnected, made with the first peer's
    /// channel): every peer's datagrams of a pass go out in one `sendmmsg`.
    udp_out: Option<UdpSocket>,
    /// Where `udp_out` is connected (a client's one server, a server's first UDP client):
    /// datagrams to it go without an address, through the socket's cached route and IP-id
    /// counter; the others name their destination.
    udp_out_peer: Option<SocketAddrV4>,
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
        udp_source: None,
        udp_dest: None,
    });
}

impl Shell {
    /// A connection without sockets (loopback, replay).
    pub(crate) fn none() -> Shell {
        Shell {
            reactor: None,
            deadline: None,
            any_connecting: false,
            listeners: Listeners::None,
            peers: Vec::new(),
            request_buf: [0; 256],
            udp_out: None,
            udp_out_peer: None,
        }
    }

    /// A server listening on UDP and TCP at `nic:port` (every interface without a NIC).
    pub(crate) fn server(
        reactor: &Reactor,
        nic: Option<Ipv4Addr>,
        port: u16,
    ) -> Result<Shell, Error> {
        let ip = nic.unwrap_or(Ipv4Addr::UNSPECIFIED);
        let (tcp, udp, port) = bind_listeners(ip, port)?;
        let tcp = Sock::register_listener(reactor, tcp)
            .map_err(|e| Error::io("registering listeners", e))?;
        let udp = Sock::register_listener(reactor, udp)
            .map_err(|e| Error::io("registering listeners", e))?;
        Ok(Shell {
            reactor: Some(reactor.clone()),
            deadline: None,
            any_connecting: false,
            listeners: Listeners::Server {
                tcp,
                udp,
                nic,
                port,
            },
            peers: Vec::new(),
            request_buf: [0; 256],
            udp_out: None,
            udp_out_peer: None,
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
            any_connecting: false,
            listeners: Listeners::Client {
                listener,
                request: None,
            },
            peers: Vec::new(),
            request_buf: [0; 256],
            udp_out: None,
            udp_out_peer: None,
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
    #[inline]
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

    /// Whether a listener or a connecting socket may have something for [`service`]
    /// (a few loads: most passes have nothing to set up).
    #[inline]
    fn setup_pending(&self) -> bool {
        self.any_connecting
            || match &self.listeners {
                Listeners::Server { tcp, udp, .. } => tcp.ready.readable() || udp.ready.readable(),
                Listeners::Client { listener, request } => {
                    listener.as_ref().is_some_and(|l| l.ready.readable())
                        || request.as_ref().is_some_and(|r| r.ready.readable())
                }
                Listeners::None => false,
            }
    }

    /// Takes what the listeners and connecting sockets are ready for to the session, then
    /// carries out what the session asks.
    #[inline]
    pub(crate) fn service(&mut self, clock: &dyn TimeSource, session: &mut Session) {
        if self.setup_pending() {
            self.service_setup(clock, session);
        }
        if session.has_io() {
            self.carry_out(clock, session);
        }
    }

    #[inline(never)]
    fn service_setup(&mut self, clock: &dyn TimeSource, session: &mut Session) {
        let Some(reactor) = self.reactor.clone() else {
            return;
        };
        let Shell {
            listeners,
            peers,
            request_buf,
            ..
        } = self;
        match listeners {
            Listeners::Server { tcp, udp, .. } => {
                for _ in 0..REQUESTS_PER_PASS {
                    if !udp.ready.readable() {
                        break;
                    }
                    match udp.sock.recv_from(request_buf) {
                        Ok((n, from)) => {
                            session.handle_request(clock.now(), v4(from), &request_buf[..n]);
                        }
                        Err(e) if would_block(&e) => udp.ready.clear(ReadyBits::READABLE),
                        Err(e) if interrupted(&e) => {}
                        Err(_) => {}
                    }
                }
                for _ in 0..ACCEPTS_PER_PASS {
                    if !tcp.ready.readable() {
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
                        Err(e) if would_block(&e) => tcp.ready.clear(ReadyBits::READABLE),
                        Err(e) if interrupted(&e) => {}
                        Err(_) => tcp.ready.clear(ReadyBits::READABLE),
                    }
                }
            }
            Listeners::Client { listener, request } => {
                if let Some(l) = listener.as_mut() {
                    while l.ready.readable() {
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
                            Err(e) if would_block(&e) => l.ready.clear(ReadyBits::READABLE),
                            Err(e) if interrupted(&e) => {}
                            Err(_) => l.ready.clear(ReadyBits::READABLE),
                        }
                    }
                }
                if let Some(r) = request.as_mut() {
                    if r.ready.readable() {
                        r.ready.clear(ReadyBits::READABLE);
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
        // Connects in progress.
        if !self.any_connecting {
            return;
        }
        self.any_connecting = false;
        for slot in 0..self.peers.len() {
            let Some(p) = self.peers[slot].as_mut() else {
                continue;
            };
            if !p.connecting {
                continue;
            }
            self.any_connecting = true;
            if !p.tcp.ready.writable() {
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
                    p.tcp.ready.clear(ReadyBits::WRITABLE);
                }
                Err(e) => session.handle_connect_failed(clock.now(), id, &e),
            }
        }
    }

    /// Carries out every request the session has queued, reporting each outcome.
    #[inline(never)]
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
                        Ok(tcp) => {
                            tcp.ready.clear(ReadyBits::WRITABLE);
                            put_peer(&mut self.peers, &reactor, peer, tcp, true);
                            self.any_connecting = true;
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
                    if self.udp_out.is_none() {
                        self.udp_out = open_udp_out().ok();
                    }
                    // Connect the socket to this peer unless another live peer holds that
                    // fast path already (a client's one server, or a server's first client;
                    // datagrams to the others carry their address).
                    let taken = self.udp_out_peer.is_some_and(|held| {
                        held != addr
                            && self
                                .peers
                                .iter()
                                .flatten()
                                .any(|p| p.id != peer && p.udp_dest == Some(held))
                    });
                    if let (false, Some(s)) = (taken, &self.udp_out) {
                        self.udp_out_peer = s.connect(SocketAddr::V4(addr)).ok().map(|_| addr);
                    }
                    let have_socket = self.udp_out.is_some();
                    let ok = match self.peer_io(peer) {
                        Some(p) if have_socket => {
                            p.udp_dest = Some(addr);
                            true
                        }
                        _ => false,
                    };
                    session.handle_udp_out(clock.now(), peer, ok);
                }
                IoRequest::PinUdpSource { peer, source } => {
                    // Best effort: a socket that cannot be connected keeps receiving with
                    // sources, and the session keeps checking them.
                    if let Some(p) = self.peer_io(peer) {
                        if let Some(u) = &p.udp_in {
                            if u.sock.connect(SocketAddr::V4(source)).is_ok() {
                                p.udp_source = Some(source);
                            }
                        }
                    }
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
                        Ok(s) => {
                            s.ready.clear(ReadyBits::READABLE);
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
    ///
    /// The loop only looks at readiness bits; the reads themselves are in functions of their
    /// own, so the many passes that find nothing to read stay cheap.
    pub(crate) fn read(&mut self, clock: &dyn TimeSource, session: &mut Session) -> bool {
        let mut got = false;
        for p in self.peers.iter_mut().flatten() {
            if p.connecting {
                continue;
            }
            if p.tcp.ready.readable() {
                match read_tcp(&mut p.tcp, p.id, clock, session) {
                    Some(bytes) => got |= bytes,
                    // Closed: its UDP channel went with it.
                    None => continue,
                }
            }
            if let Some(u) = &p.udp_in {
                if u.ready.readable() {
                    got |= read_udp(u, p.udp_source, p.id, session);
                }
            }
        }
        if got {
            if let Some(r) = &self.reactor {
                r.note_activity();
            }
        }
        got
    }

    /// Writes what the session queued, as far as the sockets take it: one write per peer with
    /// reliable bytes waiting, and every peer's datagrams in one `sendmmsg` (a batch of
    /// [`SEND_BATCH`]; more go in further calls).
    pub(crate) fn flush(&mut self, clock: &dyn TimeSource, session: &mut Session) {
        let mut datagrams = false;
        for p in self.peers.iter_mut().flatten() {
            if p.connecting {
                continue;
            }
            let id = p.id;
            // After a WouldBlock, wait for the writable event instead of retrying every pass:
            // a stalled peer would otherwise cost a failing write per pass.
            if p.tcp.ready.writable()
                && !session.tcp_pending(id).is_empty()
                && !write_tcp(&mut p.tcp, id, clock, session)
            {
                continue;
            }
            datagrams |= p.udp_dest.is_some() && session.udp_queue(id).is_some();
        }
        if datagrams {
            self.send_datagrams(session);
        }
        if session.has_io() {
            self.carry_out(clock, session);
        }
    }

    /// Sends the datagrams waiting for every peer, peer after peer, in as few `sendmmsg`
    /// calls as the batch size allows. What the socket does not take now stays queued (the
    /// peer's ring drops its oldest datagrams if that goes on).
    #[inline(never)]
    fn send_datagrams(&mut self, session: &mut Session) {
        let Some(out) = &self.udp_out else {
            return;
        };
        loop {
            let mut batch = SendBatch::new();
            'fill: for p in self.peers.iter().flatten() {
                let (Some(dest), Some(queue)) = (p.udp_dest, session.udp_queue(p.id)) else {
                    continue;
                };
                let to = (self.udp_out_peer != Some(dest)).then_some(dest);
                for datagram in queue.iter() {
                    if !batch.push(to, datagram) {
                        break 'fill;
                    }
                }
            }
            let total = batch.len();
            if total == 0 {
                return;
            }
            let sent = batch.send(out);
            // Take out what went, walking the peers in the same order as the batch was filled.
            let mut left = sent;
            for p in self.peers.iter().flatten() {
                if left == 0 {
                    break;
                }
                if p.udp_dest.is_some() {
                    left -= session.udp_consume(p.id, left);
                }
            }
            if sent < total || total < SEND_BATCH {
                return;
            }
        }
    }
}

/// The shell's outbound UDP socket: unbound to any peer, on any interface (the kernel picks
/// the source address by route, as it did for one connected socket per peer), with room for a
/// pass's datagrams to every peer.
fn open_udp_out() -> io::Result<UdpSocket> {
    let s = UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0)))?;
    // Best effort: the kernel caps it at net.core.wmem_max.
    let _ = nix::sys::socket::setsockopt(
        std::os::fd::AsRawFd::as_raw_fd(&s),
        nix::sys::socket::sockopt::SndBuf,
        &(1usize << 20),
    );
    Ok(s)
}

/// One read from a peer's TCP socket into the session. `Some(true)` when bytes came, `None`
/// when the peer closed (or the socket failed).
#[inline(never)]
fn read_tcp(
    tcp: &mut Sock<TcpStream>,
    id: PeerId,
    clock: &dyn TimeSource,
    session: &mut Session,
) -> Option<bool> {
    let spare = session.rx_spare(id);
    let spare_len = spare.len();
    if spare_len == 0 {
        return Some(false);
    }
    match tcp.sock.read(spare) {
        Ok(0) => {
            session.handle_closed(clock.now(), id, None);
            None
        }
        Ok(n) => {
            session.handle_tcp_data(id, n);
            if SHORT_READ_DRAINS && n < spare_len && !tcp.ready.read_closed() {
                tcp.ready.clear(ReadyBits::READABLE);
            }
            Some(true)
        }
        Err(e) if would_block(&e) => {
            tcp.ready.clear(ReadyBits::READABLE);
            Some(false)
        }
        Err(e) if interrupted(&e) => Some(false),
        Err(e) => {
            session.handle_closed(clock.now(), id, Some(&e));
            None
        }
    }
}

/// One batch of datagrams from a peer's UDP socket into the session; true when any came.
#[inline(never)]
fn read_udp(
    u: &Sock<UdpSocket>,
    source: Option<SocketAddrV4>,
    id: PeerId,
    session: &mut Session,
) -> bool {
    let Some(inbox) = session.udp_inbox(id) else {
        return false;
    };
    match recv_datagrams(&u.sock, inbox, source) {
        Ok(n) => {
            // As `handle_datagrams`, without looking the peer up again.
            inbox.filled(n);
            session.note_input();
            // A short batch proves the queue empty (edge-triggered epoll raises a new event
            // for the next arrival): no WouldBlock call needed.
            if n < INBOX_SLOTS && SHORT_READ_DRAINS {
                u.ready.clear(ReadyBits::READABLE);
            }
            true
        }
        Err(_) => {
            u.ready.clear(ReadyBits::READABLE);
            false
        }
    }
}

/// Writes a peer's queued stream bytes until done or the socket is full. False when the
/// write failed (the session was told and drops the peer).
#[inline(never)]
fn write_tcp(
    tcp: &mut Sock<TcpStream>,
    id: PeerId,
    clock: &dyn TimeSource,
    session: &mut Session,
) -> bool {
    while tcp.ready.writable() {
        let pending = session.tcp_pending(id);
        if pending.is_empty() {
            break;
        }
        match tcp.sock.write(pending) {
            Ok(0) => break,
            Ok(n) => session.tcp_sent(id, n),
            Err(e) if would_block(&e) => tcp.ready.clear(ReadyBits::WRITABLE),
            Err(e) if interrupted(&e) => {}
            Err(e) => {
                session.handle_send_failed(clock.now(), id, &e);
                return false;
            }
        }
    }
    true
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

/// Binds a server's TCP and UDP listeners to one port. TCP is bound first so that port 0 picks
/// a number UDP then shares; that number may already be some other program's UDP port, in which
/// case another number is tried (only for port 0: a port the user named is theirs to fix).
fn bind_listeners(ip: Ipv4Addr, wanted: u16) -> Result<(TcpListener, UdpSocket, u16), Error> {
    const ATTEMPTS: usize = 16;
    let mut attempt = 0;
    loop {
        attempt += 1;
        let tcp = TcpListener::bind(SocketAddr::V4(SocketAddrV4::new(ip, wanted)))
            .map_err(|e| Error::io(format!("listening on TCP {ip}:{wanted}"), e))?;
        let port = tcp
            .local_addr()
            .map_err(|e| Error::io("reading the TCP listener address", e))?
            .port();
        match UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(ip, port))) {
            Ok(udp) => return Ok((tcp, udp, port)),
            Err(e) if wanted == 0 && e.kind() == io::ErrorKind::AddrInUse && attempt < ATTEMPTS => {
            }
            Err(e) => return Err(Error::io(format!("listening on UDP {ip}:{port}"), e)),
        }
    }
}
