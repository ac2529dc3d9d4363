//! Serial drivers and the server loop, measured end to end on one machine:
//!
//! * `first-byte`: how close a serial driver's report timestamp is to the moment the record's
//!   first byte reached the line. A simulated Fastrak on a pseudo-terminal streams one station
//!   at 120 Hz and notes the wall time just before each write that carries a record's first
//!   byte; a server (`SerialDevice` with the Fastrak driver in a `ServerLoop`, in its own
//!   thread) serves it on 127.0.0.1; a `TrackerRemote` in the main thread receives the poses.
//!   Printed: report timestamp minus first-byte time (and client arrival minus first-byte
//!   time), p50 / p90 / p99 / max.
//! * `startup`: server start to the first report at a client, Fastrak and Flock of Birds
//!   simulators on pseudo-terminals, three runs each.
//! * `trackers`: the bare-pty baseline again, then first-byte accuracy and start-up of the
//!   Polaris, Liberty, ISOTRAK and 3SPACE drivers on their simulators (`serial_trackers.rs`):
//!   each report's stamp against the write of its own record's first byte (a frame's second
//!   station leaves a record's transmission after the first), matched by sensor and values.
//! * `khz`: a `vrpn_server` child process with a 1 kHz NULL tracker: report intervals as a
//!   client sees them (sender timestamps) and the server's CPU over 10 s (from /proc).
//!
//! `cargo bench --bench first_byte [-- first-byte|startup|khz|trackers]` (all by default).
//!
//! For comparisons with another implementation's server, by hand:
//! * `FIRST_BYTE_EXTERNAL=PORT FIRST_BYTE_TTY=PATH`: only the simulator (its pseudo-terminal
//!   at PATH) and the client (to 127.0.0.1:PORT); start the other server, with a Fastrak
//!   entry on PATH at 115200 baud, once the bench says the simulator runs.
//! * `DEVICE_SIM=KIND FIRST_BYTE_TTY=PATH [DEVICE_SIM_SECONDS=N] [DEVICE_SIM_EXPECT=FILE]`:
//!   only a simulator on PATH for N seconds (30), to serve it with any server and read it
//!   with any client: `fastrak` (as in `first-byte`), `flock` (as in `startup`), `magellan`,
//!   `cerealbox`, `dyna`, `joylin`, `liberty`, `isotrak`, `3space`, `polaris`, `crossbow` or
//!   `gps`; FILE gets what a client must have received, and
//!   `DEVICE_SIM_MUTE=S` keeps the device silent for its first S seconds, `DEVICE_SIM_REST=S`
//!   the Magellan's puck still (see `device_sim.rs`).
//! * `VRPN_KHZ_SERVER=PROGRAM`: the `khz` part runs PROGRAM (it must take
//!   `-f FILE -NIC 127.0.0.1 PORT`, as `vrpn_server` does) instead of ours.

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

mod device_sim;
mod serial_trackers;

use nix::poll::{poll, PollFd, PollFlags};
use vrpn::drivers::fastrak::record::METRES_PER_INCH;
use vrpn::drivers::fastrak::sim::{self as fastrak_sim, FastrakSim};
use vrpn::drivers::flock::sim::{self as flock_sim, FlockSim};
use vrpn::server::config::parse_str;
use vrpn::server::{build_devices, ServerLoop, SleepPolicy};
use vrpn::sim::DeviceModel;
use vrpn::sim::PtyDevice;
use vrpn::{Connection, Now, TimeVal, TrackerRemote};

/// Records measured by `first-byte` (override with `FIRST_BYTE_RECORDS`).
const RECORDS: usize = 3000;
/// The simulated Fastrak's output cycle: 120 Hz.
const CYCLE: Duration = Duration::from_micros(8_333);

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let want = |part: &str| args.is_empty() || args.iter().any(|a| a == part);
    if let Ok(kind) = std::env::var("DEVICE_SIM") {
        let tty = std::env::var("FIRST_BYTE_TTY").expect("FIRST_BYTE_TTY: the simulator's path");
        let secs = std::env::var("DEVICE_SIM_SECONDS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(30);
        let expect = std::env::var_os("DEVICE_SIM_EXPECT").map(PathBuf::from);
        let mute: f64 = std::env::var("DEVICE_SIM_MUTE")
            .map(|v| v.parse().expect("DEVICE_SIM_MUTE: seconds"))
            .unwrap_or(0.0);
        let rest: f64 = std::env::var("DEVICE_SIM_REST")
            .map(|v| v.parse().expect("DEVICE_SIM_REST: seconds"))
            .unwrap_or(0.0);
        device_sim::simulate(
            &kind,
            Path::new(&tty),
            Duration::from_secs(secs),
            expect.as_deref(),
            Duration::from_secs_f64(mute),
            Duration::from_secs_f64(rest),
        );
        return;
    }
    if let Ok(port) = std::env::var("FIRST_BYTE_EXTERNAL") {
        let port: u16 = port.parse().expect("FIRST_BYTE_EXTERNAL: a port number");
        let tty = std::env::var("FIRST_BYTE_TTY").expect("FIRST_BYTE_TTY: the simulator's path");
        first_byte(Some((port, PathBuf::from(tty))));
        return;
    }
    if want("first-byte") {
        pty_baseline();
        first_byte(None);
    }
    if want("startup") {
        startup();
    }
    if want("khz") {
        khz_loop();
    }
    if want("trackers") {
        pty_baseline();
        serial_trackers::run();
    }
    let _ = std::fs::remove_dir_all(tty_dir());
}

// ------------------------------------------------------------------ the simulator thread

/// A device model on a pseudo-terminal, stepped by its own thread as soon as the driver writes
/// or the model has something to send; `observe` runs after every step with the time the
/// step read just before it wrote.
struct SimThread {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl SimThread {
    fn start<M: DeviceModel + 'static>(
        path: &Path,
        model: impl FnOnce() -> M + Send + 'static,
        mut observe: impl FnMut(&mut PtyDevice<M>, Now) + Send + 'static,
    ) -> SimThread {
        let stop = Arc::new(AtomicBool::new(false));
        let s = stop.clone();
        let path = path.to_path_buf();
        let (ready_tx, ready_rx) = mpsc::channel();
        let thread = std::thread::spawn(move || {
            let mut dev = PtyDevice::open(model(), &path).expect("a pseudo-terminal");
            ready_tx.send(()).expect("the bench waits");
            while !s.load(Ordering::Relaxed) {
                let fd = dev.master_fd().expect("plugged");
                // Poll takes whole milliseconds: round up, so a deadline is never early.
                let wait = dev.next_deadline().map_or(10, |t| {
                    let d = t.saturating_duration_since(Instant::now());
                    d.as_micros().div_ceil(1000).min(10) as i32
                });
                let mut fds = [PollFd::new(fd, PollFlags::POLLIN)];
                let _ = poll(&mut fds, wait);
                let now = Now::read();
                dev.step(now).expect("simulator step");
                observe(&mut dev, now);
            }
        });
        ready_rx
            .recv_timeout(Duration::from_secs(5))
            .expect("simulator started");
        SimThread {
            stop,
            thread: Some(thread),
        }
    }
}

impl Drop for SimThread {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// This run's directory for pseudo-terminal links and files (removed at the end).
fn tty_dir() -> PathBuf {
    std::env::temp_dir().join(format!("vrpn-bench-{}", std::process::id()))
}

/// A fresh path for a simulator's pseudo-terminal link.
fn tty_path(name: &str) -> PathBuf {
    let dir = tty_dir();
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

/// One station at 120 Hz, 115200 baud, 8-byte chunks (a UART FIFO's hand-over).
fn fastrak_model() -> FastrakSim {
    let mut cfg = fastrak_sim::SimConfig::new(115_200);
    cfg.stations = 1;
    cfg.cycle = CYCLE;
    FastrakSim::new(cfg)
}

/// Two receivers and an extended-range transmitter (the entry's default), 115200 baud; RTS
/// is not wired through a pseudo-terminal.
fn flock_model() -> FlockSim {
    let mut cfg = flock_sim::SimConfig::new(2, true, 115_200);
    cfg.rts_wired = false;
    FlockSim::new(cfg)
}

// ------------------------------------------------------------------ the server thread

/// Our server in a thread: a server connection on 127.0.0.1 (port 0), the devices of `cfg`,
/// the event-driven loop of `vrpn_server`.
struct ServerThread {
    port: u16,
    started: Instant,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl ServerThread {
    fn start(cfg: &str) -> ServerThread {
        let cfg = cfg.to_string();
        let stop = Arc::new(AtomicBool::new(false));
        let s = stop.clone();
        let (tx, rx) = mpsc::channel();
        let thread = std::thread::spawn(move || {
            let started = Instant::now();
            let conn = Connection::server(Some(std::net::Ipv4Addr::LOCALHOST), 0).expect("server");
            let entries = parse_str(&cfg, "bench.cfg").expect("config");
            let devices = build_devices(&entries, &conn, false, None, |_| {}).expect("devices");
            tx.send((conn.local_port().expect("a port"), started))
                .expect("the bench waits");
            let sleep = SleepPolicy::EventDriven {
                busy_window: vrpn::server::run::DEFAULT_BUSY_WINDOW,
                max_block: Duration::from_millis(100),
            };
            let mut server = ServerLoop::new(conn, devices, sleep);
            server.run(&s).expect("server loop");
        });
        let (port, started) = rx
            .recv_timeout(Duration::from_secs(10))
            .expect("server started");
        ServerThread {
            port,
            started,
            stop,
            thread: Some(thread),
        }
    }
}

impl Drop for ServerThread {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

// ------------------------------------------------------------------ first-byte accuracy

/// A pose as the client received it.
struct Received {
    pos: [f64; 3],
    stamp: TimeVal,
    arrived: TimeVal,
}

fn micros(a: TimeVal, b: TimeVal) -> i64 {
    (a.sec - b.sec) * 1_000_000 + (a.usec - b.usec)
}

fn first_byte(external: Option<(u16, PathBuf)>) {
    let records: usize = std::env::var("FIRST_BYTE_RECORDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(RECORDS);
    let path = external
        .as_ref()
        .map_or_else(|| tty_path("fastrak"), |(_, p)| p.clone());
    // (record count of station 1, wall time just before the write carrying its first byte)
    let sent: Arc<Mutex<Vec<(u64, TimeVal)>>> = Arc::default();
    let s = sent.clone();
    let mut seen = 0usize;
    let _sim = SimThread::start(&path, fastrak_model, move |dev, now| {
        // Records logged by this step had their first byte in this step's write.
        let log = &dev.model.log;
        if log.len() > seen {
            let mut s = s.lock().unwrap();
            s.extend(log.iter().skip(seen).map(|r| (r.seq, now.wall)));
            seen = log.len();
        }
    });
    let (port, server, label) = match &external {
        Some((port, _)) => {
            let port = *port;
            println!(
                "first-byte: simulator on {}; start the server on 127.0.0.1:{port} now",
                path.display()
            );
            (port, None, "external server")
        }
        None => {
            let cfg = format!("vrpn_Tracker_Fastrak Tracker0 {} 115200\n", path.display());
            let server = ServerThread::start(&cfg);
            (server.port, Some(server), "our server")
        }
    };
    let tracker = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{port}")).expect("client");
    let got: Rc<RefCell<Vec<Received>>> = Rc::default();
    let g = got.clone();
    tracker.on_pose(move |p| {
        g.borrow_mut().push(Received {
            pos: [p.pos.x, p.pos.y, p.pos.z],
            stamp: p.time,
            arrived: TimeVal::now(),
        })
    });
    let start = Instant::now();
    let limit = Duration::from_secs(120) + CYCLE * records as u32;
    let mut first_at = None;
    while got.borrow().len() < records {
        assert!(
            start.elapsed() < limit,
            "first-byte: {} poses after {limit:?}",
            got.borrow().len()
        );
        tracker.mainloop().expect("client mainloop");
        if first_at.is_none() && !got.borrow().is_empty() {
            first_at = Some(start.elapsed());
            if external.is_some() {
                // For start-up times by hand: the other server's start is known in wall time.
                let t = TimeVal::now();
                println!(
                    "first-byte: first pose at wall time {}.{:06}",
                    t.sec, t.usec
                );
            }
        }
        let _ = tracker.connection().wait(Duration::from_millis(2));
    }
    drop(server);
    let sent = sent.lock().unwrap();
    let (stamp, arrival, unmatched) = match_records(&sent, &got.borrow());
    println!(
        "first-byte ({label}, Fastrak 1 station at 120 Hz on a pty, UDP path): {} poses, {} \
         matched, {unmatched} unmatched; first pose {:.2} s after the client started",
        got.borrow().len(),
        stamp.len(),
        first_at.unwrap_or_default().as_secs_f64()
    );
    print_us("  report timestamp - first-byte write", stamp);
    print_us("  client arrival   - first-byte write", arrival);
    println!("  (C++ 07.38 measured earlier on this machine: p50 552, p90 999, p99 1150 µs)");
}

/// The bare pseudo-terminal: a thread writes one byte every 8.333 ms (noting the wall time
/// just before), another waits in `poll` on the slave and notes the time it woke. What the
/// kernel and the scheduler cost before any server sees a byte.
fn pty_baseline() {
    use std::os::fd::AsRawFd;
    let records: usize = std::env::var("FIRST_BYTE_RECORDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(RECORDS);
    let (master, slave) = serialport::TTYPort::pair().expect("a pseudo-terminal");
    let written: Arc<Mutex<Vec<TimeVal>>> = Arc::default();
    let w = written.clone();
    let writer = std::thread::spawn(move || {
        let fd = master.as_raw_fd();
        let mut next = Instant::now();
        for _ in 0..records {
            next += CYCLE;
            std::thread::sleep(next.saturating_duration_since(Instant::now()));
            let now = Now::read();
            w.lock().unwrap().push(now.wall);
            nix::unistd::write(fd, b"x").expect("pty write");
        }
        // Keep the master open until the reader has everything.
        std::thread::sleep(Duration::from_millis(200));
        drop(master);
    });
    let fd = slave.as_raw_fd();
    let mut woke = Vec::with_capacity(records);
    let mut buf = [0u8; 64];
    while woke.len() < records {
        let mut fds = [PollFd::new(fd, PollFlags::POLLIN)];
        assert!(
            poll(&mut fds, 5000).expect("poll") > 0,
            "pty baseline stalled"
        );
        let now = Now::read();
        let n = nix::unistd::read(fd, &mut buf).expect("pty read");
        woke.extend(std::iter::repeat(now.wall).take(n));
    }
    writer.join().expect("writer thread");
    let written = written.lock().unwrap();
    let lat: Vec<i64> = woke
        .iter()
        .zip(written.iter())
        .map(|(&r, &w)| micros(r, w))
        .collect();
    println!("pty baseline (one byte at 120 Hz, a thread waiting in poll on the slave):");
    print_us("  wake - write", lat);
}

/// Pairs each received pose with the simulator's record of the same position (the values
/// are a known function of the record count); returns the two latencies per pair in µs and
/// how many poses matched nothing.
fn match_records(sent: &[(u64, TimeVal)], got: &[Received]) -> (Vec<i64>, Vec<i64>, usize) {
    let expected = |seq: u64| {
        let (pos, _) = fastrak_sim::pose(1, seq);
        pos.map(|v| f64::from(v) * METRES_PER_INCH)
    };
    let (mut stamp, mut arrival, mut unmatched) = (Vec::new(), Vec::new(), 0);
    let mut cursor = 0;
    for r in got {
        // Records arrive in order; a few may be lost at start-up, none after.
        let hit = sent[cursor..].iter().take(200).position(|&(seq, _)| {
            let e = expected(seq);
            (0..3).all(|i| (e[i] - r.pos[i]).abs() < 1e-9)
        });
        match hit {
            Some(i) => {
                let (_, wrote) = sent[cursor + i];
                stamp.push(micros(r.stamp, wrote));
                arrival.push(micros(r.arrived, wrote));
                cursor += i + 1;
            }
            None => unmatched += 1,
        }
    }
    (stamp, arrival, unmatched)
}

fn print_us(what: &str, mut v: Vec<i64>) {
    assert!(!v.is_empty(), "{what}: nothing measured");
    v.sort_unstable();
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    println!(
        "{what:<40} n={:<5} min {:>6} p50 {:>6} p90 {:>6} p99 {:>6} max {:>7} µs",
        v.len(),
        v[0],
        q(0.5),
        q(0.9),
        q(0.99),
        v[v.len() - 1]
    );
}

// ------------------------------------------------------------------ start-up time

fn startup() {
    for (name, runs) in [("Fastrak", 3), ("Flock", 3)] {
        let mut times = Vec::new();
        for run in 0..runs {
            let path = tty_path(&format!("{}-{run}", name.to_lowercase()));
            let (_sim, cfg) = if name == "Fastrak" {
                let sim = SimThread::start(&path, fastrak_model, |_, _| {});
                let cfg = format!("vrpn_Tracker_Fastrak Tracker0 {} 115200\n", path.display());
                (sim, cfg)
            } else {
                let sim = SimThread::start(&path, flock_model, |_, _| {});
                let cfg = format!(
                    "vrpn_Tracker_Flock Tracker0 2 {} 115200 0\n",
                    path.display()
                );
                (sim, cfg)
            };
            let server = ServerThread::start(&cfg);
            let tracker =
                TrackerRemote::new(&format!("Tracker0@127.0.0.1:{}", server.port)).expect("client");
            let first: Rc<RefCell<Option<Instant>>> = Rc::default();
            let f = first.clone();
            tracker.on_pose(move |_| {
                f.borrow_mut().get_or_insert_with(Instant::now);
            });
            while first.borrow().is_none() {
                assert!(
                    server.started.elapsed() < Duration::from_secs(60),
                    "{name}: no report within 60 s"
                );
                tracker.mainloop().expect("client mainloop");
                let _ = tracker.connection().wait(Duration::from_millis(2));
            }
            let t = first.borrow().expect("checked") - server.started;
            times.push(t.as_secs_f64());
        }
        let mut sorted = times.clone();
        sorted.sort_by(f64::total_cmp);
        println!(
            "startup {name:<8} server start to first report: median {:.3} s (runs: {})",
            sorted[sorted.len() / 2],
            times
                .iter()
                .map(|t| format!("{t:.3}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    println!("  (C++ 07.38 measured earlier: about 7 s Fastrak, 19 s Flock)");
}

// ------------------------------------------------------------------ the 1 kHz loop

/// utime + stime of `pid` in clock ticks.
fn cpu_ticks(pid: u32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("/proc stat");
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')').expect("stat format") + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    f[11].parse::<u64>().expect("utime") + f[12].parse::<u64>().expect("stime")
}

/// Kills and reaps a child this bench started, by its PID, when dropped.
struct Child(std::process::Child);

impl Drop for Child {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn khz_loop() {
    let program = std::env::var("VRPN_KHZ_SERVER")
        .unwrap_or_else(|_| env!("CARGO_BIN_EXE_vrpn_server").to_string());
    let cfg = tty_path("khz.cfg");
    std::fs::write(&cfg, "vrpn_Tracker_NULL T 1 1000\n").expect("config file");
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    let child = Child(
        std::process::Command::new(&program)
            .args(["-f", cfg.to_str().expect("UTF-8 path"), "-NIC", "127.0.0.1"])
            .arg(port.to_string())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("the server program"),
    );
    let pid = child.0.id();
    let tracker = TrackerRemote::new(&format!("T@127.0.0.1:{port}")).expect("client");
    let stamps: Rc<RefCell<Vec<TimeVal>>> = Rc::default();
    let s = stamps.clone();
    tracker.on_pose(move |p| s.borrow_mut().push(p.sender_time));
    let start = Instant::now();
    while stamps.borrow().is_empty() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "khz: no report in 20 s"
        );
        tracker.mainloop().expect("client mainloop");
        let _ = tracker.connection().wait(Duration::from_millis(1));
    }
    // Settle, then measure 10 s.
    let settle = Instant::now();
    while settle.elapsed() < Duration::from_secs(1) {
        tracker.mainloop().expect("client mainloop");
        let _ = tracker.connection().wait(Duration::from_millis(1));
    }
    stamps.borrow_mut().clear();
    let ticks0 = cpu_ticks(pid);
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(10) {
        tracker.mainloop().expect("client mainloop");
        let _ = tracker.connection().wait(Duration::from_millis(1));
    }
    let ticks1 = cpu_ticks(pid);
    let wall = t0.elapsed().as_secs_f64();
    drop(child);
    // /proc counts in USER_HZ, 100 on Linux.
    let hz = 100.0;
    let stamps = stamps.borrow();
    let intervals: Vec<i64> = stamps.windows(2).map(|w| micros(w[1], w[0])).collect();
    println!(
        "khz ({}): {} reports in {wall:.1} s ({:.0}/s), server CPU {:.1}%",
        Path::new(&program)
            .file_name()
            .map_or(program.clone(), |n| n.to_string_lossy().into_owned()),
        stamps.len(),
        stamps.len() as f64 / wall,
        (ticks1 - ticks0) as f64 / hz / wall * 100.0
    );
    let backwards = intervals.iter().filter(|&&i| i < 0).count();
    let bunched = intervals.iter().filter(|&&i| (0..200).contains(&i)).count();
    print_us("  report interval (sender timestamps)", intervals);
    println!("  intervals < 0: {backwards}, 0-200 µs (catching up after a late wake): {bunched}");
}
