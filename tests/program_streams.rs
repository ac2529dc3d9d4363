//! What the programs say and where: data on stdout, diagnostics on stderr, once
//! (`vrpn_server -v` shows its devices' texts; `vrpn_print_devices` prints device texts of
//! every severity with the reports, in text and JSON); clear messages for log files that
//! cannot be created or read; `vrpn_ping` gives up on a missing server; `--until-eof`.

use std::io::{BufRead, BufReader, Read};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use vrpn::{Connection, TextSender, TextSeverity, TrackerServer};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const PRINT: &str = env!("CARGO_BIN_EXE_vrpn_print_devices");
const PING: &str = env!("CARGO_BIN_EXE_vrpn_ping");
const LOG: &str = env!("CARGO_BIN_EXE_vrpn_log");

/// A scratch folder, removed on drop.
struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("vrpn-streams-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    fn path(&self, name: &str) -> String {
        self.0.join(name).to_str().unwrap().to_owned()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `bin args` to its end; returns exit code, stdout, stderr.
fn run(bin: &str, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(bin).args(args).output().unwrap();
    (
        out.status.code().expect("an exit code, not a signal"),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// Collects a pipe in a thread.
fn collect(mut pipe: impl Read + Send + 'static) -> Arc<Mutex<String>> {
    let text = Arc::new(Mutex::new(String::new()));
    let t = text.clone();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = pipe.read(&mut buf) {
            if n == 0 {
                break;
            }
            t.lock()
                .unwrap()
                .push_str(&String::from_utf8_lossy(&buf[..n]));
        }
    });
    text
}

#[test]
fn server_verbose_shows_device_texts_on_stderr_and_stdout_keeps_the_port_line() {
    let dir = Scratch::new("verbose");
    let cfg = dir.path("vrpn.cfg");
    std::fs::write(
        &cfg,
        "vrpn_Text_Example Text0 0.1 hello from the server\nvrpn_Tracker_NULL Tracker0 1 10\n",
    )
    .unwrap();
    let mut child = Command::new(SERVER)
        .args(["-v", "-f", &cfg, "0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    out.read_line(&mut first).unwrap();
    let stdout = collect(out);
    let stderr = collect(child.stderr.take().unwrap());
    let wanted = "vrpn_server: message from Text0 (level 0): hello from the server";
    let end = Instant::now() + Duration::from_secs(10);
    while Instant::now() < end && stderr.lock().unwrap().matches(wanted).count() < 2 {
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    std::thread::sleep(Duration::from_millis(50));
    let err = stderr.lock().unwrap().clone();
    assert!(
        first.starts_with("vrpn_server: serving 2 device(s)"),
        "{first}"
    );
    assert!(err.matches(wanted).count() >= 2, "{err}");
    assert!(
        err.contains("vrpn_server: opening vrpn_Text_Example: Text0"),
        "{err}"
    );
    assert_eq!(
        stdout.lock().unwrap().as_str(),
        "",
        "stdout after the port line"
    );
}

/// A serial port that cannot be opened is told on stderr exactly once, with or without `-v`
/// (under `-v` by the device's own text, otherwise by the status line), though the device
/// retries every second.
#[test]
fn server_reports_a_missing_serial_port_once_with_and_without_verbose() {
    let dir = Scratch::new("missing-port");
    let cfg = dir.path("vrpn.cfg");
    let port = dir.path("no-such-tty");
    std::fs::write(
        &cfg,
        format!("vrpn_Tracker_Fastrak Fastrak0 {port} 19200\n"),
    )
    .unwrap();
    for verbose in [false, true] {
        let mut args = vec!["-f", cfg.as_str(), "0"];
        if verbose {
            args.insert(0, "-v");
        }
        let mut child = Command::new(SERVER)
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut out = BufReader::new(child.stdout.take().unwrap());
        let mut first = String::new();
        out.read_line(&mut first).unwrap();
        let stderr = collect(child.stderr.take().unwrap());
        // Long enough for two more attempts to open the port.
        let end = Instant::now() + Duration::from_millis(2500);
        while Instant::now() < end {
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = child.kill();
        let _ = child.wait();
        std::thread::sleep(Duration::from_millis(50));
        let err = stderr.lock().unwrap().clone();
        let told: Vec<&str> = err.lines().filter(|l| l.contains(&port)).collect();
        assert_eq!(told.len(), 1, "-v {verbose}: {err}");
        assert!(told[0].contains("no such file"), "{err}");
    }
}

/// A server in this process: a tracker and a text sender that warns, both named `Dev0`.
struct Warner {
    conn: Connection,
    tracker: TrackerServer,
    text: TextSender,
}

impl Warner {
    fn new() -> Warner {
        let conn = Connection::server(Some([127, 0, 0, 1].into()), 0).unwrap();
        Warner {
            tracker: TrackerServer::new("Dev0", &conn, 1).unwrap(),
            text: TextSender::new("Dev0", &conn).unwrap(),
            conn,
        }
    }

    /// Serves until `child` exits (at most 20 s), sending a pose and a warning every 50 ms.
    fn serve(&self, child: &mut std::process::Child) {
        let end = Instant::now() + Duration::from_secs(20);
        let mut next = Instant::now();
        while child.try_wait().unwrap().is_none() && Instant::now() < end {
            if self.conn.connected() && Instant::now() >= next {
                let now = self.conn.now().wall;
                let _ =
                    self.tracker
                        .report_pose(0usize, now, [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]);
                let _ = self
                    .text
                    .send_message("careful now", TextSeverity::Warning, 2, None);
                next += Duration::from_millis(50);
            }
            self.conn.mainloop().unwrap();
            let _ = self.conn.wait(Duration::from_millis(5));
        }
    }
}

#[test]
fn print_devices_puts_device_texts_with_the_reports_and_notices_on_stderr_once() {
    for json in [false, true] {
        let server = Warner::new();
        let port = server.conn.local_port().unwrap();
        let dev = format!("Dev0@127.0.0.1:{port}");
        let missing = format!("Nope@127.0.0.1:{port}");
        let mut args = vec!["--seconds", "2.5", dev.as_str(), missing.as_str()];
        if json {
            args.insert(0, "--json");
        }
        let mut child = Command::new(PRINT)
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stdout = collect(child.stdout.take().unwrap());
        let stderr = collect(child.stderr.take().unwrap());
        server.serve(&mut child);
        // A device name the server does not offer makes the run fail (after printing the
        // others for the whole time asked).
        assert_eq!(child.wait().unwrap().code(), Some(1));
        std::thread::sleep(Duration::from_millis(50));
        let (out, err) = (
            stdout.lock().unwrap().clone(),
            stderr.lock().unwrap().clone(),
        );
        // The device's warnings are data: on stdout, with the poses, and nowhere else.
        assert!(!err.contains("careful now"), "json={json} stderr:\n{err}");
        if json {
            let texts: Vec<serde_json::Value> = out
                .lines()
                .map(|l| serde_json::from_str(l).unwrap())
                .filter(|r: &serde_json::Value| r["kind"] == "text")
                .collect();
            assert!(texts.len() >= 3, "{out}");
            assert_eq!(texts[0]["severity"], "warning");
            assert_eq!(texts[0]["text"], "careful now");
            assert_eq!(texts[0]["level"], 2);
        } else {
            let line = format!("{dev}: Warning: careful now");
            assert!(out.matches(&line).count() >= 3, "{out}");
            assert!(out.contains("pos ( 1.00,  2.00,  3.00)"), "{out}");
        }
        // Diagnostics (here: the device the server does not have) only on stderr, each
        // line prefixed with the program's name.
        assert!(err.contains("Nope"), "json={json} stderr:\n{err}");
        for line in err.lines() {
            let text = line
                .strip_prefix("vrpn_print_devices: ")
                .unwrap_or_else(|| panic!("{line:?}"));
            assert!(
                !out.contains(text),
                "json={json}: {text:?} on stdout too:\n{out}"
            );
        }
    }
}

#[test]
fn log_files_that_cannot_be_written_or_read_say_why() {
    let dir = Scratch::new("logs");
    let existing = dir.path("existing.vrpn");
    std::fs::write(&existing, b"precious").unwrap();
    let (code, _, err) = run(PRINT, &["--log", &existing, "T@127.0.0.1:9"]);
    assert_eq!(code, 2);
    assert_eq!(
        err.trim_end(),
        format!(
            "vrpn_print_devices: --log: cannot create log file {existing}: it exists already (a \
             log is never overwritten: choose another name or move the old file away)"
        )
    );
    assert_eq!(std::fs::read(&existing).unwrap(), b"precious");

    let (code, _, err) = run(
        PRINT,
        &["--log", "/nonexistent-dir/x.vrpn", "T@127.0.0.1:9"],
    );
    assert_eq!(code, 2);
    assert_eq!(
        err.trim_end(),
        "vrpn_print_devices: --log: cannot create log file /nonexistent-dir/x.vrpn: folder \
         /nonexistent-dir does not exist"
    );

    let cfg = dir.path("vrpn.cfg");
    std::fs::write(&cfg, "vrpn_Tracker_NULL Tracker0 1 10\n").unwrap();
    let (code, _, err) = run(SERVER, &["-f", &cfg, "-lo", &existing, "0"]);
    assert_eq!(code, 1);
    assert!(
        err.contains(&format!(
            "vrpn_server: -lo: cannot create log file {existing}: it exists already"
        )),
        "{err}"
    );

    let (code, out, err) = run(LOG, &["summary", "/nonexistent.vrpn"]);
    assert_eq!((code, out.as_str()), (1, ""));
    assert_eq!(
        err.trim_end(),
        "vrpn_log: cannot read log file /nonexistent.vrpn: no such file"
    );
    let (code, _, err) = run(PRINT, &["--seconds", "0.1", "T@file:/nonexistent.vrpn"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("cannot read log file /nonexistent.vrpn: no such file"),
        "{err}"
    );
}

#[test]
fn ping_gives_up_on_a_missing_server_after_2_s() {
    // A port nothing listens on: bound and closed again.
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let name = format!("Tracker0@127.0.0.1:{port}");
    let start = Instant::now();
    let (code, out, err) = run(PING, &["-n", "3", &name]);
    let took = start.elapsed();
    assert_eq!((code, out.as_str()), (1, ""), "{err}");
    assert!(
        err.starts_with(&format!("vrpn_ping: no connection to {name} within 2 s (")),
        "{err}"
    );
    assert!(err.contains("is a VRPN server running there?"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    // Gave up after the 2 s bound (the old program waited 10 s).
    assert!(
        took >= Duration::from_millis(1900) && took < Duration::from_secs(8),
        "{took:?}"
    );
}

#[test]
fn print_devices_until_eof_ends_with_the_replayed_file() {
    let dir = Scratch::new("eof");
    let log = dir.path("session.vrpn");
    {
        let conn = Connection::server(Some([127, 0, 0, 1].into()), 0).unwrap();
        conn.log_outgoing(&log).unwrap();
        let tracker = TrackerServer::new("Tracker0", &conn, 1).unwrap();
        let t0 = conn.now().wall;
        for i in 0..20u32 {
            let t = t0.plus(Duration::from_millis(25 * u64::from(i)));
            tracker
                .report_pose(0usize, t, [f64::from(i), 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
                .unwrap();
        }
        conn.close_logs().unwrap();
    }
    let name = format!("Tracker0@file:{log}");
    let start = Instant::now();
    let (code, out, err) = run(PRINT, &["--json", "--until-eof", &name]);
    assert_eq!(code, 0, "{err}");
    assert!(start.elapsed() < Duration::from_secs(10));
    let xs: Vec<f64> = out
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|r| r["kind"] == "pose")
        .map(|r| r["pos"][0].as_f64().unwrap())
        .collect();
    assert_eq!(xs, (0..20).map(f64::from).collect::<Vec<_>>(), "{out}");

    let (code, _, err) = run(PRINT, &["--until-eof", "Tracker0@127.0.0.1:9"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--until-eof needs DEVICE@file:FILE names"),
        "{err}"
    );
}
