//! Forwarders, remote-controlled forwarding and the relay, over real sockets on 127.0.0.1.

use std::cell::{Cell, RefCell};
use std::net::{Ipv4Addr, TcpListener, UdpSocket};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::analog_output::AnalogOutputServer;
use vrpn::devices::ServerDevice;
use vrpn::forward::{ForwarderController, ForwarderServer, Relay, StreamForwarder};
use vrpn::{Connection, Now, TextReceiver, TrackerNull, TrackerRemote};

/// Runs every connection and device once per pass until `done`, for at most 10 s.
struct Loop {
    conns: Vec<Connection>,
    devices: Vec<Rc<RefCell<dyn ServerDevice>>>,
}

impl Loop {
    fn pass(&self) {
        let now = Now::read();
        for d in &self.devices {
            d.borrow_mut().mainloop(now);
        }
        for c in &self.conns {
            c.mainloop().unwrap();
        }
        std::thread::sleep(Duration::from_micros(300));
    }

    fn until(&self, what: &str, mut done: impl FnMut() -> bool) {
        let start = Instant::now();
        while !done() {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "timed out: {what}"
            );
            self.pass();
        }
    }

    fn for_a_while(&self, d: Duration) {
        let start = Instant::now();
        while start.elapsed() < d {
            self.pass();
        }
    }
}

fn server() -> (Connection, u16) {
    let c = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = c.local_port().unwrap();
    (c, port)
}

fn device<D: ServerDevice + 'static>(d: D) -> Rc<RefCell<dyn ServerDevice>> {
    Rc::new(RefCell::new(d))
}

/// A port free for both UDP and TCP right now (the forwarding server opens it later).
fn free_port() -> u16 {
    loop {
        let t = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
        let port = t.local_addr().unwrap().port();
        if UdpSocket::bind((Ipv4Addr::LOCALHOST, port)).is_ok() {
            return port;
        }
    }
}

#[test]
fn stream_forwarder_renames_and_filters() {
    // C++ forward.C: a client of one server re-serves a tracker's poses on another port.
    let (a, a_port) = server();
    let tracker = TrackerNull::new("Tracker0", &a, 1, 200.0).unwrap();
    let upstream = Connection::client("127.0.0.1", a_port, false, Default::default()).unwrap();
    let (b, b_port) = server();
    let mut fwd = StreamForwarder::new(&upstream, "Tracker0", &b, "Head").unwrap();
    fwd.forward(
        "vrpn_Tracker Pos_Quat",
        "vrpn_Tracker Pos_Quat",
        vrpn::ServiceClass::RELIABLE,
    )
    .unwrap();
    let head = TrackerRemote::new(&format!("Head@127.0.0.1:{b_port}")).unwrap();
    let vels = Rc::new(Cell::new(0));
    let v = vels.clone();
    head.on_velocity(move |_| v.set(v.get() + 1));
    let l = Loop {
        conns: vec![a, upstream, b, head.connection().clone()],
        devices: vec![device(tracker)],
    };
    l.until("forwarded poses", || head.pose_count(0) >= 50);
    // Only the type asked for goes through.
    assert_eq!(vels.get(), 0);
    assert!(fwd.counts().forwarded >= 50);
    // Unforward: no more poses.
    assert!(fwd.unforward(
        "vrpn_Tracker Pos_Quat",
        "vrpn_Tracker Pos_Quat",
        vrpn::ServiceClass::RELIABLE
    ));
    l.for_a_while(Duration::from_millis(100));
    let n = head.pose_count(0);
    l.for_a_while(Duration::from_millis(200));
    assert_eq!(head.pose_count(0), n);
}

#[test]
fn forwarder_server_opens_allowed_ports_on_request() {
    let (a, a_port) = server();
    let tracker = TrackerNull::new("Tracker0", &a, 2, 200.0).unwrap();
    let fs = ForwarderServer::new(&a).unwrap();
    let notices = Rc::new(RefCell::new(Vec::<String>::new()));
    let n = notices.clone();
    a.on_notice(move |x| n.borrow_mut().push(x.text.clone()));
    let port = free_port();
    fs.allow_ports(port..=port);
    let fs = Rc::new(RefCell::new(fs));
    let control = Connection::client("127.0.0.1", a_port, false, Default::default()).unwrap();
    let controller = ForwarderController::new(&control).unwrap();
    let l = Loop {
        conns: vec![a.clone(), control.clone()],
        devices: vec![device(tracker), fs.clone() as Rc<RefCell<dyn ServerDevice>>],
    };
    l.until("controller connected", || control.connected());
    // A port outside the range is refused, with a notice on the server.
    controller
        .start_remote_forwarding(port.wrapping_add(1))
        .unwrap();
    l.until("refusal", || {
        notices
            .borrow()
            .iter()
            .any(|t| t.contains("outside the ports allowed"))
    });
    controller.start_remote_forwarding(port).unwrap();
    controller
        .forward_message_type(port, "Tracker0", "vrpn_Tracker Pos_Quat")
        .unwrap();
    l.until("port open", || !fs.borrow().ports().is_empty());
    let remote = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{port}")).unwrap();
    let start = Instant::now();
    while remote.pose_count(1) < 20 {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "no forwarded poses"
        );
        l.pass();
        remote.mainloop().unwrap();
    }
    assert_eq!(fs.borrow().ports(), vec![port]);
    // Opening it twice is refused.
    controller.start_remote_forwarding(port).unwrap();
    l.until("second refusal", || {
        notices
            .borrow()
            .iter()
            .any(|t| t.contains("already forwarding"))
    });
}

#[test]
fn relay_reserves_a_device_both_ways() {
    // The device's server, which clients cannot reach directly.
    let (inner, inner_port) = server();
    let tracker = TrackerNull::new("Tracker0", &inner, 1, 200.0).unwrap();
    let out = AnalogOutputServer::new("Out0", &inner, 2).unwrap();
    let requested = Rc::new(RefCell::new(Vec::new()));
    let r = requested.clone();
    out.on_request(move |v| r.borrow_mut().push(v.channels().to_vec()));
    // The relay, which they can.
    let (relay_conn, relay_port) = server();
    let relay = Relay::new(
        &relay_conn,
        &format!("Tracker0@127.0.0.1:{inner_port}"),
        Some("Head"),
    )
    .unwrap();
    let relay_out = Relay::new(&relay_conn, &format!("Out0@127.0.0.1:{inner_port}"), None).unwrap();
    assert!(relay.upstream().same_as(relay_out.upstream()));
    let relay = Rc::new(RefCell::new(relay));
    let head = TrackerRemote::new(&format!("Head@127.0.0.1:{relay_port}")).unwrap();
    let texts = Rc::new(RefCell::new(Vec::new()));
    let t = texts.clone();
    let head_texts = TextReceiver::on_connection("Head", head.connection()).unwrap();
    head_texts.on_message(move |m| t.borrow_mut().push(m.text().to_string()));
    let remote_out =
        vrpn::devices::analog_output::AnalogOutputRemote::on_connection("Out0", head.connection())
            .unwrap();
    let l = Loop {
        conns: vec![inner.clone(), relay_conn.clone(), head.connection().clone()],
        devices: vec![
            device(tracker),
            relay.clone() as Rc<RefCell<dyn ServerDevice>>,
            device(relay_out),
        ],
    };
    // A remote pings from its first mainloop on (as in C++).
    head.mainloop().unwrap();
    remote_out.mainloop().unwrap();
    l.until("relayed poses", || head.pose_count(0) >= 100);
    // Requests go up to the real device.
    l.until("connected", || {
        remote_out.request_change_channels(&[0.25, 0.5]).is_ok()
    });
    l.until("request relayed", || !requested.borrow().is_empty());
    assert_eq!(requested.borrow()[0], vec![0.25, 0.5]);
    // The client's pings reach the real tracker and its pongs come back: for 4 s, more
    // than the 3 s after which an unanswered remote complains, nothing is said.
    l.for_a_while(Duration::from_secs(4));
    assert!(texts.borrow().is_empty(), "{:?}", texts.borrow());
    assert!(head.ping_cycle().last_pong().is_some());
    assert!(relay.borrow().relayed_up().forwarded > 0);
    assert!(relay.borrow().relayed_down().forwarded >= 100);
}

#[test]
fn relay_waits_for_an_unreachable_server() {
    // Nothing listens there yet: the relay serves nothing until it does.
    let port = free_port();
    let (relay_conn, relay_port) = server();
    relay_conn.on_notice(|_| {});
    let relay = Relay::new(&relay_conn, &format!("Tracker0@127.0.0.1:{port}"), None).unwrap();
    relay.upstream().on_notice(|_| {});
    let head = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{relay_port}")).unwrap();
    head.connection().on_notice(|_| {});
    let l = Loop {
        conns: vec![relay_conn.clone(), head.connection().clone()],
        devices: vec![device(relay)],
    };
    l.for_a_while(Duration::from_millis(300));
    assert_eq!(head.pose_count(0), 0);
    let inner = Connection::server(Some(Ipv4Addr::LOCALHOST), port).unwrap();
    let tracker = device(TrackerNull::new("Tracker0", &inner, 1, 200.0).unwrap());
    let start = Instant::now();
    while head.pose_count(0) < 20 {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "relay never connected"
        );
        tracker.borrow_mut().mainloop(Now::read());
        inner.mainloop().unwrap();
        l.pass();
    }
}
