//! Tracker reports per second over loopback TCP with the sender and the receiver in separate
//! threads (each owning its own connection), as the C++ figures were measured with a separate
//! server and client process. The sender reports K poses per `mainloop()` (one flush) while its
//! reliable backlog stays under 256 KiB; every report must arrive. Baseline: a raw TCP socket
//! pair doing the same with 88-byte messages, K per `write`.

use std::cell::Cell;
use std::io::{ErrorKind, Read, Write};
use std::net::{Ipv4Addr, TcpListener, TcpStream};
use std::rc::Rc;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use vrpn::{Connection, TimeVal, TrackerRemote, TrackerServer};

const RUN: Duration = Duration::from_millis(1500);
const MSG: usize = 88;

fn vrpn_tcp(k: usize) -> (u64, f64) {
    let (port_tx, port_rx) = mpsc::channel();
    let (sent_tx, sent_rx) = mpsc::channel();
    let sender = std::thread::spawn(move || {
        let conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        port_tx.send(conn.local_port().unwrap()).unwrap();
        let server = TrackerServer::new("Tracker0", &conn, 1).unwrap();
        while conn.connected_peers() == 0 {
            conn.mainloop().unwrap();
        }
        // Let the handshake settle before timing.
        let t = Instant::now();
        while t.elapsed() < Duration::from_millis(100) {
            conn.mainloop().unwrap();
        }
        let mut sent = 0u64;
        let start = Instant::now();
        while start.elapsed() < RUN {
            if conn.pending_output() < 256 * 1024 {
                let now = TimeVal::now();
                for _ in 0..k {
                    server
                        .report_pose(0, now, [sent as f64, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
                        .unwrap();
                    sent += 1;
                }
            }
            conn.mainloop().unwrap();
        }
        while conn.pending_output() > 0 {
            conn.mainloop().unwrap();
        }
        sent_tx.send(sent).unwrap();
        // Keep the connection open until the receiver has counted.
        let t = Instant::now();
        while t.elapsed() < Duration::from_secs(2) {
            conn.mainloop().unwrap();
            std::thread::sleep(Duration::from_millis(1));
        }
    });
    let port: u16 = port_rx.recv().unwrap();
    let remote = TrackerRemote::new(&format!("Tracker0@tcp://127.0.0.1:{port}")).unwrap();
    let got = Rc::new(Cell::new(0u64));
    let first = Rc::new(Cell::new(None::<Instant>));
    let last = Rc::new(Cell::new(None::<Instant>));
    let (g, f, l) = (got.clone(), first.clone(), last.clone());
    remote.on_pose(move |p| {
        // Reports arrive in order and complete: the position carries the sequence number.
        assert_eq!(p.pos.x, g.get() as f64, "lost or reordered report");
        g.set(g.get() + 1);
        let now = Instant::now();
        if f.get().is_none() {
            f.set(Some(now));
        }
        l.set(Some(now));
    });
    let mut sent = None;
    let deadline = Instant::now() + RUN + Duration::from_secs(10);
    while Instant::now() < deadline {
        remote.mainloop().unwrap();
        if sent.is_none() {
            sent = sent_rx.try_recv().ok();
        }
        if sent.is_some_and(|s| got.get() >= s) {
            break;
        }
    }
    sender.join().unwrap();
    let sent = sent.expect("sender finished");
    assert_eq!(got.get(), sent, "TCP lost reports");
    let secs = last
        .get()
        .unwrap()
        .duration_since(first.get().unwrap())
        .as_secs_f64();
    (sent, got.get() as f64 / secs)
}

fn raw_tcp(k: usize) -> (u64, f64) {
    let l = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    let addr = l.local_addr().unwrap();
    let (sent_tx, sent_rx) = mpsc::channel();
    let sender = std::thread::spawn(move || {
        let (mut tx, _) = l.accept().unwrap();
        tx.set_nodelay(true).unwrap();
        tx.set_nonblocking(true).unwrap();
        let msg = [7u8; MSG];
        let mut out: Vec<u8> = Vec::with_capacity(512 * 1024);
        let mut written = 0;
        let mut sent = 0u64;
        let start = Instant::now();
        while start.elapsed() < RUN {
            if out.len() - written < 256 * 1024 {
                for _ in 0..k {
                    out.extend_from_slice(&msg);
                    sent += 1;
                }
            }
            while written < out.len() {
                match tx.write(&out[written..]) {
                    Ok(n) => written += n,
                    Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                    Err(e) => panic!("{e}"),
                }
            }
            if written == out.len() {
                out.clear();
                written = 0;
            }
        }
        tx.set_nonblocking(false).unwrap();
        tx.write_all(&out[written..]).unwrap();
        sent_tx.send(sent).unwrap();
        std::thread::sleep(Duration::from_secs(1));
    });
    let mut rx = TcpStream::connect(addr).unwrap();
    rx.set_nonblocking(true).unwrap();
    let mut buf = vec![0u8; 128 * 1024];
    let mut bytes = 0u64;
    let mut first = None;
    let mut last = Instant::now();
    let mut sent = None;
    loop {
        match rx.read(&mut buf) {
            Ok(n) => {
                bytes += n as u64;
                last = Instant::now();
                first.get_or_insert(last);
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => {}
            Err(e) => panic!("{e}"),
        }
        if sent.is_none() {
            sent = sent_rx.try_recv().ok();
        }
        if sent.is_some_and(|s| bytes >= s * MSG as u64) {
            break;
        }
    }
    sender.join().unwrap();
    let got = bytes / MSG as u64;
    let secs = last.duration_since(first.unwrap()).as_secs_f64();
    (got, got as f64 / secs)
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    println!("tracker reports per second over 127.0.0.1 TCP, sender and receiver in two threads");
    for k in [1, 10, 100] {
        let (n_raw, raw) = raw_tcp(k);
        let (n, vrpn) = vrpn_tcp(k);
        println!(
            "K={k:>3} per flush: raw {:>10.0}/s ({n_raw} msgs)   vrpn {:>10.0}/s ({n} reports, 0 lost) \
             = {:.2}× raw, {:.1}× C++ ({})",
            raw,
            vrpn,
            vrpn / raw,
            vrpn / if k == 1 { 120e3 } else { 440e3 },
            if k == 1 { "C++ 120k/s at 1 per flush" } else { "C++ 440k/s at 10 per flush" }
        );
    }
}
