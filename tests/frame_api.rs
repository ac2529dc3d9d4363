//! The client API a frame loop uses, on real sockets on 127.0.0.1: latest state that says
//! whether it is new (`seq`, `take_*`) and when it arrived, state changes across a server
//! restart, sending before the connection is up, the remote builder's limits, typed classes
//! of service, and the log errors a user matches.

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::button::ButtonState;
use vrpn::{
    AnalogRemote, AnalogServer, ButtonRemote, ButtonServer, Connection, ConnectionState,
    DialRemote, DialServer, Error, Limits, SenderFilter, ServiceClass, TimeVal, TrackerRemote,
    TrackerServer,
};

/// A server connection on an OS-chosen port of 127.0.0.1.
fn server() -> (Connection, u16) {
    let conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = conn.local_port().unwrap();
    (conn, port)
}

/// Runs both sides until `done` or `limit` (then fails naming `what`).
fn pump(conns: &[&Connection], limit: Duration, what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(start.elapsed() < limit, "timed out waiting for {what}");
        for c in conns {
            c.mainloop().unwrap();
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

fn run(conns: &[&Connection], d: Duration) {
    let start = Instant::now();
    while start.elapsed() < d {
        for c in conns {
            c.mainloop().unwrap();
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

fn connect(client: &Connection, srv: &Connection) {
    pump(
        &[client, srv],
        Duration::from_secs(5),
        "the connection",
        || client.connected() && srv.connected(),
    );
}

#[test]
fn tracker_latest_state_says_what_is_new_and_when_it_arrived() {
    let (srv, port) = server();
    let tracker = TrackerServer::new("Tracker0", &srv, 2).unwrap();
    let remote = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{port}")).unwrap();
    let client = remote.connection().clone();
    connect(&client, &srv);
    assert_eq!(remote.take_pose(1), None);

    // Three poses of sensor 1 arrive between two frames: the frame sees the newest, once.
    let stamps: Vec<TimeVal> = (0..3u64)
        .map(|i| {
            let t = srv.now().wall;
            let x = i as f64;
            tracker
                .report_pose(1usize, t, [x, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
                .unwrap();
            t
        })
        .collect();
    srv.mainloop().unwrap();
    pump(&[&client, &srv], Duration::from_secs(5), "3 poses", || {
        remote.pose_count(1) == 3
    });
    let p = remote.take_pose(1).expect("a new pose");
    assert_eq!((p.seq, p.sensor, p.pos.x), (3, 1, 2.0));
    assert_eq!(
        p.sender_time, stamps[2],
        "the sender's stamp is kept as sent"
    );
    let after = client.now().wall;
    assert!(p.arrival >= stamps[2] && p.arrival <= after, "{p:?}");
    // Nothing new: `take` says so, the latest value is still there.
    assert_eq!(remote.take_pose(1), None);
    assert_eq!(remote.pose(1).map(|p| p.seq), Some(3));
    assert_eq!(remote.take_pose(0), None);
    // The next report is new again.
    tracker
        .report_pose(
            1usize,
            srv.now().wall,
            [9.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        )
        .unwrap();
    srv.mainloop().unwrap();
    pump(&[&client, &srv], Duration::from_secs(5), "pose 4", || {
        remote.pose_count(1) == 4
    });
    assert_eq!(
        remote.take_pose(1).map(|p| (p.seq, p.pos.x)),
        Some((4, 9.0))
    );
    // A sensor outside the server's count is refused, whatever integer type names it.
    assert!(tracker
        .report_pose(2usize, TimeVal::ZERO, [0.0; 3], [0.0, 0.0, 0.0, 1.0])
        .is_err());
    assert!(tracker
        .report_pose(-1i32, TimeVal::ZERO, [0.0; 3], [0.0, 0.0, 0.0, 1.0])
        .is_err());
}

#[test]
fn one_mainloop_serves_every_remote_of_a_shared_connection() {
    let (srv, port) = server();
    let tracker = TrackerServer::new("Tracker0", &srv, 1).unwrap();
    let analog = AnalogServer::new("Analog0", &srv, 2);
    let mut analog = analog.unwrap();
    let t = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{port}")).unwrap();
    let a = AnalogRemote::new(&format!("Analog0@127.0.0.1:{port}")).unwrap();
    assert!(t.connection().same_as(a.connection()));
    connect(t.connection(), &srv);
    tracker
        .report_pose(
            0usize,
            srv.now().wall,
            [1.0, 2.0, 3.0],
            [0.0, 0.0, 0.0, 1.0],
        )
        .unwrap();
    analog.set_channel(1, 0.5);
    analog.report(None).unwrap();
    srv.mainloop().unwrap();
    // Only the tracker's mainloop is called: the analog remote is served too.
    let start = Instant::now();
    while t.pose(0).is_none() || !a.got_report() {
        assert!(start.elapsed() < Duration::from_secs(5), "not served");
        t.mainloop().unwrap();
        srv.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    let r = a.take_report().expect("a new analog report");
    assert_eq!((r.seq, r.channels()), (1, &[0.0, 0.5][..]));
    assert!(a.take_report().is_none());
    assert_eq!(a.latest().seq, 1);
}

#[test]
fn buttons_and_dials_keep_what_happened_between_frames() {
    let (srv, port) = server();
    let buttons = ButtonServer::new("Button0", &srv, 4).unwrap();
    let mut dials = DialServer::new("Dial0", &srv, 2).unwrap();
    let br = ButtonRemote::new(&format!("Button0@127.0.0.1:{port}")).unwrap();
    let dr = DialRemote::new(&format!("Dial0@127.0.0.1:{port}")).unwrap();
    let client = br.connection().clone();
    connect(&client, &srv);
    // A click (press and release) and a press of another button between two frames.
    for pressed in [true, false] {
        buttons.set_button(2, pressed);
        buttons.report_changes().unwrap();
    }
    buttons.set_button(3, true);
    buttons.report_changes().unwrap();
    dials.add_rotation(1, 0.25);
    dials.report_changes().unwrap();
    dials.add_rotation(1, 0.5);
    dials.report_changes().unwrap();
    srv.mainloop().unwrap();
    pump(
        &[&client, &srv],
        Duration::from_secs(5),
        "the reports",
        || br.last_change(3).is_some() && dr.last_update(1).map(|u| u.seq) == Some(2),
    );
    // The frame: button 2 is up now but was clicked; button 3 is down.
    assert_eq!(br.state(2), ButtonState::Released);
    assert_eq!(br.take_presses(2), 1);
    assert_eq!(br.take_presses(2), 0);
    assert!(br.pressed(3));
    let c = br.take_change(2).expect("button 2 changed");
    assert_eq!((c.seq, c.button, c.state), (2, 2, ButtonState::Released));
    assert_eq!(br.take_change(2), None);
    assert_eq!(br.take_change(0), None);
    // Both dial updates are summed for the frame, then nothing until the next one.
    assert_eq!(dr.take_rotation(1), 0.75);
    assert_eq!(dr.take_rotation(1), 0.0);
    assert_eq!(dr.take_rotation(0), 0.0);
    assert_eq!(dr.last_update(1).map(|u| u.change), Some(0.5));
}

#[test]
fn state_changes_follow_a_server_restart() {
    let (srv, port) = server();
    let limits = Limits {
        retry_interval: Duration::from_millis(100),
        ..Limits::default()
    };
    let remote = TrackerRemote::builder(&format!("Tracker0@127.0.0.1:{port}"))
        .limits(limits)
        .build()
        .unwrap();
    let client = remote.connection().clone();
    let seen = Rc::new(RefCell::new(Vec::new()));
    let s = seen.clone();
    client.on_state_change(move |st| s.borrow_mut().push(*st));
    assert_eq!(client.state(), ConnectionState::Connecting);
    connect(&client, &srv);
    drop(srv);
    pump(&[&client], Duration::from_secs(5), "the drop", || {
        client.state() == ConnectionState::Reconnecting
    });
    run(&[&client], Duration::from_millis(300));
    let again = Connection::server(Some(Ipv4Addr::LOCALHOST), port).unwrap();
    connect(&client, &again);
    assert_eq!(
        *seen.borrow(),
        [
            ConnectionState::Connected,
            ConnectionState::Reconnecting,
            ConnectionState::Connected
        ]
    );
}

#[test]
fn sending_before_the_connection_is_up_says_so() {
    let (srv, port) = server();
    let tracker = TrackerServer::new("Tracker0", &srv, 1).unwrap();
    let rates = Rc::new(RefCell::new(Vec::new()));
    let r = rates.clone();
    tracker.on_update_rate(move |hz| r.borrow_mut().push(hz));
    // A server with no client reports without error.
    tracker
        .report_pose(0usize, srv.now().wall, [0.0; 3], [0.0, 0.0, 0.0, 1.0])
        .unwrap();

    let remote = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{port}")).unwrap();
    match remote.set_update_rate(30.0) {
        Err(Error::NotConnected(ConnectionState::Connecting)) => {}
        other => panic!("expected NotConnected, got {other:?}"),
    }
    connect(remote.connection(), &srv);
    remote.set_update_rate(60.0).unwrap();
    pump(
        &[remote.connection(), &srv],
        Duration::from_secs(5),
        "the rate request",
        || !rates.borrow().is_empty(),
    );
    run(&[remote.connection(), &srv], Duration::from_millis(50));
    // Only the request sent once connected arrived: the early one was not queued.
    assert_eq!(*rates.borrow(), [60.0]);
}

#[test]
fn the_builder_gives_limits_to_the_connection() {
    let (srv, port) = server();
    let name = format!("Tracker0@127.0.0.1:{port}");
    let limits = Limits {
        retry_interval: Duration::from_millis(300),
        handshake_timeout: Duration::from_secs(2),
        ..Limits::default()
    };
    let first = TrackerRemote::builder(&name)
        .limits(limits)
        .build()
        .unwrap();
    assert_eq!(first.connection().limits(), limits);
    // Later devices at the location share that connection, with its limits.
    let shared = ButtonRemote::new(&format!("Button0@127.0.0.1:{port}")).unwrap();
    assert!(shared.connection().same_as(first.connection()));
    // Other limits cannot be given to a connection already in use: an error, not silence.
    let other = Limits {
        retry_interval: Duration::from_secs(2),
        ..Limits::default()
    };
    let refused = TrackerRemote::builder(&name).limits(other).build();
    assert!(matches!(refused, Err(Error::Unsupported(_))));
    // A private connection may have its own.
    let private = TrackerRemote::builder(&name)
        .limits(other)
        .private()
        .build()
        .unwrap();
    assert!(!private.connection().same_as(first.connection()));
    assert_eq!(private.connection().limits(), other);
    connect(first.connection(), &srv);
}

#[test]
fn typed_classes_of_service_are_taken_where_raw_masks_are() {
    let (srv, port) = server();
    let client = Connection::client("127.0.0.1", port, false, Limits::default()).unwrap();
    let ty = srv.register_type("app msg").unwrap();
    let from = srv.register_sender("app").unwrap();
    let cty = client.register_type("app msg").unwrap();
    let got = Rc::new(Cell::new(0));
    let g = got.clone();
    client.register_handler(cty, SenderFilter::Any, move |m| {
        assert_eq!(m.payload, b"x");
        g.set(g.get() + 1);
    });
    connect(&client, &srv);
    srv.pack_message(srv.now().wall, ty, from, b"x", ServiceClass::RELIABLE)
        .unwrap();
    srv.pack_message(
        srv.now().wall,
        ty,
        from,
        b"x",
        ServiceClass::LOW_LATENCY | ServiceClass::RELIABLE,
    )
    .unwrap();
    srv.pack_message(srv.now().wall, ty, from, b"x", vrpn::wire::class::RELIABLE)
        .unwrap();
    pump(
        &[&client, &srv],
        Duration::from_secs(5),
        "3 messages",
        || got.get() == 3,
    );
}

#[test]
fn log_errors_say_missing_or_damaged() {
    let dir = std::env::temp_dir().join(format!("vrpn-frame-api-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("missing.vrpn");
    match Connection::replay_file(missing.to_str().unwrap()) {
        Err(Error::LogNotFound { path }) => assert_eq!(path, missing),
        other => panic!("expected LogNotFound, got {other:?}"),
    }
    let damaged = dir.join("damaged.vrpn");
    std::fs::write(&damaged, b"this is not a VRPN log file at all, just text").unwrap();
    match Connection::replay_file(damaged.to_str().unwrap()) {
        Err(e @ Error::LogDamaged(_)) => {
            assert!(e.to_string().contains("damaged.vrpn"), "{e}")
        }
        other => panic!("expected LogDamaged, got {other:?}"),
    }
    // Through a device name as well.
    let r = TrackerRemote::new(&format!("Tracker0@file:{}", missing.display()));
    assert!(
        matches!(r, Err(Error::LogNotFound { .. })),
        "{r:?}",
        r = r.err()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_clock_sync_sender_is_not_offered_as_a_device() {
    let (srv, port) = server();
    let _tracker = TrackerServer::new("Tracker0", &srv, 1).unwrap();
    // A first client synchronises clocks: the server now has its clock-sync names, which
    // it describes to every later client along with its devices.
    let first = Connection::client("127.0.0.1", port, false, Limits::default()).unwrap();
    connect(&first, &srv);
    pump(
        &[&first, &srv],
        Duration::from_secs(5),
        "clock sync",
        || first.clock_estimate().is_some(),
    );
    let second = Connection::client("127.0.0.1", port, false, Limits::default()).unwrap();
    let offered = Rc::new(RefCell::new(Vec::new()));
    let o = offered.clone();
    second.on_peer_sender(move |name| o.borrow_mut().push(name.to_string()));
    pump(
        &[&first, &second, &srv],
        Duration::from_secs(5),
        "2nd",
        || second.connected(),
    );
    run(&[&first, &second, &srv], Duration::from_millis(300));
    // "VRPN Control" is the system sender every server (C++ too) describes.
    let devices = |names: Vec<String>| -> Vec<String> {
        names.into_iter().filter(|n| n != "VRPN Control").collect()
    };
    assert_eq!(devices(second.peer_senders()), ["Tracker0"]);
    assert_eq!(devices(offered.borrow().clone()), ["Tracker0"]);
}

/// The default printer (defect 4): a device's warning nobody registered for is one line on
/// stderr, nothing on stdout, and a later connection — which may reuse the memory of a
/// dropped one — still gets its warnings printed. Runs in a child process, whose output
/// this test reads.
#[test]
fn default_printer_is_one_stderr_line_per_warning_on_every_connection() {
    if std::env::var_os("VRPN_PRINTER_CHILD").is_some() {
        for round in ["first", "second", "third"] {
            let conn = Connection::new_loopback();
            let server = TrackerServer::new("Tracker0", &conn, 1).unwrap();
            let _remote = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
            server
                .send_text(vrpn::TextSeverity::Warning, 0, &format!("{round} warning"))
                .unwrap();
            conn.mainloop().unwrap();
        }
        return;
    }
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "default_printer_is_one_stderr_line_per_warning_on_every_connection",
            "--nocapture",
            "--test-threads=1",
        ])
        .env("VRPN_PRINTER_CHILD", "1")
        .output()
        .unwrap();
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stdout.contains("from Tracker0"),
        "printed to stdout: {stdout}"
    );
    for round in ["first", "second", "third"] {
        let lines: Vec<&str> = stderr
            .lines()
            .filter(|l| l.contains(&format!("{round} warning")))
            .collect();
        assert_eq!(lines.len(), 1, "{round}: {stderr}");
        assert!(lines[0].contains("from Tracker0"), "{}", lines[0]);
    }
}
