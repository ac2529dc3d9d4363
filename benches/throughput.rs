//! Tracker reports per second over loopback, one sender and one receiver in one thread.
//!
//! Each step the server reports K poses (88 bytes each on the wire) and calls `mainloop()`,
//! which flushes them; then the client runs `mainloop()` once. K = 1 and K = 10 per flush,
//! over the `tcp://` path (no loss allowed) and the default UDP path (delivered rate and loss
//! reported). Baselines do the same with raw nonblocking sockets: K 88-byte messages
//! appended to a buffer and written with one `write` (TCP) or sent as one datagram (UDP), the
//! receiver reading whatever is there each step.

mod common;

use std::cell::Cell;
use std::io::{ErrorKind, Read, Write};
use std::net::{Ipv4Addr, TcpListener, TcpStream, UdpSocket};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::{Connection, TimeVal, TrackerRemote, TrackerServer};

const ROUNDS: usize = 10;
const SLICE: Duration = Duration::from_millis(100);
const MSG: usize = 88;

/// One sender/receiver pair: `step` sends K messages with one flush and lets the receiver
/// read once; `drain` waits for what is in flight.
trait Pair {
    fn step(&mut self);
    fn drain(&mut self);
    /// (sent, received)
    fn counts(&self) -> (u64, u64);
}

struct RawTcp {
    k: usize,
    tx: TcpStream,
    rx: TcpStream,
    out: Vec<u8>,
    written: usize,
    inbuf: Vec<u8>,
    partial: usize,
    sent: u64,
    received: u64,
}

impl RawTcp {
    fn new(k: usize) -> RawTcp {
        let l = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
        let tx = TcpStream::connect(l.local_addr().unwrap()).unwrap();
        let (rx, _) = l.accept().unwrap();
        for s in [&tx, &rx] {
            s.set_nodelay(true).unwrap();
            s.set_nonblocking(true).unwrap();
        }
        RawTcp {
            k,
            tx,
            rx,
            out: Vec::with_capacity(64 * 1024),
            written: 0,
            inbuf: vec![0; 128 * 1024],
            partial: 0,
            sent: 0,
            received: 0,
        }
    }

    /// Writes as much as the socket takes, keeping the rest for the next step.
    fn flush(&mut self) {
        while self.written < self.out.len() {
            match self.tx.write(&self.out[self.written..]) {
                Ok(n) => self.written += n,
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) => panic!("{e}"),
            }
        }
        if self.written == self.out.len() {
            self.out.clear();
            self.written = 0;
        }
    }

    fn recv(&mut self) {
        loop {
            match self.rx.read(&mut self.inbuf) {
                Ok(0) => panic!("closed"),
                Ok(n) => {
                    self.partial += n;
                    self.received += (self.partial / MSG) as u64;
                    self.partial %= MSG;
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) => panic!("{e}"),
            }
        }
    }
}

impl Pair for RawTcp {
    fn step(&mut self) {
        for _ in 0..self.k {
            self.out.extend_from_slice(&[5u8; MSG]);
        }
        self.sent += self.k as u64;
        self.flush();
        self.recv();
    }

    fn drain(&mut self) {
        common::spin_until(Duration::from_secs(5), || {
            self.flush();
            self.recv();
            self.received >= self.sent
        });
    }

    fn counts(&self) -> (u64, u64) {
        (self.sent, self.received)
    }
}

struct RawUdp {
    k: usize,
    tx: UdpSocket,
    rx: UdpSocket,
    buf: [u8; 2048],
    sent: u64,
    received: u64,
}

impl RawUdp {
    fn new(k: usize) -> RawUdp {
        let tx = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
        let rx = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
        tx.connect(rx.local_addr().unwrap()).unwrap();
        tx.set_nonblocking(true).unwrap();
        rx.set_nonblocking(true).unwrap();
        RawUdp {
            k,
            tx,
            rx,
            buf: [0; 2048],
            sent: 0,
            received: 0,
        }
    }

    fn recv(&mut self) {
        loop {
            match self.rx.recv(&mut self.buf) {
                Ok(n) => self.received += (n / MSG) as u64,
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) => panic!("{e}"),
            }
        }
    }
}

impl Pair for RawUdp {
    fn step(&mut self) {
        let mut dg = [5u8; MSG * 10];
        dg[0] = self.k as u8;
        self.sent += self.k as u64;
        let _ = self.tx.send(&dg[..MSG * self.k]);
        self.recv();
    }

    fn drain(&mut self) {
        let t = Instant::now();
        while self.received < self.sent && t.elapsed() < Duration::from_millis(20) {
            self.recv();
        }
    }

    fn counts(&self) -> (u64, u64) {
        (self.sent, self.received)
    }
}

struct Vrpn {
    k: usize,
    server: Connection,
    tracker: TrackerServer,
    remote: TrackerRemote,
    poses: Rc<Cell<u64>>,
    p0: u64,
    sent: u64,
    tcp_only: bool,
}

const POS: [f64; 3] = [1.0, 2.0, 3.0];
const QUAT: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

impl Vrpn {
    fn new(k: usize, tcp_only: bool) -> Vrpn {
        let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let port = server.local_port().unwrap();
        let tracker = TrackerServer::new("Tracker0", &server, 1).unwrap();
        let name = if tcp_only {
            format!("Tracker0@tcp://127.0.0.1:{port}")
        } else {
            format!("Tracker0@127.0.0.1:{port}")
        };
        let remote = TrackerRemote::new(&name).unwrap();
        let poses = Rc::new(Cell::new(0u64));
        let p = poses.clone();
        remote.on_pose(move |_| p.set(p.get() + 1));
        // Connect, let the ping cycle finish and the UDP channel come up.
        let warm = Instant::now();
        // Unreliable reports keep to TCP for Limits::udp_after_descriptions after the
        // handshake: warm up past that.
        let hold = vrpn::Limits::default().udp_after_descriptions + Duration::from_millis(50);
        while poses.get() < 1000 || remote.ping_cycle().waiting_for_pong() || warm.elapsed() < hold
        {
            assert!(warm.elapsed() < Duration::from_secs(10), "warm-up stalled");
            tracker.report_pose(0, TimeVal::now(), POS, QUAT).unwrap();
            server.mainloop().unwrap();
            remote.mainloop().unwrap();
        }
        for _ in 0..100 {
            server.mainloop().unwrap();
            remote.mainloop().unwrap();
        }
        let p0 = poses.get();
        Vrpn {
            k,
            server,
            tracker,
            remote,
            poses,
            p0,
            sent: 0,
            tcp_only,
        }
    }
}

impl Pair for Vrpn {
    fn step(&mut self) {
        let t = TimeVal::now();
        for _ in 0..self.k {
            self.tracker.report_pose(0, t, POS, QUAT).unwrap();
        }
        self.sent += self.k as u64;
        self.server.mainloop().unwrap();
        self.remote.mainloop().unwrap();
    }

    fn drain(&mut self) {
        let limit = if self.tcp_only {
            Duration::from_secs(5)
        } else {
            Duration::from_millis(20)
        };
        let t = Instant::now();
        while self.counts().1 < self.sent && t.elapsed() < limit {
            self.server.mainloop().unwrap();
            self.remote.mainloop().unwrap();
        }
    }

    fn counts(&self) -> (u64, u64) {
        (self.sent, self.poses.get() - self.p0)
    }
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let mut pairs: Vec<(String, Box<dyn Pair>)> = Vec::new();
    for k in [1, 10] {
        pairs.push((
            format!("raw TCP, {k} × 88 B per write"),
            Box::new(RawTcp::new(k)),
        ));
        pairs.push((
            format!("vrpn tcp://, {k} report(s) per flush"),
            Box::new(Vrpn::new(k, true)),
        ));
    }
    for k in [1, 10] {
        pairs.push((
            format!("raw UDP, {k} × 88 B per datagram"),
            Box::new(RawUdp::new(k)),
        ));
        pairs.push((
            format!("vrpn UDP, {k} report(s) per flush"),
            Box::new(Vrpn::new(k, false)),
        ));
    }
    // Interleaved slices, so that load from other processes hits every scenario alike.
    let mut elapsed = vec![Duration::ZERO; pairs.len()];
    for _ in 0..ROUNDS {
        for (i, (_, p)) in pairs.iter_mut().enumerate() {
            let start = Instant::now();
            while start.elapsed() < SLICE {
                p.step();
            }
            p.drain();
            elapsed[i] += start.elapsed();
        }
    }
    println!(
        "tracker reports per second, sender and receiver alternating in one thread \
         ({ROUNDS} interleaved slices of {SLICE:?} each)"
    );
    let mut base_rate = 0.0;
    for (i, (name, p)) in pairs.iter().enumerate() {
        let (sent, received) = p.counts();
        let rate = received as f64 / elapsed[i].as_secs_f64();
        let loss = 1.0 - received as f64 / sent as f64;
        let mut extra = format!("  loss {:.3}%", loss * 100.0);
        if i % 2 == 0 {
            base_rate = rate;
        } else {
            extra += &format!("  = {:.2}× raw", rate / base_rate);
        }
        common::print_rate(name, received, elapsed[i], &extra);
        if name.contains("tcp") {
            assert_eq!(received, sent, "{name}: TCP lost reports");
        }
    }
}
