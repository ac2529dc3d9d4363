//! Load: many TCP-only clients each receiving a 1 kHz, 8-sensor tracker stream from the
//! vrpn_server binary; every client must receive exactly the same reports (nothing lost), with
//! server RSS bounded and its CPU reported. Then many connect/disconnect cycles against one
//! server: its open descriptors return to the baseline and its RSS does not grow.
//!
//! Optimised builds (CI runs `cargo test --release`) use the full figures: 64 clients for 3 s
//! and 1000 connect/disconnect cycles; debug builds use 32 clients for 2 s. Override with
//! `VRPN_LOAD_CLIENTS`, `VRPN_LOAD_SECONDS`, `VRPN_CHURN_CYCLES`.

mod common;

use std::cell::RefCell;
use std::io::{Read, Write};
use std::net::{Ipv4Addr, TcpStream};
use std::rc::Rc;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use common::*;
use vrpn::wire::Cookie;
use vrpn::{Connection, Limits, TimeVal, TrackerRemote};

/// The two tests measure CPU and timing: run them one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

fn env_or<T: std::str::FromStr>(key: &str, default: T) -> T {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

#[derive(Default)]
struct Stats {
    in_window: [u64; 8],
    total: u64,
    last: TimeVal,
}

#[test]
fn many_clients_receive_every_report() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // The full figures (64 clients, 3 s) in optimised builds, which is how CI runs the suite;
    // a debug build's single test thread cannot read 64 streams at 1 kHz.
    let full = !cfg!(debug_assertions);
    let clients: usize = env_or("VRPN_LOAD_CLIENTS", if full { 64 } else { 32 });
    let secs: f64 = env_or("VRPN_LOAD_SECONDS", if full { 3.0 } else { 2.0 });
    let server = start_server("vrpn_Tracker_NULL Tracker0 8 1000\n", 0);
    let rss_idle = rss_kb(server.pid);
    let window = Rc::new(RefCell::new(None::<(TimeVal, TimeVal)>));
    let mut all = Vec::new();
    for _ in 0..clients {
        let conn = Connection::client("127.0.0.1", server.port, true, Limits::default()).unwrap();
        conn.on_notice(|n| eprintln!("client: {}", n.text));
        let t = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
        let stats = Rc::new(RefCell::new(Stats::default()));
        let (s, w) = (stats.clone(), window.clone());
        t.on_pose(move |p| {
            let mut s = s.borrow_mut();
            s.total += 1;
            // The server's own stamp: every client translates it with its own clock estimate,
            // so a report near the window's edge could fall inside for one client and outside
            // for another by a few microseconds.
            s.last = p.sender_time;
            if let Some((t0, t1)) = *w.borrow() {
                if p.sender_time >= t0 && p.sender_time < t1 && (0..8).contains(&p.sensor) {
                    s.in_window[p.sensor] += 1;
                }
            }
        });
        all.push((conn, t, stats));
    }
    let pump = |all: &Vec<(Connection, TrackerRemote, Rc<RefCell<Stats>>)>| {
        let mut any = false;
        for (c, t, _) in all {
            t.mainloop().unwrap();
            any |= c.take_activity();
        }
        if !any {
            std::thread::sleep(Duration::from_micros(100));
        }
    };
    let start = Instant::now();
    while !all
        .iter()
        .all(|(c, _, s)| c.connected() && s.borrow().total > 0)
    {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "clients never connected"
        );
        pump(&all);
    }
    let connect_time = start.elapsed();
    // Count reports stamped inside a window that starts after every client is in.
    let t0 = TimeVal::now().as_secs_f64() + 0.3;
    let to_tv = |s: f64| TimeVal::new(s.floor() as i64, ((s - s.floor()) * 1e6) as i64);
    let (w0, w1) = (to_tv(t0), to_tv(t0 + secs));
    *window.borrow_mut() = Some((w0, w1));
    let wall0 = Instant::now();
    let cpu0 = cpu_seconds(server.pid);
    let mut rss_max = 0;
    let mut last_rss = Instant::now();
    loop {
        pump(&all);
        if last_rss.elapsed() > Duration::from_millis(100) {
            rss_max = rss_max.max(rss_kb(server.pid));
            last_rss = Instant::now();
        }
        if all.iter().all(|(_, _, s)| s.borrow().last >= w1) {
            break;
        }
        assert!(
            wall0.elapsed() < Duration::from_secs_f64(secs + 20.0),
            "reports stopped"
        );
    }
    let wall = wall0.elapsed().as_secs_f64();
    let cpu = (cpu_seconds(server.pid) - cpu0) / wall;
    let expected = all[0].2.borrow().in_window[0];
    let stderr = server.stderr.lock().unwrap().clone();
    for (i, (c, _, s)) in all.iter().enumerate() {
        let s = s.borrow();
        assert!(c.connected(), "client {i} lost its connection");
        for (sensor, &n) in s.in_window.iter().enumerate() {
            assert_eq!(
                n, expected,
                "client {i} sensor {sensor}: {n} reports in the window, client 0 sensor 0 got \
                 {expected} (server said: {stderr})"
            );
        }
    }
    let total: u64 = all.iter().map(|(_, _, s)| s.borrow().total).sum();
    let rate = expected as f64 / secs;
    println!(
        "load: {clients} TCP clients x 8 sensors, {rate:.0} reports/s per sensor \
         ({:.0} messages/s out of the server), {expected} reports per sensor per client in \
         the {secs} s window, identical on every client; {total} reports received in all",
        rate * 8.0 * clients as f64
    );
    println!(
        "load: server CPU {:.0}% of one core, RSS idle {rss_idle} KiB, max under load \
         {rss_max} KiB; all clients connected in {connect_time:?}",
        cpu * 100.0
    );
    assert!(
        !stderr.contains("not reading") && !stderr.contains("falling behind"),
        "{stderr}"
    );
    assert!(
        expected as f64 >= secs * 1000.0 * 0.1,
        "{expected} reports in {secs} s"
    );
    assert!(
        rss_max < rss_idle + 2048 * clients as u64 + 32 * 1024,
        "server RSS {rss_max} KiB"
    );
}

#[test]
fn connect_disconnect_cycles_leak_nothing() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cycles: usize = env_or("VRPN_CHURN_CYCLES", 1000);
    let server = start_server("vrpn_Tracker_NULL Tracker0 2 60\n", 0);
    let port = server.port;
    let one = |i: usize| match i % 4 {
        // Full clients: UDP call-back path and TCP-only path.
        0 | 1 => {
            let conn =
                Connection::client("127.0.0.1", port, i % 4 == 1, Limits::default()).unwrap();
            conn.on_notice(|_| {});
            pump_until(&conn, Duration::from_secs(10), "client connect", || {
                conn.connected()
            });
        }
        // Raw peer: cookie exchange, then close.
        2 => {
            let mut s = TcpStream::connect((Ipv4Addr::LOCALHOST, port)).unwrap();
            s.write_all(&Cookie::ours(0).to_bytes()).unwrap();
            let mut c = [0u8; 24];
            s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
            s.read_exact(&mut c).unwrap();
        }
        // Raw peer that closes before its cookie.
        _ => {
            let _ = TcpStream::connect((Ipv4Addr::LOCALHOST, port)).unwrap();
        }
    };
    let settle = || {
        // Until the server has closed what it holds for departed peers.
        let start = Instant::now();
        let mut last = fd_count(server.pid);
        loop {
            std::thread::sleep(Duration::from_millis(50));
            let now = fd_count(server.pid);
            if now == last || start.elapsed() > Duration::from_secs(3) {
                return now;
            }
            last = now;
        }
    };
    for i in 0..8 {
        one(i);
    }
    let fds_base = settle();
    let rss_base = rss_kb(server.pid);
    let t = Instant::now();
    for i in 0..cycles {
        one(i);
    }
    let took = t.elapsed();
    let start = Instant::now();
    let mut fds = settle();
    while fds > fds_base && start.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(50));
        fds = fd_count(server.pid);
    }
    let rss = rss_kb(server.pid);
    println!(
        "churn: {cycles} connect/disconnect cycles in {took:?}; server fds {fds_base} -> {fds}, \
         RSS {rss_base} -> {rss} KiB"
    );
    assert_eq!(fds, fds_base, "server leaked descriptors");
    assert!(
        rss <= rss_base + 4096,
        "server RSS grew {rss_base} -> {rss} KiB"
    );
    // And it still serves.
    one(0);
}
