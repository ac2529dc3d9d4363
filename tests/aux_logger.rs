//! Auxiliary logger and remote logging over real sockets on 127.0.0.1: a client asks a server
//! to log a connection; the server writes only plain names inside its folder and refuses the
//! rest with a reply the client sees.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::ServerDevice;
use vrpn::log::{LogFolder, LogReader, NameTable};
use vrpn::{
    AuxLoggerRemote, AuxLoggerServer, Connection, LogFiles, LoggingReport, Now, TextReceiver,
    TrackerNull,
};

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vrpn-auxlog-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A server with a 100 Hz tracker and a logger that logs the server itself.
struct Rig {
    server: Connection,
    devices: Vec<Box<dyn ServerDevice>>,
    logger: Rc<RefCell<AuxLoggerServer>>,
    remote: AuxLoggerRemote,
    reports: Rc<RefCell<Vec<LoggingReport>>>,
    texts: Rc<RefCell<Vec<String>>>,
    _text: TextReceiver,
}

impl Rig {
    fn new(folder: &Path) -> Rig {
        let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let port = server.local_port().unwrap();
        let tracker = TrackerNull::new("Tracker0", &server, 1, 100.0).unwrap();
        let logger = AuxLoggerServer::new(
            "Logger0",
            &server,
            &format!("127.0.0.1:{port}"),
            LogFolder::new(folder).unwrap(),
        )
        .unwrap();
        let logger = Rc::new(RefCell::new(logger));
        let remote = AuxLoggerRemote::builder(&format!("Logger0@127.0.0.1:{port}"))
            .private()
            .build()
            .unwrap();
        let reports = Rc::new(RefCell::new(Vec::new()));
        let r = reports.clone();
        remote.on_report(move |rep| r.borrow_mut().push(rep.clone()));
        let text = TextReceiver::on_connection("Logger0", remote.connection()).unwrap();
        let texts = Rc::new(RefCell::new(Vec::new()));
        let t = texts.clone();
        text.on_message(move |m| t.borrow_mut().push(m.text().to_string()));
        Rig {
            server,
            devices: vec![Box::new(tracker)],
            logger,
            remote,
            reports,
            texts,
            _text: text,
        }
    }

    fn pass(&mut self) {
        let now = Now::read();
        for d in &mut self.devices {
            d.mainloop(now);
        }
        self.logger.borrow_mut().mainloop(now);
        self.server.mainloop().unwrap();
        self.remote.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(500));
    }

    fn run_until(&mut self, what: &str, mut done: impl FnMut(&Rig) -> bool) {
        let start = Instant::now();
        while !done(self) {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "timed out: {what}"
            );
            self.pass();
        }
    }

    fn run_for(&mut self, d: Duration) {
        let start = Instant::now();
        while start.elapsed() < d {
            self.pass();
        }
    }

    /// Sends a request and waits for the report it brings.
    fn request(&mut self, files: LogFiles) -> LoggingReport {
        self.run_until("connected", |r| r.remote.connection().connected());
        let before = self.reports.borrow().len();
        self.remote.request_logging(&files).unwrap();
        self.run_until("report", |r| r.reports.borrow().len() > before);
        self.reports.borrow().last().unwrap().clone()
    }
}

/// User messages in a log, by type name.
fn user_types(path: &Path) -> Vec<String> {
    let log = LogReader::open(path).unwrap();
    let mut names = NameTable::new();
    let mut types = Vec::new();
    let mut entries = log.entries();
    while let Some(e) = entries.next_entry() {
        let e = e.unwrap();
        names.observe(&e).ok();
        if !e.is_system() {
            types.push(
                names
                    .type_name(e.type_id())
                    .map(str::to_string)
                    .unwrap_or_default(),
            );
        }
    }
    types
}

#[test]
fn logs_start_and_stop_inside_the_folder() {
    let dir = temp_dir("startstop");
    let mut rig = Rig::new(&dir);
    let files = LogFiles::new("in.vrpn", "out.vrpn", "", "");
    let report = rig.request(files.clone());
    assert_eq!(report.files, files);
    assert_eq!(rig.logger.borrow().current(), files);
    rig.run_for(Duration::from_millis(500));
    // Status: the same names.
    let before = rig.reports.borrow().len();
    rig.remote.request_status().unwrap();
    rig.run_until("status", |r| r.reports.borrow().len() > before);
    assert_eq!(rig.reports.borrow().last().unwrap().files, files);
    // Stop: four empty names, and the logs are closed.
    let report = rig.request(LogFiles::default());
    assert!(report.files.is_empty());
    assert!(rig.logger.borrow().logging_connection().is_none());
    let poses = user_types(&dir.join("in.vrpn"))
        .iter()
        .filter(|t| *t == "vrpn_Tracker Pos_Quat")
        .count();
    assert!(poses >= 20, "{poses} poses in the incoming log");
    // The outgoing log holds the logging connection's own descriptions (and its pings).
    assert!(LogReader::open(dir.join("out.vrpn")).is_ok());
    assert!(rig.texts.borrow().is_empty(), "{:?}", rig.texts.borrow());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn paths_and_existing_files_are_refused_with_a_reply() {
    let dir = temp_dir("refuse");
    std::fs::write(dir.join("taken.vrpn"), b"keep me").unwrap();
    let mut rig = Rig::new(&dir);
    for (files, says) in [
        (LogFiles::new("../escape.vrpn", "", "", ""), "names folders"),
        (LogFiles::new("", "/tmp/abs.vrpn", "", ""), "absolute path"),
        (LogFiles::new("taken.vrpn", "", "", ""), "exists already"),
        (LogFiles::new("", "", "sub/x.vrpn", ""), "names folders"),
        // One good and one bad local name: nothing is created.
        (
            LogFiles::new("fine.vrpn", "..", "", ""),
            "not a usable file name",
        ),
    ] {
        let texts_before = rig.texts.borrow().len();
        let report = rig.request(files.clone());
        assert!(report.files.is_empty(), "{files:?} was accepted");
        rig.run_until("refusal text", |r| r.texts.borrow().len() > texts_before);
        let text = rig.texts.borrow().last().unwrap().clone();
        assert!(text.contains("refused") && text.contains(says), "{text}");
    }
    assert_eq!(std::fs::read(dir.join("taken.vrpn")).unwrap(), b"keep me");
    assert!(!dir.join("fine.vrpn").exists());
    assert!(!dir.parent().unwrap().join("escape.vrpn").exists());
    let mut left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    left.sort();
    assert_eq!(left, ["taken.vrpn"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn remote_logs_are_written_by_the_logged_server_in_its_folder() {
    let dir = temp_dir("remote");
    let server_dir = temp_dir("remote-server");
    let mut rig = Rig::new(&dir);
    rig.server
        .set_remote_log_folder(Some(LogFolder::new(&server_dir).unwrap()));
    let files = LogFiles::new("", "", "srv-in.vrpn", "srv-out.vrpn");
    assert_eq!(rig.request(files.clone()).files, files);
    rig.run_until("remote logs", |_| {
        server_dir.join("srv-out.vrpn").exists() && server_dir.join("srv-in.vrpn").exists()
    });
    rig.run_for(Duration::from_millis(400));
    rig.request(LogFiles::default());
    rig.run_for(Duration::from_millis(100));
    // The server's outgoing log for that client replays alone: descriptions, then poses.
    let out = user_types(&server_dir.join("srv-out.vrpn"));
    let poses = out.iter().filter(|t| *t == "vrpn_Tracker Pos_Quat").count();
    assert!(poses >= 10, "{poses} poses in {out:?}");
    // Nothing was written in the logger's own folder.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&server_dir);
}

#[test]
fn remote_logging_without_a_folder_is_refused_and_serving_goes_on() {
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server.local_port().unwrap();
    let mut tracker = TrackerNull::new("Tracker0", &server, 1, 200.0).unwrap();
    let notices = Rc::new(RefCell::new(Vec::new()));
    let n = notices.clone();
    server.on_notice(move |x| n.borrow_mut().push(x.text.clone()));
    let client = Connection::client("127.0.0.1", port, false, Default::default()).unwrap();
    client
        .request_remote_logging("/etc/should-not-exist.vrpn", "")
        .unwrap();
    let remote = vrpn::TrackerRemote::on_connection("Tracker0", &client).unwrap();
    let start = Instant::now();
    while remote.pose_count(0) < 20 {
        assert!(start.elapsed() < Duration::from_secs(10), "no poses");
        tracker.mainloop(Now::read());
        server.mainloop().unwrap();
        client.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(500));
    }
    assert!(
        notices.borrow().iter().any(|t| t.contains("refused")),
        "{:?}",
        notices.borrow()
    );
    assert!(!Path::new("/etc/should-not-exist.vrpn").exists());
}

#[test]
fn a_refused_remote_log_closes_the_connection() {
    let server_dir = temp_dir("drop");
    std::fs::write(server_dir.join("exists.vrpn"), b"x").unwrap();
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    server.set_remote_log_folder(Some(LogFolder::new(&server_dir).unwrap()));
    let port = server.local_port().unwrap();
    let notices = Rc::new(RefCell::new(Vec::new()));
    let n = notices.clone();
    server.on_notice(move |x| n.borrow_mut().push(x.text.clone()));
    let client = Connection::client("127.0.0.1", port, false, Default::default()).unwrap();
    client.on_notice(|_| {});
    client.request_remote_logging("exists.vrpn", "").unwrap();
    let dropped = Rc::new(std::cell::Cell::new(false));
    let d = dropped.clone();
    client.on_state_change(move |s| {
        if *s == vrpn::ConnectionState::Reconnecting {
            d.set(true)
        }
    });
    let start = Instant::now();
    while !dropped.get() {
        assert!(start.elapsed() < Duration::from_secs(10), "not dropped");
        server.mainloop().unwrap();
        client.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(500));
    }
    assert!(
        notices
            .borrow()
            .iter()
            .any(|t| t.contains("exists already")),
        "{:?}",
        notices.borrow()
    );
    // The reconnect does not ask again, and is served.
    let start = Instant::now();
    while !client.connected() {
        assert!(start.elapsed() < Duration::from_secs(10), "no reconnect");
        server.mainloop().unwrap();
        client.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(500));
    }
    assert_eq!(std::fs::read(server_dir.join("exists.vrpn")).unwrap(), b"x");
    let _ = std::fs::remove_dir_all(&server_dir);
}
