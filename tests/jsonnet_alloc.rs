//! vrpn_Tracker_JsonNet reads datagrams without allocating: the device on a real UDP socket, a
//! client's tracker, button, analog and text remotes over TCP, datagrams of every message type
//! with refused ones between them. A counting global allocator covers every pass of the
//! device, the server and the client once the first of each kind has been heard. Datagrams
//! that are not JSON, and unknown fields holding nested arrays or objects, cost serde_json one
//! allocation each (its error value; its stack for skipping): that bound is checked too.

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::cell::Cell;
use std::net::{Ipv4Addr, UdpSocket};
use std::rc::Rc;
use std::time::{Duration, Instant};

use counting_alloc::{COUNT, ENABLED};
use vrpn::drivers::jsonnet::{JsonNet, JsonNetDevice};
use vrpn::net::Reactor;
use vrpn::ServerDevice;
use vrpn::{AnalogRemote, ButtonRemote, Connection, Limits, Now, TextReceiver, TrackerRemote};

/// The datagrams of round `k`, written into `out` (the sender's buffers are not counted).
fn round(k: u32, out: &mut Vec<Vec<u8>>) {
    let x = f64::from(k) * 0.001;
    out.clear();
    out.push(
        format!(
            r#"{{"type":1,"id":{},"quat":[0,0,0.6,0.8],"pos":[{x},1.5,-2.25e-1]}}"#,
            k % 3
        )
        .into_bytes(),
    );
    out.push(
        format!(
            r#"{{"type":2,"button":{},"state":{}}}"#,
            k % 4,
            (k / 4) % 2 == 0
        )
        .into_bytes(),
    );
    out.push(format!(r#"{{"type":3,"num":{},"data":{x}}}"#, k % 5).into_bytes());
    out.push(format!(r#"{{"type":4,"data":"round {k}"}}"#).into_bytes());
    out.push(format!(r#"{{"type":4,"data":{x}}}"#).into_bytes());
    out.push(br#"{"type":1,"id":"x"} "#.to_vec());
    out.push(br#"{"type":9,"data":"unknown type","extra":7}"#.to_vec());
}

/// Datagrams serde_json allocates once for.
const ONE_ALLOCATION: [&[u8]; 2] = [
    b"not json \x00 [[",
    br#"{"type":2,"button":1,"state":true,"extra":{"a":[1,{"b":null}]}}"#,
];

#[test]
fn json_datagrams_stream_without_allocating() {
    vrpn::devices::base::set_print_threshold(vrpn::TextSeverity::Other(u32::MAX));
    let reactor = Reactor::new().unwrap();
    let server =
        Connection::server_in(&reactor, Some(Ipv4Addr::LOCALHOST), 0, Limits::default()).unwrap();
    let client = Connection::client_in(
        &reactor,
        "127.0.0.1",
        server.local_port().unwrap(),
        false,
        Limits::default(),
    )
    .unwrap();
    let cfg = JsonNet {
        name: "JN".into(),
        port: 0,
    };
    let mut device = JsonNetDevice::new(&cfg, &server).unwrap();
    let to = (Ipv4Addr::LOCALHOST, device.local_port());
    let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
    let tracker = TrackerRemote::on_connection("JN", &client).unwrap();
    let button = ButtonRemote::on_connection("JN", &client).unwrap();
    let analog = AnalogRemote::on_connection("JN", &client).unwrap();
    let text = TextReceiver::on_connection("JN", &client).unwrap();
    let counts: [Rc<Cell<u64>>; 4] = Default::default();
    let c = counts.clone();
    tracker.on_pose(move |_| c[0].set(c[0].get() + 1));
    let c = counts.clone();
    button.on_change(move |_| c[1].set(c[1].get() + 1));
    let c = counts.clone();
    analog.on_report(move |_| c[2].set(c[2].get() + 1));
    let c = counts.clone();
    text.on_message(move |_| c[3].set(c[3].get() + 1));
    let seen = || counts.each_ref().map(|c| c.get());

    let pass = |device: &mut JsonNetDevice, counting: bool| {
        ENABLED.with(|e| e.set(counting));
        device.mainloop(Now::read());
        server.mainloop().unwrap();
        client.mainloop().unwrap();
        ENABLED.with(|e| e.set(false));
        reactor
            .wait(device.next_deadline(), Duration::from_millis(1))
            .unwrap();
    };
    let mut datagrams = Vec::new();
    // Warm up: connect, hear every kind of message.
    let start = Instant::now();
    let mut k = 0;
    while seen().iter().any(|&n| n < 10) {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "heard {:?}",
            seen()
        );
        k += 1;
        round(k, &mut datagrams);
        for d in &datagrams {
            sender.send_to(d, to).unwrap();
        }
        for _ in 0..5 {
            pass(&mut device, false);
        }
    }
    let before = seen();
    let stats_before = device.stats();
    COUNT.with(|c| c.set(0));
    for _ in 0..200 {
        k += 1;
        round(k, &mut datagrams);
        for d in &datagrams {
            sender.send_to(d, to).unwrap();
        }
        for _ in 0..3 {
            pass(&mut device, true);
        }
    }
    let start = Instant::now();
    while device.stats().datagrams < stats_before.datagrams + 1400
        && start.elapsed() < Duration::from_secs(10)
    {
        pass(&mut device, true);
    }
    for _ in 0..20 {
        pass(&mut device, true);
    }
    let after = seen();
    let stats = device.stats();
    assert_eq!(stats.datagrams, stats_before.datagrams + 1400, "{stats:?}");
    assert!(stats.rejected >= stats_before.rejected + 400, "{stats:?}");
    for i in 0..4 {
        assert!(after[i] >= before[i] + 150, "{before:?} → {after:?}");
    }
    assert_eq!(COUNT.with(Cell::get), 0, "allocations while streaming");

    // Malformed datagrams and nested unknown fields: at most one allocation each.
    COUNT.with(|c| c.set(0));
    let before = device.stats();
    for _ in 0..100 {
        for d in ONE_ALLOCATION {
            sender.send_to(d, to).unwrap();
        }
        pass(&mut device, true);
    }
    let start = Instant::now();
    while device.stats().datagrams < before.datagrams + 200
        && start.elapsed() < Duration::from_secs(10)
    {
        pass(&mut device, true);
    }
    let stats = device.stats();
    assert_eq!(stats.datagrams, before.datagrams + 200, "{stats:?}");
    assert_eq!(stats.malformed, before.malformed + 100, "{stats:?}");
    let n = COUNT.with(Cell::get);
    assert!(n <= 200, "{n} allocations for 200 such datagrams");
}
