//! A client that stops reading must not block the server or delay other clients: its
//! unreliable traffic gives way first, and once its reliable backlog passes the limit it is
//! dropped with a notice. Also measures a normal client's ping round trip with and without a
//! stalled client on the same server (vrpn_server binary), and prints the figures.

mod common;

use std::cell::{Cell, RefCell};
use std::io::Write;
use std::net::{Ipv4Addr, TcpStream};
use std::rc::Rc;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use common::*;
use vrpn::wire::{class, Cookie};
use vrpn::{Connection, Limits, Notice, ServerDevice, TimeVal, TrackerNull, TrackerRemote};

/// The two tests run one at a time: one pushes megabytes through the machine, the other
/// measures latency, and on 2 cores the first would distort the second.
static SERIAL: Mutex<()> = Mutex::new(());

#[test]
fn stalled_client_sheds_unreliable_then_is_dropped() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let limit = 256 * 1024;
    let server = Connection::server_with_limits(
        Some(Ipv4Addr::LOCALHOST),
        0,
        Limits {
            max_pending_output: limit,
            ..Limits::default()
        },
    )
    .unwrap();
    let port = server.local_port().unwrap();
    let notices = Rc::new(RefCell::new(Vec::<Notice>::new()));
    let n = notices.clone();
    server.on_notice(move |x| n.borrow_mut().push(x.clone()));
    let mut null = TrackerNull::new("Tracker0", &server, 8, 1000.0).unwrap();
    let good_conn = Connection::client("127.0.0.1", port, false, Limits::default()).unwrap();
    good_conn.on_notice(|_| {});
    let good = TrackerRemote::on_connection("Tracker0", &good_conn).unwrap();
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    good.on_pose(move |_| p.set(p.get() + 1));
    let mut step = || {
        null.mainloop(vrpn::Now::read());
        server.mainloop().unwrap();
        good.mainloop().unwrap();
    };
    let start = Instant::now();
    while poses.get() < 100 {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "good client got no poses"
        );
        step();
        std::thread::sleep(Duration::from_micros(200));
    }

    // The stalled client: a raw TCP peer that sends its cookie and never reads.
    let mut stalled = TcpStream::connect((Ipv4Addr::LOCALHOST, port)).unwrap();
    stalled.write_all(&Cookie::ours(0).to_bytes()).unwrap();
    while server.connected_peers() < 2 {
        assert!(start.elapsed() < Duration::from_secs(10));
        step();
    }
    let flood = server.register_sender("Flood").unwrap();
    let ft = server.register_type("flood").unwrap();
    let payload = [0u8; 1000];
    // New names keep the good client's unreliable messages on TCP for
    // Limits::udp_after_descriptions (or until it answers a clock query sent in that time):
    // the flood starts after that, so that it goes to the good client by UDP and only the
    // stalled peer's TCP backlog grows.
    let described = Instant::now();
    while described.elapsed() < Limits::default().udp_after_descriptions + Duration::from_millis(20)
    {
        step();
        std::thread::sleep(Duration::from_micros(200));
    }

    // 1. Unreliable flood, far more than the limit: shed, never dropped for it. The kernel
    // absorbs megabytes first (loopback receive buffers autotune up to net.ipv4.tcp_rmem's
    // maximum), so the flood goes on until shedding is seen, within a bound.
    let mut max_pending = 0;
    let mut sent = 0usize;
    let t = Instant::now();
    let shedding = |n: &RefCell<Vec<Notice>>| {
        n.borrow()
            .iter()
            .any(|n| n.text.contains("is falling behind"))
    };
    while (sent < 40 * limit || !shedding(&notices))
        && sent < 400 * limit
        && t.elapsed() < Duration::from_secs(20)
    {
        for _ in 0..50 {
            server
                .pack_message(TimeVal::now(), ft, flood, &payload, class::LOW_LATENCY)
                .unwrap();
            sent += payload.len();
        }
        max_pending = max_pending.max(server.pending_output());
        step();
    }
    assert_eq!(server.connected_peers(), 2, "{:?}", notices.borrow());
    assert!(
        max_pending <= limit / 2 + 2048,
        "unreliable backlog {max_pending} passed half the limit {limit}"
    );
    assert!(
        notices
            .borrow()
            .iter()
            .any(|n| n.text.contains("is falling behind")),
        "{:?}",
        notices.borrow()
    );
    println!(
        "unreliable flood: {sent} bytes packed, stalled peer kept, max backlog {max_pending} B"
    );

    // 2. Reliable flood: the stalled peer passes the limit and is dropped with a notice.
    let before = poses.get();
    let t = Instant::now();
    while server.connected_peers() > 1 {
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "stalled peer never dropped"
        );
        for _ in 0..20 {
            server
                .pack_message(TimeVal::now(), ft, flood, &payload, class::RELIABLE)
                .unwrap();
        }
        step();
    }
    assert!(
        notices
            .borrow()
            .iter()
            .any(|n| n.text.contains("is not reading: more than 262144 bytes")),
        "{:?}",
        notices.borrow()
    );
    // The good client stayed and keeps receiving.
    assert!(good_conn.connected());
    let t = Instant::now();
    while poses.get() < before + 200 {
        assert!(t.elapsed() < Duration::from_secs(10), "good client starved");
        step();
        std::thread::sleep(Duration::from_micros(200));
    }
    drop(stalled);
}

#[test]
fn stalled_client_does_not_delay_others() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let server = start_server("vrpn_Tracker_NULL Tracker0 8 1000\n", 0);
    let conn = Connection::client("127.0.0.1", server.port, false, Limits::default()).unwrap();
    conn.on_notice(|_| {});
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    tracker.on_pose(move |_| p.set(p.get() + 1));
    let pinger = Pinger::new(&conn, "Tracker0");
    pump_until(&conn, Duration::from_secs(10), "connect", || {
        poses.get() > 100
    });
    let n = std::env::var("VRPN_PING_COUNT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(300);
    let _ = pinger.round_trips(20, || {}); // warm-up
    let cpu0 = cpu_seconds(server.pid);
    let t0 = Instant::now();
    let mut without = pinger.round_trips(n, || {});
    let cpu_without = (cpu_seconds(server.pid) - cpu0) / t0.elapsed().as_secs_f64();

    // A stalled client: cookie exchange, then never reads.
    let mut stalled = TcpStream::connect((Ipv4Addr::LOCALHOST, server.port)).unwrap();
    stalled.write_all(&Cookie::ours(0).to_bytes()).unwrap();
    // Let its backlog build for a while (the normal client keeps reading meanwhile).
    let t = Instant::now();
    while t.elapsed() < Duration::from_millis(1500) {
        conn.mainloop().unwrap();
        let _ = conn.wait(Duration::from_millis(2));
    }
    let cpu0 = cpu_seconds(server.pid);
    let t0 = Instant::now();
    let mut with = pinger.round_trips(n, || {});
    let cpu_with = (cpu_seconds(server.pid) - cpu0) / t0.elapsed().as_secs_f64();

    let (a50, a99) = p50_p99(&mut without);
    let (b50, b99) = p50_p99(&mut with);
    println!(
        "ping round trip over {n} pings, server streaming 8 sensors at 1 kHz:\n  \
         without stalled client: p50 {a50:.0} µs  p99 {a99:.0} µs  (server CPU {:.0}%)\n  \
         with stalled client:    p50 {b50:.0} µs  p99 {b99:.0} µs  (server CPU {:.0}%)",
        cpu_without * 100.0,
        cpu_with * 100.0
    );
    // Generous: loaded 2-core CI machines are noisy.
    assert!(
        b50 <= (a50 * 5.0).max(a50 + 3000.0),
        "p50 degraded from {a50:.0} µs to {b50:.0} µs"
    );
    assert!(poses.get() > 1000);
    drop(stalled);
}
