//! Factoring in vrpn.cfg: several entries give one name to devices of different interfaces, as
//! C++ allows, and one vrpn_server serves them all under that name.

mod common;

use std::cell::Cell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::{ButtonRemote, TrackerRemote};

#[test]
fn tracker_and_button_under_one_name() {
    let server = common::start_server(
        "vrpn_Tracker_NULL Dev0 1 20.0\nvrpn_Button_Example Dev0 2 4.0\n",
        0,
    );
    let name = format!("Dev0@127.0.0.1:{}", server.port);
    let tracker = TrackerRemote::new(&name).unwrap();
    let button = ButtonRemote::new(&name).unwrap();
    let (poses, changes) = (Rc::new(Cell::new(0u32)), Rc::new(Cell::new(0u32)));
    let p = poses.clone();
    tracker.on_pose(move |r| {
        assert_eq!(r.sensor, 0);
        p.set(p.get() + 1);
    });
    let c = changes.clone();
    button.on_change(move |b| {
        assert!(b.button < 2, "button {}", b.button);
        c.set(c.get() + 1);
    });
    let start = Instant::now();
    while poses.get() < 5 || changes.get() < 2 {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "after 10 s: {} poses, {} button changes",
            poses.get(),
            changes.get()
        );
        tracker.mainloop().unwrap();
        button.mainloop().unwrap();
        let _ = tracker.connection().wait(Duration::from_millis(5));
    }
    // No warning: distinct interfaces under one name are not a clash.
    let err = server.stderr.lock().unwrap().clone();
    assert!(!err.contains("warning"), "{err}");
}

#[test]
fn same_interface_twice_is_served_with_a_warning() {
    let server = common::start_server(
        "vrpn_Tracker_NULL Dev0 1 20.0\nvrpn_Tracker_NULL Dev0 1 20.0\n",
        0,
    );
    // Both run, as in C++: the client sees reports at about twice the rate of one.
    let name = format!("Dev0@127.0.0.1:{}", server.port);
    let tracker = TrackerRemote::new(&name).unwrap();
    let poses = Rc::new(Cell::new(0u32));
    let p = poses.clone();
    tracker.on_pose(move |_| p.set(p.get() + 1));
    let start = Instant::now();
    while poses.get() < 3 {
        assert!(start.elapsed() < Duration::from_secs(10), "no poses");
        tracker.mainloop().unwrap();
        let _ = tracker.connection().wait(Duration::from_millis(5));
    }
    let first = Instant::now();
    let before = poses.get();
    while first.elapsed() < Duration::from_secs(1) {
        tracker.mainloop().unwrap();
        let _ = tracker.connection().wait(Duration::from_millis(5));
    }
    let rate = poses.get() - before;
    // One 20 Hz tracker alone gives at most about 21.
    assert!(rate > 28, "{rate} poses in 1 s from two 20 Hz trackers");
    let err = server.stderr.lock().unwrap().clone();
    assert!(
        err.contains(
            "vrpn.cfg:2: vrpn_Tracker_NULL: device name 'Dev0' is already a tracker \
             (vrpn_Tracker_NULL at line 1); both run"
        ),
        "{err}"
    );
}
