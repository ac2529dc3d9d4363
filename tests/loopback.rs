//! Our server and our client over real loopback sockets: both connection paths, ids,
//! callbacks, requests, events, pings.

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::{
    Connection, ConnectionEvent, ConnectionState, ServerDevice, TrackerNull, TrackerRemote,
};

/// Runs server and client loops until `done` or the timeout; returns whether `done` held.
fn run_until(
    server: &Connection,
    devices: &mut [&mut dyn ServerDevice],
    client: &TrackerRemote,
    timeout: Duration,
    mut done: impl FnMut() -> bool,
) -> bool {
    let start = Instant::now();
    while start.elapsed() < timeout {
        let now = vrpn::Now::read();
        for d in devices.iter_mut() {
            d.mainloop(now);
        }
        server.mainloop().unwrap();
        client.mainloop().unwrap();
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    false
}

fn server_with_null(sensors: usize, rate: f64) -> (Connection, TrackerNull, u16) {
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server.local_port().unwrap();
    let null = TrackerNull::new("Tracker0", &server, sensors, rate).unwrap();
    (server, null, port)
}

fn poses_arrive(name_fmt: &str) {
    let (server, mut null, port) = server_with_null(2, 200.0);
    let name = name_fmt.replace("PORT", &port.to_string());
    let client = TrackerRemote::new(&name).unwrap();
    assert_ne!(client.connection().state(), ConnectionState::Connected);
    let seen = Rc::new(RefCell::new([0usize; 2]));
    let s = seen.clone();
    client.on_pose(move |p| {
        assert_eq!(p.quat.w, 1.0);
        s.borrow_mut()[p.sensor] += 1;
    });
    let vels = Rc::new(Cell::new(0));
    let v = vels.clone();
    client.on_velocity(move |r| {
        assert_eq!(r.vel_quat_dt, 1.0);
        v.set(v.get() + 1)
    });
    let ok = run_until(
        &server,
        &mut [&mut null],
        &client,
        Duration::from_secs(10),
        || {
            let s = seen.borrow();
            s[0] >= 20 && s[1] >= 20 && vels.get() >= 20
        },
    );
    assert!(ok, "poses did not arrive over {name}: {:?}", seen.borrow());
    assert_eq!(client.connection().state(), ConnectionState::Connected);
    assert_eq!(server.connected_peers(), 1);
    let latest = client.pose(1).expect("latest pose of sensor 1");
    assert_eq!(latest.sensor, 1);
    assert!(client
        .connection()
        .peer_senders()
        .contains(&"Tracker0".to_string()));
}

#[test]
fn poses_over_udp_request_and_tcp_callback() {
    poses_arrive("Tracker0@127.0.0.1:PORT");
}

#[test]
fn poses_over_tcp_only() {
    poses_arrive("Tracker0@tcp://127.0.0.1:PORT");
}

#[test]
fn ping_gets_pong_and_requests_are_answered() {
    let (server, mut null, port) = server_with_null(3, 0.0);
    let client = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{port}")).unwrap();
    let u2s = Rc::new(Cell::new(0));
    let u = u2s.clone();
    client.on_unit_to_sensor(move |_| u.set(u.get() + 1));
    let ws = Rc::new(Cell::new(false));
    let w = ws.clone();
    client.on_workspace(move |r| {
        assert_eq!(r.min.x, -0.5);
        w.set(true)
    });
    assert!(run_until(
        &server,
        &mut [&mut null],
        &client,
        Duration::from_secs(10),
        || { client.connection().connected() }
    ));
    client.request_unit_to_sensor().unwrap();
    client.request_workspace().unwrap();
    assert!(run_until(
        &server,
        &mut [&mut null],
        &client,
        Duration::from_secs(10),
        || { u2s.get() == 3 && ws.get() && !client.ping_cycle().waiting_for_pong() }
    ));
}

#[test]
fn server_events_and_client_reconnect() {
    let (server, mut null, port) = server_with_null(1, 100.0);
    let events = Rc::new(RefCell::new(Vec::new()));
    for ev in [
        ConnectionEvent::GotFirstConnection,
        ConnectionEvent::GotConnection,
        ConnectionEvent::DroppedConnection,
        ConnectionEvent::DroppedLastConnection,
    ] {
        let e = events.clone();
        server.on_event(ev, move || e.borrow_mut().push(ev));
    }
    let client = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{port}")).unwrap();
    let client_events = Rc::new(RefCell::new(Vec::new()));
    let ce = client_events.clone();
    client
        .connection()
        .on_event(ConnectionEvent::DroppedConnection, move || {
            ce.borrow_mut().push("dropped")
        });
    let count = Rc::new(Cell::new(0));
    let c = count.clone();
    client.on_pose(move |_| c.set(c.get() + 1));
    assert!(run_until(
        &server,
        &mut [&mut null],
        &client,
        Duration::from_secs(10),
        || count.get() > 5
    ));
    assert_eq!(
        *events.borrow(),
        vec![
            ConnectionEvent::GotFirstConnection,
            ConnectionEvent::GotConnection
        ]
    );
    // Kill the server: the client notices, keeps going, and reconnects to a new server.
    drop(null);
    drop(server);
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(5) && client_events.borrow().is_empty() {
        client.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(*client_events.borrow(), vec!["dropped"]);
    assert_eq!(client.connection().state(), ConnectionState::Reconnecting);
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), port).unwrap();
    let mut null = TrackerNull::new("Tracker0", &server, 1, 100.0).unwrap();
    let before = count.get();
    assert!(run_until(
        &server,
        &mut [&mut null],
        &client,
        Duration::from_secs(10),
        || count.get() > before + 5
    ));
    assert_eq!(client.connection().state(), ConnectionState::Connected);
}
