//! In-process connections: a server object and a remote in one process, no sockets; callbacks
//! that call back into the library; application-level messages.

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::wire::class;
use vrpn::{
    Connection, SenderFilter, ServerDevice, TimeVal, TrackerNull, TrackerRemote, TrackerServer,
};

#[test]
fn reports_reach_callbacks_directly_without_mainloop() {
    let conn = Connection::new_loopback();
    let server = TrackerServer::new("Tracker0", &conn, 2).unwrap();
    let remote = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let got = Rc::new(RefCell::new(Vec::new()));
    let g = got.clone();
    remote.on_pose(move |p| g.borrow_mut().push((p.sensor, p.pos.x, p.quat.w)));
    let t = TimeVal::new(1_700_000_000, 5);
    server
        .report_pose(1, t, [0.25, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
        .unwrap();
    // Delivered inside report_pose: no mainloop, no sockets.
    assert_eq!(*got.borrow(), vec![(1, 0.25, 1.0)]);
    let latest = remote.pose(1).unwrap();
    assert_eq!(latest.time, t);
    assert!(remote.pose(0).is_none());
    // A sensor beyond the configured count is refused.
    assert!(server
        .report_pose(2, t, [0.0; 3], [0.0, 0.0, 0.0, 1.0])
        .is_err());
}

#[test]
fn loopback_name_shares_the_process_connection() {
    let a = Connection::open("Tracker0@loopback:").unwrap();
    let b = Connection::loopback();
    assert!(a.same_as(&b));
    let mut null = TrackerNull::new("Tracker0", &a, 1, 1000.0).unwrap();
    let remote = TrackerRemote::new("Tracker0@loopback:").unwrap();
    let n = Rc::new(Cell::new(0));
    let c = n.clone();
    remote.on_pose(move |_| c.set(c.get() + 1));
    let start = Instant::now();
    while n.get() < 3 && start.elapsed() < Duration::from_secs(5) {
        null.mainloop(vrpn::Now::read());
        remote.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(n.get() >= 3);
    // The remote's ping is answered in process too.
    assert!(!remote.ping_cycle().waiting_for_pong());
}

#[test]
fn callbacks_may_send_register_and_read_state_without_panic() {
    let conn = Connection::new_loopback();
    let server = Rc::new(TrackerServer::new("Tracker0", &conn, 1).unwrap());
    let remote = Rc::new(TrackerRemote::on_connection("Tracker0", &conn).unwrap());
    let sender = conn.register_sender("app").unwrap();
    let echo = conn.register_type("app echo").unwrap();
    let echoes = Rc::new(Cell::new(0));
    let e = echoes.clone();
    conn.register_handler(echo, SenderFilter::Only(sender), move |m| {
        assert_eq!(m.payload, b"hi");
        e.set(e.get() + 1)
    });
    let calls = Rc::new(Cell::new(0));
    let (c, r, s, cn) = (calls.clone(), remote.clone(), server.clone(), conn.clone());
    remote.on_pose(move |p| {
        c.set(c.get() + 1);
        // Read the remote's state from inside its own callback.
        assert_eq!(r.pose(0).unwrap().time, p.time);
        // Send an application message and another report from inside the callback.
        cn.pack_message(p.time, echo, sender, b"hi", class::RELIABLE)
            .unwrap();
        if c.get() == 1 {
            s.report_pose(0, TimeVal::now(), [1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
                .unwrap();
            // Register another callback while this one runs.
            r.on_pose(|_| {});
        }
    });
    server
        .report_pose(0, TimeVal::now(), [0.0; 3], [0.0, 0.0, 0.0, 1.0])
        .unwrap();
    // The nested report is delivered after the first callback returns.
    assert_eq!(calls.get(), 2);
    assert_eq!(echoes.get(), 2);
    assert_eq!(remote.pose(0).unwrap().pos.x, 1.0);
}

#[test]
fn application_messages_and_any_sender_handlers() {
    let conn = Connection::new_loopback();
    let s1 = conn.register_sender("robot arm").unwrap();
    let s2 = conn.register_sender("gripper").unwrap();
    let t = conn.register_type("lab joint_angles").unwrap();
    let from_arm = Rc::new(Cell::new(0));
    let any = Rc::new(Cell::new(0));
    let (a, b) = (from_arm.clone(), any.clone());
    conn.register_handler(t, SenderFilter::Only(s1), move |_| a.set(a.get() + 1));
    let h = conn.register_handler(t, SenderFilter::Any, move |_| b.set(b.get() + 1));
    for s in [s1, s2, s1] {
        conn.pack_message(TimeVal::now(), t, s, &[1, 2, 3], class::RELIABLE)
            .unwrap();
    }
    assert_eq!((from_arm.get(), any.get()), (2, 3));
    assert!(conn.remove_handler(h));
    conn.pack_message(TimeVal::now(), t, s2, &[], class::RELIABLE)
        .unwrap();
    assert_eq!(any.get(), 3);
    assert_eq!(conn.sender_name(s1).as_deref(), Some("robot arm"));
    let too_big = vec![0u8; vrpn::connection::MAX_PAYLOAD + 1];
    assert!(conn
        .pack_message(TimeVal::now(), t, s1, &too_big, class::RELIABLE)
        .is_err());
}
