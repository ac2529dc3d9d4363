//! User-level round trip over loopback, both ends spinning in one thread.
//!
//! Baselines: raw nonblocking TCP (TCP_NODELAY) and UDP sockets ping-ponging a 24-byte
//! message. VRPN: a client pings a `TrackerServer` (RELIABLE, so over TCP) and waits for the
//! pong, on the TCP-only path and on the default UDP path; and on the UDP path a LOW_LATENCY
//! user message is echoed by a server handler, so that the UDP channel is what is measured.
//! Every VRPN message here is a bare 24-byte header, the size of the raw messages.
//!
//! A second pair of baselines runs the same raw sockets the way an event-driven library must:
//! each side has its own epoll set (mio) and polls it once per pass before it reads, and the
//! passes alternate as they do for VRPN (client: poll, read, send; server: poll, read, reply),
//! so a round trip makes the same three `epoll_wait`s, two sends and two receives as the VRPN
//! scenarios. VRPN over that baseline is what the library itself costs (user code, buffers);
//! the epoll baseline over the raw one is what any reactor costs.
//!
//! Scenarios are measured in interleaved rounds, so that load from other processes affects
//! baseline and VRPN alike.

mod common;

use std::cell::Cell;
use std::io::{ErrorKind, Read, Write};
use std::net::{Ipv4Addr, TcpListener, TcpStream, UdpSocket};
use std::rc::Rc;
use std::time::Duration;

use common::{spin_until, Samples};
use vrpn::wire::class;
use vrpn::{Connection, Limits, SenderFilter, TimeVal, TrackerServer};

const N: usize = 20_000;
const ROUNDS: usize = 10;
const LIMIT: Duration = Duration::from_secs(5);

fn read_spin(s: &mut TcpStream, buf: &mut [u8]) {
    let mut got = 0;
    spin_until(LIMIT, || {
        match s.read(&mut buf[got..]) {
            Ok(0) => panic!("peer closed"),
            Ok(n) => got += n,
            Err(e) if e.kind() == ErrorKind::WouldBlock => {}
            Err(e) => panic!("{e}"),
        }
        got == buf.len()
    });
}

fn raw_tcp() -> impl FnMut() {
    let l = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    let mut a = TcpStream::connect(l.local_addr().unwrap()).unwrap();
    let (mut b, _) = l.accept().unwrap();
    for s in [&a, &b] {
        s.set_nodelay(true).unwrap();
        s.set_nonblocking(true).unwrap();
    }
    let msg = [7u8; 24];
    let mut buf = [0u8; 24];
    move || {
        a.write_all(&msg).unwrap();
        read_spin(&mut b, &mut buf);
        b.write_all(&buf).unwrap();
        read_spin(&mut a, &mut buf);
    }
}

fn recv_spin(s: &UdpSocket, buf: &mut [u8]) {
    spin_until(LIMIT, || match s.recv(buf) {
        Ok(n) => {
            assert_eq!(n, 24);
            true
        }
        Err(e) if e.kind() == ErrorKind::WouldBlock => false,
        Err(e) => panic!("{e}"),
    });
}

fn raw_udp() -> impl FnMut() {
    let a = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    let b = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    a.connect(b.local_addr().unwrap()).unwrap();
    b.connect(a.local_addr().unwrap()).unwrap();
    a.set_nonblocking(true).unwrap();
    b.set_nonblocking(true).unwrap();
    let msg = [7u8; 24];
    let mut buf = [0u8; 64];
    move || {
        a.send(&msg).unwrap();
        recv_spin(&b, &mut buf);
        b.send(&buf[..24]).unwrap();
        recv_spin(&a, &mut buf);
    }
}

/// One side of an epoll ping-pong: a socket in an epoll set of its own.
struct EpollSide<S> {
    poll: mio::Poll,
    events: mio::Events,
    sock: S,
}

impl<S: mio::event::Source> EpollSide<S> {
    /// `interest` as the library registers the same kind of socket: a TCP stream for reading
    /// and writing, a UDP socket for reading only (a UDP socket registered for writing would
    /// get a write-space event after every datagram it sends).
    fn new(mut sock: S, interest: mio::Interest) -> EpollSide<S> {
        let poll = mio::Poll::new().unwrap();
        poll.registry()
            .register(&mut sock, mio::Token(1), interest)
            .unwrap();
        EpollSide {
            poll,
            events: mio::Events::with_capacity(256),
            sock,
        }
    }

    /// One poll without waiting: whether the socket became readable.
    fn readable(&mut self) -> bool {
        self.poll
            .poll(&mut self.events, Some(Duration::ZERO))
            .unwrap();
        self.events.iter().any(|e| e.is_readable())
    }
}

/// Reads one 24-byte message from an edge-triggered stream: a read shorter than the buffer
/// proves the socket empty (what the library does too).
fn read_message(s: &mut mio::net::TcpStream, buf: &mut [u8]) -> bool {
    match s.read(buf) {
        Ok(0) => panic!("peer closed"),
        Ok(n) => {
            assert_eq!(n, 24);
            true
        }
        Err(e) if e.kind() == ErrorKind::WouldBlock => false,
        Err(e) => panic!("{e}"),
    }
}

/// Raw TCP through two epoll loops, in the passes of the VRPN scenarios.
fn epoll_tcp() -> impl FnMut() {
    let l = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    let a = TcpStream::connect(l.local_addr().unwrap()).unwrap();
    let (b, _) = l.accept().unwrap();
    for s in [&a, &b] {
        s.set_nodelay(true).unwrap();
        s.set_nonblocking(true).unwrap();
    }
    let both = mio::Interest::READABLE | mio::Interest::WRITABLE;
    let mut a = EpollSide::new(mio::net::TcpStream::from_std(a), both);
    let mut b = EpollSide::new(mio::net::TcpStream::from_std(b), both);
    let msg = [7u8; 24];
    let mut buf = vec![0u8; 4096];
    move || {
        let mut ping = true;
        spin_until(LIMIT, || {
            // Client pass: poll, read the pong if it came, send the ping if it is queued.
            let answered = a.readable() && read_message(&mut a.sock, &mut buf);
            if ping {
                a.sock.write_all(&msg).unwrap();
                ping = false;
            }
            if answered {
                return true;
            }
            // Server pass: poll, read the ping, reply.
            if b.readable() && read_message(&mut b.sock, &mut buf) {
                b.sock.write_all(&buf[..24]).unwrap();
            }
            false
        });
    }
}

/// Receives one 24-byte datagram if there is one.
fn recv_datagram(s: &mio::net::UdpSocket, buf: &mut [u8]) -> bool {
    match s.recv(buf) {
        Ok(n) => {
            assert_eq!(n, 24);
            true
        }
        Err(e) if e.kind() == ErrorKind::WouldBlock => false,
        Err(e) => panic!("{e}"),
    }
}

/// Raw UDP through two epoll loops, in the passes of the VRPN scenarios. With `drain`, each
/// side reads after every datagram until the socket says `WouldBlock`, as an edge-triggered
/// loop must when it cannot know that one datagram was all (the library proves it with a
/// two-slot `recvmmsg` instead).
fn epoll_udp(drain: bool) -> impl FnMut() {
    let a = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    let b = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    a.connect(b.local_addr().unwrap()).unwrap();
    b.connect(a.local_addr().unwrap()).unwrap();
    a.set_nonblocking(true).unwrap();
    b.set_nonblocking(true).unwrap();
    let mut a = EpollSide::new(mio::net::UdpSocket::from_std(a), mio::Interest::READABLE);
    let mut b = EpollSide::new(mio::net::UdpSocket::from_std(b), mio::Interest::READABLE);
    let msg = [7u8; 24];
    let mut buf = [0u8; 64];
    let mut spare = [0u8; 64];
    move || {
        let mut ping = true;
        spin_until(LIMIT, || {
            let answered = a.readable() && recv_datagram(&a.sock, &mut buf);
            if answered && drain {
                assert!(!recv_datagram(&a.sock, &mut spare));
            }
            if ping {
                a.sock.send(&msg).unwrap();
                ping = false;
            }
            if answered {
                return true;
            }
            if b.readable() && recv_datagram(&b.sock, &mut buf) {
                if drain {
                    assert!(!recv_datagram(&b.sock, &mut spare));
                }
                b.sock.send(&buf[..24]).unwrap();
            }
            false
        });
    }
}

/// A server connection with a tracker (which answers pings) and a custom echo type, and a
/// client connection to it.
struct VrpnPair {
    server: Connection,
    client: Connection,
    _tracker: TrackerServer,
    ping: (vrpn::TypeId, vrpn::SenderId),
    echo: (vrpn::TypeId, vrpn::SenderId),
    answered: Rc<Cell<bool>>,
}

impl VrpnPair {
    fn new(tcp_only: bool) -> VrpnPair {
        let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let port = server.local_port().unwrap();
        let tracker = TrackerServer::new("Tracker0", &server, 1).unwrap();
        // Echo: the server answers "bench echo" from "bench client" with one from "bench server"
        // (a different sender, so the server's own echo does not reach this handler again).
        let s_echo = server.register_type("bench echo").unwrap();
        let s_from = server.register_sender("bench client").unwrap();
        let s_to = server.register_sender("bench server").unwrap();
        let weak = server.downgrade();
        server.register_handler(s_echo, SenderFilter::Only(s_from), move |m| {
            if let Some(c) = weak.upgrade() {
                c.pack_message(m.time, s_echo, s_to, m.payload, class::LOW_LATENCY)
                    .unwrap();
            }
        });

        let client = Connection::client("127.0.0.1", port, tcp_only, Limits::default()).unwrap();
        let answered = Rc::new(Cell::new(false));
        let dev = client.register_sender("Tracker0").unwrap();
        let ping = client.register_type("vrpn_Base ping_message").unwrap();
        let pong = client.register_type("vrpn_Base pong_message").unwrap();
        let a = answered.clone();
        client.register_handler(pong, SenderFilter::Only(dev), move |_| a.set(true));
        let c_echo = client.register_type("bench echo").unwrap();
        let c_from = client.register_sender("bench client").unwrap();
        let c_to = client.register_sender("bench server").unwrap();
        let a = answered.clone();
        client.register_handler(c_echo, SenderFilter::Only(c_to), move |_| a.set(true));

        spin_until(LIMIT, || {
            client.mainloop().unwrap();
            server.mainloop().unwrap();
            client.connected() && server.connected()
        });
        let pair = VrpnPair {
            server,
            client,
            _tracker: tracker,
            ping: (ping, dev),
            echo: (c_echo, c_from),
            answered,
        };
        // Unreliable messages keep to TCP for a while after the descriptions
        // (`Limits::udp_after_descriptions`): let that pass, then warm up.
        let udp_open = std::time::Instant::now()
            + Limits::default().udp_after_descriptions
            + Duration::from_millis(20);
        while std::time::Instant::now() < udp_open {
            pair.client.mainloop().unwrap();
            pair.server.mainloop().unwrap();
        }
        // Let both sides learn each other's names and UDP ports.
        for _ in 0..200 {
            pair.round_trip(pair.ping, class::RELIABLE);
            pair.round_trip(pair.echo, class::LOW_LATENCY);
        }
        pair
    }

    fn round_trip(&self, (t, s): (vrpn::TypeId, vrpn::SenderId), class_of_service: u32) {
        self.answered.set(false);
        self.client
            .pack_message(TimeVal::now(), t, s, &[], class_of_service)
            .unwrap();
        spin_until(LIMIT, || {
            self.client.mainloop().unwrap();
            if self.answered.get() {
                return true;
            }
            self.server.mainloop().unwrap();
            false
        });
    }
}

/// `OutDatagrams` of this network namespace: evidence of which channel carried messages.
fn udp_out_datagrams() -> u64 {
    let text = std::fs::read_to_string("/proc/net/snmp").unwrap_or_default();
    let mut lines = text.lines().filter(|l| l.starts_with("Udp:"));
    let (Some(names), Some(values)) = (lines.next(), lines.next()) else {
        return 0;
    };
    let col = names.split_whitespace().position(|n| n == "OutDatagrams");
    col.and_then(|c| values.split_whitespace().nth(c))
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let tcp_pair = VrpnPair::new(true);
    let udp_pair = VrpnPair::new(false);
    type Scenario<'a> = (&'static str, Box<dyn FnMut() + 'a>);
    let mut scenarios: Vec<Scenario> = vec![
        ("raw TCP 24 B ping-pong", Box::new(raw_tcp())),
        ("raw UDP 24 B ping-pong", Box::new(raw_udp())),
        ("raw TCP through epoll, 3 passes", Box::new(epoll_tcp())),
        (
            "raw UDP through epoll, 3 passes",
            Box::new(epoll_udp(false)),
        ),
        ("raw UDP through epoll, drained", Box::new(epoll_udp(true))),
        (
            "vrpn tcp:// ping→pong (TCP)",
            Box::new(|| tcp_pair.round_trip(tcp_pair.ping, class::RELIABLE)),
        ),
        (
            "vrpn udp path ping→pong (TCP)",
            Box::new(|| udp_pair.round_trip(udp_pair.ping, class::RELIABLE)),
        ),
        (
            "vrpn udp path LOW_LATENCY echo (UDP)",
            Box::new(|| udp_pair.round_trip(udp_pair.echo, class::LOW_LATENCY)),
        ),
    ];
    // `cargo bench --bench round_trip -- FILTER` keeps the scenarios whose name contains FILTER.
    if let Some(filter) = std::env::args().skip(1).find(|a| !a.starts_with('-')) {
        scenarios.retain(|(name, _)| name.contains(&filter));
    }
    let mut samples: Vec<Vec<u64>> = vec![Vec::with_capacity(N); scenarios.len()];
    let mut datagrams = vec![0u64; scenarios.len()];
    for _ in 0..ROUNDS {
        for (k, (_, f)) in scenarios.iter_mut().enumerate() {
            for _ in 0..100 {
                f();
            }
            let d0 = udp_out_datagrams();
            for _ in 0..N / ROUNDS {
                let t = std::time::Instant::now();
                f();
                samples[k].push(t.elapsed().as_nanos() as u64);
            }
            datagrams[k] += udp_out_datagrams() - d0;
        }
    }
    let s: Vec<Samples> = scenarios
        .iter()
        .zip(samples)
        .map(|((name, _), ns)| Samples::from_ns(name, ns))
        .collect();
    println!("round trip over 127.0.0.1, both ends spinning in one thread ({N} per scenario)");
    for (x, d) in s.iter().zip(&datagrams) {
        x.print_us();
        println!("    UDP datagrams sent during the measurement (whole host): {d}");
    }
    // The targets against the raw loops; against the epoll loops, what the library
    // adds to any reactor (no target: printed against 1.0).
    let find = |prefix: &str| s.iter().find(|x| x.name.starts_with(prefix));
    let ratios = [
        ("vrpn tcp://", "raw TCP 24", 1.15),
        ("vrpn udp path ping", "raw TCP 24", 1.15),
        ("vrpn udp path LOW", "raw UDP 24", 1.3),
        ("raw TCP through", "raw TCP 24", 1.0),
        ("raw UDP through epoll, 3", "raw UDP 24", 1.0),
        ("raw UDP through epoll, d", "raw UDP 24", 1.0),
        ("vrpn tcp://", "raw TCP through", 1.0),
        ("vrpn udp path ping", "raw TCP through", 1.0),
        ("vrpn udp path LOW", "raw UDP through epoll, 3", 1.0),
        ("vrpn udp path LOW", "raw UDP through epoll, d", 1.0),
    ];
    for (what, base, target) in ratios {
        if let (Some(w), Some(b)) = (find(what), find(base)) {
            common::print_ratio(w, b, target);
        }
    }
}
