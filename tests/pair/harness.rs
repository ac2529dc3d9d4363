//! A client and a server [`Session`] joined in memory on a virtual clock, with a link that can
//! lose, delay, reorder, duplicate and truncate datagrams, split and stall the TCP stream, and
//! close either side — the shape of quinn-proto's test `Pair`, for the VRPN protocol layer.
//!
//! Nothing here touches a socket or reads a clock: a test drives both sides through
//! handshakes, time-outs and reconnects in microseconds of real time, and the same seed gives
//! the same run.

use std::collections::VecDeque;
use std::net::{Ipv4Addr, SocketAddrV4};
use std::time::{Duration, Instant};

use vrpn::proto::ping::{PingAction, PingCycle};
use vrpn::proto::{ConnectionEvent, Delivery, IoRequest, Limits, Notice, PeerId, Session};
use vrpn::sim::Rng;
use vrpn::time::{Now, TimeVal};
use vrpn::wire::{self, class};

pub const SERVER: SocketAddrV4 = SocketAddrV4::new(Ipv4Addr::new(10, 0, 0, 1), 3883);
pub const CLIENT_IP: Ipv4Addr = Ipv4Addr::new(10, 0, 0, 2);
/// The client's call-back listener.
pub const CLIENT_LISTEN: SocketAddrV4 = SocketAddrV4::new(CLIENT_IP, 40000);
/// The port the server's UDP sockets get for this client.
const SERVER_UDP_PORT: u16 = 50000;
const CLIENT_UDP_PORT: u16 = 50001;

pub const DEVICE: &str = "Tracker0";
pub const PING: &str = "vrpn_Base ping_message";
pub const PONG: &str = "vrpn_Base pong_message";
pub const TEXT: &str = "vrpn_Base text_message";
pub const REPORT: &str = "vrpn_Tracker Pos_Quat";

/// Which side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Who {
    Client,
    Server,
}

/// What one side received, in order.
#[derive(Clone, Debug, PartialEq)]
pub enum Seen {
    Message {
        at: Instant,
        time: TimeVal,
        sender: String,
        type_name: String,
        payload: Vec<u8>,
    },
    Event(Instant, ConnectionEvent),
    Notice(Instant, Notice),
    /// A ping-cycle text the client sent (severity, level).
    PingText(Instant, u32, u32),
}

/// Faults on the link.
#[derive(Clone, Debug, Default)]
pub struct Faults {
    /// One-way delay of everything.
    pub latency: Duration,
    /// Extra random delay of datagrams, up to this (reorders them).
    pub udp_jitter: Duration,
    /// Probability a datagram is lost.
    pub udp_loss: f64,
    /// Probability a datagram is delivered twice.
    pub udp_duplicate: f64,
    /// Probability a datagram is cut short.
    pub udp_truncate: f64,
    /// TCP bytes arrive in random pieces.
    pub tcp_split: bool,
    /// This side stops reading its TCP stream (its peer's output backs up).
    pub stall: Option<Who>,
    /// The server ignores connection requests and refuses connects (it is down).
    pub server_down: bool,
    /// The server does not answer pings (the client's device does not exist there).
    pub no_pongs: bool,
    /// TCP-only path: the server port belongs to another program, which accepts, sends these
    /// bytes and closes (or, for an empty slice, says nothing and keeps the connection).
    pub impostor: Option<&'static [u8]>,
}

/// Bytes in flight on one TCP connection direction.
#[derive(Default)]
struct Stream {
    /// (arrival time, bytes).
    segments: VecDeque<(Instant, Vec<u8>)>,
    /// Bytes written but not yet taken by the receiver.
    in_flight: usize,
    /// The sender closed: the receiver sees the end after the last byte.
    fin: Option<Instant>,
}

/// How much one direction may hold before the sender's writes stop (a socket buffer).
const WINDOW: usize = 256 * 1024;

/// One TCP connection between the sides.
struct TcpConn {
    client: Option<PeerId>,
    server: Option<PeerId>,
    c2s: Stream,
    s2c: Stream,
    /// A call-back or connect still in progress: (who connects, when it completes).
    completing: Option<Instant>,
}

pub struct Side {
    pub session: Session,
    pub seen: Vec<Seen>,
    /// UDP target announced by the peer (our outbound socket), per connection.
    udp_out: bool,
    udp_in: bool,
}

/// Datagrams in flight: (arrival, to, bytes).
type Datagrams = VecDeque<(Instant, Who, Vec<u8>)>;

pub struct Pair {
    pub now: Now,
    pub server: Side,
    pub client: Side,
    pub faults: Faults,
    conn: Option<TcpConn>,
    datagrams: Datagrams,
    requests: VecDeque<(Instant, Vec<u8>)>,
    rng: Rng,
    /// The client's liveness cycle for [`DEVICE`].
    pub ping: PingCycle,
    /// Connection requests the client sent, with their times.
    pub requests_sent: Vec<Instant>,
    /// TCP connections the server accepted (call-backs included).
    pub connections: usize,
    /// Datagrams carried (sent into the link).
    pub datagrams_sent: usize,
    /// Datagrams delivered (after loss and duplication).
    pub datagrams_delivered: usize,
    /// Every datagram carried: who sent it, and its bytes.
    pub datagram_log: Vec<(Who, Vec<u8>)>,
}

fn start() -> Now {
    Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    }
}

impl Pair {
    /// A server and a client (UDP path unless `tcp_only`) with `limits` on both sides, the
    /// device's names registered on both, not yet connected.
    pub fn new(tcp_only: bool, limits: Limits, seed: u64) -> Pair {
        let now = start();
        let mut server = Session::server(limits, None);
        let listen = (!tcp_only).then_some(CLIENT_LISTEN);
        let mut client = Session::client(SERVER, "server.test", listen, limits, now);
        for s in [&mut server, &mut client] {
            s.register(now, true, DEVICE.as_bytes()).unwrap();
            for t in [REPORT, TEXT, PING, PONG] {
                s.register(now, false, t.as_bytes()).unwrap();
            }
        }
        Pair {
            now,
            server: Side {
                session: server,
                seen: Vec::new(),
                udp_out: false,
                udp_in: false,
            },
            client: Side {
                session: client,
                seen: Vec::new(),
                udp_out: false,
                udp_in: false,
            },
            faults: Faults::default(),
            conn: None,
            datagrams: VecDeque::new(),
            requests: VecDeque::new(),
            rng: Rng::new(seed),
            ping: PingCycle::new(),
            requests_sent: Vec::new(),
            connections: 0,
            datagrams_sent: 0,
            datagrams_delivered: 0,
            datagram_log: Vec::new(),
        }
    }

    fn side(&mut self, who: Who) -> &mut Side {
        match who {
            Who::Client => &mut self.client,
            Who::Server => &mut self.server,
        }
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && (self.rng.below(1_000_000) as f64) < p * 1e6
    }

    /// Id of a name on one side.
    fn id(&self, who: Who, sender: bool, name: &str) -> i32 {
        let s = match who {
            Who::Client => &self.client.session,
            Who::Server => &self.server.session,
        };
        s.id_of(sender, name.as_bytes()).unwrap()
    }

    /// Sends a message of `type_name` from [`DEVICE`] on one side.
    pub fn send(&mut self, who: Who, type_name: &str, payload: &[u8], class_of_service: u32) {
        let (sender, t) = (self.id(who, true, DEVICE), self.id(who, false, type_name));
        let now = self.now;
        let s = &mut self.side(who).session;
        if s.pack(now.wall, sender, t, payload, class_of_service) {
            s.drop_backlogged(now);
        }
    }

    /// True when both sides count each other as connected.
    pub fn connected(&self) -> bool {
        self.client.session.connected_peers() == 1 && self.server.session.connected_peers() == 1
    }

    /// The earliest time anything is due.
    fn next_event(&self) -> Option<Instant> {
        let mut at: Vec<Instant> = Vec::new();
        at.extend(self.client.session.poll_timeout());
        at.extend(self.server.session.poll_timeout());
        at.extend(self.ping.next_deadline());
        at.extend(self.datagrams.iter().map(|d| d.0));
        at.extend(self.requests.iter().map(|r| r.0));
        if let Some(c) = &self.conn {
            at.extend(c.completing);
            at.extend(c.c2s.segments.front().map(|s| s.0));
            at.extend(c.s2c.segments.front().map(|s| s.0));
            at.extend(c.c2s.fin);
            at.extend(c.s2c.fin);
        }
        at.into_iter().min()
    }

    /// Moves the clock to `t` (never backwards).
    fn advance_to(&mut self, t: Instant) {
        if t > self.now.mono {
            self.now = self.now.plus(t - self.now.mono);
        }
    }

    /// Runs everything due now, then moves the clock to the next event (not past `limit`).
    /// Returns false when nothing is due before `limit`.
    pub fn step(&mut self, limit: Instant) -> bool {
        self.process();
        match self.next_event() {
            Some(t) if t <= limit => {
                let t = t.max(self.now.mono + Duration::from_micros(1));
                if t > limit {
                    return false;
                }
                self.advance_to(t);
                true
            }
            _ => false,
        }
    }

    /// Runs for `d` of virtual time.
    pub fn run_for(&mut self, d: Duration) {
        let limit = self.now.mono + d;
        while self.step(limit) {}
        self.advance_to(limit);
        self.process();
    }

    /// Runs until `done` or `max` of virtual time; returns whether `done` held. `done` is
    /// checked after everything due at each moment has run, before the clock moves on.
    pub fn run_until(&mut self, max: Duration, mut done: impl FnMut(&Pair) -> bool) -> bool {
        let limit = self.now.mono + max;
        loop {
            self.process();
            if done(self) {
                return true;
            }
            match self.next_event() {
                Some(t) if t <= limit => {
                    let t = t.max(self.now.mono + Duration::from_micros(1));
                    self.advance_to(t.min(limit));
                }
                _ => {
                    self.advance_to(limit);
                    self.process();
                    return done(self);
                }
            }
            if self.now.mono >= limit {
                self.process();
                return done(self);
            }
        }
    }

    /// Everything due at the current time, until nothing changes.
    fn process(&mut self) {
        for _ in 0..10_000 {
            let mut busy = false;
            let now = self.now;
            for who in [Who::Server, Who::Client] {
                let s = &mut self.side(who).session;
                if s.poll_timeout().is_some_and(|t| t <= now.mono) {
                    s.handle_timeout(now);
                }
                s.begin_pass(&now);
                busy |= self.carry_out(who);
            }
            busy |= self.deliver_link();
            for who in [Who::Server, Who::Client] {
                busy |= self.drain(who);
                busy |= self.carry_out(who);
                busy |= self.flush(who);
            }
            busy |= self.run_ping();
            if !busy {
                return;
            }
        }
        panic!("the pair did not settle");
    }

    /// The client's liveness cycle (what a remote runs), on the virtual clock.
    fn run_ping(&mut self) -> bool {
        let connected = self.client.session.connected_peers() > 0;
        let action = self.ping.poll(self.now.mono, connected);
        let text = match action {
            PingAction::Idle => return false,
            PingAction::Ping => None,
            PingAction::PingAndWarn(s) => Some((wire::payload::text::WARNING, s)),
            PingAction::PingAndError(s) => Some((wire::payload::text::ERROR, s)),
        };
        self.send(Who::Client, PING, &[], class::RELIABLE);
        if let Some((severity, level)) = text {
            let msg =
                wire::payload::text::TextMessage::new(severity, level, b"no response").unwrap();
            let mut buf = [0u8; wire::payload::text::TEXT_PAYLOAD_LEN];
            msg.encode(&mut buf);
            self.send(Who::Client, TEXT, &buf, class::RELIABLE);
            let at = self.now.mono;
            self.client.seen.push(Seen::PingText(at, severity, level));
        }
        true
    }

    /// Carries out one side's I/O requests on the virtual network.
    fn carry_out(&mut self, who: Who) -> bool {
        let mut busy = false;
        let now = self.now;
        let latency = self.faults.latency;
        while let Some(req) = self.side(who).session.poll_io() {
            busy = true;
            match (who, req) {
                (Who::Client, IoRequest::SendRequest { .. }) => {
                    let text = self.client.session.request_text().to_vec();
                    self.requests_sent.push(now.mono);
                    self.requests.push_back((now.mono + latency, text));
                }
                (Who::Client, IoRequest::Connect { peer, .. }) => {
                    if self.faults.server_down {
                        let e = std::io::Error::from(std::io::ErrorKind::ConnectionRefused);
                        self.client.session.handle_connect_failed(now, peer, &e);
                        continue;
                    }
                    self.conn = Some(TcpConn {
                        client: Some(peer),
                        server: None,
                        c2s: Stream::default(),
                        s2c: Stream::default(),
                        completing: Some(now.mono + latency),
                    });
                    if let Some(bytes) = self.faults.impostor {
                        let c = self.conn.as_mut().unwrap();
                        if !bytes.is_empty() {
                            c.s2c
                                .segments
                                .push_back((now.mono + latency, bytes.to_vec()));
                            c.s2c.in_flight = bytes.len();
                            c.s2c.fin = Some(now.mono + latency);
                        }
                    }
                }
                (Who::Server, IoRequest::Connect { peer, addr }) => {
                    assert_eq!(addr, CLIENT_LISTEN, "call-back to the request's source");
                    self.conn = Some(TcpConn {
                        client: None,
                        server: Some(peer),
                        c2s: Stream::default(),
                        s2c: Stream::default(),
                        completing: Some(now.mono + latency),
                    });
                }
                (_, IoRequest::BindUdp { peer }) => {
                    let port = if who == Who::Server {
                        SERVER_UDP_PORT
                    } else {
                        CLIENT_UDP_PORT
                    };
                    self.side(who).udp_in = true;
                    self.side(who)
                        .session
                        .handle_udp_bound(now, peer, Some(port));
                }
                (_, IoRequest::OpenUdpOut { peer, .. }) => {
                    self.side(who).udp_out = true;
                    self.side(who).session.handle_udp_out(now, peer, true);
                }
                // Nothing to connect in memory: the link never delivers a stranger's datagram.
                (_, IoRequest::PinUdpSource { .. }) => {}
                (_, IoRequest::Close { peer }) => {
                    let Some(c) = self.conn.as_mut() else {
                        continue;
                    };
                    let mine = match who {
                        Who::Client => &mut c.client,
                        Who::Server => &mut c.server,
                    };
                    let closed = *mine == Some(peer);
                    if closed {
                        *mine = None;
                        let out = match who {
                            Who::Client => &mut c.c2s,
                            Who::Server => &mut c.s2c,
                        };
                        out.fin = Some(now.mono + latency);
                    }
                    if c.client.is_none() && c.server.is_none() {
                        self.conn = None;
                    }
                    if closed {
                        self.side(who).udp_out = false;
                        self.side(who).udp_in = false;
                    }
                }
                (_, IoRequest::SendRequest { .. }) => unreachable!("only clients request"),
            }
        }
        busy
    }

    /// Delivers what the link has due now.
    fn deliver_link(&mut self) -> bool {
        let now = self.now;
        let mut busy = false;
        // Connection requests reach the server.
        while self.requests.front().is_some_and(|r| r.0 <= now.mono) {
            let (_, text) = self.requests.pop_front().unwrap();
            busy = true;
            if !self.faults.server_down {
                let from = SocketAddrV4::new(CLIENT_IP, 40001);
                self.server.session.handle_request(now, from, &text);
            }
        }
        // A connect completes.
        if let Some(c) = self.conn.as_mut() {
            if c.completing.is_some_and(|t| t <= now.mono) {
                c.completing = None;
                busy = true;
                self.connections += 1;
                let server_end = SocketAddrV4::new(*SERVER.ip(), 3883);
                let client_end = SocketAddrV4::new(CLIENT_IP, 40002);
                match (c.client, c.server) {
                    (Some(cp), None) if self.faults.impostor.is_some() => {
                        // Another program accepts; the client's connect completes.
                        self.client.session.handle_connected(now, cp, client_end);
                    }
                    (Some(cp), None) => {
                        // TCP-only: the server accepts, the client's connect completes.
                        let sp = self
                            .server
                            .session
                            .handle_accept(now, client_end, server_end);
                        let c = self.conn.as_mut().unwrap();
                        c.server = sp;
                        self.client.session.handle_connected(now, cp, client_end);
                    }
                    (None, Some(sp)) => {
                        // Call-back: the client's listener accepts, the server's connect
                        // completes.
                        let cp =
                            self.client
                                .session
                                .handle_callback(now, server_end, CLIENT_LISTEN);
                        let c = self.conn.as_mut().unwrap();
                        c.client = cp;
                        self.server.session.handle_connected(now, sp, server_end);
                    }
                    _ => {}
                }
            }
        }
        busy |= self.deliver_stream(Who::Server);
        busy |= self.deliver_stream(Who::Client);
        // Datagrams.
        let mut i = 0;
        while i < self.datagrams.len() {
            if self.datagrams[i].0 > now.mono {
                i += 1;
                continue;
            }
            let (_, to, bytes) = self.datagrams.remove(i).unwrap();
            busy = true;
            let from = match to {
                Who::Client => SocketAddrV4::new(*SERVER.ip(), 50010),
                Who::Server => SocketAddrV4::new(CLIENT_IP, 50011),
            };
            let peer = self.peer_of(to);
            let side = self.side(to);
            if !side.udp_in {
                continue;
            }
            let Some(peer) = peer else { continue };
            if let Some(inbox) = side.session.udp_inbox(peer) {
                let n = bytes.len().min(vrpn::proto::buffers::INBOX_SLOT);
                inbox.buf[..n].copy_from_slice(&bytes[..n]);
                inbox.lens[0] = n;
                inbox.from[0] = from;
                side.session.handle_datagrams(peer, 1);
                self.datagrams_delivered += 1;
            } else {
                // The receiver cannot take it yet: it waits in the socket buffer.
                self.datagrams.insert(i, (now.mono, to, bytes));
                i += 1;
            }
        }
        busy
    }

    fn peer_of(&self, who: Who) -> Option<PeerId> {
        let c = self.conn.as_ref()?;
        match who {
            Who::Client => c.client,
            Who::Server => c.server,
        }
    }

    /// Feeds the bytes due for `to`'s end of the TCP connection.
    fn deliver_stream(&mut self, to: Who) -> bool {
        let now = self.now;
        if self.faults.stall == Some(to) {
            return false;
        }
        let Some(peer) = self.peer_of(to) else {
            return false;
        };
        let mut busy = false;
        loop {
            let split = self.faults.tcp_split;
            let piece = self.rng.below(200) as usize + 1;
            let c = self.conn.as_mut().unwrap();
            let stream = match to {
                Who::Client => &mut c.s2c,
                Who::Server => &mut c.c2s,
            };
            let Some((at, bytes)) = stream.segments.front_mut() else {
                break;
            };
            if *at > now.mono {
                break;
            }
            let len = if split {
                piece.min(bytes.len())
            } else {
                bytes.len()
            };
            let session = match to {
                Who::Client => &mut self.client.session,
                Who::Server => &mut self.server.session,
            };
            if !session.wants_tcp(peer) {
                break;
            }
            let took = session.handle_tcp(peer, &bytes[..len]);
            if took == 0 {
                break;
            }
            busy = true;
            bytes.drain(..took);
            let empty = bytes.is_empty();
            stream.in_flight -= took;
            if empty {
                stream.segments.pop_front();
            }
            // Let the receiver consume before it takes more (its buffer is bounded).
            if session.has_deliveries() || took < len {
                break;
            }
            if split {
                break;
            }
        }
        // The peer's close, once every byte before it is in.
        let c = self.conn.as_mut().unwrap();
        let stream = match to {
            Who::Client => &c.s2c,
            Who::Server => &c.c2s,
        };
        if stream.segments.is_empty() && stream.fin.is_some_and(|t| t <= now.mono) {
            match to {
                Who::Client => c.client = None,
                Who::Server => c.server = None,
            }
            self.side(to).session.handle_closed(now, peer, None);
            busy = true;
        }
        busy
    }

    /// Takes one side's deliveries, answering pings on the server and feeding pongs and
    /// events to the client's liveness cycle.
    fn drain(&mut self, who: Who) -> bool {
        let now = self.now;
        let mut busy = false;
        while let Some(d) = self.side(who).session.poll_delivery(&now) {
            busy = true;
            match d {
                Delivery::Message {
                    time,
                    sender,
                    type_id,
                    len,
                    ..
                } => {
                    let s = &self.side(who).session;
                    let sender_name = s
                        .name_of(true, sender)
                        .map(|n| String::from_utf8_lossy(n).into_owned())
                        .unwrap_or_default();
                    let type_name = s
                        .name_of(false, type_id)
                        .map(|n| String::from_utf8_lossy(n).into_owned())
                        .unwrap_or_default();
                    let payload = s.payload(len).to_vec();
                    if who == Who::Server && type_name == PING && !self.faults.no_pongs {
                        self.send(Who::Server, PONG, &[], class::RELIABLE);
                    }
                    if who == Who::Client && type_name == PONG {
                        self.ping.on_pong(time);
                    }
                    self.side(who).seen.push(Seen::Message {
                        at: now.mono,
                        time,
                        sender: sender_name,
                        type_name,
                        payload,
                    });
                }
                Delivery::Event(ev) => {
                    if who == Who::Client {
                        match ev {
                            ConnectionEvent::GotConnection => self.ping.on_connected(now.mono),
                            ConnectionEvent::DroppedConnection => self.ping.on_dropped(now.mono),
                            _ => {}
                        }
                    }
                    self.side(who).seen.push(Seen::Event(now.mono, ev));
                }
                Delivery::Notice(n) => self.side(who).seen.push(Seen::Notice(now.mono, n)),
                _ => {}
            }
        }
        busy
    }

    /// Moves one side's output into the link.
    fn flush(&mut self, who: Who) -> bool {
        let now = self.now;
        let latency = self.faults.latency;
        let Some(peer) = self.peer_of(who) else {
            return false;
        };
        let mut busy = false;
        // TCP, up to the window.
        let pending = self.side(who).session.tcp_pending(peer).to_vec();
        if !pending.is_empty() {
            let c = self.conn.as_mut().unwrap();
            let stream = match who {
                Who::Client => &mut c.c2s,
                Who::Server => &mut c.s2c,
            };
            let room = WINDOW.saturating_sub(stream.in_flight);
            let n = pending.len().min(room);
            if n > 0 && stream.fin.is_none() {
                stream
                    .segments
                    .push_back((now.mono + latency, pending[..n].to_vec()));
                stream.in_flight += n;
                self.side(who).session.tcp_sent(peer, n);
                busy = true;
            }
        }
        // UDP, through the faults.
        let to = match who {
            Who::Client => Who::Server,
            Who::Server => Who::Client,
        };
        while let Some(dg) = self.side(who).session.udp_front(peer).map(<[u8]>::to_vec) {
            self.side(who).session.udp_sent(peer);
            busy = true;
            if !self.side(who).udp_out {
                continue;
            }
            self.datagrams_sent += 1;
            self.datagram_log.push((who, dg.clone()));
            if self.chance(self.faults.udp_loss) {
                continue;
            }
            let mut dg = dg;
            if self.chance(self.faults.udp_truncate) && dg.len() > 30 {
                let cut = 25 + self.rng.below(dg.len() as u64 - 26) as usize;
                dg.truncate(cut);
            }
            let copies = if self.chance(self.faults.udp_duplicate) {
                2
            } else {
                1
            };
            for _ in 0..copies {
                let jitter = self.faults.udp_jitter.as_nanos() as u64;
                let extra = Duration::from_nanos(if jitter > 0 {
                    self.rng.below(jitter)
                } else {
                    0
                });
                let at = now.mono + latency + extra;
                // Keep the queue ordered by arrival (jitter reorders datagrams).
                let pos = self
                    .datagrams
                    .iter()
                    .position(|d| d.0 > at)
                    .unwrap_or(self.datagrams.len());
                self.datagrams.insert(pos, (at, to, dg.clone()));
            }
        }
        busy
    }

    /// Closes one side's end of the TCP connection abruptly (its session sees an error).
    pub fn break_connection(&mut self, who: Who) {
        let now = self.now;
        let Some(peer) = self.peer_of(who) else {
            return;
        };
        let e = std::io::Error::from(std::io::ErrorKind::ConnectionReset);
        self.side(who).session.handle_closed(now, peer, Some(&e));
    }

    /// Connects a raw TCP peer to the server that sends `bytes`; returns the server's peer.
    pub fn raw_peer_to_server(&mut self, bytes: &[u8]) -> Option<PeerId> {
        let now = self.now;
        let from = SocketAddrV4::new(Ipv4Addr::new(10, 0, 0, 9), 40009);
        let id = self.server.session.handle_accept(now, from, SERVER)?;
        let took = self.server.session.handle_tcp(id, bytes);
        assert!(took > 0 || bytes.is_empty());
        Some(id)
    }

    /// The notices one side saw.
    pub fn notices(&self, who: Who) -> Vec<String> {
        let side = match who {
            Who::Client => &self.client,
            Who::Server => &self.server,
        };
        side.seen
            .iter()
            .filter_map(|s| match s {
                Seen::Notice(_, n) => Some(n.text.clone()),
                _ => None,
            })
            .collect()
    }

    /// Messages of `type_name` one side received.
    pub fn received(&self, who: Who, type_name: &str) -> Vec<&Seen> {
        let side = match who {
            Who::Client => &self.client,
            Who::Server => &self.server,
        };
        side.seen
            .iter()
            .filter(|s| matches!(s, Seen::Message { type_name: t, .. } if t == type_name))
            .collect()
    }

    /// Times of one side's connection events of kind `ev`.
    pub fn events(&self, who: Who, ev: ConnectionEvent) -> Vec<Instant> {
        let side = match who {
            Who::Client => &self.client,
            Who::Server => &self.server,
        };
        side.seen
            .iter()
            .filter_map(|s| match s {
                Seen::Event(t, e) if *e == ev => Some(*t),
                _ => None,
            })
            .collect()
    }
}
