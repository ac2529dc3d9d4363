//! Faults against the vrpn_server binary and a client: a half-open peer that stops responding,
//! truncated datagrams on a client's inbound UDP port, and a server killed with SIGKILL and
//! restarted on the same port while its clients reconnect and resume.

mod common;

use std::cell::{Cell, RefCell};
use std::io::Write;
use std::net::{Ipv4Addr, TcpStream, UdpSocket};
use std::rc::Rc;
use std::time::{Duration, Instant};

use common::*;
use vrpn::wire::{header::encode_message, Cookie, Header};
use vrpn::{Connection, Limits, TimeVal, TrackerRemote};

const CFG: &str = "vrpn_Tracker_NULL Tracker0 2 200\n";

struct Client {
    conn: Connection,
    tracker: TrackerRemote,
    poses: Rc<Cell<u64>>,
    notices: Rc<RefCell<Vec<String>>>,
}

fn client(port: u16, tcp_only: bool) -> Client {
    let limits = Limits {
        retry_interval: Duration::from_millis(200),
        ..Limits::default()
    };
    let conn = Connection::client("127.0.0.1", port, tcp_only, limits).unwrap();
    let notices = Rc::new(RefCell::new(Vec::new()));
    let n = notices.clone();
    conn.on_notice(move |x| n.borrow_mut().push(x.text.clone()));
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    tracker.on_pose(move |_| p.set(p.get() + 1));
    Client {
        conn,
        tracker,
        poses,
        notices,
    }
}

/// Pumps every client until each has `more` poses beyond what it had.
fn until_more(clients: &[&Client], more: u64, what: &str) {
    let base: Vec<u64> = clients.iter().map(|c| c.poses.get()).collect();
    let start = Instant::now();
    while clients
        .iter()
        .zip(&base)
        .any(|(c, b)| c.poses.get() < b + more)
    {
        assert!(
            start.elapsed() < Duration::from_secs(15),
            "timed out: {what}"
        );
        for c in clients {
            c.tracker.mainloop().unwrap();
        }
        std::thread::sleep(Duration::from_micros(500));
    }
}

#[test]
fn half_open_peer_does_not_block_the_server() {
    let server = start_server(CFG, 0);
    let good = client(server.port, true);
    until_more(&[&good], 50, "first poses");
    // Peers that vanish without a FIN: one stops mid-handshake, one mid-message, one after
    // the handshake; none reads or writes again, their sockets stay open.
    let mut silent = Vec::new();
    for cut in [10usize, 24 + 13, 24] {
        let mut s = TcpStream::connect((Ipv4Addr::LOCALHOST, server.port)).unwrap();
        let mut bytes = Cookie::ours(0).to_bytes().to_vec();
        let h = Header {
            payload_len: 64,
            time: TimeVal::now(),
            sender: 0,
            type_id: 5,
            seq: 0,
        };
        let mut m = vec![0u8; h.wire_size()];
        encode_message(&mut m, &h, &[1; 64]).unwrap();
        bytes.extend_from_slice(&m);
        s.write_all(&bytes[..cut]).unwrap();
        silent.push(s);
    }
    let pinger = Pinger::new(&good.conn, "Tracker0");
    let mut rtts = pinger.round_trips(100, || {});
    let (p50, p99) = p50_p99(&mut rtts);
    println!("with 3 half-open peers: ping p50 {p50:.0} µs, p99 {p99:.0} µs");
    until_more(&[&good], 100, "poses with half-open peers present");
    assert!(good.conn.connected());
}

/// UDP ports bound by sockets of this process (from /proc/self/fd and /proc/net/udp).
fn own_udp_ports() -> Vec<u16> {
    let mut inodes = Vec::new();
    for e in std::fs::read_dir("/proc/self/fd").unwrap().flatten() {
        if let Ok(l) = std::fs::read_link(e.path()) {
            let l = l.to_string_lossy().to_string();
            if let Some(i) = l.strip_prefix("socket:[").and_then(|r| r.strip_suffix(']')) {
                inodes.push(i.to_string());
            }
        }
    }
    let table = std::fs::read_to_string("/proc/net/udp").unwrap();
    let mut ports = Vec::new();
    for line in table.lines().skip(1) {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() > 9 && inodes.iter().any(|i| i == f[9]) {
            if let Some(p) = f[1].split(':').nth(1) {
                ports.push(u16::from_str_radix(p, 16).unwrap());
            }
        }
    }
    ports
}

/// Junk sent to every UDP socket of a connected client from another port of the server's host
/// (truncated messages, a bad length, garbage). Once the server's first datagram arrived, the
/// client's UDP channel is pinned to the server's source (`IoRequest::PinUdpSource`), so the
/// kernel drops the junk before the session sees it; the client keeps its connection and its
/// reports. (The session's own handling of a malformed datagram from the peer, with its notice,
/// is tested on the in-memory pair, whose link truncates datagrams.)
#[test]
fn junk_datagrams_to_a_client_are_dropped_before_they_reach_it() {
    let server = start_server(CFG, 0);
    let c = client(server.port, false);
    until_more(&[&c], 50, "first poses");
    // Reports come by UDP once Limits::udp_after_descriptions has passed (or sooner, once the
    // client has answered a clock query), and the client's UDP socket takes only the server's
    // datagrams from the first one on: the junk must come after that.
    let hold = Instant::now();
    while hold.elapsed() < Limits::default().udp_after_descriptions {
        until_more(&[&c], 1, "poses during the hold");
    }
    until_more(&[&c], 50, "first poses over UDP");
    let ports = own_udp_ports();
    assert!(!ports.is_empty(), "no UDP socket found for the client");
    let h = Header {
        payload_len: 100,
        time: TimeVal::now(),
        sender: 0,
        type_id: 5,
        seq: 0,
    };
    let mut whole = vec![0u8; h.wire_size()];
    encode_message(&mut whole, &h, &[9; 100]).unwrap();
    let mut bad_len = whole.clone();
    bad_len[0..4].copy_from_slice(&7u32.to_be_bytes());
    let junk: Vec<&[u8]> = vec![
        &whole[..30],
        &whole[..24],
        &whole[..5],
        &bad_len,
        b"\xff\xff\xff\xff garbage",
    ];
    let udp = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    for _ in 0..20 {
        for p in &ports {
            for j in &junk {
                let _ = udp.send_to(j, (Ipv4Addr::LOCALHOST, *p));
            }
        }
        until_more(&[&c], 5, "poses between bursts");
    }
    until_more(&[&c], 100, "poses after the junk");
    assert!(c.conn.connected());
    assert!(
        !c.notices
            .borrow()
            .iter()
            .any(|n| n.contains("malformed UDP datagram") || n.contains("another address")),
        "junk reached the session: {:?}",
        c.notices.borrow()
    );
}

#[test]
fn server_killed_and_restarted_clients_resume() {
    let mut server = start_server(CFG, 0);
    let port = server.port;
    let udp = client(port, false);
    let tcp = client(port, true);
    until_more(&[&udp, &tcp], 50, "first poses");
    for round in 0..2 {
        server.child.kill().unwrap(); // SIGKILL, by PID
        let _ = server.child.wait();
        // Clients notice and keep retrying while nothing listens.
        let start = Instant::now();
        while udp.conn.connected() || tcp.conn.connected() {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "loss not noticed"
            );
            udp.tracker.mainloop().unwrap();
            tcp.tracker.mainloop().unwrap();
            std::thread::sleep(Duration::from_millis(1));
        }
        for _ in 0..100 {
            udp.tracker.mainloop().unwrap();
            tcp.tracker.mainloop().unwrap();
            std::thread::sleep(Duration::from_millis(2));
        }
        server = start_server(CFG, port);
        assert_eq!(server.port, port);
        until_more(&[&udp, &tcp], 100, "poses after restart");
        println!("round {round}: both clients resumed after SIGKILL + restart");
    }
}
