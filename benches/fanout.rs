//! Fan-out: N clients, all started at once, each reading the whole stream of one server.
//!
//! The server (`vrpn_server`, a child process) runs an 8-sensor `vrpn_Tracker_NULL` at 1 kHz,
//! 8,000 poses a second per client, pinned to CPU 0 with `taskset`; this process holds N
//! private `TrackerRemote`s in one reactor, pinned to CPU 1. For N = 32, 128, 255 on the UDP
//! path and on `tcp://` it reports: poses per second delivered in all (and as a share of
//! N × 8,000), the slowest client's rate, the time from opening the clients to the last one's
//! first pose, the server's CPU share, the server's CPU time per delivered pose, and the
//! notices seen (client side, and lines on the server's stderr).
//!
//! `VRPN_FANOUT_BEFORE=/path/to/vrpn_server` runs every case against that server too, right
//! after the one built here, so a before/after comparison shares one run (same load).
//! `VRPN_FANOUT_SECONDS` sets the measuring window (default 3 s); `VRPN_FANOUT_ROUNDS` repeats
//! each case and reports medians (default 1). `cargo bench --bench fanout -- FILTER` keeps the
//! cases whose label contains FILTER (e.g. `255`, `tcp`).

use std::cell::Cell;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::rc::Rc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use vrpn::net::Reactor;
use vrpn::{Connection, Limits, TrackerRemote};

const CFG: &str = "vrpn_Tracker_NULL Tracker0 8 1000.0\n";
const PER_CLIENT: f64 = 8_000.0;

/// Kills and reaps the server this bench started, by its PID, when dropped.
struct Server {
    child: std::process::Child,
    port: u16,
    stderr: Arc<Mutex<Vec<String>>>,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start_server(program: &str, cfg: &std::path::Path, pin: bool) -> Server {
    let mut cmd = if pin {
        let mut c = Command::new("taskset");
        c.args(["-c", "0", program]);
        c
    } else {
        Command::new(program)
    };
    let mut child = cmd
        .args([
            "-f",
            cfg.to_str().expect("UTF-8 path"),
            "-NIC",
            "127.0.0.1",
            "0",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the server program");
    let mut out = BufReader::new(child.stdout.take().expect("stdout"));
    let mut line = String::new();
    out.read_line(&mut line).expect("the server's first line");
    let port = line
        .split("on port ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.trim_end_matches('.').parse().ok())
        .unwrap_or_else(|| panic!("no port in {line:?}"));
    std::thread::spawn(move || for _ in out.lines() {});
    let stderr: Arc<Mutex<Vec<String>>> = Arc::default();
    let err = BufReader::new(child.stderr.take().expect("stderr"));
    let e = stderr.clone();
    std::thread::spawn(move || {
        for l in err.lines().map_while(Result::ok) {
            e.lock().expect("stderr lines").push(l);
        }
    });
    Server {
        child,
        port,
        stderr,
    }
}

/// utime + stime of `pid` in seconds.
fn cpu_seconds(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    let Some(close) = stat.rfind(')') else {
        return 0.0;
    };
    let f: Vec<&str> = stat[close + 2..].split_whitespace().collect();
    let ticks: u64 = f.get(11).and_then(|v| v.parse().ok()).unwrap_or(0)
        + f.get(12).and_then(|v| v.parse().ok()).unwrap_or(0);
    ticks as f64 / 100.0
}

/// The server's PID: the child itself, or the program `taskset` became (it execs).
fn server_pid(s: &Server) -> u32 {
    s.child.id()
}

fn pin_self_to_cpu1() -> bool {
    use nix::sched::{sched_setaffinity, CpuSet};
    use nix::unistd::Pid;
    let mut set = CpuSet::new();
    set.set(1).is_ok() && sched_setaffinity(Pid::from_raw(0), &set).is_ok()
}

#[derive(Clone, Copy, Default)]
struct Figures {
    total: f64,
    slowest: f64,
    last_first: Option<f64>,
    cpu: f64,
    notices: usize,
    server_lines: usize,
}

/// One client: its remote, poses counted, when the first one came.
type Client = (TrackerRemote, Rc<Cell<u64>>, Rc<Cell<Option<Instant>>>);

fn run_case(program: &str, cfg: &std::path::Path, n: usize, tcp_only: bool, secs: f64) -> Figures {
    let server = start_server(program, cfg, true);
    let pid = server_pid(&server);
    let reactor = Reactor::new().expect("reactor");
    let notices = Rc::new(Cell::new(0usize));
    let limits = Limits::default();
    let started = Instant::now();
    let clients: Vec<Client> = (0..n)
        .map(|_| {
            let conn = Connection::client_in(&reactor, "127.0.0.1", server.port, tcp_only, limits)
                .expect("client");
            let seen = notices.clone();
            conn.on_notice(move |_| seen.set(seen.get() + 1));
            let t = TrackerRemote::on_connection("Tracker0", &conn).expect("remote");
            let count = Rc::new(Cell::new(0u64));
            let first: Rc<Cell<Option<Instant>>> = Rc::default();
            let (c, f) = (count.clone(), first.clone());
            t.on_pose(move |_| {
                c.set(c.get() + 1);
                if f.get().is_none() {
                    f.set(Some(Instant::now()));
                }
            });
            (t, count, first)
        })
        .collect();
    let pump = |until: Instant| {
        while Instant::now() < until {
            for (t, _, _) in &clients {
                let _ = t.mainloop();
            }
            let _ = reactor.wait(None, Duration::from_millis(1));
        }
    };
    // Connect: up to 10 s for the last first pose.
    let limit = started + Duration::from_secs(10);
    while Instant::now() < limit && clients.iter().any(|c| c.2.get().is_none()) {
        pump(Instant::now() + Duration::from_millis(1));
    }
    let last_first = clients
        .iter()
        .map(|c| c.2.get())
        .collect::<Option<Vec<_>>>()
        .and_then(|v| v.into_iter().max())
        .map(|t| (t - started).as_secs_f64());
    // Settle, then measure.
    pump(Instant::now() + Duration::from_millis(500));
    let before: Vec<u64> = clients.iter().map(|c| c.1.get()).collect();
    let cpu0 = cpu_seconds(pid);
    let t0 = Instant::now();
    pump(t0 + Duration::from_secs_f64(secs));
    let wall = t0.elapsed().as_secs_f64();
    let cpu = cpu_seconds(pid) - cpu0;
    let rates: Vec<f64> = clients
        .iter()
        .zip(&before)
        .map(|(c, b)| (c.1.get() - b) as f64 / wall)
        .collect();
    let total: f64 = rates.iter().sum();
    let slowest = rates.iter().cloned().fold(f64::INFINITY, f64::min);
    let server_lines = server.stderr.lock().expect("stderr").len();
    drop(clients);
    Figures {
        total,
        slowest,
        last_first,
        cpu: cpu / wall,
        notices: notices.get(),
        server_lines,
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    v[v.len() / 2]
}

fn median_figures(runs: &[Figures]) -> Figures {
    let m = |f: &dyn Fn(&Figures) -> f64| median(runs.iter().map(f).collect());
    let never = runs.iter().any(|r| r.last_first.is_none());
    Figures {
        total: m(&|r| r.total),
        slowest: m(&|r| r.slowest),
        last_first: (!never).then(|| m(&|r| r.last_first.unwrap_or(f64::INFINITY))),
        cpu: m(&|r| r.cpu),
        notices: median(runs.iter().map(|r| r.notices as f64).collect()) as usize,
        server_lines: median(runs.iter().map(|r| r.server_lines as f64).collect()) as usize,
    }
}

fn print_row(label: &str, n: usize, f: &Figures) {
    let want = n as f64 * PER_CLIENT;
    let per_pose_us = if f.total > 0.0 {
        f.cpu / f.total * 1e6
    } else {
        f64::NAN
    };
    println!(
        "| {label} | {:.0} ({:.0}%) | {:.0}/s | {} | {:.0}% | {per_pose_us:.2} µs | {} / {} |",
        f.total,
        f.total / want * 100.0,
        f.slowest,
        f.last_first
            .map_or("never (some)".to_string(), |s| format!("{s:.2} s")),
        f.cpu * 100.0,
        f.notices,
        f.server_lines,
    );
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let filter = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let secs: f64 = std::env::var("VRPN_FANOUT_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3.0);
    let rounds: usize = std::env::var("VRPN_FANOUT_ROUNDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1)
        .max(1);
    let mut servers = vec![("now", env!("CARGO_BIN_EXE_vrpn_server").to_string())];
    if let Ok(before) = std::env::var("VRPN_FANOUT_BEFORE") {
        servers.push(("before", before));
    }
    // 255 clients on the UDP path hold about five descriptors each here.
    vrpn::server::raise_descriptor_limit();
    let pinned = pin_self_to_cpu1();
    let dir = std::env::temp_dir().join(format!("vrpn-fanout-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let cfg = dir.join("vrpn.cfg");
    std::fs::write(&cfg, CFG).expect("config file");
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!(
        "fan-out: 8-sensor NULL tracker at 1 kHz; server on CPU 0 (taskset), clients on CPU 1 \
         ({}); {secs} s windows, median of {rounds}; load average {}",
        if pinned { "pinned" } else { "NOT pinned" },
        load.split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" ")
    );
    println!(
        "| server, clients | poses/s delivered (of N × 8,000) | slowest client | last client's \
         first pose | server CPU | server CPU per pose | client notices / server stderr lines |"
    );
    println!("|---|---|---|---|---|---|---|");
    for n in [32usize, 128, 255] {
        for tcp_only in [false, true] {
            let path = if tcp_only { "tcp://" } else { "UDP" };
            for (which, program) in &servers {
                let label = format!("{which}, {n} {path}");
                if filter.as_ref().is_some_and(|f| !label.contains(f.as_str())) {
                    continue;
                }
                let runs: Vec<Figures> = (0..rounds)
                    .map(|_| run_case(program, &cfg, n, tcp_only, secs))
                    .collect();
                print_row(&label, n, &median_figures(&runs));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
