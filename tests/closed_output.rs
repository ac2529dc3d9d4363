//! Every program run with its standard output closed early (`| head`) ends quietly: no panic,
//! no "Broken pipe" message, exit status 0. Children are ended by PID only.

mod common;

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::os::fd::FromRawFd;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const PRINT: &str = env!("CARGO_BIN_EXE_vrpn_print_devices");
const PING: &str = env!("CARGO_BIN_EXE_vrpn_ping");
const LOG: &str = env!("CARGO_BIN_EXE_vrpn_log");

/// Standard output whose reader is already gone: the write end of a pipe whose read end is
/// closed before the child starts, so the child's first write fails with EPIPE.
fn closed_stdout() -> Stdio {
    let (read, write) = nix::unistd::pipe().unwrap();
    nix::unistd::close(read).unwrap();
    // SAFETY: `write` is a fresh descriptor that nothing else owns.
    Stdio::from(unsafe { File::from_raw_fd(write) })
}

/// Waits for `child` (at most `limit`), killing it by PID if it does not end; returns its exit
/// code (None when a signal ended it) and its standard error.
fn finish(mut child: Child, limit: Duration) -> (Option<i32>, String) {
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the program did not end within {limit:?} after its output closed");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut err = String::new();
    if let Some(mut pipe) = child.stderr.take() {
        std::io::Read::read_to_string(&mut pipe, &mut err).unwrap();
    }
    (status.code(), err)
}

/// Asserts a quiet, successful end.
fn assert_quiet(what: &str, (code, err): (Option<i32>, String)) {
    assert!(
        !err.contains("panicked") && !err.contains("Broken pipe") && !err.contains("backtrace"),
        "{what}: {err}"
    );
    assert_eq!(code, Some(0), "{what}: {err}");
}

/// Runs `bin args` with standard output already closed.
fn run_closed(bin: &str, args: &[&str]) -> (Option<i32>, String) {
    let child = Command::new(bin)
        .args(args)
        .stdin(Stdio::null())
        .stdout(closed_stdout())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    finish(child, Duration::from_secs(20))
}

#[test]
fn print_devices_json_into_head() {
    // vrpn_print_devices --json DEV | head -n 2
    let server = common::start_server("vrpn_Tracker_NULL Tracker0 2 100.0\n", 0);
    let name = format!("Tracker0@127.0.0.1:{}", server.port);
    let mut child = Command::new(PRINT)
        .args(["--json", &name])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    for _ in 0..2 {
        let mut line = String::new();
        out.read_line(&mut line).unwrap();
        assert!(line.starts_with("{\"device\":\"Tracker0\""), "{line}");
    }
    drop(out); // what head does after two lines
    assert_quiet(
        "vrpn_print_devices --json",
        finish(child, Duration::from_secs(10)),
    );
}

#[test]
fn print_devices_text_and_list_into_a_closed_pipe() {
    let server = common::start_server("vrpn_Tracker_NULL Tracker0 1 50.0\n", 0);
    let name = format!("Tracker0@127.0.0.1:{}", server.port);
    assert_quiet("vrpn_print_devices", run_closed(PRINT, &[&name]));
    let location = format!("127.0.0.1:{}", server.port);
    assert_quiet(
        "vrpn_print_devices --list",
        run_closed(PRINT, &["--list", &location]),
    );
}

#[test]
fn ping_into_a_closed_pipe() {
    let server = common::start_server("vrpn_Tracker_NULL Tracker0 1 10.0\n", 0);
    let name = format!("Tracker0@127.0.0.1:{}", server.port);
    assert_quiet("vrpn_ping", run_closed(PING, &["-n", "20", &name]));
}

#[test]
fn log_dump_into_a_closed_pipe() {
    let log = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/golden/button_analog_dial.out.vrpn");
    let log = log.to_str().unwrap();
    for args in [
        &["dump", log][..],
        &["dump", "--json", log],
        &["summary", log],
        &["csv", log, "Analog0", "--kind", "analog"],
    ] {
        assert_quiet(&format!("vrpn_log {args:?}"), run_closed(LOG, args));
    }
}

#[test]
fn server_with_a_closed_output_ends_quietly() {
    let dir = std::env::temp_dir().join(format!("vrpn-closed-out-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = dir.join("vrpn.cfg");
    std::fs::write(&cfg, "vrpn_Tracker_NULL Tracker0 1 10.0\n").unwrap();
    let log = dir.join("out.vrpn");
    let result = run_closed(
        SERVER,
        &[
            "-f",
            cfg.to_str().unwrap(),
            "-lo",
            log.to_str().unwrap(),
            "0",
        ],
    );
    assert_quiet("vrpn_server", result);
    // It ended through its normal path: the log was closed with its DISCONNECT entry.
    let reader = vrpn::log::LogReader::open(&log).unwrap();
    let mut entries = reader.entries();
    let mut last = None;
    while let Some(e) = entries.next_entry() {
        last = Some(e.unwrap().type_id());
    }
    assert_eq!(last, Some(vrpn::wire::system::DISCONNECT));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn help_and_version_into_a_closed_pipe() {
    for bin in [SERVER, PRINT, PING, LOG] {
        for flag in ["--help", "--version"] {
            assert_quiet(&format!("{bin} {flag}"), run_closed(bin, &[flag]));
        }
    }
}
