//! The client API defects a new user found, each on real sockets: handler ids that removed the
//! wrong handler, a reconnect storm against a port that is not VRPN, a handler that kept its
//! connection alive, a false "no response" after a reconnect, and silence after a typo.

mod common;

use std::cell::{Cell, RefCell};
use std::io::{Read, Write};
use std::net::{Ipv4Addr, TcpListener};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use vrpn::devices::base::TEXT_MESSAGE;
use vrpn::devices::text::decode_text;
use vrpn::wire::class;
use vrpn::{
    Connection, ConnectionState, Limits, SenderFilter, TimeVal, TrackerRemote, TrackerServer,
};

fn pump(conns: &[&Connection], d: Duration) {
    let start = Instant::now();
    while start.elapsed() < d {
        for c in conns {
            c.mainloop().unwrap();
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Defect 1: ids from different registries no longer collide, and every `on_*` can be removed.
#[test]
fn removing_a_callback_removes_that_one_only() {
    let conn = Connection::new_loopback();
    let server = TrackerServer::new("Tracker0", &conn, 1).unwrap();
    let remote = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let poses = Rc::new(Cell::new(0));
    let handled = Rc::new(Cell::new(0));
    let p = poses.clone();
    let pose_id = remote.on_pose(move |_| p.set(p.get() + 1));
    let h = handled.clone();
    let t = conn.register_type("vrpn_Tracker Pos_Quat").unwrap();
    let handler_id = conn.register_handler(t, SenderFilter::Any, move |_| h.set(h.get() + 1));
    let notice_id = conn.on_notice(|_| {});
    assert_ne!(pose_id, handler_id);
    assert_ne!(pose_id, notice_id);
    let report = || {
        server
            .report_pose(0, TimeVal::new(1, 0), [0.0; 3], [0.0, 0.0, 0.0, 1.0])
            .unwrap()
    };
    report();
    assert_eq!((poses.get(), handled.get()), (1, 1));
    // The connection does not know the remote's id: it removes nothing.
    assert!(!conn.remove_handler(pose_id));
    report();
    assert_eq!((poses.get(), handled.get()), (2, 2));
    // The remote removes its own callback, and only that.
    assert!(remote.remove_callback(pose_id));
    assert!(!remote.remove_callback(pose_id));
    report();
    assert_eq!((poses.get(), handled.get()), (2, 3));
    assert!(conn.remove_handler(handler_id));
    assert!(conn.remove_handler(notice_id));
}

/// A TCP port held by another program: accepts, answers `answer` (or nothing) and closes
/// (or not). Counts the connections it accepted.
struct Impostor {
    port: u16,
    accepted: Arc<AtomicUsize>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Impostor {
    fn start(answer: &'static [u8], close: bool) -> Impostor {
        let l = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
        l.set_nonblocking(true).unwrap();
        let port = l.local_addr().unwrap().port();
        let accepted = Arc::new(AtomicUsize::new(0));
        let stop = Arc::new(AtomicBool::new(false));
        let (a, s) = (accepted.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            let mut held = Vec::new();
            while !s.load(Ordering::Relaxed) {
                match l.accept() {
                    Ok((mut c, _)) => {
                        a.fetch_add(1, Ordering::Relaxed);
                        let _ = c.write_all(answer);
                        if close {
                            let mut b = [0u8; 64];
                            let _ = c.set_read_timeout(Some(Duration::from_millis(5)));
                            let _ = c.read(&mut b);
                        } else {
                            held.push(c);
                        }
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(2)),
                }
            }
        });
        Impostor {
            port,
            accepted,
            stop,
            thread: Some(thread),
        }
    }
}

impl Drop for Impostor {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn notices_of(conn: &Connection) -> Rc<RefCell<Vec<String>>> {
    let n = Rc::new(RefCell::new(Vec::new()));
    let c = n.clone();
    conn.on_notice(move |x| c.borrow_mut().push(x.text.clone()));
    n
}

/// Defect 2a: a port that answers with something else and closes costs one connection per
/// retry interval, and one explanation — not tens of thousands of connections.
#[test]
fn an_impostor_server_gets_no_reconnect_storm() {
    let imp = Impostor::start(b"HTTP/1.1 400 Bad Request\r\n\r\n", true);
    let conn = Connection::client("127.0.0.1", imp.port, true, Limits::default()).unwrap();
    let notices = notices_of(&conn);
    pump(&[&conn], Duration::from_millis(3500));
    let n = imp.accepted.load(Ordering::Relaxed);
    assert!((3..=5).contains(&n), "{n} connections in 3.5 s");
    let explained: Vec<String> = notices
        .borrow()
        .iter()
        .filter(|t| t.contains("not with a VRPN greeting"))
        .cloned()
        .collect();
    assert_eq!(explained.len(), 1, "{:?}", notices.borrow());
    assert!(explained[0].contains("HTTP/1.1 400"), "{}", explained[0]);
    assert_eq!(conn.state(), ConnectionState::Connecting);
}

/// Defect 2b: a port that accepts and never answers is given up after the greeting time-out,
/// with a notice, and retried.
#[test]
fn a_silent_server_is_explained() {
    let imp = Impostor::start(b"", false);
    let limits = Limits {
        handshake_timeout: Duration::from_millis(600),
        ..Limits::default()
    };
    let conn = Connection::client("127.0.0.1", imp.port, true, limits).unwrap();
    let notices = notices_of(&conn);
    pump(&[&conn], Duration::from_millis(2500));
    let all = notices.borrow().join("\n");
    assert!(all.contains("sent no VRPN greeting within 600ms"), "{all}");
    assert!(imp.accepted.load(Ordering::Relaxed) >= 2, "not retried");
}

/// Defect 3: a handler answers through the message's connection, so it need not capture one,
/// and dropping the last handle frees the connection (and its port).
#[test]
fn a_replying_handler_does_not_keep_its_connection_alive() {
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server.local_port().unwrap();
    let ask = server.register_type("ask").unwrap();
    let answer = server.register_type("answer").unwrap();
    let me = server.register_sender("responder").unwrap();
    server.register_handler(ask, SenderFilter::Any, move |m| {
        let c = m.connection();
        c.pack_message(c.now().wall, answer, me, m.payload, class::RELIABLE)
            .unwrap();
    });
    let client = Connection::client("127.0.0.1", port, true, Limits::default()).unwrap();
    let c_ask = client.register_type("ask").unwrap();
    let c_answer = client.register_type("answer").unwrap();
    let from = client.register_sender("asker").unwrap();
    let got = Rc::new(Cell::new(false));
    let g = got.clone();
    client.register_handler(c_answer, SenderFilter::Any, move |m| {
        g.set(m.payload == b"hello")
    });
    let start = Instant::now();
    while !client.connected() || !server.connected() {
        assert!(start.elapsed() < Duration::from_secs(5));
        pump(&[&client, &server], Duration::from_millis(5));
    }
    client
        .pack_message(TimeVal::ZERO, c_ask, from, b"hello", class::RELIABLE)
        .unwrap();
    let start = Instant::now();
    while !got.get() {
        assert!(start.elapsed() < Duration::from_secs(5), "no answer");
        pump(&[&client, &server], Duration::from_millis(2));
    }
    let weak = server.downgrade();
    drop(server);
    assert!(
        weak.upgrade().is_none(),
        "the connection outlived its handles"
    );
    // Its port is free again.
    assert!(TcpListener::bind((Ipv4Addr::LOCALHOST, port)).is_ok());
}

/// Defect 4: no "no response" warning after a successful reconnect.
#[test]
fn no_false_warning_after_a_reconnect() {
    let cfg = "vrpn_Tracker_NULL Tracker0 1 50.0\n";
    let first = common::start_server(cfg, 0);
    let port = first.port;
    let tracker = TrackerRemote::new(&format!("Tracker0@tcp://127.0.0.1:{port}")).unwrap();
    let conn = tracker.connection().clone();
    conn.on_notice(|_| {});
    let texts = Rc::new(RefCell::new(Vec::<(Instant, String)>::new()));
    let t = texts.clone();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    conn.register_handler(text_type, SenderFilter::Only(tracker.sender()), move |m| {
        if let Some((_, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push((Instant::now(), text.to_string()));
        }
    });
    let poses = Rc::new(Cell::new(0u64));
    let p = poses.clone();
    tracker.on_pose(move |_| p.set(p.get() + 1));
    let run = |d: Duration| {
        let start = Instant::now();
        while start.elapsed() < d {
            tracker.mainloop().unwrap();
            std::thread::sleep(Duration::from_millis(2));
        }
    };
    run(Duration::from_millis(1500));
    assert!(poses.get() > 20);
    // The server goes away for 2 s and comes back on the same port.
    drop(first);
    run(Duration::from_millis(2000));
    let second = common::start_server(cfg, port);
    let back = Instant::now();
    let before = poses.get();
    run(Duration::from_secs(4));
    assert!(poses.get() > before + 50, "no reconnect");
    let after: Vec<String> = texts
        .borrow()
        .iter()
        .filter(|(at, text)| {
            *at > back + Duration::from_millis(500) && text.contains("No response")
        })
        .map(|(_, t)| t.clone())
        .collect();
    assert!(
        after.is_empty(),
        "false warnings after the reconnect: {after:?}"
    );
    drop(second);
}

/// Defect 5: a typo in the device name is reported at once, naming what the server offers.
#[test]
fn a_typo_names_what_the_server_offers() {
    let server = common::start_server(
        "vrpn_Tracker_NULL Tracker0 1 50.0\nvrpn_Tracker_Spin Spin0 1 50.0 0 0 1 0.5\n",
        0,
    );
    let tracker = TrackerRemote::new(&format!("Trackr0@127.0.0.1:{}", server.port)).unwrap();
    let notices = notices_of(tracker.connection());
    let start = Instant::now();
    while !notices.borrow().iter().any(|n| n.contains("none is named")) {
        assert!(
            start.elapsed() < Duration::from_secs(3),
            "{:?}",
            notices.borrow()
        );
        tracker.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(2));
    }
    let text = notices
        .borrow()
        .iter()
        .find(|n| n.contains("none is named"))
        .cloned()
        .unwrap();
    assert!(
        text.contains("Tracker0") && text.contains("Spin0") && text.contains("\"Trackr0\""),
        "{text}"
    );
    let offered = tracker.connection().peer_senders();
    assert!(!offered.contains(&"Trackr0".to_string()), "{offered:?}");
    assert!(offered.contains(&"Tracker0".to_string()), "{offered:?}");
}

/// Issue 28 item 12: `on_peer_sender` and `peer_senders()` agree; neither reports the
/// protocol's own "VRPN Control" sender.
#[test]
fn sender_discovery_callback_and_list_agree() {
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = srv.local_port().unwrap();
    let _tracker = TrackerServer::new("Tracker0", &srv, 1).unwrap();
    for tcp_only in [false, true] {
        let client = Connection::client("127.0.0.1", port, tcp_only, Limits::default()).unwrap();
        let seen = Rc::new(RefCell::new(Vec::<String>::new()));
        let s = seen.clone();
        client.on_peer_sender(move |name| s.borrow_mut().push(name.to_string()));
        let start = Instant::now();
        while client.peer_senders().is_empty() {
            assert!(start.elapsed() < Duration::from_secs(5), "not connected");
            client.mainloop().unwrap();
            srv.mainloop().unwrap();
            std::thread::sleep(Duration::from_millis(1));
        }
        pump(&[&client, &srv], Duration::from_millis(200));
        assert_eq!(client.peer_senders(), ["Tracker0"]);
        assert_eq!(*seen.borrow(), ["Tracker0"], "tcp_only {tcp_only}");
    }
}

/// Issue 28 item 12: a device name without `@HOST` says the host part is missing, instead of
/// "cannot resolve host".
#[test]
fn a_name_without_a_host_says_so() {
    let Err(err) = TrackerRemote::new("Tracker0") else {
        panic!("a name without a host was accepted");
    };
    let e = err.to_string();
    assert!(
        e.contains("no '@'") && e.contains("Tracker0@localhost"),
        "{e}"
    );
    assert!(!e.contains("resolve"), "{e}");
    assert!(matches!(err, vrpn::Error::Name(_)), "{err:?}");
}

/// Issue 28 item 8: a client names its server by the port the user gave (not the server's
/// call-back port), and its drop notices carry a reason a program can match.
#[test]
fn drop_notices_name_the_servers_port_and_a_reason() {
    let mut server = common::start_server("vrpn_Tracker_NULL Tracker0 1 60.0\n", 0);
    let port = server.port;
    let tracker = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{port}")).unwrap();
    let notices = Rc::new(RefCell::new(Vec::<vrpn::Notice>::new()));
    let n = notices.clone();
    tracker
        .connection()
        .on_notice(move |x| n.borrow_mut().push(x.clone()));
    let start = Instant::now();
    while tracker.pose(0).is_none() {
        assert!(start.elapsed() < Duration::from_secs(5), "no pose");
        tracker.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(2));
    }
    assert_eq!(
        tracker.connection().peers()[0].0,
        format!("127.0.0.1:{port}"),
        "the peer list names the server's port"
    );
    let _ = server.child.kill();
    let _ = server.child.wait();
    let start = Instant::now();
    let dropped = loop {
        let found = notices
            .borrow()
            .iter()
            .find(|n| matches!(n.kind, vrpn::NoticeKind::PeerDropped { .. }))
            .cloned();
        if let Some(n) = found {
            break n;
        }
        assert!(start.elapsed() < Duration::from_secs(5), "no drop notice");
        tracker.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(2));
    };
    assert_eq!(
        dropped.kind,
        vrpn::NoticeKind::PeerDropped {
            peer: format!("127.0.0.1:{port}"),
            reason: vrpn::DropReason::Closed,
        }
    );
    assert_eq!(dropped.drop_reason(), Some(vrpn::DropReason::Closed));
    assert!(
        dropped.to_string().starts_with(&format!(
            "127.0.0.1:{port} closed the connection; reconnecting"
        )),
        "{dropped}"
    );
}
