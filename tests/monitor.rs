//! vrpn_monitor end to end: a vrpn_server child serving a moving tracker, buttons, analogs,
//! dials and texts; a vrpn_monitor child watching them; the page read over HTTP, its event
//! stream timed, and the page loaded in headless Chromium (driven over its DevTools pipe),
//! whose DOM must name every device and change between two dumps. The browser test saves
//! `target/monitor-screenshot.png` (docs/monitor.png is such a screenshot).
//!
//! Without a `chromium` on the PATH the browser test is skipped with a note, unless
//! `VRPN_REQUIRE_BROWSER=1` (set by .ci/run, which installs Chromium) makes that a failure.

mod common;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use serde_json::{json, Value};

/// Devices whose values keep changing: a tracker flown by the analog's sine waves (so its
/// position moves), buttons, analog channels, dials and a text message every second.
const CFG: &str = "\
vrpn_Analog_Example\tAnalog0\t4\t60.0
vrpn_Button_Example\tButton0\t4\t2.0
vrpn_Dial_Example\tDial0\t2\t0.5\t10.0
vrpn_Text_Example\tText0\t1.0\tcalibration ok
vrpn_Tracker_Spin\tSpin0\t2\t60.0\t0.0\t0.0\t1.0\t0.25
vrpn_Tracker_AnalogFly\tFlyer0\t60.0\tabsolute
X\t*Analog0\t0\t0.0\t0.0\t0.5\t1.0
Y\t*Analog0\t1\t0.0\t0.0\t0.3\t1.0
Z\t*Analog0\t2\t0.0\t0.0\t0.1\t1.0
RX\tNULL\t0\t0.0\t0.0\t1.0\t1.0
RY\tNULL\t0\t0.0\t0.0\t1.0\t1.0
RZ\t*Analog0\t3\t0.0\t0.0\t-0.25\t1.0
RESET\tNULL\t0
CLUTCH\tNULL\t0

";

const DEVICES: [&str; 6] = ["Flyer0", "Spin0", "Button0", "Analog0", "Dial0", "Text0"];

/// A vrpn_monitor child (killed by its PID on drop) and the address it serves.
struct Monitor {
    child: Child,
    addr: String,
}

impl Drop for Monitor {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start_monitor(args: &[String]) -> Monitor {
    let mut child = Command::new(env!("CARGO_BIN_EXE_vrpn_monitor"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let addr = line
        .split("http://")
        .nth(1)
        .and_then(|s| s.split('/').next())
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .to_string();
    Monitor { child, addr }
}

fn monitor_for(server: &common::Server) -> Monitor {
    let mut args = vec!["--http".to_string(), "127.0.0.1:0".to_string()];
    args.extend(
        DEVICES
            .iter()
            .map(|d| format!("{d}@127.0.0.1:{}", server.port)),
    );
    start_monitor(&args)
}

/// A plain HTTP/1.0 GET: (status line, body).
fn get(addr: &str, path: &str) -> (String, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(s, "GET {path} HTTP/1.0\r\nHost: {addr}\r\n\r\n").unwrap();
    let mut all = String::new();
    s.read_to_string(&mut all).unwrap();
    let (head, body) = all.split_once("\r\n\r\n").unwrap_or((&all, ""));
    (
        head.lines().next().unwrap_or("").to_string(),
        body.to_string(),
    )
}

/// The monitor's snapshot once every device has reported something.
fn settled_state(addr: &str) -> Value {
    let start = Instant::now();
    loop {
        let (_, body) = get(addr, "/state.json");
        if let Ok(v) = serde_json::from_str::<Value>(&body) {
            let ready = v["devices"].as_array().is_some_and(|ds| {
                ds.len() == DEVICES.len()
                    && ds.iter().all(|d| {
                        d["state"] == "connected"
                            && (!d["sensors"].as_array().unwrap().is_empty()
                                || !d["buttons"].is_null()
                                || !d["analog"].is_null()
                                || !d["dials"].is_null()
                                || !d["texts"].as_array().unwrap().is_empty())
                    })
            });
            if ready {
                return v;
            }
        }
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "devices never all reported: {body}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn snapshot_has_every_kind_of_report_and_the_stream_runs_at_30_per_second() {
    let server = common::start_server(CFG, 0);
    let mon = monitor_for(&server);
    settled_state(&mon.addr);
    // A second snapshot a while later: rates are measured over half-second windows.
    std::thread::sleep(Duration::from_millis(1500));
    let state: Value = serde_json::from_str(&get(&mon.addr, "/state.json").1).unwrap();
    let dev = |name: &str| {
        state["devices"]
            .as_array()
            .unwrap()
            .iter()
            .find(|d| d["name"] == name)
            .unwrap_or_else(|| panic!("{name} missing"))
            .clone()
    };
    let flyer = dev("Flyer0");
    let s0 = &flyer["sensors"][0];
    assert_eq!(s0["quat"].as_array().unwrap().len(), 4);
    // 60 Hz at the server; a loaded machine may lag.
    assert!(s0["rate"].as_f64().unwrap() > 20.0, "rate {s0}");
    // Our server takes part in clock synchronisation, so latency is known.
    assert!(
        s0["latency"].is_f64(),
        "no latency with synchronised clocks: {s0}"
    );
    assert_eq!(dev("Spin0")["sensors"].as_array().unwrap().len(), 2);
    assert_eq!(
        dev("Analog0")["analog"]["channels"]
            .as_array()
            .unwrap()
            .len(),
        4
    );
    assert_eq!(dev("Dial0")["dials"]["totals"].as_array().unwrap().len(), 2);
    assert!(
        dev("Button0")["buttons"]["states"]
            .as_array()
            .unwrap()
            .len()
            == 4
    );
    assert_eq!(dev("Text0")["texts"][0]["text"], "calibration ok");

    let (status, page) = get(&mon.addr, "/");
    assert!(status.contains("200"), "{status}");
    assert!(page.contains("<script src=\"/monitor.js\">"));
    let (status, script) = get(&mon.addr, "/monitor.js");
    assert!(
        status.contains("200") && script.contains("EventSource"),
        "{status}"
    );
    assert!(get(&mon.addr, "/nothing").0.contains("404"));

    // The event stream: count snapshots over 2 s.
    let mut s = TcpStream::connect(&mon.addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(s, "GET /events HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
    let mut r = BufReader::new(s);
    let start = Instant::now();
    let mut events = 0;
    let mut line = String::new();
    while start.elapsed() < Duration::from_secs(2) {
        line.clear();
        if r.read_line(&mut line).unwrap() == 0 {
            break;
        }
        if line.starts_with("data: {") {
            events += 1;
        }
    }
    let rate = events as f64 / start.elapsed().as_secs_f64();
    assert!(rate >= 20.0, "{events} snapshots in 2 s ({rate:.1}/s)");
}

#[test]
fn list_monitors_every_device_the_server_announces() {
    let server = common::start_server(CFG, 0);
    let mon = start_monitor(&[
        "--http".into(),
        "127.0.0.1:0".into(),
        "--list".into(),
        format!("127.0.0.1:{}", server.port),
    ]);
    settled_state(&mon.addr);
}

#[test]
fn another_interface_needs_allow_remote() {
    let out = Command::new(env!("CARGO_BIN_EXE_vrpn_monitor"))
        .args(["--http", "0.0.0.0:0", "T@127.0.0.1:9"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--allow-remote") && err.contains("no authentication"),
        "{err}"
    );
}

// ------------------------------------------------------------------ the browser

/// Headless Chromium driven over `--remote-debugging-pipe` (JSON messages ended by NUL on
/// descriptors 3 and 4): no WebSocket client needed.
struct Browser {
    child: Child,
    to: std::fs::File,
    from: mpsc::Receiver<Value>,
    next_id: u64,
    _profile: std::path::PathBuf,
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self._profile);
    }
}

impl Browser {
    fn start(exe: &str) -> Browser {
        use std::os::fd::{AsRawFd, OwnedFd};
        use std::os::unix::process::CommandExt;
        let (their_in, our_out): (OwnedFd, OwnedFd) = nix::unistd::pipe()
            .map(|(r, w)| unsafe {
                use std::os::fd::FromRawFd;
                (OwnedFd::from_raw_fd(r), OwnedFd::from_raw_fd(w))
            })
            .unwrap();
        let (our_in, their_out): (OwnedFd, OwnedFd) = nix::unistd::pipe()
            .map(|(r, w)| unsafe {
                use std::os::fd::FromRawFd;
                (OwnedFd::from_raw_fd(r), OwnedFd::from_raw_fd(w))
            })
            .unwrap();
        let profile = std::env::temp_dir().join(format!("vrpn-chromium-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&profile);
        let (a, b) = (their_in.as_raw_fd(), their_out.as_raw_fd());
        let mut cmd = Command::new(exe);
        cmd.args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--remote-debugging-pipe",
            "--window-size=1280,1400",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg("about:blank")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null());
        // SAFETY: only dup2 between fork and exec (async-signal-safe); the new descriptors
        // 3 and 4 are not close-on-exec.
        unsafe {
            cmd.pre_exec(move || {
                nix::unistd::dup2(a, 3).map_err(std::io::Error::from)?;
                nix::unistd::dup2(b, 4).map_err(std::io::Error::from)?;
                Ok(())
            });
        }
        let child = cmd.spawn().expect("starting chromium");
        drop((their_in, their_out));
        let (tx, rx) = mpsc::channel();
        let mut reader = BufReader::new(std::fs::File::from(our_in));
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            while let Ok(n) = reader.read_until(0, &mut buf) {
                if n == 0 {
                    break;
                }
                buf.pop();
                if let Ok(v) = serde_json::from_slice::<Value>(&buf) {
                    if tx.send(v).is_err() {
                        break;
                    }
                }
                buf.clear();
            }
        });
        Browser {
            child,
            to: std::fs::File::from(our_out),
            from: rx,
            next_id: 0,
            _profile: profile,
        }
    }

    /// Sends a DevTools command (to a page when `session` is set) and waits for its result.
    fn call(&mut self, session: Option<&str>, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if let Some(s) = session {
            msg["sessionId"] = json!(s);
        }
        let mut bytes = serde_json::to_vec(&msg).unwrap();
        bytes.push(0);
        self.to.write_all(&bytes).unwrap();
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let v = self
                .from
                .recv_timeout(left)
                .unwrap_or_else(|_| panic!("chromium did not answer {method}"));
            if v["id"] == id {
                assert!(v["error"].is_null(), "{method}: {}", v["error"]);
                return v["result"].clone();
            }
        }
    }
}

fn base64_decode(text: &str) -> Vec<u8> {
    const ABC: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = Vec::with_capacity(text.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0);
    for c in text.bytes() {
        let Some(v) = ABC.iter().position(|&a| a == c) else {
            continue; // padding and line breaks
        };
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    out
}

fn find_chromium() -> Option<String> {
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|n| std::env::split_paths(&path).map(move |d| d.join(n)))
        .find(|p| p.is_file())
        .map(|p| p.display().to_string())
}

/// The page's text: its DOM as HTML.
fn dom(b: &mut Browser, session: &str) -> String {
    let r = b.call(
        Some(session),
        "Runtime.evaluate",
        json!({"expression": "document.documentElement.outerHTML", "returnByValue": true}),
    );
    r["result"]["value"]
        .as_str()
        .unwrap_or_default()
        .to_string()
}

/// The text of every cell of sensor rows, analog values and dial values in the DOM.
fn values(html: &str) -> Vec<String> {
    html.split("<td class=\"v ")
        .skip(1)
        .chain(html.split("class=\"val\">").skip(1))
        .map(|s| s.split('<').next().unwrap_or("").to_string())
        .collect()
}

#[test]
fn a_real_browser_shows_every_device_and_live_values() {
    let Some(exe) = find_chromium() else {
        assert!(
            std::env::var_os("VRPN_REQUIRE_BROWSER").is_none(),
            "VRPN_REQUIRE_BROWSER is set but no chromium is on the PATH"
        );
        eprintln!("note: no chromium on the PATH: browser test skipped");
        return;
    };
    let server = common::start_server(CFG, 0);
    let mon = monitor_for(&server);
    settled_state(&mon.addr);
    let mut b = Browser::start(&exe);
    let target = b.call(
        None,
        "Target.createTarget",
        json!({"url": format!("http://{}/", mon.addr)}),
    );
    let attached = b.call(
        None,
        "Target.attachToTarget",
        json!({"targetId": target["targetId"], "flatten": true}),
    );
    let session = attached["sessionId"].as_str().unwrap().to_string();
    // Let the page receive snapshots and fill in every device.
    let start = Instant::now();
    let first = loop {
        let html = dom(&mut b, &session);
        if DEVICES
            .iter()
            .all(|d| html.contains(&format!("id=\"dev-{d}\"")))
            && html.contains("class=\"v qw\">")
            && html.contains("calibration ok")
            && html.contains("key on")
        {
            break html;
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "the page never showed every device: {html}"
        );
        std::thread::sleep(Duration::from_millis(200));
    };
    for d in DEVICES {
        assert!(first.contains(&format!(">{d}</span>")), "{d} not named");
    }
    assert!(first.contains(">connected</span>"));
    std::thread::sleep(Duration::from_millis(1500));
    let second = dom(&mut b, &session);
    let (a, z) = (values(&first), values(&second));
    assert!(a.len() >= 20, "few values in the DOM: {a:?}");
    let changed = a.iter().zip(&z).filter(|(x, y)| x != y).count();
    assert!(
        changed >= a.len() / 3,
        "values did not change between dumps: {a:?} vs {z:?}"
    );

    // Two more seconds of trail, then the screenshot the docs show.
    std::thread::sleep(Duration::from_millis(2000));
    let shot = b.call(
        Some(&session),
        "Page.captureScreenshot",
        json!({"format": "png"}),
    );
    let png = base64_decode(shot["data"].as_str().unwrap());
    assert_eq!(&png[1..4], b"PNG");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("monitor-screenshot.png"), &png).unwrap();
    std::fs::write(dir.join("monitor-dom.html"), second).unwrap();
    let _ = b.call(None, "Browser.close", json!({}));
}
