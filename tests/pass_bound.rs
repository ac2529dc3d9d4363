//! `mainloop()` returns even when callbacks are slower than the data (issue 28, item 1): a pass
//! delivers for about `Limits::max_pass_time`, keeps the rest buffered for the next call, and
//! says so through `poll_timeout()`. On real sockets: an in-process server, and a `vrpn_server`
//! child streaming faster than the callback can keep up.

mod common;

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::{Connection, Limits, TimeVal, TrackerRemote, TrackerServer};

/// A pass may last its budget (5 ms by default) plus the callbacks run before the clock is
/// first read and the one running when it runs out: three callbacks. The margin covers a
/// loaded 2-core machine, where a 2 ms sleep can take much longer.
fn pass_bound(callback: Duration) -> Duration {
    Limits::default().max_pass_time + callback * 3 + Duration::from_millis(150)
}

/// Every report buffered at once (300 poses in the client's socket) with a 2 ms callback: the
/// passes end early, nothing is lost, and `poll_timeout()` is due while some remain.
#[test]
fn a_backlog_is_delivered_over_several_bounded_passes_and_nothing_is_lost() {
    const N: usize = 300;
    let callback = Duration::from_millis(2);
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = srv.local_port().unwrap();
    let mut tracker = TrackerServer::new("Tracker0", &srv, 1).unwrap();
    tracker.set_class_of_service(vrpn::ServiceClass::RELIABLE);
    let client = TrackerRemote::new(&format!("Tracker0@tcp://127.0.0.1:{port}")).unwrap();
    let seen = Rc::new(RefCell::new(Vec::<f64>::new()));
    let s = seen.clone();
    client.on_pose(move |p| {
        s.borrow_mut().push(p.pos.x);
        std::thread::sleep(callback);
    });
    let start = Instant::now();
    while !client.connection().connected() || srv.connected_peers() == 0 {
        assert!(start.elapsed() < Duration::from_secs(5), "no connection");
        client.mainloop().unwrap();
        srv.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    // The whole backlog, reliable, in the client's socket before its next pass.
    for i in 0..N {
        let t = TimeVal::new(1, i as i64);
        tracker
            .report_pose(0, t, [i as f64, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
            .unwrap();
    }
    srv.mainloop().unwrap();
    std::thread::sleep(Duration::from_millis(50));
    let mut passes = 0;
    let mut due_while_left = 0;
    let mut worst = Duration::ZERO;
    while seen.borrow().len() < N {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "stalled at {}",
            seen.borrow().len()
        );
        let before = seen.borrow().len();
        let t = Instant::now();
        client.mainloop().unwrap();
        worst = worst.max(t.elapsed());
        let got = seen.borrow().len() - before;
        if got > 0 {
            passes += 1;
        }
        if seen.borrow().len() < N && got > 0 {
            // Messages remain buffered: a loop waiting for the next deadline must not sleep.
            let due = client.connection().poll_timeout();
            if due.is_some_and(|d| d <= Instant::now()) {
                due_while_left += 1;
            }
        }
        srv.mainloop().unwrap();
    }
    let seen = seen.borrow();
    assert_eq!(seen.len(), N);
    assert!(
        seen.iter().enumerate().all(|(i, &x)| x == i as f64),
        "lost or reordered"
    );
    eprintln!("{N} poses with a {callback:?} callback: {passes} passes, longest {worst:?}");
    assert!(
        worst < pass_bound(callback),
        "a pass took {worst:?} (one pass used to take all {N} callbacks, {:?})",
        callback * N as u32
    );
    assert!(passes >= 10, "{passes} passes");
    assert!(
        due_while_left + 1 >= passes,
        "poll_timeout() was due after only {due_while_left} of {passes} passes that left poses"
    );
}

/// A `vrpn_server` child reporting 500 poses a second to a 10 ms callback (what a Python user
/// hit with a 9.5 ms callback on a 120 Hz tracker): every pass returns. Before passes were
/// bounded the first one never did; the callback stops sleeping after 3 s so that such a pass
/// would end (and the test fail) rather than hang.
#[test]
fn mainloop_returns_while_a_slow_callback_falls_behind() {
    let server = common::start_server("vrpn_Tracker_NULL Tracker0 1 500.0\n", 0);
    let callback = Duration::from_millis(10);
    for name in [
        format!("Tracker0@127.0.0.1:{}", server.port),
        format!("Tracker0@tcp://127.0.0.1:{}", server.port),
    ] {
        let tracker = TrackerRemote::new(&name).unwrap();
        tracker.connection().on_notice(|_| {});
        let poses = Rc::new(Cell::new(0u64));
        let begun = Instant::now();
        let p = poses.clone();
        tracker.on_pose(move |_| {
            p.set(p.get() + 1);
            if begun.elapsed() < Duration::from_secs(3) {
                std::thread::sleep(callback);
            }
        });
        let start = Instant::now();
        while poses.get() == 0 {
            assert!(start.elapsed() < Duration::from_secs(5), "{name}: no pose");
            tracker.mainloop().unwrap();
            let _ = tracker.connection().wait(Duration::from_millis(5));
        }
        let mut worst = Duration::ZERO;
        let mut passes = 0u32;
        let until = Instant::now() + Duration::from_millis(1500);
        while Instant::now() < until {
            let t = Instant::now();
            tracker.mainloop().unwrap();
            worst = worst.max(t.elapsed());
            passes += 1;
        }
        eprintln!(
            "{name}: {passes} passes in 1.5 s, longest {worst:?}, {} poses",
            poses.get()
        );
        assert!(
            worst < pass_bound(callback),
            "{name}: a pass took {worst:?}"
        );
        assert!(passes >= 10, "{name}: {passes} passes");
        assert!(poses.get() >= 50, "{name}: {} poses", poses.get());
    }
}
