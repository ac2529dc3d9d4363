//! Hostile and broken peers: each is dropped with a clear message while a well-behaved client
//! of the same server keeps receiving reports.

use std::cell::{Cell, RefCell};
use std::io::{Read, Write};
use std::net::{Ipv4Addr, TcpStream, UdpSocket};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::wire::{header::encode_message, Header};
use vrpn::{Connection, Notice, ServerDevice, TimeVal, TrackerNull, TrackerRemote};

struct Rig {
    server: Connection,
    null: TrackerNull,
    client: TrackerRemote,
    poses: Rc<Cell<u64>>,
    notices: Rc<RefCell<Vec<Notice>>>,
    port: u16,
}

impl Rig {
    fn new() -> Rig {
        let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let port = server.local_port().unwrap();
        let null = TrackerNull::new("Tracker0", &server, 1, 500.0).unwrap();
        let notices = Rc::new(RefCell::new(Vec::new()));
        let n = notices.clone();
        server.on_notice(move |x| n.borrow_mut().push(x.clone()));
        let client = TrackerRemote::new(&format!("Tracker0@tcp://127.0.0.1:{port}")).unwrap();
        let poses = Rc::new(Cell::new(0));
        let p = poses.clone();
        client.on_pose(move |_| p.set(p.get() + 1));
        let mut rig = Rig {
            server,
            null,
            client,
            poses,
            notices,
            port,
        };
        rig.run_until(|r| r.poses.get() > 10);
        rig
    }

    fn step(&mut self) {
        self.null.mainloop(vrpn::Now::read());
        self.server.mainloop().unwrap();
        self.client.mainloop().unwrap();
    }

    fn run_until(&mut self, mut done: impl FnMut(&Rig) -> bool) {
        let start = Instant::now();
        while !done(self) {
            assert!(start.elapsed() < Duration::from_secs(10), "timed out");
            self.step();
            std::thread::sleep(Duration::from_micros(200));
        }
    }

    /// Connects a raw peer to the TCP port, sends `bytes`, and checks that the server drops it
    /// with a notice containing `expect`, while the good client keeps getting poses.
    fn hostile(&mut self, bytes: &[u8], expect: &str) {
        let mut bad = TcpStream::connect((Ipv4Addr::LOCALHOST, self.port)).unwrap();
        bad.write_all(bytes).unwrap();
        bad.set_nonblocking(true).unwrap();
        let before = self.notices.borrow().len();
        let closed = Rc::new(Cell::new(false));
        let start = Instant::now();
        let mut buf = [0u8; 4096];
        while !closed.get() {
            assert!(
                start.elapsed() < Duration::from_secs(10),
                "hostile peer not dropped"
            );
            self.step();
            match bad.read(&mut buf) {
                Ok(0) => closed.set(true),
                Ok(_) => {}
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(_) => closed.set(true),
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        let notices = self.notices.borrow();
        assert!(
            notices[before..].iter().any(|n| n.text.contains(expect)),
            "no notice containing {expect:?}: {:?}",
            &notices[before..]
        );
        drop(notices);
        let p = self.poses.get();
        self.run_until(|r| r.poses.get() > p + 10);
        assert_eq!(self.server.connected_peers(), 1);
    }
}

fn cookie(version: &[u8; 5], mode: u8) -> Vec<u8> {
    let mut c = b"vrpn: ver. ".to_vec();
    c.extend_from_slice(version);
    c.extend_from_slice(b"  ");
    c.push(mode);
    c.extend_from_slice(&[0; 5]);
    c
}

fn message(len_field: u32, type_id: i32, payload: &[u8]) -> Vec<u8> {
    let h = Header {
        payload_len: payload.len(),
        time: TimeVal::now(),
        sender: 0,
        type_id,
        seq: 0,
    };
    let mut out = vec![0u8; h.wire_size()];
    encode_message(&mut out, &h, payload).unwrap();
    out[0..4].copy_from_slice(&len_field.to_be_bytes());
    out
}

#[test]
fn wrong_major_version_is_refused() {
    Rig::new().hostile(&cookie(b"08.00", b'0'), "not a VRPN 07.x peer");
}

#[test]
fn bad_log_mode_is_refused() {
    Rig::new().hostile(&cookie(b"07.38", b'9'), "log mode");
}

#[test]
fn garbage_instead_of_a_cookie_is_refused() {
    Rig::new().hostile(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n", "bad cookie");
}

#[test]
fn length_field_too_short_is_refused() {
    let mut bytes = cookie(b"07.38", b'0');
    bytes.extend(message(12, 5, &[]));
    Rig::new().hostile(&bytes, "shorter than the 24-byte header");
}

#[test]
fn length_field_too_long_is_refused() {
    let mut bytes = cookie(b"07.38", b'0');
    bytes.extend(message(1_000_000, 5, &[0; 8]));
    Rig::new().hostile(&bytes, "exceeds the VRPN limit");
}

#[test]
fn oversized_name_is_refused() {
    let mut bytes = cookie(b"07.38", b'0');
    let name = "n".repeat(150);
    let mut payload = ((name.len() + 1) as u32).to_be_bytes().to_vec();
    payload.extend_from_slice(name.as_bytes());
    payload.push(0);
    bytes.extend(message((24 + payload.len()) as u32, -1, &payload));
    Rig::new().hostile(&bytes, "bad description");
}

#[test]
fn older_minor_version_is_accepted_with_a_note() {
    let mut rig = Rig::new();
    let mut peer = TcpStream::connect((Ipv4Addr::LOCALHOST, rig.port)).unwrap();
    peer.write_all(&cookie(b"07.35", b'0')).unwrap();
    rig.run_until(|r| r.server.connected_peers() == 2);
    assert!(rig
        .notices
        .borrow()
        .iter()
        .any(|n| n.text.contains("07.35") && n.text.contains("not normally a problem")));
}

#[test]
fn bad_connection_requests_and_truncated_datagrams_are_ignored() {
    let mut rig = Rig::new();
    let udp = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    for junk in [
        &b"evil-host 5000\0"[..],
        b"127.0.0.1 80\0",
        b"\xff\xfe\x00",
        b"",
        &[0u8; 199],
    ] {
        udp.send_to(junk, (Ipv4Addr::LOCALHOST, rig.port)).unwrap();
    }
    let p = rig.poses.get();
    rig.run_until(|r| r.poses.get() > p + 20);
    assert!(rig
        .notices
        .borrow()
        .iter()
        .any(|n| n.text.contains("bad connection request")));
    assert_eq!(rig.server.connected_peers(), 1);
}

#[test]
fn peer_that_dies_mid_message_is_dropped_cleanly() {
    let mut rig = Rig::new();
    let mut bytes = cookie(b"07.38", b'0');
    let m = message(24 + 64, 5, &[7; 64]);
    bytes.extend_from_slice(&m[..40]);
    let mut peer = TcpStream::connect((Ipv4Addr::LOCALHOST, rig.port)).unwrap();
    peer.write_all(&bytes).unwrap();
    rig.run_until(|r| r.server.connected_peers() == 2);
    drop(peer);
    rig.run_until(|r| r.server.connected_peers() == 1);
    let p = rig.poses.get();
    rig.run_until(|r| r.poses.get() > p + 10);
}

#[test]
fn remote_logging_requests_are_refused_without_writing_files() {
    let mut rig = Rig::new();
    let target = std::env::temp_dir().join(format!("vrpn-remote-log-{}.vrpn", std::process::id()));
    let _ = std::fs::remove_file(&target);
    let name = target.to_str().unwrap();
    let mut bytes = cookie(b"07.38", b'1');
    let mut payload = (name.len() as i32).to_be_bytes().to_vec();
    payload.extend_from_slice(&0i32.to_be_bytes());
    payload.extend_from_slice(name.as_bytes());
    payload.extend_from_slice(&[0, 0]);
    bytes.extend(message((24 + payload.len()) as u32, -4, &payload));
    let mut peer = TcpStream::connect((Ipv4Addr::LOCALHOST, rig.port)).unwrap();
    peer.write_all(&bytes).unwrap();
    rig.run_until(|r| {
        r.notices
            .borrow()
            .iter()
            .any(|n| n.text.contains("remote logging requests are refused"))
    });
    assert!(
        !target.exists(),
        "no file may be created for a remote request"
    );
    assert_eq!(rig.server.connected_peers(), 2);
}
