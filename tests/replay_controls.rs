//! Log replay controls beyond rate and reset: absolute file times, bookmarks, a cap on what a
//! pass plays, and `vrpn_File_Controller` messages, locally and through a relay over
//! 127.0.0.1.

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::connection::FileController;
use vrpn::devices::base::{PING_MESSAGE, PONG_MESSAGE};
use vrpn::devices::ServerDevice;
use vrpn::forward::Relay;
use vrpn::log::LogWriter;
use vrpn::wire::payload::tracker::{PosQuat, POS_QUAT};
use vrpn::wire::{class, system, Cookie};
use vrpn::{Connection, Now, SenderFilter, TimeVal, TrackerRemote};

/// The first pose's time in the log.
const T0: TimeVal = TimeVal {
    sec: 1_700_000_000,
    usec: 0,
};

/// A log of Tracker0: `n` poses 10 ms apart, pose `k` at x = k.
fn write_log(tag: &str, n: usize) -> PathBuf {
    let path =
        std::env::temp_dir().join(format!("vrpn-replayctl-{tag}-{}.vrpn", std::process::id()));
    let _ = std::fs::remove_file(&path);
    let mut w = LogWriter::create(&path, &Cookie::ours(0).to_bytes()).unwrap();
    let mut buf = [0u8; 128];
    let k = system::encode_description(&mut buf, "Tracker0");
    w.log_message(system::SENDER_DESCRIPTION, 0, T0, &buf[..k])
        .unwrap();
    let k = system::encode_description(&mut buf, POS_QUAT);
    w.log_message(system::TYPE_DESCRIPTION, 0, T0, &buf[..k])
        .unwrap();
    for i in 0..n {
        let t = T0.plus_secs(i as f64 * 0.01);
        let p = PosQuat::new(0, [i as f64, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]);
        let len = p.encode(&mut buf);
        w.log_message(0, 0, t, &buf[..len]).unwrap();
    }
    w.finish().unwrap();
    path
}

/// A replay of `path` and a tracker remote on it that records each pose's x.
fn replay(path: &Path) -> (Connection, TrackerRemote, Rc<RefCell<Vec<f64>>>) {
    let conn = Connection::replay_file(path.to_str().unwrap()).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let xs = Rc::new(RefCell::new(Vec::new()));
    let x = xs.clone();
    tracker.on_pose(move |p| x.borrow_mut().push(p.pos.x));
    conn.mainloop().unwrap(); // descriptions
    (conn, tracker, xs)
}

#[test]
fn play_and_jump_to_absolute_file_times() {
    let path = write_log("abs", 100);
    let (conn, _t, xs) = replay(&path);
    let r = conn.replay().unwrap();
    r.play_to_filetime(T0.plus_secs(0.095));
    assert_eq!(*xs.borrow(), (0..10).map(f64::from).collect::<Vec<_>>());
    assert_eq!(r.file_time(), T0.plus_secs(0.095));
    // Jumping delivers nothing; playing on starts after the jump.
    assert!(r.jump_to_filetime(T0.plus_secs(0.5)));
    assert_eq!(xs.borrow().len(), 10);
    r.play_to_filetime(T0.plus_secs(0.52));
    assert_eq!(&xs.borrow()[10..], &[51.0, 52.0]);
    // Backwards: rewinds, and the same absolute time plays the same poses again.
    xs.borrow_mut().clear();
    r.play_to_filetime(T0.plus_secs(0.02));
    assert_eq!(*xs.borrow(), vec![0.0, 1.0, 2.0]);
    // Past the end: false, and at the end.
    assert!(!r.jump_to_filetime(T0.plus_secs(5.0)));
    let _ = std::fs::remove_file(&path);
}

#[test]
fn bookmarks_come_back_to_the_same_message() {
    let path = write_log("bookmark", 50);
    let (conn, _t, xs) = replay(&path);
    let r = conn.replay().unwrap();
    r.play_to_filetime(T0.plus_secs(0.105)); // x = 0..=10
    let mark = r.bookmark();
    assert_eq!(mark.file_time(), T0.plus_secs(0.105));
    r.play_to_filetime(T0.plus_secs(0.3));
    assert_eq!(*xs.borrow().last().unwrap(), 30.0);
    xs.borrow_mut().clear();
    assert!(r.go_to_bookmark(mark));
    assert!(
        xs.borrow().is_empty(),
        "going to a bookmark delivers nothing"
    );
    assert!(r.play_one());
    assert_eq!(*xs.borrow(), vec![11.0]);
    // Forward to a bookmark taken later.
    r.play_to_filetime(T0.plus_secs(0.4));
    let later = r.bookmark();
    r.reset();
    conn.mainloop().unwrap();
    xs.borrow_mut().clear();
    assert!(r.go_to_bookmark(later));
    assert!(r.play_one());
    assert_eq!(*xs.borrow(), vec![41.0]);
    let _ = std::fs::remove_file(&path);
}

#[test]
fn a_limit_caps_each_pass_and_the_replay_goes_on() {
    let path = write_log("limit", 40);
    let (conn, _t, xs) = replay(&path);
    let r = conn.replay().unwrap();
    r.limit_messages_played_back(5);
    assert_eq!(r.messages_limit(), 5);
    // A control plays at most 5 and stops at the last one played.
    r.play_to_filetime(T0.plus_secs(0.2));
    assert_eq!(xs.borrow().len(), 5);
    assert_eq!(r.file_time(), T0.plus_secs(0.04));
    // As fast as possible: every pass plays 5 more, until the end.
    r.set_rate(f64::INFINITY);
    let mut passes = 0;
    while !r.eof() {
        let before = xs.borrow().len();
        conn.mainloop().unwrap();
        assert!(xs.borrow().len() - before <= 5);
        passes += 1;
        assert!(passes < 100, "no end");
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(*xs.borrow(), (0..40).map(f64::from).collect::<Vec<_>>());
    assert!(passes >= 7, "{passes} passes for 35 poses at 5 a pass");
    // A jump is not capped.
    r.limit_messages_played_back(1);
    r.reset();
    conn.mainloop().unwrap();
    assert!(r.jump_to_filetime(T0.plus_secs(0.3)));
    assert_eq!(r.file_time(), T0.plus_secs(0.3));
    let _ = std::fs::remove_file(&path);
}

#[test]
fn a_file_controller_on_the_replay_connection() {
    let path = write_log("local", 100);
    let (conn, _t, xs) = replay(&path);
    let fc = FileController::new(&conn).unwrap();
    fc.play_to_time(TimeVal::new(0, 250_000)).unwrap();
    // The message reaches the replay's handler, which plays what it asks for before the
    // pass that delivers it returns.
    conn.mainloop().unwrap();
    assert_eq!(xs.borrow().len(), 26);
    fc.set_replay_rate(0.0).unwrap();
    conn.mainloop().unwrap();
    assert_eq!(conn.replay().unwrap().rate(), 0.0);
    fc.reset().unwrap();
    conn.mainloop().unwrap();
    assert_eq!(conn.replay().unwrap().file_time(), T0);
    let _ = std::fs::remove_file(&path);
}

#[test]
fn a_relayed_replay_is_controlled_over_the_network() {
    let path = write_log("net", 300);
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server.local_port().unwrap();
    let mut relay =
        Relay::new(&server, &format!("Tracker0@file:{}", path.display()), None).unwrap();
    let client = Connection::client("127.0.0.1", port, false, Default::default()).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &client).unwrap();
    let xs = Rc::new(RefCell::new(Vec::new()));
    let x = xs.clone();
    tracker.on_pose(move |p| x.borrow_mut().push(p.pos.x));
    let fc = FileController::new(&client).unwrap();
    let mut pass = || {
        relay.mainloop(Now::read());
        server.mainloop().unwrap();
        client.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(500));
    };
    let until = |what: &str, pass: &mut dyn FnMut(), done: &dyn Fn() -> bool| {
        let start = Instant::now();
        while !done() {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "timed out: {what}"
            );
            pass();
        }
    };
    until("connected", &mut pass, &|| client.connected());
    // A log answers no pings: the relay answers them for the device it re-serves.
    let sender = client.register_sender("Tracker0").unwrap();
    let ping = client.register_type(PING_MESSAGE).unwrap();
    let pong = client.register_type(PONG_MESSAGE).unwrap();
    let pongs = Rc::new(Cell::new(0));
    let p = pongs.clone();
    client.register_handler(pong, SenderFilter::Only(sender), move |_| {
        p.set(p.get() + 1)
    });
    client
        .pack_message(TimeVal::now(), ping, sender, &[], class::RELIABLE)
        .unwrap();
    until("pong", &mut pass, &|| pongs.get() > 0);
    // Pause: the replay stops, nothing more arrives.
    until("paused", &mut pass, &|| fc.set_replay_rate(0.0).is_ok());
    for _ in 0..100 {
        pass();
    }
    let n = xs.borrow().len();
    for _ in 0..100 {
        pass();
    }
    assert_eq!(xs.borrow().len(), n, "poses arrived while paused");
    assert!(n < 300);
    // Reset, then play to 0.5 s: poses 0..=50 arrive again, from the start.
    xs.borrow_mut().clear();
    fc.reset().unwrap();
    fc.play_to_time(TimeVal::new(0, 500_000)).unwrap();
    until("played to 0.5 s", &mut pass, &|| xs.borrow().len() >= 51);
    for _ in 0..50 {
        pass();
    }
    assert_eq!(*xs.borrow(), (0..=50).map(f64::from).collect::<Vec<_>>());
    let _ = std::fs::remove_file(&path);
}
