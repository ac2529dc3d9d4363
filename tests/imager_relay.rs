//! The imager relay (`vrpn_Imager_Stream_Buffer`): a client of the relay sees the upstream
//! imager's description and frames, throttles the relay, and the relay drops whole frames
//! with a notice; in process and as a `vrpn_server` keyword, on 127.0.0.1.

mod common;

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::imager::{BufferLayout, Extent, ImagerRelay, ImagerRemote, ImagerServer};
use vrpn::devices::ServerDevice;
use vrpn::Connection;

const COLS: usize = 64;
const ROWS: usize = 32;

fn upstream() -> (Connection, ImagerServer, u16) {
    let conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    conn.on_notice(|_| {});
    let port = conn.local_port().unwrap();
    let server = ImagerServer::new("Cam0", &conn, COLS as i32, ROWS as i32, 1).unwrap();
    server
        .add_channel("gray", "counts", 0.0, 255.0, 1.0, 0.0)
        .unwrap();
    server
        .add_channel("depth", "mm", 0.0, 4096.0, 0.5, 0.0)
        .unwrap();
    (conn, server, port)
}

fn send_frame(server: &ImagerServer, n: u8) -> Vec<u8> {
    let image: Vec<u8> = (0..COLS * ROWS)
        .map(|i| (i as u8).wrapping_add(n))
        .collect();
    let whole = Extent::whole(COLS as u16, ROWS as u16, 1);
    assert!(server.send_begin_frame(&whole, None).unwrap());
    for r0 in [0u16, 16] {
        let e = Extent::rect(0, COLS as u16 - 1, r0, r0 + 15);
        server
            .send_region(0, &e, &image, &BufferLayout::packed(COLS, ROWS), None)
            .unwrap();
    }
    server.send_end_frame(&whole, None).unwrap();
    image
}

/// A client of the relay that assembles channel 0 and logs frame ends and discards.
struct Client {
    remote: ImagerRemote,
    image: Rc<RefCell<Vec<u8>>>,
    events: Rc<RefCell<Vec<String>>>,
}

impl Client {
    fn new(name: &str) -> Client {
        let remote = ImagerRemote::new(name).unwrap();
        remote.connection().on_notice(|_| {});
        let image = Rc::new(RefCell::new(vec![0u8; COLS * ROWS]));
        let events = Rc::new(RefCell::new(Vec::new()));
        let i = image.clone();
        remote.on_region(move |r| {
            if r.channel == 0 {
                r.read_into(&mut i.borrow_mut()[..], &BufferLayout::packed(COLS, ROWS))
                    .unwrap();
            }
        });
        let e = events.clone();
        remote.on_end_frame(move |_| e.borrow_mut().push("end".into()));
        let e = events.clone();
        remote.on_discarded_frames(move |d| e.borrow_mut().push(format!("discarded {}", d.count)));
        Client {
            remote,
            image,
            events,
        }
    }
}

#[test]
fn a_relay_in_process_forwards_and_throttles() {
    let (up_conn, up, up_port) = upstream();
    let relay_conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    relay_conn.on_notice(|_| {});
    let relay_port = relay_conn.local_port().unwrap();
    let mut relay =
        ImagerRelay::new("Relay0", &relay_conn, &format!("Cam0@127.0.0.1:{up_port}")).unwrap();
    assert!(!relay.upstream_open());
    let client = Client::new(&format!("Relay0@127.0.0.1:{relay_port}"));
    let cli = client.remote.connection().clone();
    let mut step = |relay: &mut ImagerRelay| {
        up_conn.mainloop().unwrap();
        relay.mainloop(relay_conn.now());
        relay_conn.mainloop().unwrap();
        cli.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(300));
    };
    let until =
        |relay: &mut ImagerRelay, step: &mut dyn FnMut(&mut ImagerRelay), f: &dyn Fn() -> bool| {
            let start = Instant::now();
            while !f() {
                assert!(start.elapsed() < Duration::from_secs(10), "timed out");
                step(relay);
            }
        };
    // The first client opens the upstream; its description becomes the relay's.
    until(&mut relay, &mut step, &|| {
        client.remote.description().is_some_and(|d| d.channels == 2)
    });
    assert!(relay.upstream_open() && relay.upstream_described());
    let d = client.remote.description().unwrap();
    assert_eq!((d.cols, d.rows, d.depth), (COLS as i32, ROWS as i32, 1));
    assert_eq!(client.remote.channel(1).unwrap().units.as_str(), Some("mm"));
    // Frames pass through whole.
    let img = send_frame(&up, 1);
    until(&mut relay, &mut step, &|| client.events.borrow().len() == 1);
    assert_eq!(*client.image.borrow(), img);
    // Throttled to one frame: one passes, the next three are dropped, then a notice.
    client.remote.throttle_sender(1).unwrap();
    for _ in 0..50 {
        step(&mut relay);
    }
    for n in 2..6 {
        send_frame(&up, n);
        for _ in 0..20 {
            step(&mut relay);
        }
    }
    until(&mut relay, &mut step, &|| client.events.borrow().len() == 2);
    assert_eq!(relay.frames_dropped(), 3);
    client.remote.throttle_sender(-1).unwrap();
    for _ in 0..50 {
        step(&mut relay);
    }
    let img = send_frame(&up, 9);
    until(&mut relay, &mut step, &|| client.events.borrow().len() == 4);
    assert_eq!(
        *client.events.borrow(),
        ["end", "end", "discarded 3", "end"]
    );
    assert_eq!(*client.image.borrow(), img);
    // The last client leaving closes the upstream connection.
    drop(client);
    drop(cli);
    let start = Instant::now();
    while relay.upstream_open() {
        assert!(start.elapsed() < Duration::from_secs(10));
        up_conn.mainloop().unwrap();
        relay.mainloop(relay_conn.now());
        relay_conn.mainloop().unwrap();
        std::thread::sleep(Duration::from_micros(300));
    }
}

#[test]
fn vrpn_server_relays_with_the_cpp_keyword() {
    let (up_conn, up, up_port) = upstream();
    let cfg = format!("vrpn_Imager_Stream_Buffer Relay0 Cam0@127.0.0.1:{up_port}\n");
    let server = common::start_server(&cfg, 0);
    let client = Client::new(&format!("Relay0@127.0.0.1:{}", server.port));
    let cli = client.remote.connection().clone();
    let pump = |f: &dyn Fn() -> bool| {
        let start = Instant::now();
        while !f() {
            assert!(start.elapsed() < Duration::from_secs(15), "timed out");
            up_conn.mainloop().unwrap();
            cli.mainloop().unwrap();
            std::thread::sleep(Duration::from_micros(500));
        }
    };
    pump(&|| client.remote.description().is_some_and(|d| d.channels == 2));
    let mut last = Vec::new();
    for n in 0..5 {
        last = send_frame(&up, n);
        pump(&|| client.events.borrow().len() == n as usize + 1);
    }
    assert_eq!(*client.image.borrow(), last);
    assert_eq!(client.remote.bad_messages(), 0);
}
