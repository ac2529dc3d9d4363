//! vrpn_Tracker_DTrack reports without allocating: a server with the DTrack device on a real
//! UDP socket, a client's tracker, button and analog remotes over TCP, frames of every line
//! type with garbage and late frames between them. A counting global allocator covers every
//! pass of the server and the client once the targets have been seen (the first frames size
//! the target lists).

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::cell::Cell;
use std::net::{Ipv4Addr, SocketAddr};
use std::rc::Rc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use counting_alloc::{COUNT, ENABLED};
use vrpn::drivers::dtrack::config::{DTrack, Source};
use vrpn::drivers::dtrack::sim::{Controller, Frame};
use vrpn::drivers::dtrack::DTrackDevice;
use vrpn::net::Reactor;
use vrpn::ServerDevice;
use vrpn::{AnalogRemote, ButtonRemote, Connection, Limits, Now, TrackerRemote};

fn frame(k: u32) -> Vec<u8> {
    let d = SystemTime::now().duration_since(UNIX_EPOCH).unwrap();
    Frame::standard(k, d.as_secs() as u32, d.subsec_micros())
        .text()
        .into_bytes()
}

#[test]
fn dtrack_frames_stream_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let reactor = Reactor::new().unwrap();
    let server =
        Connection::server_in(&reactor, Some(Ipv4Addr::LOCALHOST), 0, Limits::default()).unwrap();
    let port = server.local_port().unwrap();
    let client =
        Connection::client_in(&reactor, "127.0.0.1", port, false, Limits::default()).unwrap();
    let cfg = DTrack {
        name: "DT".into(),
        source: Source::Port(0),
        time_to_reach_joy: 0.0,
        fixed: None,
        markers: true,
        tracing: false,
    };
    let mut device = DTrackDevice::new(&cfg, &server).unwrap();
    let ctl =
        Controller::new(SocketAddr::from((Ipv4Addr::LOCALHOST, device.local_port()))).unwrap();
    let tracker = TrackerRemote::on_connection("DT", &client).unwrap();
    let button = ButtonRemote::on_connection("DT", &client).unwrap();
    let analog = AnalogRemote::on_connection("DT", &client).unwrap();
    let poses = Rc::new(Cell::new(0u64));
    let (p, b, a) = (
        poses.clone(),
        Rc::new(Cell::new(0u64)),
        Rc::new(Cell::new(0u64)),
    );
    tracker.on_pose(move |_| p.set(p.get() + 1));
    let bc = b.clone();
    button.on_change(move |_| bc.set(bc.get() + 1));
    let ac = a.clone();
    analog.on_report(move |_| ac.set(ac.get() + 1));

    let mut pass = |counting: bool| {
        ENABLED.with(|e| e.set(counting));
        device.mainloop(Now::read());
        server.mainloop().unwrap();
        client.mainloop().unwrap();
        ENABLED.with(|e| e.set(false));
        reactor
            .wait(device.next_deadline(), Duration::from_millis(1))
            .unwrap();
    };
    // Warm up: connect, see every target (markers 0..2), fill the queues once.
    let start = Instant::now();
    let mut k = 1;
    while poses.get() < 50 {
        assert!(start.elapsed() < Duration::from_secs(10), "no poses");
        ctl.send(&frame(k)).unwrap();
        k += 1;
        for _ in 0..5 {
            pass(false);
        }
    }
    let before = (poses.get(), b.get(), a.get());
    COUNT.with(|c| c.set(0));
    for _ in 0..200 {
        ctl.send(&frame(k)).unwrap();
        ctl.send(b"garbage \x00 [[").unwrap();
        ctl.send(&frame(k - 3)).unwrap();
        k += 1;
        for _ in 0..5 {
            pass(true);
        }
    }
    let start = Instant::now();
    while poses.get() < before.0 + 600 && start.elapsed() < Duration::from_secs(10) {
        pass(true);
    }
    let after = (poses.get(), b.get(), a.get());
    assert!(after.0 >= before.0 + 600, "poses {before:?} → {after:?}");
    assert!(
        after.1 > before.1 && after.2 > before.2,
        "{before:?} → {after:?}"
    );
    let stats = device.stats();
    assert!(
        stats.malformed >= 100 && stats.out_of_order >= 100,
        "{stats:?}"
    );
    assert_eq!(COUNT.with(Cell::get), 0, "allocations while streaming");
}
