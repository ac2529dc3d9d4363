//! DTrack latency: from the moment a controller's UDP datagram is sent to the moment a VRPN
//! client's pose callback runs, beside the raw UDP floor measured in the same run.
//!
//! * `dtrack`: a server (`vrpn_Tracker_DTrack` built from its `vrpn.cfg` line, in a
//!   `ServerLoop` with `vrpn_server`'s event-driven sleep, in its own thread) receives a
//!   standard frame (two bodies, a Flystick, a tool, markers) on 127.0.0.1; the main thread
//!   notes the time just before `send_to` and polls a `TrackerRemote` (TCP) until the frame's
//!   first pose arrives.
//! * `udp floor`: the same path with nothing but sockets: a thread blocked in `recv_from`
//!   answers each datagram with a one-byte datagram, which the main thread polls for. Both
//!   involve one datagram, one thread wake-up and one message back.
//!
//! Datagrams are spaced 3 ms apart (the server is asleep in its poll when each arrives, past
//! its 2 ms busy window, as at a controller's 60-300 Hz). Printed: median, p90, p99 in
//! microseconds, and the ratio of the medians. `cargo bench --bench dtrack_latency`
//! (`DTRACK_BENCH_FRAMES=N`, default 1000).

use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use vrpn::drivers::dtrack::sim::{free_udp_port, Frame};
use vrpn::server::config::parse_str;
use vrpn::server::{build_devices, ServerLoop, SleepPolicy};
use vrpn::{Connection, TrackerRemote};

const GAP: Duration = Duration::from_millis(3);

fn frames() -> usize {
    std::env::var("DTRACK_BENCH_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000)
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn summary(name: &str, mut us: Vec<f64>) -> f64 {
    us.sort_by(f64::total_cmp);
    let median = percentile(&us, 0.5);
    println!(
        "{name:>10}: median {median:7.1} us  p90 {:7.1} us  p99 {:7.1} us  ({} samples)",
        percentile(&us, 0.9),
        percentile(&us, 0.99),
        us.len()
    );
    median
}

fn frame_bytes(k: u32) -> Vec<u8> {
    let d = SystemTime::now().duration_since(UNIX_EPOCH).unwrap();
    Frame::standard(k, d.as_secs() as u32, d.subsec_micros())
        .text()
        .into_bytes()
}

fn dtrack(n: usize) -> Vec<f64> {
    let udp = free_udp_port().expect("a free port");
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, rx) = mpsc::channel();
    let s = stop.clone();
    let server = std::thread::spawn(move || {
        let conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).expect("server");
        let cfg = format!("vrpn_Tracker_DTrack DT {udp}\n");
        let entries = parse_str(&cfg, "bench.cfg").expect("config");
        let devices = build_devices(&entries, &conn, false, None, |_| {}).expect("devices");
        tx.send(conn.local_port().expect("a port"))
            .expect("the bench waits");
        let sleep = SleepPolicy::EventDriven {
            busy_window: vrpn::server::run::DEFAULT_BUSY_WINDOW,
            max_block: Duration::from_millis(100),
        };
        ServerLoop::new(conn, devices, sleep)
            .run(&s)
            .expect("server loop");
    });
    let port = rx.recv_timeout(Duration::from_secs(10)).expect("server up");
    let tracker = TrackerRemote::new(&format!("DT@tcp://127.0.0.1:{port}")).expect("remote");
    let got = Arc::new(std::sync::Mutex::new(None::<Instant>));
    let g = got.clone();
    tracker.on_pose(move |p| {
        if p.sensor == 0 {
            if let Ok(mut slot) = g.lock() {
                slot.get_or_insert_with(Instant::now);
            }
        }
    });
    let sock = UdpSocket::bind("127.0.0.1:0").expect("controller socket");
    let to = SocketAddr::from((Ipv4Addr::LOCALHOST, udp));
    let mut k = 1;
    // Connect: frames until a pose arrives.
    let start = Instant::now();
    while got.lock().unwrap().is_none() {
        assert!(start.elapsed() < Duration::from_secs(10), "no pose");
        sock.send_to(&frame_bytes(k), to).expect("send");
        k += 1;
        let t = Instant::now();
        while t.elapsed() < Duration::from_millis(10) {
            let _ = tracker.mainloop();
        }
    }
    let mut out = Vec::with_capacity(n);
    for _ in 0..n + 20 {
        std::thread::sleep(GAP);
        let _ = tracker.mainloop();
        *got.lock().unwrap() = None;
        let bytes = frame_bytes(k);
        k += 1;
        let sent = Instant::now();
        sock.send_to(&bytes, to).expect("send");
        let deadline = sent + Duration::from_secs(2);
        let arrived = loop {
            let _ = tracker.mainloop();
            if let Some(t) = *got.lock().unwrap() {
                break Some(t);
            }
            if Instant::now() > deadline {
                break None;
            }
        };
        if let Some(t) = arrived {
            out.push(t.duration_since(sent).as_secs_f64() * 1e6);
        }
    }
    stop.store(true, Ordering::Relaxed);
    let _ = server.join();
    // The first frames after connecting warm caches and queues.
    out.split_off(out.len().min(20))
}

fn udp_floor(n: usize) -> Vec<f64> {
    let echo = UdpSocket::bind("127.0.0.1:0").expect("echo socket");
    let echo_addr = echo.local_addr().expect("address");
    let stop = Arc::new(AtomicBool::new(false));
    let s = stop.clone();
    echo.set_read_timeout(Some(Duration::from_millis(100)))
        .expect("timeout");
    let thread = std::thread::spawn(move || {
        let mut buf = [0u8; 20_000];
        while !s.load(Ordering::Relaxed) {
            if let Ok((_, from)) = echo.recv_from(&mut buf) {
                let _ = echo.send_to(&[1], from);
            }
        }
    });
    let sock = UdpSocket::bind("127.0.0.1:0").expect("socket");
    sock.set_nonblocking(true).expect("nonblocking");
    let mut buf = [0u8; 16];
    let mut out = Vec::with_capacity(n);
    for k in 0..n + 20 {
        std::thread::sleep(GAP);
        let bytes = frame_bytes(k as u32);
        let sent = Instant::now();
        sock.send_to(&bytes, echo_addr).expect("send");
        let deadline = sent + Duration::from_secs(2);
        loop {
            if sock.recv_from(&mut buf).is_ok() {
                out.push(sent.elapsed().as_secs_f64() * 1e6);
                break;
            }
            if Instant::now() > deadline {
                break;
            }
        }
    }
    stop.store(true, Ordering::Relaxed);
    let _ = thread.join();
    out.split_off(out.len().min(20))
}

fn main() {
    let n = frames();
    println!("DTrack frame datagram → client pose callback, {n} frames, 3 ms apart");
    let floor = summary("udp floor", udp_floor(n));
    let dt = summary("dtrack", dtrack(n));
    println!("ratio of medians (dtrack / udp floor): {:.2}", dt / floor);
}
