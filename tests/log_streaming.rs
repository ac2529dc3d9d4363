//! Logs are read with bounded memory and only from regular files: the cookie is checked
//! before anything else is read, a large log costs a window rather than its size (in
//! `vrpn_log` and in replay), `/dev/zero` and FIFOs are refused at once, and replay keeps every
//! control across the window's refills without allocating.

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::cell::Cell;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::rc::Rc;
use std::time::{Duration, Instant};

use counting_alloc::allocations_in;
use vrpn::log::LogWriter;
use vrpn::wire::payload::tracker::PosQuat;
use vrpn::wire::system::encode_description;
use vrpn::wire::Cookie;
use vrpn::{Connection, TimeVal, TrackerRemote};

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("vrpn-log-streaming-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A log of one tracker reporting every millisecond for `n` ms from t = 1000 s, descriptions
/// first: 88 bytes per pose, so `n` = 20,000 spans several windows.
fn tracker_log(path: &Path, n: u32) {
    let _ = std::fs::remove_file(path);
    let mut w = LogWriter::create(path, &Cookie::ours(0).to_bytes()).unwrap();
    let t0 = TimeVal::new(1000, 0);
    let mut d = [0u8; 64];
    let len = encode_description(&mut d, "Tracker0");
    w.log_message(-1, 0, t0, &d[..len]).unwrap();
    let len = encode_description(&mut d, "vrpn_Tracker Pos_Quat");
    w.log_message(-2, 0, t0, &d[..len]).unwrap();
    let mut p = [0u8; PosQuat::LEN];
    for i in 0..n {
        PosQuat {
            sensor: 0,
            pad: 0,
            pos: [f64::from(i), 0.0, 0.0],
            quat: [0.0, 0.0, 0.0, 1.0],
        }
        .encode(&mut p);
        w.log_message(0, 0, t0.plus(Duration::from_millis(u64::from(i))), &p)
            .unwrap();
    }
    w.finish().unwrap();
}

/// A sparse file of about `len` bytes that starts with a valid cookie: every entry after it
/// is 24 zero bytes (a message of type 0 from sender 0 at time 0, never described).
fn sparse_log(path: &Path, len: u64) {
    let f = std::fs::File::create(path).unwrap();
    std::io::Write::write_all(&mut &f, &Cookie::ours(0).to_bytes()).unwrap();
    f.set_len(len / 24 * 24).unwrap();
}

/// Runs `program args` to completion (killed after `limit`); returns exit code, stderr and the
/// largest resident set seen (VmHWM, KiB). `None` for the code when it had to be killed.
fn run_measured(program: &str, args: &[&str], limit: Duration) -> (Option<i32>, String, u64) {
    let mut child = Command::new(program)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let status_path = format!("/proc/{}/status", child.id());
    let start = Instant::now();
    let mut peak = 0;
    let code = loop {
        if let Ok(status) = std::fs::read_to_string(&status_path) {
            if let Some(kib) = status
                .lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<u64>().ok())
            {
                peak = peak.max(kib);
            }
        }
        if let Some(s) = child.try_wait().unwrap() {
            break s.code();
        }
        if start.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    (code, err, peak)
}

#[test]
fn vrpn_log_reads_a_large_log_in_bounded_memory() {
    let path = dir().join("sparse-256m.vrpn");
    sparse_log(&path, 128 << 20);
    let p = path.to_str().unwrap();
    // The summary reads every entry; the CSV export reads them all looking for a device the
    // log does not have (exit status 1).
    for (args, status) in [(vec!["summary", p], 0), (vec!["csv", p, "Tracker0"], 1)] {
        let (code, err, peak_kib) = run_measured(
            env!("CARGO_BIN_EXE_vrpn_log"),
            &args,
            Duration::from_secs(120),
        );
        eprintln!(
            "vrpn_log {}: peak RSS {peak_kib} KiB, exit {code:?}",
            args[0]
        );
        assert_eq!(code, Some(status), "vrpn_log {}: {err}", args[0]);
        assert!(
            peak_kib < 32 * 1024,
            "vrpn_log {} held {peak_kib} KiB for a 128 MiB log",
            args[0]
        );
    }
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn files_that_are_not_logs_are_refused_at_once() {
    let fifo = dir().join("fifo.vrpn");
    let _ = std::fs::remove_file(&fifo);
    nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::S_IRWXU).unwrap();
    let zeros = dir().join("zeros.vrpn");
    sparse_log(&zeros, 1 << 20);
    // A cookie of zeros: a regular file whose first bytes are not a VRPN cookie.
    std::fs::write(&zeros, vec![0u8; 1 << 20]).unwrap();
    for (path, says) in [
        (
            Path::new("/dev/zero"),
            "a character device, not a regular file",
        ),
        (fifo.as_path(), "a FIFO, not a regular file"),
        (zeros.as_path(), "not a VRPN 04..07 log"),
    ] {
        let start = Instant::now();
        let err = Connection::replay_file(path.to_str().unwrap()).unwrap_err();
        assert!(start.elapsed() < Duration::from_secs(1));
        assert!(err.to_string().contains(says), "{}: {err}", path.display());
        // The client program exits with the error too (and its --seconds is moot).
        let device = format!("Tracker0@file:{}", path.display());
        let (code, err, _) = run_measured(
            env!("CARGO_BIN_EXE_vrpn_print_devices"),
            &["--seconds", "30", &device],
            Duration::from_secs(20),
        );
        assert!(
            code.is_some_and(|c| c != 0),
            "{}: {code:?} {err}",
            path.display()
        );
        assert!(err.contains(says), "{}: {err}", path.display());
        let (code, err, _) = run_measured(
            env!("CARGO_BIN_EXE_vrpn_log"),
            &["summary", path.to_str().unwrap()],
            Duration::from_secs(20),
        );
        assert_eq!(code, Some(1), "{}: {err}", path.display());
        assert!(err.contains(says), "{}: {err}", path.display());
    }
    std::fs::remove_file(&fifo).unwrap();
    std::fs::remove_file(&zeros).unwrap();
}

/// Replay of a log several windows long: every control behaves as it does on a small log.
#[test]
fn replay_keeps_every_control_across_the_window() {
    let path = dir().join("tracker-20s.vrpn");
    tracker_log(&path, 20_000);
    let conn = Connection::replay_file(path.to_str().unwrap()).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let seen = Rc::new(Cell::new((0u32, -1.0f64)));
    let s = seen.clone();
    tracker.on_pose(move |p| s.set((s.get().0 + 1, p.pos[0])));
    let r = conn.replay().unwrap();
    assert!((r.length_secs() - 19.999).abs() < 1e-9);
    r.set_rate(0.0);
    r.play_to_time(5.0);
    assert_eq!(seen.get(), (5001, 5000.0));
    // Forward over several windows without delivering, then on.
    assert!(r.jump_to_time(15.0));
    assert_eq!(seen.get().0, 5001);
    r.play_to_time(15.5);
    assert_eq!(seen.get(), (5001 + 500, 15_500.0));
    // Back to the start: the window is refilled from the beginning.
    r.reset();
    assert!(r.play_one() && r.play_one());
    assert_eq!(seen.get(), (5503, 1.0));
    r.play_to_time(100.0);
    assert_eq!(seen.get(), (25_501, 19_999.0));
    assert!(r.eof());
    assert!(!r.play_one());
    // A seek backwards rewinds.
    assert!(r.jump_to_time(19.990));
    r.play_to_time(100.0);
    assert_eq!(seen.get(), (25_510, 19_999.0));
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn replay_across_the_window_does_not_allocate() {
    let path = dir().join("tracker-alloc.vrpn");
    tracker_log(&path, 20_000);
    let conn = Connection::replay_file(path.to_str().unwrap()).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let n = Rc::new(Cell::new(0u32));
    let c = n.clone();
    tracker.on_pose(move |_| c.set(c.get() + 1));
    let r = conn.replay().unwrap();
    r.set_rate(0.0);
    r.play_to_time(0.5);
    let allocs = allocations_in(|| {
        r.play_to_time(8.0);
        r.jump_to_time(12.0);
        r.play_to_time(100.0);
    });
    assert_eq!(allocs, 0, "allocations while replaying across windows");
    assert_eq!(n.get(), 501 + 7500 + 7999);
    // At rate, through mainloop(), as an application runs it.
    r.reset();
    r.play_to_time(0.5);
    r.set_rate(f64::INFINITY);
    let before = n.get();
    let start = Instant::now();
    let allocs = allocations_in(|| {
        while !r.eof() && start.elapsed() < Duration::from_secs(20) {
            tracker.mainloop().unwrap();
        }
    });
    assert_eq!(allocs, 0, "allocations while replaying at rate");
    assert_eq!(n.get() - before, 19_499);
    std::fs::remove_file(&path).unwrap();
}

/// A replay opened on a large log holds a window, not the file.
#[test]
fn replay_of_a_large_log_holds_a_window() {
    let path = dir().join("sparse-replay.vrpn");
    sparse_log(&path, 128 << 20);
    let (code, err, peak_kib) = run_measured(
        env!("CARGO_BIN_EXE_vrpn_print_devices"),
        &[
            "--seconds",
            "0.5",
            &format!("Tracker0@file:{}", path.display()),
        ],
        Duration::from_secs(120),
    );
    eprintln!("replay of a 128 MiB log: peak RSS {peak_kib} KiB, exit {code:?}");
    assert_eq!(code, Some(0), "{err}");
    assert!(peak_kib < 32 * 1024, "{peak_kib} KiB");
    std::fs::remove_file(&path).unwrap();
}
