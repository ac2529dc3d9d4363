//! Helpers shared by the robustness tests: the vrpn_server binary as a child on port 0, /proc
//! readings of a process, ping round trips, and percentiles.
#![allow(dead_code)]

use std::cell::Cell;
use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, Stdio};
use std::rc::Rc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use vrpn::devices::base::{PING_MESSAGE, PONG_MESSAGE};
use vrpn::wire::class;
use vrpn::{Connection, SenderFilter, TimeVal};

/// A vrpn_server child process, killed (by its PID, through `Child`) on drop.
pub struct Server {
    pub child: Child,
    pub port: u16,
    pub pid: u32,
    /// Everything the server wrote to stderr (its notices).
    pub stderr: Arc<Mutex<String>>,
    cfg_dir: std::path::PathBuf,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.cfg_dir);
    }
}

static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Starts vrpn_server on `cfg` text at `port` (0: any) and reads the port from its first line.
pub fn start_server(cfg: &str, port: u16) -> Server {
    start_server_with(cfg, port, &[])
}

/// [`start_server`] with more `vrpn_server` options before the port.
pub fn start_server_with(cfg: &str, port: u16, options: &[&str]) -> Server {
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("vrpn-robust-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("vrpn.cfg");
    std::fs::write(&path, cfg).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_vrpn_server"))
        .args(["-f", path.to_str().unwrap()])
        .args(options)
        .arg(port.to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    let port = line
        .split("on port ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no port in {line:?}"));
    // Drain both pipes so the server never blocks on a full pipe.
    std::thread::spawn(move || {
        let mut sink = Vec::new();
        let _ = out.read_to_end(&mut sink);
    });
    let stderr = Arc::new(Mutex::new(String::new()));
    let mut err = child.stderr.take().unwrap();
    let e = stderr.clone();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = err.read(&mut buf) {
            if n == 0 {
                break;
            }
            e.lock()
                .unwrap()
                .push_str(&String::from_utf8_lossy(&buf[..n]));
        }
    });
    let pid = child.id();
    Server {
        child,
        port,
        pid,
        stderr,
        cfg_dir: dir,
    }
}

fn status_field(pid: u32, key: &str) -> u64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    s.lines()
        .find(|l| l.starts_with(key))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

/// Resident set size in KiB.
pub fn rss_kb(pid: u32) -> u64 {
    status_field(pid, "VmRSS:")
}

/// Peak resident set size in KiB.
pub fn hwm_kb(pid: u32) -> u64 {
    status_field(pid, "VmHWM:")
}

/// utime + stime in seconds.
pub fn cpu_seconds(pid: u32) -> f64 {
    let s = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap();
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &s[s.rfind(')').unwrap() + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: u64 = f[11].parse::<u64>().unwrap() + f[12].parse::<u64>().unwrap();
    // USER_HZ is 100 on every Linux configuration that exposes /proc/PID/stat this way.
    ticks as f64 / 100.0
}

/// Open file descriptors.
pub fn fd_count(pid: u32) -> usize {
    std::fs::read_dir(format!("/proc/{pid}/fd"))
        .map(|d| d.count())
        .unwrap_or(0)
}

/// A ping client of `device` on `conn`: sends one reliable ping and pumps `conn` (and `also`)
/// until the pong arrives. Returns round-trip times in µs.
pub struct Pinger {
    conn: Connection,
    ping: vrpn::TypeId,
    sender: vrpn::SenderId,
    pongs: Rc<Cell<u64>>,
}

impl Pinger {
    pub fn new(conn: &Connection, device: &str) -> Pinger {
        let sender = conn.register_sender(device).unwrap();
        let ping = conn.register_type(PING_MESSAGE).unwrap();
        let pong = conn.register_type(PONG_MESSAGE).unwrap();
        let pongs = Rc::new(Cell::new(0u64));
        let p = pongs.clone();
        conn.register_handler(pong, SenderFilter::Only(sender), move |_| {
            p.set(p.get() + 1)
        });
        Pinger {
            conn: conn.clone(),
            ping,
            sender,
            pongs,
        }
    }

    pub fn round_trips(&self, count: usize, mut also: impl FnMut()) -> Vec<f64> {
        let mut rtts = Vec::with_capacity(count);
        for i in 0..count {
            let before = self.pongs.get();
            let t0 = Instant::now();
            self.conn
                .pack_message(TimeVal::now(), self.ping, self.sender, &[], class::RELIABLE)
                .unwrap();
            loop {
                self.conn.mainloop().unwrap();
                also();
                if self.pongs.get() > before {
                    break;
                }
                assert!(t0.elapsed() < Duration::from_secs(5), "ping {i}: no pong");
            }
            rtts.push(t0.elapsed().as_secs_f64() * 1e6);
        }
        rtts
    }
}

/// (p50, p99) of `v`.
pub fn p50_p99(v: &mut [f64]) -> (f64, f64) {
    v.sort_unstable_by(f64::total_cmp);
    let pct = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    (pct(0.5), pct(0.99))
}

/// Pumps `conn` until `done` or `limit`; panics with `what` on timeout.
pub fn pump_until(conn: &Connection, limit: Duration, what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(start.elapsed() < limit, "timed out: {what}");
        conn.mainloop().unwrap();
        let _ = conn.wait(Duration::from_millis(2));
    }
}
