//! Every connection limit: its default, and that passing it drops the peer with a notice that
//! names the limit, while the server keeps running.

use std::cell::RefCell;
use std::io::{Read, Write};
use std::net::{Ipv4Addr, TcpStream};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::wire::{self, header::encode_message, Cookie, Header};
use vrpn::{Connection, Limits, Notice, SenderId, TimeVal};

struct Server {
    conn: Connection,
    port: u16,
    notices: Rc<RefCell<Vec<Notice>>>,
}

impl Server {
    fn new(limits: Limits) -> Server {
        let conn = Connection::server_with_limits(Some(Ipv4Addr::LOCALHOST), 0, limits).unwrap();
        let port = conn.local_port().unwrap();
        let notices = Rc::new(RefCell::new(Vec::new()));
        let n = notices.clone();
        conn.on_notice(move |x| n.borrow_mut().push(x.clone()));
        Server {
            conn,
            port,
            notices,
        }
    }

    fn pump_until(&self, what: &str, mut done: impl FnMut(&Server) -> bool) {
        let start = Instant::now();
        while !done(self) {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "timed out: {what}"
            );
            self.conn.mainloop().unwrap();
            let _ = self.conn.wait(Duration::from_millis(2));
        }
    }

    fn noticed(&self, text: &str) -> bool {
        self.notices.borrow().iter().any(|n| n.text.contains(text))
    }

    /// A raw TCP peer that completed the cookie exchange.
    fn raw_peer(&self) -> TcpStream {
        let before = self.conn.connected_peers();
        let mut s = TcpStream::connect((Ipv4Addr::LOCALHOST, self.port)).unwrap();
        s.write_all(&Cookie::ours(0).to_bytes()).unwrap();
        self.pump_until("handshake", |sv| sv.conn.connected_peers() > before);
        s
    }
}

fn message(type_id: i32, sender: i32, payload: &[u8]) -> Vec<u8> {
    let h = Header {
        payload_len: payload.len(),
        time: TimeVal::now(),
        sender,
        type_id,
        seq: 0,
    };
    let mut out = vec![0u8; h.wire_size()];
    encode_message(&mut out, &h, payload).unwrap();
    out
}

fn description(id: i32, is_sender: bool, name: &str) -> Vec<u8> {
    let mut p = ((name.len() + 1) as u32).to_be_bytes().to_vec();
    p.extend_from_slice(name.as_bytes());
    p.push(0);
    message(
        if is_sender {
            wire::system::SENDER_DESCRIPTION
        } else {
            wire::system::TYPE_DESCRIPTION
        },
        id,
        &p,
    )
}

/// True once the server closed `s` (EOF or reset), reading and discarding what it sent.
fn closed(s: &mut TcpStream) -> bool {
    s.set_nonblocking(true).unwrap();
    let mut buf = [0u8; 65536];
    loop {
        match s.read(&mut buf) {
            Ok(0) => return true,
            Ok(_) => continue,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => return false,
            Err(_) => return true,
        }
    }
}

#[test]
fn defaults_match_cpp() {
    let l = Limits::default();
    assert_eq!(l.max_message_payload, wire::MAX_TCP_PADDED_PAYLOAD);
    assert_eq!(l.max_names_per_peer, 2000);
    assert_eq!(l.max_connections, 255);
    assert_eq!(l.max_pending_output, 4 * 1024 * 1024);
}

#[test]
fn message_length_cap() {
    let sv = Server::new(Limits {
        max_message_payload: 1000,
        ..Limits::default()
    });
    let mut peer = sv.raw_peer();
    // At the cap: accepted.
    peer.write_all(&description(0, false, "big")).unwrap();
    peer.write_all(&message(0, 0, &[7; 1000])).unwrap();
    for _ in 0..20 {
        sv.conn.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(sv.conn.connected_peers(), 1, "{:?}", sv.notices.borrow());
    // Past it: dropped, with a notice naming the limit.
    peer.write_all(&message(0, 0, &[7; 1001])).unwrap();
    sv.pump_until("drop", |s| s.conn.connected_peers() == 0);
    assert!(sv.noticed("1001-byte message; the limit is 1000 bytes (Limits::max_message_payload)"));
    let start = Instant::now();
    while !closed(&mut peer) {
        assert!(start.elapsed() < Duration::from_secs(5));
        sv.conn.mainloop().unwrap();
    }
    // The server still serves.
    let _again = sv.raw_peer();
}

#[test]
fn names_per_peer_cap() {
    for is_sender in [true, false] {
        let sv = Server::new(Limits {
            max_names_per_peer: 10,
            ..Limits::default()
        });
        let mut peer = sv.raw_peer();
        for i in 0..10 {
            peer.write_all(&description(i, is_sender, &format!("name{i}")))
                .unwrap();
        }
        // Describing the same binding again does not count.
        peer.write_all(&description(3, is_sender, "name3")).unwrap();
        for _ in 0..20 {
            sv.conn.mainloop().unwrap();
            std::thread::sleep(Duration::from_millis(1));
        }
        assert_eq!(sv.conn.connected_peers(), 1, "{:?}", sv.notices.borrow());
        // Re-binding id 0 to an 11th name does.
        peer.write_all(&description(0, is_sender, "name10"))
            .unwrap();
        sv.pump_until("drop", |s| s.conn.connected_peers() == 0);
        let kind = if is_sender { "sender" } else { "type" };
        assert!(
            sv.noticed(&format!(
                "described more than 10 {kind} names (Limits::max_names_per_peer)"
            )),
            "{:?}",
            sv.notices.borrow()
        );
        // The 11th name never reached the server's table.
        if is_sender {
            assert!(sv.conn.peer_senders().iter().all(|n| n != "name10"));
        }
    }
}

#[test]
fn pending_output_cap() {
    let limit = 256 * 1024;
    let sv = Server::new(Limits {
        max_pending_output: limit,
        ..Limits::default()
    });
    let _stalled = sv.raw_peer(); // never reads
    let sender = sv.conn.register_sender("Flood").unwrap();
    let t = sv.conn.register_type("flood").unwrap();
    assert_eq!(sender, SenderId(1));
    let payload = [0u8; 1000];
    let start = Instant::now();
    let mut max_pending = 0;
    while sv.conn.connected_peers() > 0 {
        assert!(start.elapsed() < Duration::from_secs(10), "never dropped");
        for _ in 0..100 {
            sv.conn
                .pack_message(TimeVal::now(), t, sender, &payload, wire::class::RELIABLE)
                .unwrap();
        }
        max_pending = max_pending.max(sv.conn.pending_output());
        sv.conn.mainloop().unwrap();
    }
    assert!(max_pending <= limit, "{max_pending} > {limit}");
    assert!(sv.noticed(&format!(
        "is not reading: more than {limit} bytes of reliable output pending"
    )));
    assert_eq!(sv.conn.pending_output(), 0);
}

#[test]
fn connections_per_server_cap() {
    let sv = Server::new(Limits {
        max_connections: 2,
        ..Limits::default()
    });
    let _a = sv.raw_peer();
    let _b = sv.raw_peer();
    let mut c = TcpStream::connect((Ipv4Addr::LOCALHOST, sv.port)).unwrap();
    let _ = c.write_all(&Cookie::ours(0).to_bytes());
    let start = Instant::now();
    while !closed(&mut c) {
        assert!(start.elapsed() < Duration::from_secs(5), "third peer kept");
        sv.conn.mainloop().unwrap();
        std::thread::sleep(Duration::from_millis(1));
    }
    assert!(sv.noticed("2 clients already connected (limit)"));
    assert_eq!(sv.conn.connected_peers(), 2);
    // A slot frees when a peer leaves.
    drop(_a);
    sv.pump_until("drop", |s| s.conn.connected_peers() == 1);
    let _d = sv.raw_peer();
    assert_eq!(sv.conn.connected_peers(), 2);
}
