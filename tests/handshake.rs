//! Our handshake bytes against the C++ ones recorded in the golden captures.
//!
//! Each test plays the C++ peer from a capture over a real loopback socket and compares what
//! our side sends with what the C++ side sent in the same situation, byte for byte, masking only
//! what cannot match: timestamps, ephemeral ports, and padding (junk in C++).

use std::io::{Read, Write};
use std::net::{Ipv4Addr, TcpListener, TcpStream, UdpSocket};
use std::time::{Duration, Instant};

use serde_json::Value;
use vrpn::devices::base;
use vrpn::devices::tracker::{TrackerIds, TrackerNull};
use vrpn::{Connection, Limits};

fn fixture(name: &str) -> Vec<u8> {
    let p = format!(
        "{}/tests/fixtures/golden/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read(&p).unwrap_or_else(|e| panic!("{p}: {e}"))
}

fn expected(scenario: &str) -> Value {
    serde_json::from_slice(&fixture(&format!("{scenario}.expected.json"))).unwrap()
}

/// The system-message prefix of a stream: (end offset, per-byte "must match" mask).
fn description_prefix(stream: &Value, total_len: usize) -> (usize, Vec<bool>) {
    let mut mask = vec![true; total_len];
    let mut end = 24;
    for m in stream["messages"].as_array().unwrap() {
        if m.get("system").is_none() {
            break;
        }
        let off = m["offset"].as_u64().unwrap() as usize;
        let plen = m["payload_len"].as_u64().unwrap() as usize;
        let wire = m["wire_size"].as_u64().unwrap() as usize;
        for b in &mut mask[off + 4..off + 12] {
            *b = false; // timestamp
        }
        if m["system"] == "UDP_DESCRIPTION" {
            for b in &mut mask[off + 12..off + 16] {
                *b = false; // the ephemeral UDP port travels in the sender field
            }
        }
        for b in &mut mask[off + 24 + plen..off + wire] {
            *b = false; // padding
        }
        end = off + wire;
    }
    (end, mask)
}

fn assert_same(ours: &[u8], theirs: &[u8], mask: &[bool], what: &str) {
    assert!(
        ours.len() >= theirs.len(),
        "{what}: only {} of {} bytes",
        ours.len(),
        theirs.len()
    );
    for (i, (a, b)) in ours.iter().zip(theirs).enumerate() {
        if mask[i] && a != b {
            let start = i.saturating_sub(16);
            panic!(
                "{what}: byte {i} differs: ours {:02x?} C++ {:02x?}",
                &ours[start..(i + 16).min(ours.len())],
                &theirs[start..(i + 16).min(theirs.len())]
            );
        }
    }
}

/// Reads from `sock` while running `pump` until `want` bytes arrived.
fn read_while(sock: &mut TcpStream, want: usize, mut pump: impl FnMut()) -> Vec<u8> {
    sock.set_nonblocking(true).unwrap();
    let mut got = Vec::new();
    let mut buf = [0u8; 65536];
    let start = Instant::now();
    while got.len() < want && start.elapsed() < Duration::from_secs(10) {
        pump();
        match sock.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => got.extend_from_slice(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_micros(200))
            }
            Err(e) => panic!("read: {e}"),
        }
    }
    got
}

/// A server set up like the C++ `vrpn_server` of the captures: a NULL tracker, then the
/// forwarder's sender and types.
fn cpp_like_server() -> (Connection, TrackerNull) {
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let null = TrackerNull::new("Tracker0", &server, 2, 0.0).unwrap();
    server.register_sender("vrpn_Forwarder_Brain").unwrap();
    server
        .register_type("vrpn_Forwarder_Brain start_forwarding")
        .unwrap();
    server
        .register_type("vrpn_Forwarder_Brain forward")
        .unwrap();
    (server, null)
}

#[test]
fn server_handshake_matches_cpp_on_the_tcp_only_path() {
    let exp = expected("tracker_tcp_only");
    let conn_json = &exp["connections"][0];
    let golden_s2c = fixture("tracker_tcp_only.server_to_client.bin");
    let golden_c2s = fixture("tracker_tcp_only.client_to_server.bin");
    let (server, _null) = cpp_like_server();
    let port = server.local_port().unwrap();
    let mut sock = TcpStream::connect((Ipv4Addr::LOCALHOST, port)).unwrap();
    // Play the C++ client: its cookie and descriptions, as recorded.
    let (c2s_end, _) = description_prefix(&conn_json["client_to_server"], golden_c2s.len());
    sock.write_all(&golden_c2s[..c2s_end]).unwrap();
    let (end, mask) = description_prefix(&conn_json["server_to_client"], golden_s2c.len());
    let ours = read_while(&mut sock, end, || server.mainloop().unwrap());
    // The C++ server also described, as new types, the five names it learned from the client.
    assert_same(
        &ours[..end],
        &golden_s2c[..end],
        &mask,
        "server handshake (tcp-only)",
    );
    assert_eq!(server.connected_peers(), 1);
}

#[test]
fn server_handshake_matches_cpp_on_the_udp_request_path() {
    let exp = expected("tracker_udp_lob");
    let conn_json = &exp["connections"][0];
    let golden_s2c = fixture("tracker_udp_lob.server_to_client.bin");
    let (server, _null) = cpp_like_server();
    let port = server.local_port().unwrap();
    // Play the C++ client: listen for the call-back and send the request datagram.
    let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    listener.set_nonblocking(true).unwrap();
    let cb_port = listener.local_addr().unwrap().port();
    let lob = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    lob.send_to(
        format!("127.0.0.1 {cb_port}\0").as_bytes(),
        (Ipv4Addr::LOCALHOST, port),
    )
    .unwrap();
    let start = Instant::now();
    let mut sock = loop {
        server.mainloop().unwrap();
        if let Ok((s, _)) = listener.accept() {
            break s;
        }
        assert!(start.elapsed() < Duration::from_secs(5), "no call-back");
        std::thread::sleep(Duration::from_micros(200));
    };
    let golden_c2s = fixture("tracker_udp_lob.client_to_server.bin");
    let (c2s_end, _) = description_prefix(&conn_json["client_to_server"], golden_c2s.len());
    sock.write_all(&golden_c2s[..c2s_end]).unwrap();
    let (end, mask) = description_prefix(&conn_json["server_to_client"], golden_s2c.len());
    let ours = read_while(&mut sock, end, || server.mainloop().unwrap());
    assert_same(
        &ours[..end],
        &golden_s2c[..end],
        &mask,
        "server handshake (UDP path)",
    );
}

#[test]
fn client_handshake_matches_cpp_on_the_tcp_only_path() {
    let exp = expected("tracker_tcp_only");
    let conn_json = &exp["connections"][0];
    let golden_s2c = fixture("tracker_tcp_only.server_to_client.bin");
    let golden_c2s = fixture("tracker_tcp_only.client_to_server.bin");
    // Play the C++ server.
    let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    listener.set_nonblocking(true).unwrap();
    let port = listener.local_addr().unwrap().port();
    // Register what C++ vrpn_print_devices registers, in its order.
    let client = Connection::client("127.0.0.1", port, true, Limits::default()).unwrap();
    let sender = client.register_sender("Tracker0").unwrap();
    TrackerIds::register(&client).unwrap();
    base::register_base_types(&client, sender).unwrap();
    for t in [
        "vrpn_Analog Channel",
        "vrpn_Button Change",
        "vrpn_Button States",
        "vrpn_Button Admin",
        "vrpn_Dial update",
    ] {
        client.register_type(t).unwrap();
    }
    let start = Instant::now();
    let mut sock = loop {
        client.mainloop().unwrap();
        if let Ok((s, _)) = listener.accept() {
            break s;
        }
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "client did not connect"
        );
        std::thread::sleep(Duration::from_micros(200));
    };
    let (s2c_end, _) = description_prefix(&conn_json["server_to_client"], golden_s2c.len());
    sock.write_all(&golden_s2c[..s2c_end]).unwrap();
    let (end, mask) = description_prefix(&conn_json["client_to_server"], golden_c2s.len());
    let ours = read_while(&mut sock, end, || client.mainloop().unwrap());
    // Includes the echo of the server's forwarder names, described back with our new ids.
    assert_same(
        &ours[..end],
        &golden_c2s[..end],
        &mask,
        "client handshake (tcp-only)",
    );
}
