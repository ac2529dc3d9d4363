//! The vrpn.cfg keywords of the auxiliary logger and the relay, through `vrpn_server` children
//! on 127.0.0.1.

mod common;

use std::cell::RefCell;
use std::process::{Command, Stdio};
use std::rc::Rc;
use std::time::{Duration, Instant};

use common::{start_server, start_server_with};
use vrpn::{AuxLoggerRemote, LogFiles, TrackerRemote};

fn temp_dir(tag: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("vrpn-keywords-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_relay_line_reserves_another_servers_tracker() {
    let inner = start_server("vrpn_Tracker_NULL Tracker0 2 200\n", 0);
    let relay = start_server(
        &format!("vrpn_Relay Tracker0@127.0.0.1:{} Head\n", inner.port),
        0,
    );
    let head = TrackerRemote::new(&format!("Head@127.0.0.1:{}", relay.port)).unwrap();
    let start = Instant::now();
    while head.pose_count(1) < 100 {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "no relayed poses"
        );
        head.mainloop().unwrap();
        let _ = head.connection().wait(Duration::from_millis(5));
    }
    // The real tracker answers the client's pings through the relay.
    let start = Instant::now();
    while head.ping_cycle().last_pong().is_none() {
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "no pong through the relay"
        );
        head.mainloop().unwrap();
        let _ = head.connection().wait(Duration::from_millis(5));
    }
}

#[test]
fn an_auxiliary_logger_line_logs_into_its_folder() {
    let dir = temp_dir("aux");
    // The logger logs the server itself: its port must be known before it starts.
    let port = {
        let probe = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        probe.local_addr().unwrap().port()
    };
    let cfg = format!(
        "vrpn_Tracker_NULL Tracker0 1 100\n\
         vrpn_Auxiliary_Logger_Server_Generic Logger0 Logger0@127.0.0.1:{port} {}\n",
        dir.display()
    );
    let server = start_server(&cfg, port);
    let logger = AuxLoggerRemote::new(&format!("Logger0@127.0.0.1:{}", server.port)).unwrap();
    let reports = Rc::new(RefCell::new(Vec::new()));
    let r = reports.clone();
    logger.on_report(move |rep| r.borrow_mut().push(rep.files.clone()));
    let pump_until = |what: &str, done: &dyn Fn() -> bool| {
        let start = Instant::now();
        while !done() {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "timed out: {what}"
            );
            logger.mainloop().unwrap();
            let _ = logger.connection().wait(Duration::from_millis(5));
        }
    };
    pump_until("connected", &|| logger.connection().connected());
    let files = LogFiles::new("in.vrpn", "", "", "");
    logger.request_logging(&files).unwrap();
    pump_until("report", &|| !reports.borrow().is_empty());
    assert_eq!(reports.borrow()[0], files);
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(500) {
        logger.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(5));
    }
    logger.stop_logging().unwrap();
    pump_until("stop report", &|| reports.borrow().len() >= 2);
    assert!(reports.borrow()[1].is_empty());
    let log = vrpn::log::LogReader::open(dir.join("in.vrpn")).unwrap();
    let entries = log.entries().count_whole();
    assert!(entries > 30, "{entries} entries in the logger's log");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_auxiliary_logger_needs_a_folder() {
    let dir = temp_dir("nofolder");
    let cfg = dir.join("vrpn.cfg");
    std::fs::write(
        &cfg,
        "vrpn_Tracker_NULL Tracker0 1 100\nvrpn_Auxiliary_Logger_Server_Generic Logger0 localhost\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_vrpn_server"))
        .args(["-f", cfg.to_str().unwrap(), "0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("vrpn.cfg:2") && err.contains("-logdir"),
        "{err}"
    );
    // With -logdir the same line starts.
    let server = start_server_with(
        "vrpn_Auxiliary_Logger_Server_Generic Logger0 localhost\n",
        0,
        &["-logdir", dir.to_str().unwrap()],
    );
    assert!(server.port > 0);
    let _ = std::fs::remove_dir_all(&dir);
}
