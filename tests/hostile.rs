//! Hostile peers against a `vrpn_server` child process on loopback: each attack runs while a
//! legitimate client reads poses, and the test checks that the client keeps being served, that
//! the server does not amplify or redirect anything, and that memory comes back.
//!
//! Every attack is bounded in count and time, and uses addresses in 127.0.0.0/8 only.

mod common;

use std::cell::Cell;
use std::collections::HashSet;
use std::io::{ErrorKind, Read, Write};
use std::net::{Ipv4Addr, TcpListener, TcpStream, UdpSocket};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::wire::{header::encode_message, system, Cookie, Header};
use vrpn::{Connection, Limits, TimeVal, TrackerRemote};

/// A NULL tracker reporting 200 poses a second.
const CFG: &str = "vrpn_Tracker_NULL Tracker0 1 200.0\n";

/// A client counting poses.
struct Legit {
    tracker: TrackerRemote,
    poses: Rc<Cell<u64>>,
    fake: Rc<Cell<u64>>,
    _watcher: Option<Watcher>,
}

/// An outside client run beside ours when `VRPN_HOSTILE_WATCHER` names a command (for checks by
/// hand, e.g. another implementation's `vrpn_print_devices Tracker0@127.0.0.1:{port}`): it runs
/// for the whole attack and the lines it printed are counted when it is stopped.
struct Watcher {
    child: std::process::Child,
    lines: std::sync::Arc<std::sync::atomic::AtomicU64>,
    started: Instant,
}

impl Watcher {
    fn start(port: u16) -> Option<Watcher> {
        use std::io::BufRead;
        let command = std::env::var("VRPN_HOSTILE_WATCHER").ok()?;
        let command = command.replace("{port}", &port.to_string());
        let mut words = command.split_whitespace();
        let mut child = std::process::Command::new(words.next()?)
            .args(words)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("VRPN_HOSTILE_WATCHER command");
        let out = child.stdout.take().expect("piped stdout");
        let lines = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
        let l = lines.clone();
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(out).lines() {
                if line.is_ok_and(|t| t.contains("pos")) {
                    l.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                }
            }
        });
        Some(Watcher {
            child,
            lines,
            started: Instant::now(),
        })
    }
}

impl Drop for Watcher {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        eprintln!(
            "outside watcher: {} pose lines in {:.1} s",
            self.lines.load(std::sync::atomic::Ordering::Relaxed),
            self.started.elapsed().as_secs_f64()
        );
    }
}

impl Legit {
    fn new(port: u16, tcp_only: bool) -> Legit {
        let conn = Connection::client("127.0.0.1", port, tcp_only, Limits::default()).unwrap();
        conn.on_notice(|_| {});
        let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
        let poses = Rc::new(Cell::new(0));
        let fake = Rc::new(Cell::new(0));
        let (p, f) = (poses.clone(), fake.clone());
        tracker.on_pose(move |pose| {
            if pose.pos.x == 666.0 {
                f.set(f.get() + 1);
            }
            p.set(p.get() + 1);
        });
        Legit {
            tracker,
            poses,
            fake,
            _watcher: Watcher::start(port),
        }
    }

    /// Runs the client for `d`; returns the poses it received meanwhile.
    fn run_for(&self, d: Duration) -> u64 {
        let before = self.poses.get();
        let start = Instant::now();
        while start.elapsed() < d {
            self.tracker.mainloop().unwrap();
            let _ = self.tracker.connection().wait(Duration::from_millis(2));
        }
        self.poses.get() - before
    }

    /// Runs until the first pose or `max`; returns whether one came.
    fn wait_for_poses(&self, max: Duration) -> bool {
        let start = Instant::now();
        while start.elapsed() < max {
            self.tracker.mainloop().unwrap();
            if self.poses.get() > 0 {
                return true;
            }
            let _ = self.tracker.connection().wait(Duration::from_millis(2));
        }
        false
    }
}

fn message(type_id: i32, sender: i32, payload: &[u8]) -> Vec<u8> {
    let h = Header {
        payload_len: payload.len(),
        time: TimeVal::now(),
        sender,
        type_id,
        seq: 0,
    };
    let mut out = vec![0u8; h.wire_size()];
    encode_message(&mut out, &h, payload).unwrap();
    out
}

fn description(id: i32, is_sender: bool, name: &[u8]) -> Vec<u8> {
    let mut p = ((name.len() + 1) as u32).to_be_bytes().to_vec();
    p.extend_from_slice(name);
    p.push(0);
    let t = if is_sender {
        system::SENDER_DESCRIPTION
    } else {
        system::TYPE_DESCRIPTION
    };
    message(t, id, &p)
}

/// A raw TCP peer that sent its cookie.
fn raw_peer(port: u16) -> TcpStream {
    let mut s = TcpStream::connect((Ipv4Addr::LOCALHOST, port)).unwrap();
    s.set_nodelay(true).unwrap();
    s.write_all(&Cookie::ours(0).to_bytes()).unwrap();
    s
}

/// True once the server closed `s` (EOF or reset), discarding what it sent.
fn closed_by_server(s: &mut TcpStream) -> bool {
    s.set_nonblocking(true).unwrap();
    let mut buf = [0u8; 4096];
    loop {
        match s.read(&mut buf) {
            Ok(0) => return true,
            Ok(_) => continue,
            Err(e) if e.kind() == ErrorKind::WouldBlock => return false,
            Err(_) => return true,
        }
    }
}

/// The UDP ports a process has open (its sockets' inodes matched against /proc/net/udp).
fn udp_ports_of(pid: u32) -> Vec<u16> {
    let inodes: HashSet<String> = std::fs::read_dir(format!("/proc/{pid}/fd"))
        .unwrap()
        .filter_map(|e| std::fs::read_link(e.ok()?.path()).ok())
        .filter_map(|l| {
            let l = l.to_string_lossy().into_owned();
            l.strip_prefix("socket:[")
                .and_then(|r| r.strip_suffix(']'))
                .map(str::to_string)
        })
        .collect();
    let table = std::fs::read_to_string("/proc/net/udp").unwrap();
    table
        .lines()
        .skip(1)
        .filter_map(|line| {
            let f: Vec<&str> = line.split_whitespace().collect();
            let inode = f.get(9)?;
            if !inodes.contains(*inode) {
                return None;
            }
            let port = f.get(1)?.split(':').nth(1)?;
            u16::from_str_radix(port, 16).ok()
        })
        .collect()
}

/// Hole 1: One peer describing ~2000 names cannot lock anyone out: a new client that describes a
/// type the server never heard of is served, and the flooder's names are freed when it goes.
#[test]
fn a_name_flood_locks_nobody_out() {
    let server = common::start_server(CFG, 0);
    let a = Legit::new(server.port, true);
    assert!(a.wait_for_poses(Duration::from_secs(5)));
    // The flood: 1999 distinct type names (the per-peer limit is C++'s 2000), one connection.
    let mut flooder = raw_peer(server.port);
    let mut flood = Vec::new();
    for i in 0..1999 {
        flood.extend(description(
            i,
            false,
            format!("junk type {i:04}").as_bytes(),
        ));
    }
    let (rss0, cpu0) = (common::rss_kb(server.pid), common::cpu_seconds(server.pid));
    flooder.write_all(&flood).unwrap();
    let during = a.run_for(Duration::from_millis(500));
    assert!(during > 50, "the connected client starved: {during} poses");
    // A new client whose connection describes a type the server does not hold.
    let conn = Connection::client("127.0.0.1", server.port, true, Limits::default()).unwrap();
    conn.on_notice(|_| {});
    conn.register_type("my own type nobody else has").unwrap();
    let b_tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let b_poses = Rc::new(Cell::new(0u64));
    let p = b_poses.clone();
    b_tracker.on_pose(move |_| p.set(p.get() + 1));
    let start = Instant::now();
    while b_poses.get() < 100 && start.elapsed() < Duration::from_secs(5) {
        b_tracker.mainloop().unwrap();
        a.tracker.mainloop().unwrap();
        let _ = conn.wait(Duration::from_millis(2));
    }
    assert!(
        b_poses.get() >= 100,
        "a new client got {} poses; server: {}",
        b_poses.get(),
        server.stderr.lock().unwrap()
    );
    assert_eq!(conn.connected_peers(), 1, "the new client was dropped");
    assert!(!closed_by_server(&mut flooder), "the flooder broke no rule");
    let secs = start.elapsed().as_secs_f64() + 0.5;
    let cpu = (common::cpu_seconds(server.pid) - cpu0) / secs * 100.0;
    let rss1 = common::rss_kb(server.pid);
    drop(flooder);
    let after = a.run_for(Duration::from_millis(300));
    eprintln!(
        "name flood: connected client {during} poses in 0.5 s, new client {} poses in {:.2} s, \
         {after} in 0.3 s after; server CPU {cpu:.0}%, RSS {rss0} → {rss1} KiB",
        b_poses.get(),
        secs - 0.5
    );
    assert!(after > 20);
}

/// Hole 1b: A description with an id no peer may use is refused before its name enters the table.
#[test]
fn a_bad_id_leaves_no_name_behind() {
    let server = common::start_server(CFG, 0);
    let mut bad = raw_peer(server.port);
    bad.write_all(&description(5000, true, b"smuggled sender"))
        .unwrap();
    let start = Instant::now();
    while !closed_by_server(&mut bad) {
        assert!(start.elapsed() < Duration::from_secs(5), "not dropped");
        std::thread::sleep(Duration::from_millis(10));
    }
    // A client listing the server's senders does not see the name.
    let conn = Connection::client("127.0.0.1", server.port, true, Limits::default()).unwrap();
    let start = Instant::now();
    while !conn.peer_senders().contains(&"Tracker0".to_string()) {
        assert!(start.elapsed() < Duration::from_secs(5));
        conn.mainloop().unwrap();
        let _ = conn.wait(Duration::from_millis(5));
    }
    conn.mainloop().unwrap();
    assert!(!conn.peer_senders().iter().any(|s| s.contains("smuggled")));
}

/// Hole 2: Silent connections cannot hold every slot: a real client gets in at once (the one
/// greeting longest gives way), and the silent ones are dropped at the greeting deadline.
#[test]
fn silent_connections_cannot_hold_every_slot() {
    let server = common::start_server(CFG, 0);
    let fds_before = common::fd_count(server.pid);
    let mut silent: Vec<TcpStream> = (0..300)
        .map(|_| TcpStream::connect((Ipv4Addr::LOCALHOST, server.port)).unwrap())
        .collect();
    std::thread::sleep(Duration::from_millis(300));
    let a = Legit::new(server.port, true);
    assert!(
        a.wait_for_poses(Duration::from_secs(3)),
        "a real client was kept out; server: {}",
        server.stderr.lock().unwrap()
    );
    // After the 5 s greeting deadline every silent connection is closed by the server.
    let got = a.run_for(Duration::from_millis(5800));
    assert!(got > 500, "{got} poses during the attack");
    let closed = silent
        .iter_mut()
        .map(closed_by_server)
        .filter(|&c| c)
        .count();
    assert_eq!(closed, 300, "silent connections still held");
    let rss = common::rss_kb(server.pid);
    drop(silent);
    std::thread::sleep(Duration::from_millis(300));
    let fds_after = common::fd_count(server.pid);
    eprintln!(
        "300 silent connections: client {got} poses in 5.8 s (200/s), all 300 closed at the \
         deadline, RSS {rss} KiB, fds {fds_before} → {fds_after}"
    );
    assert!(
        fds_after <= fds_before + 8,
        "fds {fds_before} → {fds_after}"
    );
}

/// Hole 2b: Connection requests that make the server call back silent listeners, from 260
/// addresses: the call-backs are rate-limited and give way when the server is full, so a real
/// client on the UDP path still gets in.
#[test]
fn call_backs_to_silent_listeners_cannot_fill_the_slots() {
    let server = common::start_server(CFG, 0);
    // One listener on every loopback address, never accepting: each call-back completes in the
    // kernel and then sits there without a word.
    let trap = TcpListener::bind((Ipv4Addr::UNSPECIFIED, 0)).unwrap();
    let trap_port = trap.local_addr().unwrap().port();
    let started = Instant::now();
    for i in 0..260u32 {
        let ip = Ipv4Addr::from(u32::from(Ipv4Addr::new(127, 0, 0, 2)) + i);
        let s = UdpSocket::bind((ip, 0)).unwrap();
        s.send_to(
            format!("{ip} {trap_port}\0").as_bytes(),
            (Ipv4Addr::LOCALHOST, server.port),
        )
        .unwrap();
        if i % 50 == 49 {
            std::thread::sleep(Duration::from_millis(200));
        }
    }
    std::thread::sleep(Duration::from_millis(300));
    let a = Legit::new(server.port, false);
    assert!(
        a.wait_for_poses(Duration::from_secs(3)),
        "a real client was kept out; server: {}",
        server.stderr.lock().unwrap()
    );
    let got = a.run_for(Duration::from_millis(500));
    assert!(got > 50);
    // Count the call-backs the trap received (the kernel queued them; accept them now).
    trap.set_nonblocking(true).unwrap();
    let mut callbacks = 0u64;
    while trap.accept().is_ok() {
        callbacks += 1;
    }
    let secs = started.elapsed().as_secs_f64();
    let cap = 100.0 + 100.0 * secs;
    eprintln!(
        "260 requests naming a silent listener: {callbacks} call-backs in {secs:.1} s, \
         UDP-path client {got} poses in 0.5 s"
    );
    assert!(
        (callbacks as f64) <= cap,
        "{callbacks} call-backs in {secs:.1} s (the rate allows {cap:.0})"
    );
}

/// Hole 3: A flood of connection requests: call-backs are rate-limited, notices too, memory stays,
/// and a connected client on the UDP path keeps its poses.
#[test]
fn a_request_flood_is_rate_limited() {
    let server = common::start_server(CFG, 0);
    let a = Legit::new(server.port, false);
    assert!(a.wait_for_poses(Duration::from_secs(5)));
    a.run_for(Duration::from_millis(300));
    let rss_before = common::rss_kb(server.pid);
    let cpu_before = common::cpu_seconds(server.pid);
    let stderr_before = server.stderr.lock().unwrap().lines().count();
    let port = server.port;
    // 20 000 requests a second for 3 s, from 16 sockets, naming ports nobody listens on.
    let flood = std::thread::spawn(move || {
        let socks: Vec<UdpSocket> = (0..16)
            .map(|_| UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap())
            .collect();
        let start = Instant::now();
        let mut sent = 0u64;
        while start.elapsed() < Duration::from_secs(3) {
            let due = (start.elapsed().as_secs_f64() * 20_000.0) as u64;
            while sent < due {
                let text = format!("127.0.0.1 {}\0", 20000 + sent % 30000);
                let _ = socks[(sent % 16) as usize]
                    .send_to(text.as_bytes(), (Ipv4Addr::LOCALHOST, port));
                sent += 1;
            }
            std::thread::sleep(Duration::from_micros(500));
        }
        sent
    });
    let got = a.run_for(Duration::from_secs(3));
    let sent = flood.join().unwrap();
    let cpu = common::cpu_seconds(server.pid) - cpu_before;
    let rss_after = common::rss_kb(server.pid);
    let stderr_lines = server.stderr.lock().unwrap().lines().count() - stderr_before;
    eprintln!(
        "request flood: {sent} requests in 3 s; client got {got} poses (200/s expected); \
         server CPU {:.0}%, RSS {rss_before} → {rss_after} KiB, {stderr_lines} notice lines",
        cpu / 3.0 * 100.0
    );
    assert!(sent > 40_000, "the flood itself fell short: {sent}");
    assert!(
        got >= 480,
        "the client got {got} of ~600 poses during the flood"
    );
    assert!(
        stderr_lines <= 5,
        "{stderr_lines} notice lines for one flood"
    );
    assert!(
        rss_after < rss_before + 4096,
        "RSS {rss_before} → {rss_after} KiB"
    );
}

/// Hole 4a: A connection request is called back at its source address, never at the address it
/// names (no reflection at a third host).
#[test]
fn call_backs_go_to_the_source_address() {
    let server = common::start_server(CFG, 0);
    // A "victim" at 127.0.0.2 and the attacker at 127.0.0.1, same port number.
    let victim = TcpListener::bind((Ipv4Addr::new(127, 0, 0, 2), 0)).unwrap();
    let port = victim.local_addr().unwrap().port();
    let attacker = match TcpListener::bind((Ipv4Addr::LOCALHOST, port)) {
        Ok(l) => l,
        Err(_) => return, // the port is taken on 127.0.0.1: nothing to compare with
    };
    let s = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    s.send_to(
        format!("127.0.0.2 {port}\0").as_bytes(),
        (Ipv4Addr::LOCALHOST, server.port),
    )
    .unwrap();
    victim.set_nonblocking(true).unwrap();
    attacker.set_nonblocking(true).unwrap();
    let start = Instant::now();
    let mut to_attacker = false;
    while start.elapsed() < Duration::from_secs(1) {
        assert!(
            victim.accept().is_err(),
            "the server connected to the named host"
        );
        to_attacker |= attacker.accept().is_ok();
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(to_attacker, "the call-back went to the request's source");
}

/// Hole 4b: Datagrams from a stranger to the server's UDP sockets change nothing: a UDP description
/// sent that way does not move a client's stream.
#[test]
fn udp_descriptions_from_strangers_move_nothing() {
    let server = common::start_server(CFG, 0);
    let a = Legit::new(server.port, false);
    assert!(a.wait_for_poses(Duration::from_secs(5)));
    let attacker = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    attacker.set_nonblocking(true).unwrap();
    let mine = attacker.local_addr().unwrap().port();
    let mut payload = b"127.0.0.1".to_vec();
    payload.push(0);
    let hijack = message(system::UDP_DESCRIPTION, i32::from(mine), &payload);
    let ports = udp_ports_of(server.pid);
    assert!(ports.len() >= 2, "server UDP ports: {ports:?}");
    for p in &ports {
        let _ = attacker.send_to(&hijack, (Ipv4Addr::LOCALHOST, *p));
    }
    let got = a.run_for(Duration::from_secs(2));
    assert!(got > 200, "the client's stream moved: {got} poses");
    let mut buf = [0u8; 2048];
    let mut stolen = 0;
    while let Ok(n) = attacker.recv(&mut buf) {
        stolen += n;
    }
    eprintln!("UDP hijack attempt: client {got} poses in 2 s, attacker received {stolen} bytes");
    assert_eq!(stolen, 0, "the attacker received {stolen} bytes");
}

/// Hole 4c: Messages injected into a client's UDP socket from another address are not delivered.
#[test]
fn injected_datagrams_reach_no_callback() {
    let server = common::start_server(CFG, 0);
    let a = Legit::new(server.port, false);
    assert!(a.wait_for_poses(Duration::from_secs(5)));
    // Fake poses (x = 666) for every plausible id, sent to every UDP socket of this process.
    let mut pose = [0u8; 64];
    pose[8..16].copy_from_slice(&666.0f64.to_be_bytes());
    pose[56..64].copy_from_slice(&1.0f64.to_be_bytes());
    let mut dgram = Vec::new();
    for t in 0..20 {
        dgram.extend(message(t, 1, &pose));
    }
    let attacker = UdpSocket::bind((Ipv4Addr::new(127, 0, 0, 3), 0)).unwrap();
    for p in udp_ports_of(std::process::id()) {
        for chunk in dgram.chunks(88 * 10) {
            let _ = attacker.send_to(chunk, (Ipv4Addr::LOCALHOST, p));
        }
    }
    let got = a.run_for(Duration::from_millis(500));
    eprintln!(
        "injected datagrams: {} fake poses delivered, {got} real poses in 0.5 s",
        a.fake.get()
    );
    assert_eq!(a.fake.get(), 0, "an injected pose was delivered");
    assert!(a.poses.get() > 0);
}

/// Hole 5: A name that is not UTF-8, described by one peer and echoed by the server to everyone,
/// cuts nobody off.
#[test]
fn a_name_that_is_not_utf8_cuts_nobody_off() {
    let server = common::start_server(CFG, 0);
    let a = Legit::new(server.port, true);
    assert!(a.wait_for_poses(Duration::from_secs(5)));
    let mut odd = raw_peer(server.port);
    odd.write_all(&description(7, false, b"Tr\xe4cker type"))
        .unwrap();
    odd.write_all(&description(8, true, b"S\xe4nder")).unwrap();
    a.run_for(Duration::from_millis(300));
    let got = a.run_for(Duration::from_secs(1));
    eprintln!("non-UTF-8 names: client {got} poses in the next second");
    assert!(got > 100, "{got} poses after the odd name");
    assert!(a.tracker.connection().connected());
    let names = a.tracker.connection().peer_senders();
    assert!(names.iter().any(|n| n.contains('\u{fffd}')), "{names:?}");
}

/// Hole 6: Connection churn leaves memory and descriptors where they were.
#[test]
fn churn_leaves_memory_flat() {
    let server = common::start_server(CFG, 0);
    let cycle = |n: usize| {
        for i in 0..n {
            let mut s = TcpStream::connect((Ipv4Addr::LOCALHOST, server.port)).unwrap();
            if i % 2 == 0 {
                // Half complete the greeting, half close at once.
                s.write_all(&Cookie::ours(0).to_bytes()).unwrap();
                let mut c = [0u8; 24];
                let _ = s.read_exact(&mut c);
            }
        }
    };
    // The legitimate client (and an outside watcher, if any) is connected through the churn.
    let a = Legit::new(server.port, true);
    assert!(a.wait_for_poses(Duration::from_secs(5)));
    cycle(300);
    std::thread::sleep(Duration::from_millis(300));
    let (rss0, fds0) = (common::rss_kb(server.pid), common::fd_count(server.pid));
    cycle(2000);
    std::thread::sleep(Duration::from_millis(500));
    let (rss1, fds1) = (common::rss_kb(server.pid), common::fd_count(server.pid));
    eprintln!("churn: RSS {rss0} → {rss1} KiB, fds {fds0} → {fds1}");
    assert!(rss1 < rss0 + 2048, "RSS {rss0} → {rss1} KiB");
    assert!(fds1 <= fds0 + 2, "fds {fds0} → {fds1}");
    // It was not read during the churn: what queued meanwhile and what follows arrives.
    let got = a.run_for(Duration::from_millis(500));
    assert!(got >= 50, "client got {got} poses in 0.5 s after the churn");
    eprintln!("churn: client {} poses in all", a.poses.get());
}

/// Hole 7: Host names in connection requests and UDP descriptions are never looked up in the
/// loop: the server answers others at once while they pour in.
#[test]
fn host_names_are_not_resolved_in_the_loop() {
    let server = common::start_server(CFG, 0);
    let conn = Connection::client("127.0.0.1", server.port, true, Limits::default()).unwrap();
    let pinger = common::Pinger::new(&conn, "Tracker0");
    let start = Instant::now();
    while !conn.connected() {
        assert!(start.elapsed() < Duration::from_secs(5));
        conn.mainloop().unwrap();
        let _ = conn.wait(Duration::from_millis(2));
    }
    let s = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    let mut odd = raw_peer(server.port);
    let mut rtts = Vec::new();
    for i in 0..50 {
        s.send_to(
            format!("hangs{i}.example.invalid {}\0", 30000 + i).as_bytes(),
            (Ipv4Addr::LOCALHOST, server.port),
        )
        .unwrap();
        let mut p = format!("host{i}.example.invalid").into_bytes();
        p.push(0);
        let _ = odd.write_all(&message(system::UDP_DESCRIPTION, 40000 + i, &p));
        rtts.extend(pinger.round_trips(1, || {}));
    }
    let (p50, p99) = common::p50_p99(&mut rtts);
    eprintln!("pings while host names pour in: p50 {p50:.0} µs, p99 {p99:.0} µs");
    // A name resolved in the loop stalls it for the resolver's time-outs (seconds for these
    // names without a network); 250 ms leaves room for a loaded 2-core machine's scheduling.
    assert!(p99 < 250_000.0, "a ping took {p99:.0} µs: the loop stalled");
}
