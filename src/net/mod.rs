//! The mio shell: sockets, readiness and the byte movement between sockets and endpoints.
//!
//! [`Core`] owns every socket of one connection and the sans-IO [`Endpoint`]s they feed. It
//! never calls user code: it produces [`Delivery`] items that the public
//! [`Connection`](crate::Connection) hands to handlers with no borrow held.

use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4, ToSocketAddrs};
use std::time::{Duration, Instant};

use mio::net::{TcpListener, TcpStream, UdpSocket};
use mio::{Events, Interest, Poll, Token};

use crate::connection::endpoint::{
    Channel, DatagramInbox, Endpoint, Phase, INBOX_SLOT, INBOX_SLOTS,
};
use crate::connection::names::Names;
use crate::connection::{ConnectionEvent, ConnectionState, Limits, Notice, Severity};
use crate::error::Error;
use crate::log::replay::Replay;
use crate::log::{log_cookie_from_peer, LogError, LogWriter};
use crate::time::TimeVal;
use crate::wire::{self, class, system, Cookie, COOKIE_LEN};

const SERVER_TCP: Token = Token(0);
const SERVER_UDP: Token = Token(1);
const CLIENT_LISTEN: Token = Token(2);
const CLIENT_LOB: Token = Token(3);
/// The timerfd that wakes the poll at a device deadline with sub-millisecond precision.
const TIMER: Token = Token(4);
const PEER_BASE: usize = 16;
const TOK_TCP: usize = 0;
const TOK_UDP_IN: usize = 1;

/// Whether a TCP read that leaves part of the buffer unfilled proves the socket empty, so the
/// read that would only return `WouldBlock` can be skipped (one system call per pass saved).
///
/// True for epoll, where mio registers sockets edge-triggered and the kernel raises a new
/// event for every later arrival (epoll(7), Q9; netty's epoll transport and tokio do the
/// same). Not after the poller reported the peer's close, which must be read to the end.
const SHORT_READ_DRAINS: bool = cfg!(any(target_os = "linux", target_os = "android"));

/// What the core hands to the dispatcher, in order.
pub(crate) enum Delivery {
    /// A user message; its payload is in `Core::scratch[..len]`.
    Message {
        time: TimeVal,
        sender: i32,
        type_id: i32,
        len: usize,
    },
    Event(ConnectionEvent),
    Notice(Notice),
    /// A sender name the peer described for the first time (local id).
    PeerSender(i32),
}

/// Sockets of one peer.
pub(crate) struct PeerIo {
    tcp: TcpStream,
    udp_in: Option<UdpSocket>,
    udp_out: Option<UdpSocket>,
    tcp_readable: bool,
    /// The poller reported the peer's close or an error: read until `WouldBlock` or end.
    tcp_read_closed: bool,
    udp_readable: bool,
    tcp_writable: bool,
    /// Deadline for a call-back or TCP connect to complete.
    connect_deadline: Option<Instant>,
}

pub(crate) struct Peer {
    pub(crate) ep: Endpoint,
    io: PeerIo,
    /// This peer's incoming log (`vrpn_server -li`: one file per client).
    log_in: Option<LogWriter>,
}

/// Server-side listening sockets.
pub(crate) struct ServerNet {
    tcp: TcpListener,
    udp: UdpSocket,
    nic: Option<Ipv4Addr>,
    tcp_readable: bool,
    udp_readable: bool,
    pub(crate) port: u16,
}

/// Client-side connection attempt state.
pub(crate) struct ClientNet {
    host: String,
    server: SocketAddrV4,
    tcp_only: bool,
    listener: Option<TcpListener>,
    listen_addr: SocketAddrV4,
    listener_readable: bool,
    lob: Option<UdpSocket>,
    lob_readable: bool,
    next_attempt: Instant,
    attempts_since_connected: u32,
    waiting_since: Instant,
    warned_no_answer: bool,
    warned_refused: bool,
    ever_connected: bool,
    /// Sequence numbers carried across reconnects, as a C++ client does.
    seq: (u32, u32),
    /// Per-endpoint state is kept here while no peer exists (reconnect).
    pub(crate) retry_interval: Duration,
}

pub(crate) enum Kind {
    Loopback,
    Server(ServerNet),
    Client(Box<ClientNet>),
    /// Replay of a log file: entries go through the same translation as a live peer's.
    File(Box<FileNet>),
}

/// A log replay and the id tables of the session it recorded.
pub(crate) struct FileNet {
    pub(crate) replay: Replay,
    ep: Endpoint,
}

/// Everything a connection owns except its handlers.
pub(crate) struct Core {
    pub(crate) kind: Kind,
    pub(crate) names: Names,
    pub(crate) peers: Vec<Option<Peer>>,
    poll: Option<Poll>,
    events: Events,
    pub(crate) scratch: Vec<u8>,
    pub(crate) connected: usize,
    queue: VecDeque<Delivery>,
    /// Local ids newly registered because a peer described them: to be described to all peers.
    to_describe: Vec<(bool, i32)>,
    pub(crate) limits: Limits,
    cursor: usize,
    budget: usize,
    /// Set whenever a socket showed activity; the server loop uses it for its busy-poll window.
    pub(crate) activity: bool,
    /// Connection-wide incoming log (client connections).
    log_in: Option<LogWriter>,
    /// Outgoing log: everything this side packs (client, or `vrpn_server -lo`).
    log_out: Option<LogWriter>,
    /// `vrpn_server -li`: file name to which `-N` is added for the N-th client.
    log_in_template: Option<(String, u32)>,
    log_failed: bool,
    /// Precise wake-ups (epoll timeouts are whole milliseconds, rounded up).
    timer: Option<Timer>,
}

/// A one-shot monotonic timer in the poll set (Linux timerfd).
#[cfg(any(target_os = "linux", target_os = "android"))]
struct Timer(nix::sys::timerfd::TimerFd);

#[cfg(not(any(target_os = "linux", target_os = "android")))]
struct Timer;

#[cfg(any(target_os = "linux", target_os = "android"))]
impl Timer {
    fn new(poll: &Poll) -> Option<Timer> {
        use nix::sys::timerfd::{ClockId, TimerFd, TimerFlags};
        use std::os::fd::AsRawFd;
        let fd = TimerFd::new(ClockId::CLOCK_MONOTONIC, TimerFlags::TFD_NONBLOCK).ok()?;
        poll.registry()
            .register(
                &mut mio::unix::SourceFd(&fd.as_raw_fd()),
                TIMER,
                Interest::READABLE,
            )
            .ok()?;
        Some(Timer(fd))
    }

    /// Fires once after `d`; false if the timer cannot be set.
    fn arm(&self, d: Duration) -> bool {
        use nix::sys::time::TimeSpec;
        use nix::sys::timerfd::{Expiration, TimerSetTimeFlags};
        let d = d.max(Duration::from_nanos(1));
        self.0
            .set(
                Expiration::OneShot(TimeSpec::from_duration(d)),
                TimerSetTimeFlags::empty(),
            )
            .is_ok()
    }

    fn clear(&self) {
        use std::os::fd::AsRawFd;
        let _ = nix::unistd::read(self.0.as_raw_fd(), &mut [0u8; 8]);
    }
}

#[cfg(not(any(target_os = "linux", target_os = "android")))]
impl Timer {
    fn new(_: &Poll) -> Option<Timer> {
        None
    }
    fn arm(&self, _: Duration) -> bool {
        false
    }
    fn clear(&self) {}
}

fn would_block(e: &io::Error) -> bool {
    e.kind() == io::ErrorKind::WouldBlock
}

fn interrupted(e: &io::Error) -> bool {
    e.kind() == io::ErrorKind::Interrupted
}

/// Resolves `host` to its first IPv4 address.
pub(crate) fn resolve_v4(host: &str, port: u16) -> Result<SocketAddrV4, Error> {
    let addrs = (host, port).to_socket_addrs().map_err(|e| Error::Resolve {
        host: host.to_string(),
        reason: e.to_string(),
    })?;
    for a in addrs {
        if let SocketAddr::V4(v4) = a {
            return Ok(v4);
        }
    }
    Err(Error::Resolve {
        host: host.to_string(),
        reason: "no IPv4 address (VRPN 07 is IPv4 only)".into(),
    })
}

/// The local address that routes to `server`, found the way C++ does: connect a throw-away
/// UDP socket towards the server and read its local name.
fn local_ip_towards(server: Ipv4Addr) -> Ipv4Addr {
    let probe = std::net::UdpSocket::bind((Ipv4Addr::UNSPECIFIED, 0))
        .and_then(|s| s.connect((server, wire::DEFAULT_PORT)).map(|_| s))
        .and_then(|s| s.local_addr());
    match probe {
        Ok(SocketAddr::V4(a)) if !a.ip().is_unspecified() => *a.ip(),
        _ => Ipv4Addr::UNSPECIFIED,
    }
}

impl Core {
    fn with_kind(kind: Kind, poll: Option<Poll>, limits: Limits) -> Core {
        Core {
            kind,
            names: Names::new(),
            peers: Vec::new(),
            poll,
            events: Events::with_capacity(256),
            scratch: vec![0; wire::MAX_TCP_PADDED_PAYLOAD],
            connected: 0,
            queue: VecDeque::with_capacity(64),
            to_describe: Vec::with_capacity(16),
            limits,
            cursor: 0,
            budget: 0,
            activity: false,
            log_in: None,
            log_out: None,
            log_in_template: None,
            log_failed: false,
            timer: None,
        }
    }

    /// Waits for socket readiness until `deadline` (precisely, through a timerfd) or at most
    /// `max`. Returns whether a socket became ready.
    pub(crate) fn wait_until(
        &mut self,
        deadline: Option<Instant>,
        max: Duration,
    ) -> Result<bool, Error> {
        let mut timeout = max;
        if let Some(d) = deadline {
            let until = d.saturating_duration_since(Instant::now());
            if until.is_zero() {
                return self.poll_io(Some(Duration::ZERO));
            }
            if until < max {
                if self.timer.is_none() {
                    self.timer = self.poll.as_ref().and_then(Timer::new);
                }
                let armed = self.timer.as_ref().is_some_and(|t| t.arm(until));
                // Without a timer, fall back to the poll's millisecond timeout.
                timeout = if armed { max } else { until };
            }
        }
        self.poll_io(Some(timeout))
    }

    /// A replay of the log at `path`.
    pub(crate) fn file(path: &str, limits: Limits) -> Result<Core, Error> {
        let replay = Replay::open(path).map_err(|e| Error::Log(e.to_string()))?;
        let net = FileNet {
            replay,
            ep: {
                let mut ep = Endpoint::new(true, format!("file:{path}"), 0);
                ep.phase = Phase::Connected;
                ep
            },
        };
        Ok(Core::with_kind(Kind::File(Box::new(net)), None, limits))
    }

    // ------------------------------------------------------------------ logging

    /// Starts logging what this side receives. Clients: one file, across reconnects. Servers:
    /// one file per accepted client, `-N` added before the extension.
    pub(crate) fn log_incoming(&mut self, path: &str) -> Result<(), Error> {
        match &self.kind {
            Kind::Server(_) => {
                self.log_in_template = Some((path.to_string(), 0));
                Ok(())
            }
            _ => {
                let w = LogWriter::create(path, &Cookie::ours(0).to_bytes())
                    .map_err(|e| Error::Log(e.to_string()))?;
                self.log_in = Some(w);
                Ok(())
            }
        }
    }

    /// Starts logging everything this side packs, from now on.
    pub(crate) fn log_outgoing(&mut self, path: &str) -> Result<(), Error> {
        let w = LogWriter::create(path, &Cookie::ours(0).to_bytes())
            .map_err(|e| Error::Log(e.to_string()))?;
        self.log_out = Some(w);
        Ok(())
    }

    fn open_peer_log(&mut self, slot: usize) {
        let Some((template, n)) = self.log_in_template.as_mut() else {
            return;
        };
        *n += 1;
        let name = compound_log_name(template, *n);
        match LogWriter::create(&name, &Cookie::ours(0).to_bytes()) {
            Ok(w) => {
                if let Some(Some(p)) = self.peers.get_mut(slot) {
                    p.log_in = Some(w);
                }
            }
            Err(e) => self.notice(Severity::Error, format!("cannot open incoming log: {e}")),
        }
    }

    fn log_outgoing_message(&mut self, type_id: i32, sender: i32, time: TimeVal, payload: &[u8]) {
        if let Some(w) = self.log_out.as_mut() {
            if let Err(e) = w.log_message(type_id, sender, time, payload) {
                self.log_error(e);
            }
        }
    }

    fn log_error(&mut self, e: LogError) {
        if !self.log_failed {
            self.log_failed = true;
            self.notice(Severity::Error, format!("logging failed: {e}"));
        }
    }

    /// Writes a bounded amount of buffered log data (called every pass; never stalls long).
    pub(crate) fn flush_logs_some(&mut self, max_bytes: usize) {
        let mut err = None;
        for w in self.log_in.iter_mut().chain(self.log_out.iter_mut()).chain(
            self.peers
                .iter_mut()
                .flatten()
                .filter_map(|p| p.log_in.as_mut()),
        ) {
            if w.pending() > 0 {
                if let Err(e) = w.flush_some(max_bytes) {
                    err = Some(e);
                }
            }
        }
        if let Some(e) = err {
            self.log_error(e);
        }
    }

    /// Writes every buffered log byte.
    pub(crate) fn flush_logs_all(&mut self) -> Result<(), Error> {
        for w in self.log_in.iter_mut().chain(self.log_out.iter_mut()).chain(
            self.peers
                .iter_mut()
                .flatten()
                .filter_map(|p| p.log_in.as_mut()),
        ) {
            w.flush_all().map_err(|e| Error::Log(e.to_string()))?;
        }
        Ok(())
    }

    /// Ends logging: a DISCONNECT entry closes the outgoing log (as C++ at shutdown).
    pub(crate) fn close_logs(&mut self) -> Result<(), Error> {
        if self.log_out.is_some() && !matches!(self.kind, Kind::Client(_)) || self.connected > 0 {
            self.log_outgoing_message(system::DISCONNECT, 0, TimeVal::now(), &[]);
        }
        let r = self.flush_logs_all();
        self.log_out = None;
        self.log_in = None;
        for p in self.peers.iter_mut().flatten() {
            p.log_in = None;
        }
        r
    }

    // ------------------------------------------------------------------ replay

    fn next_from_file(&mut self) -> Option<Delivery> {
        loop {
            let Kind::File(f) = &mut self.kind else {
                return None;
            };
            if f.replay.take_reset() {
                f.ep.clear_remote_names();
                return Some(Delivery::Event(ConnectionEvent::DroppedConnection));
            }
            let Some(due) = f.replay.next_due() else {
                if let Some(e) = f.replay.take_error() {
                    let text = format!(
                        "replay stopped at damaged data (every whole message before it was played): {e}"
                    );
                    return Some(Delivery::Notice(Notice {
                        severity: Severity::Error,
                        text,
                    }));
                }
                return None;
            };
            let len = due.header.payload_len as usize;
            let payload = &f.replay.bytes()[due.payload_at..due.payload_at + len];
            self.scratch[..len].copy_from_slice(payload);
            if let Some(w) = self.log_in.as_mut() {
                // Re-log of a replay: original entry, playback wall-clock time (C++ §7.3).
                let _ = w.log_message(
                    due.header.type_id,
                    due.header.sender,
                    TimeVal::now(),
                    &self.scratch[..len],
                );
            }
            let h = wire::Header {
                payload_len: len,
                time: due.header.time(),
                sender: due.header.sender,
                type_id: due.header.type_id,
                seq: 0,
            };
            if let Some(d) = Self::handle_message(
                &mut self.names,
                &mut self.to_describe,
                &mut self.queue,
                &mut f.ep,
                None,
                h,
                &self.scratch[..len],
                true,
            ) {
                return Some(d);
            }
            f.ep.protocol_error = false;
            if !self.to_describe.is_empty() {
                self.describe_new_names();
            }
            if let Some(d) = self.queue.pop_front() {
                return Some(d);
            }
        }
    }

    /// The replay, for control calls.
    pub(crate) fn replay_mut(&mut self) -> Option<&mut Replay> {
        match &mut self.kind {
            Kind::File(f) => Some(&mut f.replay),
            _ => None,
        }
    }

    pub(crate) fn loopback(limits: Limits) -> Core {
        Core::with_kind(Kind::Loopback, None, limits)
    }

    /// A server listening on UDP and TCP at `nic:port` (all interfaces without a NIC).
    pub(crate) fn server(nic: Option<Ipv4Addr>, port: u16, limits: Limits) -> Result<Core, Error> {
        let ip = nic.unwrap_or(Ipv4Addr::UNSPECIFIED);
        let poll = Poll::new().map_err(|e| Error::io("creating the poll instance", e))?;
        // Bind TCP first so port 0 picks a number that UDP then shares.
        let mut tcp = TcpListener::bind(SocketAddr::V4(SocketAddrV4::new(ip, port)))
            .map_err(|e| Error::io(format!("listening on TCP {ip}:{port}"), e))?;
        let port = tcp
            .local_addr()
            .map_err(|e| Error::io("reading the TCP listener address", e))?
            .port();
        let mut udp = UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(ip, port)))
            .map_err(|e| Error::io(format!("listening on UDP {ip}:{port}"), e))?;
        poll.registry()
            .register(&mut tcp, SERVER_TCP, Interest::READABLE)
            .and_then(|_| {
                poll.registry()
                    .register(&mut udp, SERVER_UDP, Interest::READABLE)
            })
            .map_err(|e| Error::io("registering listeners", e))?;
        let net = ServerNet {
            tcp,
            udp,
            nic,
            tcp_readable: true,
            udp_readable: true,
            port,
        };
        Ok(Core::with_kind(Kind::Server(net), Some(poll), limits))
    }

    /// A client of the server at `host:port`; the first attempt starts at once.
    pub(crate) fn client(
        host: &str,
        port: u16,
        tcp_only: bool,
        limits: Limits,
    ) -> Result<Core, Error> {
        let server = resolve_v4(host, port)?;
        let poll = Poll::new().map_err(|e| Error::io("creating the poll instance", e))?;
        let now = Instant::now();
        let mut net = ClientNet {
            host: host.to_string(),
            server,
            tcp_only,
            listener: None,
            listen_addr: SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0),
            listener_readable: false,
            lob: None,
            lob_readable: false,
            next_attempt: now,
            attempts_since_connected: 0,
            waiting_since: now,
            warned_no_answer: false,
            warned_refused: false,
            ever_connected: false,
            seq: (0, 0),
            retry_interval: limits.retry_interval,
        };
        if !tcp_only {
            let ip = local_ip_towards(*server.ip());
            let mut l = TcpListener::bind(SocketAddr::V4(SocketAddrV4::new(ip, 0)))
                .map_err(|e| Error::io("opening the TCP call-back listener", e))?;
            let port = l
                .local_addr()
                .map_err(|e| Error::io("reading the call-back listener address", e))?
                .port();
            let shown_ip = if ip.is_unspecified() {
                Ipv4Addr::LOCALHOST
            } else {
                ip
            };
            net.listen_addr = SocketAddrV4::new(shown_ip, port);
            poll.registry()
                .register(&mut l, CLIENT_LISTEN, Interest::READABLE)
                .map_err(|e| Error::io("registering the call-back listener", e))?;
            net.listener = Some(l);
        }
        let mut core = Core::with_kind(Kind::Client(Box::new(net)), Some(poll), limits);
        core.client_attempt(now);
        Ok(core)
    }

    pub(crate) fn state(&self) -> ConnectionState {
        match &self.kind {
            Kind::Loopback | Kind::File(_) => ConnectionState::Connected,
            Kind::Server(_) => {
                if self.connected > 0 {
                    ConnectionState::Connected
                } else {
                    ConnectionState::Listening
                }
            }
            Kind::Client(c) => {
                if self.connected > 0 {
                    ConnectionState::Connected
                } else if c.ever_connected {
                    ConnectionState::Reconnecting
                } else {
                    ConnectionState::Connecting
                }
            }
        }
    }

    fn notice(&mut self, severity: Severity, text: String) {
        self.queue
            .push_back(Delivery::Notice(Notice { severity, text }));
    }

    // ------------------------------------------------------------------ readiness

    /// Waits up to `timeout` for socket readiness and records it. Returns whether any arrived.
    pub(crate) fn poll_io(&mut self, timeout: Option<Duration>) -> Result<bool, Error> {
        let Some(poll) = self.poll.as_mut() else {
            if let Some(t) = timeout {
                if !t.is_zero() {
                    std::thread::sleep(t);
                }
            }
            return Ok(false);
        };
        match poll.poll(&mut self.events, timeout) {
            Ok(()) => {}
            Err(e) if interrupted(&e) => return Ok(false),
            Err(e) => return Err(Error::io("polling sockets", e)),
        }
        let mut any = false;
        for ev in self.events.iter() {
            // Only incoming data counts as activity: write-space events follow every send.
            any |= ev.is_readable() && ev.token() != TIMER;
            let t = ev.token().0;
            match (&mut self.kind, t) {
                (Kind::Server(s), 0) => s.tcp_readable = true,
                (Kind::Server(s), 1) => s.udp_readable = true,
                (Kind::Client(c), 2) => c.listener_readable = true,
                (Kind::Client(c), 3) => c.lob_readable = true,
                (_, 4) => {
                    if let Some(t) = &self.timer {
                        t.clear();
                    }
                }
                (_, t) if t >= PEER_BASE => {
                    let slot = (t - PEER_BASE) / 4;
                    if let Some(Some(p)) = self.peers.get_mut(slot) {
                        match (t - PEER_BASE) % 4 {
                            TOK_TCP => {
                                if ev.is_readable() || ev.is_read_closed() || ev.is_error() {
                                    p.io.tcp_readable = true;
                                }
                                if ev.is_read_closed() || ev.is_error() {
                                    p.io.tcp_read_closed = true;
                                }
                                if ev.is_writable() || ev.is_error() {
                                    p.io.tcp_writable = true;
                                }
                            }
                            TOK_UDP_IN => p.io.udp_readable = true,
                            _ => {}
                        }
                    }
                }
                _ => {}
            }
        }
        self.activity |= any;
        Ok(any)
    }

    // ------------------------------------------------------------------ connection set-up

    /// Accepts new peers, completes connects, retries client attempts. Called every mainloop.
    ///
    /// The clock is read only on the paths that need it, never in a connected steady state.
    pub(crate) fn service_setup(&mut self) {
        if matches!(self.kind, Kind::Server(_)) {
            self.server_accept_requests();
            self.server_accept_tcp();
        }
        if matches!(self.kind, Kind::Client(_)) {
            self.client_service();
        }
        if let Kind::File(f) = &mut self.kind {
            f.replay.tick(Instant::now());
        }
        for i in 0..self.peers.len() {
            self.complete_connect(i);
        }
    }

    fn server_accept_requests(&mut self) {
        let mut buf = [0u8; 200];
        loop {
            let Kind::Server(s) = &mut self.kind else {
                return;
            };
            if !s.udp_readable {
                return;
            }
            let (n, from) = match s.udp.recv_from(&mut buf) {
                Ok(r) => r,
                Err(e) if would_block(&e) => {
                    s.udp_readable = false;
                    return;
                }
                Err(e) if interrupted(&e) => continue,
                Err(_) => continue,
            };
            let nic = s.nic;
            let req = match wire::lob::parse_request(&buf[..n]) {
                Ok(r) => r,
                Err(e) => {
                    self.notice(
                        Severity::Warning,
                        format!("ignored a bad connection request from {from}: {e}"),
                    );
                    continue;
                }
            };
            if self.live_peers() >= self.limits.max_connections {
                self.notice(
                    Severity::Warning,
                    format!(
                        "refused connection request from {from}: {} clients already connected \
                         (limit)",
                        self.limits.max_connections
                    ),
                );
                continue;
            }
            let target = match req.host.parse::<Ipv4Addr>() {
                Ok(ip) => SocketAddrV4::new(ip, req.port),
                Err(_) => match resolve_v4(req.host, req.port) {
                    Ok(a) => a,
                    Err(e) => {
                        self.notice(Severity::Warning, format!("connection request: {e}"));
                        continue;
                    }
                },
            };
            let _ = nic;
            // A client that re-sends its request while its call-back is already in progress
            // must not get a second connection.
            let dup = self.peers.iter().flatten().any(|p| {
                !p.ep.tcp_only
                    && p.ep.phase != Phase::Connected
                    && p.io.tcp.peer_addr().ok() == Some(SocketAddr::V4(target))
            });
            if dup {
                continue;
            }
            match TcpStream::connect(SocketAddr::V4(target)) {
                Ok(stream) => {
                    let _ = stream.set_nodelay(true);
                    let deadline = Instant::now() + self.limits.connect_timeout;
                    self.add_peer(stream, false, target.to_string(), Some(deadline));
                }
                Err(e) => self.notice(
                    Severity::Warning,
                    format!("cannot call back client at {target}: {e}"),
                ),
            }
        }
    }

    fn server_accept_tcp(&mut self) {
        loop {
            let Kind::Server(s) = &mut self.kind else {
                return;
            };
            if !s.tcp_readable {
                return;
            }
            match s.tcp.accept() {
                Ok((stream, addr)) => {
                    if self.live_peers() >= self.limits.max_connections {
                        self.notice(
                            Severity::Warning,
                            format!(
                                "refused TCP client {addr}: {} clients already connected (limit)",
                                self.limits.max_connections
                            ),
                        );
                        continue;
                    }
                    let _ = stream.set_nodelay(true);
                    let slot = self.add_peer(stream, true, addr.to_string(), None);
                    self.start_handshake(slot);
                }
                Err(e) if would_block(&e) => s.tcp_readable = false,
                Err(e) if interrupted(&e) => {}
                Err(_) => s.tcp_readable = false,
            }
        }
    }

    fn live_peers(&self) -> usize {
        self.peers.iter().flatten().count()
    }

    fn add_peer(
        &mut self,
        mut tcp: TcpStream,
        tcp_only: bool,
        peer: String,
        connect_deadline: Option<Instant>,
    ) -> usize {
        let slot = match self.peers.iter().position(Option::is_none) {
            Some(s) => s,
            None => {
                self.peers.push(None);
                self.peers.len() - 1
            }
        };
        if let Some(poll) = &self.poll {
            let _ = poll.registry().register(
                &mut tcp,
                Token(PEER_BASE + slot * 4 + TOK_TCP),
                Interest::READABLE | Interest::WRITABLE,
            );
        }
        let mut ep = Endpoint::new(tcp_only, peer, self.limits.max_pending_output);
        ep.max_payload = self.limits.max_message_payload;
        ep.max_names = self.limits.max_names_per_peer;
        if let Kind::Client(c) = &self.kind {
            ep.seq_tcp = c.seq.0;
            ep.seq_udp = c.seq.1;
        }
        self.peers[slot] = Some(Peer {
            ep,
            io: PeerIo {
                tcp,
                udp_in: None,
                udp_out: None,
                tcp_readable: true,
                tcp_read_closed: false,
                udp_readable: false,
                tcp_writable: true,
                connect_deadline,
            },
            log_in: None,
        });
        self.open_peer_log(slot);
        slot
    }

    /// Checks whether a pending TCP connect finished, failed or timed out.
    fn complete_connect(&mut self, i: usize) {
        let Some(p) = self.peers[i].as_mut() else {
            return;
        };
        if p.ep.phase != Phase::TcpConnecting {
            return;
        }
        let now = Instant::now();
        if !p.io.tcp_writable {
            if p.io.connect_deadline.is_some_and(|d| now >= d) {
                let who = p.ep.peer.clone();
                self.drop_peer(i, format!("TCP connection to {who} timed out"), now);
            }
            return;
        }
        match p.io.tcp.take_error() {
            Ok(Some(e)) | Err(e) => {
                let who = p.ep.peer.clone();
                self.connect_failed(i, who, e, now);
                return;
            }
            Ok(None) => {}
        }
        match p.io.tcp.peer_addr() {
            Ok(_) => self.start_handshake(i),
            Err(e) if e.kind() == io::ErrorKind::NotConnected => {
                p.io.tcp_writable = false;
            }
            Err(e) => {
                let who = p.ep.peer.clone();
                self.connect_failed(i, who, e, now);
            }
        }
    }

    fn connect_failed(&mut self, i: usize, who: String, e: io::Error, now: Instant) {
        let text = match &mut self.kind {
            Kind::Client(c) => {
                let first = !c.warned_refused;
                c.warned_refused = true;
                if !first {
                    None
                } else if e.kind() == io::ErrorKind::ConnectionRefused {
                    Some(format!(
                        "no VRPN server is listening on {who} (connection refused); will keep \
                         retrying every {:?}",
                        c.retry_interval
                    ))
                } else {
                    Some(format!("cannot connect to {who}: {e}; will keep retrying"))
                }
            }
            _ => Some(format!(
                "cannot call back client at {who}: {e} (a firewall on the client may block the \
                 call-back; the client can use the tcp:// name form)"
            )),
        };
        self.remove_peer_silently(i);
        if let Some(t) = text {
            self.notice(Severity::Warning, t);
        }
        if let Kind::Client(c) = &mut self.kind {
            c.next_attempt = now + c.retry_interval;
        }
    }

    /// TCP is up: send our cookie at once and wait for the peer's.
    fn start_handshake(&mut self, i: usize) {
        let Some(p) = self.peers[i].as_mut() else {
            return;
        };
        p.ep.phase = Phase::AwaitingCookie;
        p.io.connect_deadline = None;
        let _ = p.ep.tx.push_raw(&Cookie::ours(0).to_bytes());
        p.io.tcp_writable = true;
        self.flush_peer(i);
    }

    fn client_service(&mut self) {
        // Accept a call-back.
        let accepted = {
            let Kind::Client(c) = &mut self.kind else {
                return;
            };
            let mut got = None;
            if c.listener_readable {
                if let Some(l) = &c.listener {
                    loop {
                        match l.accept() {
                            Ok((s, addr)) => {
                                if got.is_none() {
                                    got = Some((s, addr));
                                }
                                // Further call-backs while one is live are dropped on close.
                            }
                            Err(e) if would_block(&e) => {
                                c.listener_readable = false;
                                break;
                            }
                            Err(e) if interrupted(&e) => {}
                            Err(_) => {
                                c.listener_readable = false;
                                break;
                            }
                        }
                    }
                }
            }
            got
        };
        let has_peer = self.peers.iter().flatten().next().is_some();
        if let Some((stream, addr)) = accepted {
            if !has_peer {
                let _ = stream.set_nodelay(true);
                if let Kind::Client(c) = &mut self.kind {
                    if let (Some(mut lob), Some(poll)) = (c.lob.take(), &self.poll) {
                        let _ = poll.registry().deregister(&mut lob);
                    }
                }
                let slot = self.add_peer(stream, false, addr.to_string(), None);
                self.start_handshake(slot);
                return;
            }
        }
        // Diagnose a lob that draws ICMP port-unreachable.
        let mut refused = false;
        if let Kind::Client(c) = &mut self.kind {
            if c.lob_readable {
                c.lob_readable = false;
                if let Some(lob) = &c.lob {
                    let mut b = [0u8; 16];
                    if let Err(e) = lob.recv(&mut b) {
                        refused = e.kind() == io::ErrorKind::ConnectionRefused;
                    }
                }
            }
        }
        if refused {
            let first = if let Kind::Client(c) = &mut self.kind {
                let f = !c.warned_refused;
                c.warned_refused = true;
                f
            } else {
                false
            };
            if first {
                let server = self.client_server_text();
                self.notice(
                    Severity::Warning,
                    format!(
                        "no VRPN server at {server}: its UDP port answered 'port unreachable'; \
                         will keep retrying"
                    ),
                );
            }
        }
        if has_peer {
            return;
        }
        let now = Instant::now();
        // No answer yet: warn once, then retry on schedule.
        let warn = if let Kind::Client(c) = &mut self.kind {
            if !c.tcp_only
                && !c.warned_no_answer
                && now.duration_since(c.waiting_since) >= self.limits.no_answer_warning
            {
                c.warned_no_answer = true;
                Some((c.host.clone(), c.server.port(), c.listen_addr))
            } else {
                None
            }
        } else {
            None
        };
        if let Some((host, port, listen)) = warn {
            self.notice(
                Severity::Warning,
                format!(
                    "no answer from the VRPN server at {host}:{port} after {:?}: either no \
                     server runs there, or it cannot connect back to this machine at {listen} \
                     (a firewall or NAT). If the server runs, use DEVICE@tcp://{host}:{port} to \
                     connect over TCP only",
                    self.limits.no_answer_warning
                ),
            );
        }
        let due = matches!(&self.kind, Kind::Client(c) if now >= c.next_attempt);
        if due {
            self.client_attempt(now);
        }
    }

    fn client_server_text(&self) -> String {
        match &self.kind {
            Kind::Client(c) => format!("{}:{}", c.host, c.server.port()),
            _ => String::new(),
        }
    }

    /// Sends a connection request (new lob socket each time) or starts a TCP connect.
    fn client_attempt(&mut self, now: Instant) {
        let Kind::Client(c) = &mut self.kind else {
            return;
        };
        c.next_attempt = now + c.retry_interval;
        c.attempts_since_connected += 1;
        if c.tcp_only {
            let server = c.server;
            match TcpStream::connect(SocketAddr::V4(server)) {
                Ok(s) => {
                    let _ = s.set_nodelay(true);
                    let deadline = now + self.limits.connect_timeout;
                    self.add_peer(s, true, server.to_string(), Some(deadline));
                }
                Err(e) => self.notice(
                    Severity::Warning,
                    format!("cannot start a TCP connection to {server}: {e}"),
                ),
            }
            return;
        }
        if let (Some(mut old), Some(poll)) = (c.lob.take(), &self.poll) {
            let _ = poll.registry().deregister(&mut old);
        }
        let server = c.server;
        let mut text = [0u8; 64];
        let ip = c.listen_addr.ip().to_string();
        let n = wire::lob::encode_request(&mut text, &ip, c.listen_addr.port());
        let lob = UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0)))
            .and_then(|s| s.connect(SocketAddr::V4(server)).map(|_| s));
        match lob {
            Ok(mut s) => {
                let _ = s.send(&text[..n]);
                if let Some(poll) = &self.poll {
                    let _ = poll
                        .registry()
                        .register(&mut s, CLIENT_LOB, Interest::READABLE);
                }
                c.lob = Some(s);
            }
            Err(e) => {
                let t = format!("cannot send a connection request to {server}: {e}");
                self.notice(Severity::Warning, t);
            }
        }
    }

    // ------------------------------------------------------------------ incoming

    /// The next thing to deliver, or `None` when all input is consumed.
    pub(crate) fn next_delivery(&mut self) -> Option<Delivery> {
        loop {
            if let Some(d) = self.queue.pop_front() {
                return Some(d);
            }
            if !self.to_describe.is_empty() {
                self.describe_new_names();
                continue;
            }
            if matches!(self.kind, Kind::File(_)) {
                return self.next_from_file();
            }
            let n = self.peers.len();
            if n == 0 {
                return None;
            }
            let mut produced = false;
            for k in 0..n {
                let i = (self.cursor + k) % n;
                if self.budget >= self.limits.max_messages_per_peer_per_loop {
                    self.budget = 0;
                    continue;
                }
                if let Some(d) = self.next_from_peer(i) {
                    self.cursor = i;
                    self.budget += 1;
                    return Some(d);
                }
                self.budget = 0;
                if !self.queue.is_empty() || !self.to_describe.is_empty() {
                    produced = true;
                    self.cursor = i;
                    break;
                }
            }
            if !produced {
                return None;
            }
        }
    }

    /// Starts a new mainloop pass (resets per-pass budgets).
    pub(crate) fn begin_pass(&mut self) {
        self.budget = 0;
    }

    fn next_from_peer(&mut self, i: usize) -> Option<Delivery> {
        loop {
            let p = self.peers[i].as_mut()?;
            match p.ep.phase {
                Phase::TcpConnecting => return None,
                Phase::AwaitingCookie => {
                    if let Some(bytes) = p.ep.rx.take_exact(COOKIE_LEN) {
                        let cookie = Cookie::parse(bytes).expect("24 bytes");
                        self.handle_cookie(i, cookie, Instant::now());
                        if !self.queue.is_empty() {
                            return self.queue.pop_front();
                        }
                        continue;
                    }
                }
                Phase::Connected => {
                    let tcp_only = p.ep.tcp_only;
                    match p.ep.rx.next_message() {
                        Some(Ok((h, payload))) => {
                            let len = payload.len();
                            self.scratch[..len].copy_from_slice(payload);
                            if let Some(w) = p.log_in.as_mut().or(self.log_in.as_mut()) {
                                let _ = w.log_message(
                                    h.type_id,
                                    h.sender,
                                    h.time,
                                    &self.scratch[..len],
                                );
                            }
                            if let Some(d) = Self::handle_message(
                                &mut self.names,
                                &mut self.to_describe,
                                &mut self.queue,
                                &mut p.ep,
                                Some(&mut p.io.udp_out),
                                h,
                                &self.scratch[..len],
                                tcp_only,
                            ) {
                                return Some(d);
                            }
                            if p.ep.protocol_error {
                                let reason =
                                    format!("dropped {} after a protocol error", p.ep.peer);
                                self.drop_peer(i, reason, Instant::now());
                                return self.queue.pop_front();
                            }
                            if !self.queue.is_empty() || !self.to_describe.is_empty() {
                                return None;
                            }
                            continue;
                        }
                        Some(Err(e)) => {
                            let reason = format!("malformed message from {}: {e}", p.ep.peer);
                            self.drop_peer(i, reason, Instant::now());
                            return self.queue.pop_front();
                        }
                        None => {}
                    }
                }
            }
            // Need more TCP bytes.
            let p = self.peers[i].as_mut()?;
            if p.io.tcp_readable {
                let spare = p.ep.rx.spare();
                if spare.is_empty() {
                    // Cannot happen: the buffer holds a maximal message; treat as a protocol error.
                    let reason = format!("{} sent a message larger than the buffer", p.ep.peer);
                    self.drop_peer(i, reason, Instant::now());
                    return self.queue.pop_front();
                }
                let spare_len = spare.len();
                match p.io.tcp.read(spare) {
                    Ok(0) => {
                        let reason = format!("{} closed the connection", p.ep.peer);
                        self.drop_peer(i, reason, Instant::now());
                        return self.queue.pop_front();
                    }
                    Ok(n) => {
                        p.ep.rx.commit(n);
                        self.activity = true;
                        if SHORT_READ_DRAINS && n < spare_len && !p.io.tcp_read_closed {
                            p.io.tcp_readable = false;
                        }
                        continue;
                    }
                    Err(e) if would_block(&e) => p.io.tcp_readable = false,
                    Err(e) if interrupted(&e) => continue,
                    Err(e) => {
                        let reason = format!("connection to {} failed: {e}", p.ep.peer);
                        self.drop_peer(i, reason, Instant::now());
                        return self.queue.pop_front();
                    }
                }
            }
            // Then UDP.
            let p = self.peers[i].as_mut()?;
            if p.ep.phase != Phase::Connected {
                return None;
            }
            if p.ep.udp_rx.is_drained() {
                if !p.io.udp_readable {
                    return None;
                }
                let Some(sock) = &p.io.udp_in else {
                    p.io.udp_readable = false;
                    return None;
                };
                match recv_datagrams(sock, &mut p.ep.udp_rx) {
                    Ok(n) => {
                        p.ep.udp_rx.filled(n);
                        self.activity = true;
                        // A short batch proves the queue empty (edge-triggered epoll raises a
                        // new event for the next arrival): no WouldBlock call needed.
                        if n < INBOX_SLOTS && SHORT_READ_DRAINS {
                            p.io.udp_readable = false;
                        }
                    }
                    Err(e) if would_block(&e) => {
                        p.io.udp_readable = false;
                        return None;
                    }
                    Err(_) => return None,
                }
            }
            let dg = p.ep.udp_rx.current();
            let mut it = wire::DatagramMessages::new(dg);
            match it.next() {
                Some(Ok((h, payload))) => {
                    let advance = h.wire_size().min(dg.len());
                    // Copy out before borrowing the endpoint mutably.
                    let len = payload.len();
                    self.scratch[..len].copy_from_slice(payload);
                    let p = self.peers[i].as_mut()?;
                    p.ep.udp_rx.advance(advance);
                    let tcp_only = p.ep.tcp_only;
                    if let Some(w) = p.log_in.as_mut().or(self.log_in.as_mut()) {
                        let _ = w.log_message(h.type_id, h.sender, h.time, &self.scratch[..len]);
                    }
                    if let Some(d) = Self::handle_message(
                        &mut self.names,
                        &mut self.to_describe,
                        &mut self.queue,
                        &mut p.ep,
                        Some(&mut p.io.udp_out),
                        h,
                        &self.scratch[..len],
                        tcp_only,
                    ) {
                        return Some(d);
                    }
                    if p.ep.protocol_error {
                        let reason = format!("dropped {} after a protocol error", p.ep.peer);
                        self.drop_peer(i, reason, Instant::now());
                        return self.queue.pop_front();
                    }
                    if !self.queue.is_empty() || !self.to_describe.is_empty() {
                        return None;
                    }
                }
                Some(Err(e)) => {
                    // C++ drops the whole connection on a bad datagram; we drop the datagram,
                    // since the inbound socket accepts any source and one stray packet must not
                    // cut a client off.
                    let p = self.peers[i].as_mut()?;
                    p.ep.udp_rx.skip_datagram();
                    let t = format!("discarded a malformed UDP datagram from {}: {e}", p.ep.peer);
                    self.notice(Severity::Warning, t);
                    return self.queue.pop_front();
                }
                None => {
                    let p = self.peers[i].as_mut()?;
                    p.ep.udp_rx.skip_datagram();
                }
            }
        }
    }

    /// Interprets one message whose payload the caller copied into `Core::scratch`: system
    /// messages update tables; user messages are translated and returned for delivery.
    #[allow(clippy::too_many_arguments)]
    fn handle_message(
        names: &mut Names,
        to_describe: &mut Vec<(bool, i32)>,
        queue: &mut VecDeque<Delivery>,
        ep: &mut Endpoint,
        udp_out: Option<&mut Option<UdpSocket>>,
        h: wire::Header,
        payload: &[u8],
        tcp_only: bool,
    ) -> Option<Delivery> {
        if payload.len() > ep.max_payload {
            queue.push_back(Delivery::Notice(Notice {
                severity: Severity::Warning,
                text: format!(
                    "{} sent a {}-byte message; the limit is {} bytes \
                     (Limits::max_message_payload)",
                    ep.peer,
                    payload.len(),
                    ep.max_payload
                ),
            }));
            ep.protocol_error = true;
            return None;
        }
        match h.type_id {
            system::SENDER_DESCRIPTION | system::TYPE_DESCRIPTION => {
                let is_sender = h.type_id == system::SENDER_DESCRIPTION;
                let name = match system::decode_description(payload) {
                    Ok(n) => n,
                    Err(e) => {
                        queue.push_back(Delivery::Notice(Notice {
                            severity: Severity::Error,
                            text: format!("bad description from {}: {e}", ep.peer),
                        }));
                        ep.protocol_error = true;
                        return None;
                    }
                };
                let table = if is_sender {
                    &mut names.senders
                } else {
                    &mut names.types
                };
                let remote_table = if is_sender {
                    &ep.remote_senders
                } else {
                    &ep.remote_types
                };
                let rebinds = !matches!(table.get(name),
                    Some(l) if Endpoint::lookup(remote_table, h.sender) == l);
                if rebinds && !ep.note_description(is_sender) {
                    queue.push_back(Delivery::Notice(Notice {
                        severity: Severity::Warning,
                        text: format!(
                            "{} described more than {} {} names (Limits::max_names_per_peer)",
                            ep.peer,
                            ep.max_names,
                            if is_sender { "sender" } else { "type" }
                        ),
                    }));
                    ep.protocol_error = true;
                    return None;
                }
                let (local, new) = match table.register(name) {
                    Ok(r) => r,
                    Err(e) => {
                        queue.push_back(Delivery::Notice(Notice {
                            severity: Severity::Error,
                            text: format!("{} described a name we cannot hold: {e}", ep.peer),
                        }));
                        ep.protocol_error = true;
                        return None;
                    }
                };
                let remote_table = if is_sender {
                    &mut ep.remote_senders
                } else {
                    &mut ep.remote_types
                };
                let was_known = Endpoint::lookup(remote_table, h.sender) == local;
                if !Endpoint::map_remote(remote_table, h.sender, local) {
                    queue.push_back(Delivery::Notice(Notice {
                        severity: Severity::Error,
                        text: format!(
                            "{} described id {} outside VRPN's 0..2000 range",
                            ep.peer, h.sender
                        ),
                    }));
                    ep.protocol_error = true;
                    return None;
                }
                if new {
                    to_describe.push((is_sender, local));
                }
                if is_sender && !was_known {
                    queue.push_back(Delivery::PeerSender(local));
                }
                None
            }
            system::UDP_DESCRIPTION => {
                // Replayed logs carry UDP descriptions too; they open nothing.
                let udp_out = udp_out?;
                if tcp_only || ep.udp_ready {
                    if !tcp_only {
                        // A repeated description (new port after the peer reconnected its UDP).
                        ep.udp_ready = false;
                    } else {
                        return None;
                    }
                }
                let host = match system::decode_udp_description(payload) {
                    Ok(h) => h,
                    Err(_) => return None,
                };
                let port = h.sender;
                let ip: Ipv4Addr = match host.parse() {
                    Ok(ip) => ip,
                    Err(_) => match resolve_v4(host, 0) {
                        Ok(a) => *a.ip(),
                        Err(_) => return None,
                    },
                };
                if !(1..=65535).contains(&port) {
                    return None;
                }
                let target = SocketAddr::V4(SocketAddrV4::new(ip, port as u16));
                let sock =
                    UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(Ipv4Addr::UNSPECIFIED, 0)))
                        .and_then(|s| s.connect(target).map(|_| s));
                if let Ok(s) = sock {
                    *udp_out = Some(s);
                    ep.udp_ready = true;
                }
                None
            }
            system::LOG_DESCRIPTION => {
                // C++ servers open the named files on the server machine. An unauthenticated
                // peer choosing paths we write to is a hazard, so the request is refused.
                if let Ok(d) = system::decode_log_description(payload) {
                    queue.push_back(Delivery::Notice(Notice {
                        severity: Severity::Warning,
                        text: format!(
                            "{} asked this side to log (incoming {:?}, outgoing {:?}); remote \
                             logging requests are refused: log locally with -li/-lo instead",
                            ep.peer, d.incoming, d.outgoing
                        ),
                    }));
                }
                None
            }
            system::DISCONNECT => {
                ep.clear_remote_names();
                None
            }
            t if t < 0 => None,
            t => {
                let local_type = Endpoint::lookup(&ep.remote_types, t);
                if local_type < 0 {
                    return None; // never described: ignored, as C++ does
                }
                let local_sender = Endpoint::lookup(&ep.remote_senders, h.sender);
                Some(Delivery::Message {
                    time: h.time,
                    sender: local_sender,
                    type_id: local_type,
                    len: payload.len(),
                })
            }
        }
    }

    fn handle_cookie(&mut self, i: usize, cookie: Cookie, now: Instant) {
        if let Err(e) = cookie.check() {
            let who = self.peers[i]
                .as_ref()
                .map(|p| p.ep.peer.clone())
                .unwrap_or_default();
            self.drop_peer(i, format!("{who}: {e}"), now);
            return;
        }
        let tv = TimeVal::now();
        let nic = match &self.kind {
            Kind::Server(s) => s.nic,
            _ => None,
        };
        let Some(p) = self.peers[i].as_mut() else {
            return;
        };
        if cookie.minor_differs() {
            let t = format!(
                "{} speaks VRPN {} and we speak {}: minor versions differ, which is not \
                 normally a problem",
                p.ep.peer,
                cookie.version(),
                Cookie::ours(0).version()
            );
            self.queue.push_back(Delivery::Notice(Notice {
                severity: Severity::Info,
                text: t,
            }));
        }
        p.ep.peer_version = Some(cookie.version());
        p.ep.phase = Phase::Connected;
        // An incoming log carries the peer's cookie (LOGFILE.md §1.1).
        let peer_cookie = log_cookie_from_peer(&cookie.to_bytes());
        if let Some(w) = p.log_in.as_mut().or(self.log_in.as_mut()) {
            w.set_cookie(&peer_cookie);
        }
        let log_handshake = matches!(self.kind, Kind::Client(_)) && self.log_out.is_some();
        // UDP inbound socket and its description, unless TCP-only.
        if !p.ep.tcp_only {
            let local_ip = match p.io.tcp.local_addr() {
                Ok(SocketAddr::V4(a)) => *a.ip(),
                _ => Ipv4Addr::LOCALHOST,
            };
            let bind_ip = nic.unwrap_or(Ipv4Addr::UNSPECIFIED);
            if let Ok(mut u) = UdpSocket::bind(SocketAddr::V4(SocketAddrV4::new(bind_ip, 0))) {
                let port = u.local_addr().map(|a| a.port()).unwrap_or(0);
                if let Some(poll) = &self.poll {
                    let _ = poll.registry().register(
                        &mut u,
                        Token(PEER_BASE + i * 4 + TOK_UDP_IN),
                        Interest::READABLE,
                    );
                }
                p.io.udp_in = Some(u);
                p.io.udp_readable = true;
                let ip_text = nic.unwrap_or(local_ip).to_string();
                let mut buf = [0u8; 32];
                let n = system::encode_udp_description(&mut buf, &ip_text);
                let _ = p.ep.pack_always(
                    tv,
                    port as i32,
                    system::UDP_DESCRIPTION,
                    &buf[..n],
                    class::RELIABLE,
                );
                if log_handshake {
                    if let Some(w) = self.log_out.as_mut() {
                        let _ = w.log_message(system::UDP_DESCRIPTION, port as i32, tv, &buf[..n]);
                    }
                }
            }
        }
        let mut buf = [0u8; 128];
        let tables = [
            (system::SENDER_DESCRIPTION, &self.names.senders),
            (system::TYPE_DESCRIPTION, &self.names.types),
        ];
        for (kind, table) in tables {
            for (id, name) in table.iter() {
                let n = system::encode_description(&mut buf, name);
                let _ = p.ep.pack_always(tv, id, kind, &buf[..n], class::RELIABLE);
                if log_handshake {
                    if let Some(w) = self.log_out.as_mut() {
                        let _ = w.log_message(kind, id, tv, &buf[..n]);
                    }
                }
            }
        }
        if let Kind::Client(c) = &mut self.kind {
            c.ever_connected = true;
            c.warned_no_answer = false;
            c.warned_refused = false;
            c.attempts_since_connected = 0;
        }
        self.flush_peer(i);
        if self.connected == 0 {
            self.queue
                .push_back(Delivery::Event(ConnectionEvent::GotFirstConnection));
        }
        self.connected += 1;
        self.queue
            .push_back(Delivery::Event(ConnectionEvent::GotConnection));
    }

    /// Describes names that peers taught us to every connected peer (the C++ echo).
    fn describe_new_names(&mut self) {
        let list = std::mem::take(&mut self.to_describe);
        for &(is_sender, id) in &list {
            self.describe_to_all(is_sender, id);
        }
        self.to_describe = list;
        self.to_describe.clear();
    }

    /// Sends one description to every connected peer.
    pub(crate) fn describe_to_all(&mut self, is_sender: bool, id: i32) {
        let name = if is_sender {
            self.names.senders.name(id)
        } else {
            self.names.types.name(id)
        };
        let Some(name) = name else {
            return;
        };
        let mut buf = [0u8; 128];
        let n = system::encode_description(&mut buf, name);
        let t = if is_sender {
            system::SENDER_DESCRIPTION
        } else {
            system::TYPE_DESCRIPTION
        };
        let tv = TimeVal::now();
        for p in self.peers.iter_mut().flatten() {
            let _ = p.ep.pack(tv, id, t, &buf[..n], class::RELIABLE);
        }
        self.log_outgoing_message(t, id, tv, &buf[..n]);
    }

    // ------------------------------------------------------------------ outgoing

    /// Queues a message to every connected peer. Peers whose backlog overflows are dropped.
    pub(crate) fn pack_to_peers(
        &mut self,
        time: TimeVal,
        sender: i32,
        type_id: i32,
        payload: &[u8],
        class_of_service: u32,
    ) {
        self.log_outgoing_message(type_id, sender, time, payload);
        let mut overflow = None;
        let mut shedding = None;
        for (i, p) in self.peers.iter_mut().enumerate() {
            if let Some(p) = p {
                match p.ep.pack(time, sender, type_id, payload, class_of_service) {
                    Err(_) => overflow = Some(i),
                    // Say so once per peer, when it first sheds unreliable traffic.
                    Ok(Channel::Discarded) if p.ep.unreliable_dropped == 1 => {
                        shedding = Some((p.ep.peer.clone(), p.ep.tx.pending_len()));
                    }
                    Ok(_) => {}
                }
            }
        }
        if let Some((who, pending)) = shedding {
            self.notice(
                Severity::Warning,
                format!(
                    "{who} is falling behind ({pending} bytes of output pending): dropping \
                     its unreliable messages while the backlog exceeds half of \
                     Limits::max_pending_output"
                ),
            );
        }
        if let Some(i) = overflow {
            // Rare path: one slow peer at a time is enough to handle per message.
            let limit = self.limits.max_pending_output;
            let who = self.peers[i]
                .as_ref()
                .map(|p| p.ep.peer.clone())
                .unwrap_or_default();
            self.drop_peer(
                i,
                format!("{who} is not reading: more than {limit} bytes of reliable output pending"),
                Instant::now(),
            );
        }
    }

    /// Writes what the peers' buffers hold, as far as the sockets take it.
    pub(crate) fn flush(&mut self) {
        for i in 0..self.peers.len() {
            self.flush_peer(i);
        }
    }

    fn flush_peer(&mut self, i: usize) {
        let Some(p) = self.peers[i].as_mut() else {
            return;
        };
        if p.ep.phase == Phase::TcpConnecting {
            return;
        }
        let mut failed = None;
        // After a WouldBlock, wait for epoll's writable event instead of retrying every pass
        // (a stalled peer would otherwise cost a failing write per pass).
        while p.io.tcp_writable && p.ep.tx.pending_len() > 0 {
            match p.io.tcp.write(p.ep.tx.pending()) {
                Ok(0) => break,
                Ok(n) => p.ep.tx.consume(n),
                Err(e) if would_block(&e) => {
                    p.io.tcp_writable = false;
                    break;
                }
                Err(e) if interrupted(&e) => {}
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            }
        }
        if let Some(sock) = &p.io.udp_out {
            while let Some(dg) = p.ep.udp_tx.front() {
                match sock.send(dg) {
                    Ok(_) => p.ep.udp_tx.pop_front(),
                    Err(e) if would_block(&e) => break,
                    // Unreliable: a refused or failed datagram is simply lost.
                    Err(_) => p.ep.udp_tx.pop_front(),
                }
            }
        } else {
            p.ep.udp_tx.clear();
        }
        if let Some(e) = failed {
            let reason = format!("sending to {} failed: {e}", p.ep.peer);
            self.drop_peer(i, reason, Instant::now());
        }
    }

    /// Bytes of reliable output waiting for a peer (for tests and diagnostics).
    pub(crate) fn pending_output(&self) -> usize {
        self.peers
            .iter()
            .flatten()
            .map(|p| p.ep.tx.pending_len())
            .sum()
    }

    // ------------------------------------------------------------------ drops

    fn remove_peer_silently(&mut self, i: usize) {
        if let Some(mut p) = self.peers[i].take() {
            if let Kind::Client(c) = &mut self.kind {
                c.seq = (p.ep.seq_tcp, p.ep.seq_udp);
            }
            if let Some(poll) = &self.poll {
                let _ = poll.registry().deregister(&mut p.io.tcp);
                if let Some(u) = p.io.udp_in.as_mut() {
                    let _ = poll.registry().deregister(u);
                }
            }
        }
    }

    /// Drops a peer: closes its sockets, discards its output, fires the dropped events if it
    /// had connected, and (client) schedules the reconnect.
    pub(crate) fn drop_peer(&mut self, i: usize, reason: String, now: Instant) {
        let was_connected = self.peers[i]
            .as_ref()
            .is_some_and(|p| p.ep.phase == Phase::Connected);
        self.remove_peer_silently(i);
        let is_client = matches!(self.kind, Kind::Client(_));
        if let Kind::Client(c) = &mut self.kind {
            c.next_attempt = now;
            c.waiting_since = now;
        }
        if is_client && was_connected {
            self.log_outgoing_message(system::DISCONNECT, 0, TimeVal::now(), &[]);
        }
        let severity = if is_client {
            Severity::Warning
        } else {
            Severity::Info
        };
        let text = if is_client && was_connected {
            format!("{reason}; reconnecting")
        } else {
            reason
        };
        self.notice(severity, text);
        if was_connected {
            self.connected -= 1;
            self.queue
                .push_back(Delivery::Event(ConnectionEvent::DroppedConnection));
            if self.connected == 0 {
                self.queue
                    .push_back(Delivery::Event(ConnectionEvent::DroppedLastConnection));
            }
        }
    }

    /// The server's port (after binding port 0, the one the OS chose).
    pub(crate) fn server_port(&self) -> Option<u16> {
        match &self.kind {
            Kind::Server(s) => Some(s.port),
            _ => None,
        }
    }

    /// The remote sender names every connected peer described.
    pub(crate) fn peer_sender_names(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for p in self.peers.iter().flatten() {
            for &local in &p.ep.remote_senders {
                if let Some(n) = self.names.senders.name(local) {
                    if !out.iter().any(|o| o == n) {
                        out.push(n.to_string());
                    }
                }
            }
        }
        out
    }

    /// Descriptions of connected peers (address and VRPN version).
    pub(crate) fn peer_descriptions(&self) -> Vec<(String, Option<String>)> {
        self.peers
            .iter()
            .flatten()
            .filter(|p| p.ep.phase == Phase::Connected)
            .map(|p| (p.ep.peer.clone(), p.ep.peer_version.clone()))
            .collect()
    }

    /// When the core next needs attention even without socket activity (client retries).
    pub(crate) fn next_deadline(&self) -> Option<Instant> {
        let mut d = None;
        if let Kind::Client(c) = &self.kind {
            if self.peers.iter().flatten().next().is_none() {
                d = Some(c.next_attempt);
            }
        }
        for p in self.peers.iter().flatten() {
            if let Some(cd) = p.io.connect_deadline {
                d = Some(d.map_or(cd, |x: Instant| x.min(cd)));
            }
        }
        d
    }
}

impl Drop for Core {
    fn drop(&mut self) {
        let _ = self.close_logs();
    }
}

/// `in.vrpn` → `in-3.vrpn`: `-N` before the last `.` (appended when there is none), as C++.
pub(crate) fn compound_log_name(template: &str, n: u32) -> String {
    match template.rfind('.') {
        Some(i) => format!("{}-{n}{}", &template[..i], &template[i..]),
        None => format!("{template}-{n}"),
    }
}

/// Receives up to [`INBOX_SLOTS`] datagrams with one `recvmmsg` call. Returns how many arrived.
#[cfg(any(target_os = "linux", target_os = "android"))]
fn recv_datagrams(sock: &UdpSocket, inbox: &mut DatagramInbox) -> io::Result<usize> {
    use nix::libc;
    use std::os::fd::AsRawFd;
    let base = inbox.buf.as_mut_ptr();
    // SAFETY: every iovec points into `inbox.buf`, which holds INBOX_SLOTS slots of INBOX_SLOT
    // bytes and outlives the call; the mmsghdr array is zero-initialised (a valid empty header
    // for recvmmsg) and only its iov fields are set; the kernel writes at most iov_len bytes
    // per slot and the message lengths into `msg_len`.
    unsafe {
        let mut iov: [libc::iovec; INBOX_SLOTS] = std::mem::zeroed();
        let mut msgs: [libc::mmsghdr; INBOX_SLOTS] = std::mem::zeroed();
        for k in 0..INBOX_SLOTS {
            iov[k].iov_base = base.add(k * INBOX_SLOT).cast();
            iov[k].iov_len = INBOX_SLOT;
            msgs[k].msg_hdr.msg_iov = &mut iov[k];
            msgs[k].msg_hdr.msg_iovlen = 1;
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
        for (len, msg) in inbox.lens.iter_mut().zip(&msgs).take(n) {
            *len = msg.msg_len as usize;
        }
        Ok(n)
    }
}

/// Portable fallback: one datagram per call.
#[cfg(not(any(target_os = "linux", target_os = "android")))]
fn recv_datagrams(sock: &UdpSocket, inbox: &mut DatagramInbox) -> io::Result<usize> {
    let n = sock.recv(&mut inbox.buf[..INBOX_SLOT])?;
    inbox.lens[0] = n;
    Ok(1)
}
