//! Diagnostics where users get stuck: unresolvable names, servers that do not answer, devices
//! that do not exist (no pong), device names with spaces, connection state.

use std::cell::{Cell, RefCell};
use std::net::{Ipv4Addr, UdpSocket};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::base;
use vrpn::{Connection, ConnectionState, Error, Limits, ServerDevice, TrackerNull, TrackerRemote};

#[test]
fn bad_names_and_unresolvable_hosts_are_clear_errors() {
    let e = TrackerRemote::new("Tracker0@host:notaport").err().unwrap();
    assert!(matches!(e, Error::Name(_)), "{e}");
    assert!(e.to_string().contains("port"));
    let e = TrackerRemote::new("Tracker0@no-such-host.invalid")
        .err()
        .unwrap();
    assert!(matches!(e, Error::Resolve { .. }), "{e}");
    assert!(e.to_string().contains("no-such-host.invalid"));
}

/// A port nobody listens on (bound then released).
fn dead_port() -> u16 {
    let s = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    s.local_addr().unwrap().port()
}

#[test]
fn silent_server_gets_an_explanation_and_mainloop_never_blocks() {
    let port = dead_port();
    let limits = Limits {
        no_answer_warning: Duration::from_millis(300),
        ..Limits::default()
    };
    let conn = Connection::client("127.0.0.1", port, false, limits).unwrap();
    let notices = Rc::new(RefCell::new(Vec::new()));
    let n = notices.clone();
    conn.on_notice(move |x| n.borrow_mut().push(x.text.clone()));
    let start = Instant::now();
    let mut slowest = Duration::ZERO;
    while start.elapsed() < Duration::from_millis(800) {
        let t = Instant::now();
        conn.mainloop().unwrap();
        slowest = slowest.max(t.elapsed());
        std::thread::sleep(Duration::from_millis(2));
    }
    // A blocking connect (as C++ does) would stall for about 1 s; allow for a loaded machine.
    assert!(
        slowest < Duration::from_millis(250),
        "mainloop blocked {slowest:?}"
    );
    assert_eq!(conn.state(), ConnectionState::Connecting);
    let all = notices.borrow().join("\n");
    assert!(all.contains("tcp://"), "no tcp:// hint in: {all}");
    // The request drew an ICMP port-unreachable on loopback: say so.
    assert!(all.contains("port unreachable"), "{all}");
}

#[test]
fn tcp_only_refused_is_reported_once_and_retried() {
    let port = dead_port();
    let conn = Connection::client("127.0.0.1", port, true, Limits::default()).unwrap();
    let notices = Rc::new(RefCell::new(Vec::new()));
    let n = notices.clone();
    conn.on_notice(move |x| n.borrow_mut().push(x.text.clone()));
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(2500) {
        conn.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(5));
    }
    let refused: Vec<_> = notices
        .borrow()
        .iter()
        .filter(|t| t.contains("refused"))
        .cloned()
        .collect();
    assert_eq!(refused.len(), 1, "{:?}", notices.borrow());
}

#[test]
fn missing_device_warns_after_three_seconds_on_both_sides() {
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server.local_port().unwrap();
    let mut null = TrackerNull::new("Tracker0", &server, 1, 10.0).unwrap();
    // The server hears the client's warning text too (C++ sends it over the connection).
    let heard = Rc::new(Cell::new(false));
    let h = heard.clone();
    let text_t = server.register_type(base::TEXT_MESSAGE).unwrap();
    server.register_handler(text_t, vrpn::SenderFilter::Any, move |m| {
        if let Some((_, level, text)) = vrpn::devices::text::decode_text(m.payload) {
            if text.contains(">= 3 seconds") && level >= 3 {
                h.set(true);
            }
        }
    });
    let nobody = TrackerRemote::new(&format!("Nobody@127.0.0.1:{port}")).unwrap();
    let start = Instant::now();
    while !heard.get() && start.elapsed() < Duration::from_secs(8) {
        null.mainloop(vrpn::Now::read());
        server.mainloop().unwrap();
        nobody.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(
        heard.get(),
        "no 'No response from server' warning reached the server"
    );
    assert!(nobody.ping_cycle().waiting_for_pong());
    // The server learned the client's sender name and can list it.
    assert!(server.peer_senders().contains(&"Nobody".to_string()));
}

#[test]
fn device_names_with_spaces_work_end_to_end() {
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server.local_port().unwrap();
    let mut null = TrackerNull::new("Rigid Body 1", &server, 1, 200.0).unwrap();
    let remote = TrackerRemote::new(&format!("Rigid Body 1@127.0.0.1:{port}")).unwrap();
    let new_senders = Rc::new(RefCell::new(Vec::new()));
    let ns = new_senders.clone();
    remote
        .connection()
        .on_peer_sender(move |s| ns.borrow_mut().push(s.to_string()));
    let n = Rc::new(Cell::new(0));
    let c = n.clone();
    remote.on_pose(move |_| c.set(c.get() + 1));
    let start = Instant::now();
    while n.get() < 5 && start.elapsed() < Duration::from_secs(10) {
        null.mainloop(vrpn::Now::read());
        server.mainloop().unwrap();
        remote.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(n.get() >= 5);
    assert!(new_senders.borrow().contains(&"Rigid Body 1".to_string()));
    assert_eq!(remote.connection().peers().len(), 1);
    assert_eq!(remote.connection().peers()[0].1.as_deref(), Some("07.38"));
}
