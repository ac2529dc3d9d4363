//! The programs as a user runs them: vrpn_server on a config, vrpn_print_devices (text, --json,
//! --list) and vrpn_ping against it, over real loopback sockets. Every child is ended by PID.

use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

struct Server {
    child: Child,
    port: u16,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts vrpn_server on port 0 and reads the port it chose from its first line.
fn start_server(cfg: &str, extra: &[&str]) -> Server {
    let dir = std::env::temp_dir().join(format!("vrpn-test-{}-{}", std::process::id(), cfg.len()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("vrpn.cfg");
    std::fs::write(&path, cfg).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_vrpn_server"))
        .args(["-f", path.to_str().unwrap()])
        .args(extra)
        .arg("0")
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.as_mut().unwrap())
        .read_line(&mut line)
        .unwrap();
    let port = line
        .split("on port ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no port in {line:?}"));
    Server { child, port }
}

fn run(bin: &str, args: &[&str]) -> (i32, String, String) {
    let mut child = Command::new(bin)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Drain both pipes on threads so a chatty child never blocks on a full pipe.
    let mut out_pipe = child.stdout.take().unwrap();
    let mut err_pipe = child.stderr.take().unwrap();
    let out_t = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out_pipe.read_to_string(&mut s);
        s
    });
    let err_t = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err_pipe.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code().unwrap_or(-1);
        }
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{bin} {args:?} did not finish");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    (code, out_t.join().unwrap(), err_t.join().unwrap())
}

const PRINT: &str = env!("CARGO_BIN_EXE_vrpn_print_devices");
const PING: &str = env!("CARGO_BIN_EXE_vrpn_ping");

#[test]
fn print_devices_shows_both_sensors_over_both_paths() {
    let server = start_server("vrpn_Tracker_NULL Tracker0 2 60.0\n", &[]);
    for name in [
        format!("Tracker0@127.0.0.1:{}", server.port),
        format!("Tracker0@tcp://127.0.0.1:{}", server.port),
    ] {
        let (code, out, err) = run(PRINT, &["--seconds", "1.5", &name]);
        assert_eq!(code, 0, "{err}");
        assert!(out.contains(&format!("Opened {name} as:")), "{out}");
        for s in ["sensor 0:", "sensor 1:"] {
            assert!(out.contains(&format!("Tracker {name}, {s}")), "{out}");
        }
        assert!(out.contains(
            "     vel ( 0.00,  0.00,  0.00); quatvel ( 0.00,  0.00,  0.00,  1.00), dt  1.00"
        ));
        assert!(out.contains(
            "     acc ( 0.00,  0.00,  0.00); quatacc ( 0.00,  0.00,  0.00,  1.00), dt  1.00"
        ));
    }
}

#[test]
fn print_devices_json_lines_parse() {
    let server = start_server("vrpn_Tracker_Spin Spin0 1 50.0 0.0 1.0 0.0 0.5\n", &[]);
    let name = format!("Spin0@127.0.0.1:{}", server.port);
    let (code, out, err) = run(PRINT, &["--json", "--seconds", "1.0", &name]);
    assert_eq!(code, 0, "{err}");
    let mut kinds = std::collections::HashSet::new();
    for line in out.lines() {
        let v: serde_json::Value =
            serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {line}"));
        assert_eq!(v["device"], "Spin0");
        assert!(v["time"].as_f64().unwrap() > 1.6e9);
        let kind = v["kind"].as_str().unwrap().to_string();
        if kind == "pose" {
            let q: Vec<f64> = v["quat"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!((norm - 1.0).abs() < 1e-9);
            assert_eq!(q[0], 0.0);
        }
        if kind == "velocity" {
            assert_eq!(v["vel_quat_dt"].as_f64().unwrap(), 0.9);
            // 0.5 rev/s about y: π rad/s.
            let w = v["angular_velocity"][1].as_f64().unwrap();
            assert!((w - std::f64::consts::PI).abs() < 1e-9, "{w}");
        }
        kinds.insert(kind);
    }
    assert!(kinds.contains("pose") && kinds.contains("velocity") && kinds.contains("acceleration"));
}

#[test]
fn list_and_ping_and_bad_config() {
    let server = start_server(
        "vrpn_Tracker_NULL Tracker0 1 10.0\nvrpn_Tracker_NULL Head 1 10.0\n",
        &[],
    );
    let (code, out, err) = run(PRINT, &["--list", &format!("127.0.0.1:{}", server.port)]);
    assert_eq!(code, 0, "{err}");
    let names: Vec<&str> = out.lines().collect();
    assert_eq!(names, vec!["Tracker0", "Head"]);
    // Over TCP the server's clock-sync answer (and its sender's description) usually arrives
    // before the list is printed: the clock-sync sender is no device.
    for _ in 0..3 {
        let (code, out, err) = run(
            PRINT,
            &["--list", &format!("tcp://127.0.0.1:{}", server.port)],
        );
        assert_eq!(code, 0, "{err}");
        assert_eq!(out.lines().collect::<Vec<_>>(), vec!["Tracker0", "Head"]);
    }
    let (code, out, err) = run(
        PING,
        &[&format!("Head@127.0.0.1:{}", server.port), "-n", "200"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.starts_with("200 pings to Head@") && out.contains("p50"),
        "{out}"
    );
    // A device the server does not have never answers.
    let (code, _, err) = run(
        PING,
        &[&format!("Nobody@127.0.0.1:{}", server.port), "-n", "1"],
    );
    assert_eq!(code, 1);
    assert!(err.contains("does Nobody exist"), "{err}");
    // A bad config line names file, line and problem, and the server does not start.
    let dir = std::env::temp_dir().join(format!("vrpn-badcfg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = dir.join("bad.cfg");
    std::fs::write(&cfg, "# comment\nvrpn_Tracker_NULL Tracker0 two 60.0\n").unwrap();
    let (code, _, err) = run(
        env!("CARGO_BIN_EXE_vrpn_server"),
        &["-f", cfg.to_str().unwrap(), "0"],
    );
    assert_eq!(code, 1);
    assert!(err.contains("bad.cfg:2:") && err.contains("two"), "{err}");
}

#[test]
fn quit_after_last_client_leaves() {
    let mut server = start_server("vrpn_Tracker_NULL Tracker0 1 100.0\n", &["-q"]);
    let (code, _, err) = run(
        PRINT,
        &[
            "--seconds",
            "0.5",
            &format!("Tracker0@127.0.0.1:{}", server.port),
        ],
    );
    assert_eq!(code, 0, "{err}");
    let start = Instant::now();
    loop {
        if let Some(status) = server.child.try_wait().unwrap() {
            assert!(status.success());
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "server did not quit"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A device name the server does not offer: one line naming the server's own port (not the
/// call-back connection's), on either path, and a non-zero exit well before `--seconds`.
#[test]
fn print_devices_reports_a_missing_device_once_and_fails() {
    let server = start_server("vrpn_Tracker_NULL Tracker0 1 60.0\n", &[]);
    for name in [
        format!("Nope@127.0.0.1:{}", server.port),
        format!("Nope@tcp://127.0.0.1:{}", server.port),
    ] {
        let start = Instant::now();
        let (code, _out, err) = run(PRINT, &["--seconds", "8", &name]);
        assert_eq!(code, 1, "{err}");
        assert!(
            start.elapsed() < Duration::from_secs(6),
            "took {:?}",
            start.elapsed()
        );
        let lines: Vec<&str> = err
            .lines()
            .filter(|l| l.contains("none is named"))
            .collect();
        assert_eq!(lines.len(), 1, "{err}");
        assert!(
            lines[0].contains(&format!("127.0.0.1:{} offers Tracker0;", server.port))
                && lines[0].contains("\"Nope\""),
            "{err}"
        );
    }
}
