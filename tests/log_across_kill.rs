//! A logging client under a server process that is killed (SIGKILL) and restarted: the client
//! reconnects by itself, keeps logging into the same file, and the log holds every message the
//! client received.

mod common;

use std::cell::Cell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::log::{LogReader, NameTable};
use vrpn::{Connection, Limits, TrackerRemote};

#[test]
fn every_received_message_is_in_the_log_across_a_server_kill() {
    let dir = std::env::temp_dir().join(format!("vrpn-killlog-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("client.vrpn");
    let _ = std::fs::remove_file(&path);
    let path = path.to_str().unwrap().to_string();

    let cfg = "vrpn_Tracker_NULL Tracker0 2 200.0\n";
    let server = common::start_server(cfg, 0);
    let port = server.port;
    {
        let conn = Connection::client("127.0.0.1", port, true, Limits::default()).unwrap();
        conn.log_incoming(&path).unwrap();
        let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
        let received = Rc::new(Cell::new(0usize));
        let r = received.clone();
        tracker.on_pose(move |_| r.set(r.get() + 1));
        let pump = |until: &dyn Fn() -> bool, what: &str| {
            let start = Instant::now();
            while !until() {
                assert!(
                    start.elapsed() < Duration::from_secs(15),
                    "timed out: {what}"
                );
                tracker.mainloop().unwrap();
                let _ = conn.wait(Duration::from_millis(2));
            }
        };
        pump(&|| received.get() >= 100, "first reports");
        // SIGKILL: no goodbye from the server.
        drop(server);
        pump(&|| !conn.connected(), "noticing the kill");
        let mid = received.get();
        let server2 = common::start_server(cfg, port);
        pump(&|| received.get() >= mid + 100, "reports after the restart");
        drop(tracker);
        conn.close_logs().unwrap();
        drop(server2);

        let reader = LogReader::open(&path).unwrap();
        let mut names = NameTable::new();
        let mut logged = 0;
        let mut tracker_descriptions = 0;
        let mut entries = reader.entries();
        while let Some(e) = entries.next_entry() {
            let e = e.unwrap();
            if e.type_id() == -1 && e.payload.ends_with(b"Tracker0\0") {
                tracker_descriptions += 1;
            }
            let _ = names.observe(&e);
            if e.type_id() >= 0 && names.type_name(e.type_id()) == Some("vrpn_Tracker Pos_Quat") {
                logged += 1;
            }
        }
        assert_eq!(logged, received.get(), "poses in the log vs poses received");
        assert!(received.get() >= mid + 100);
        // Both sessions' descriptions are in the one file.
        assert_eq!(tracker_descriptions, 2);
    }
}
