//! A relay passes reports down and pings up without allocating, once every type has been seen:
//! checked with a counting global allocator while a tracker streams through a relay to a
//! client over loopback TCP, and the client pings it.

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::cell::Cell;
use std::net::Ipv4Addr;
use std::time::{Duration, Instant};

use counting_alloc::allocations_in;
use vrpn::devices::ServerDevice;
use vrpn::forward::Relay;
use vrpn::wire::class;
use vrpn::{Connection, Now, SenderFilter, TimeVal, TrackerRemote, TrackerServer};

#[test]
fn relaying_does_not_allocate() {
    let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server.local_port().unwrap();
    let tracker = TrackerServer::new("Tracker0", &server, 2).unwrap();
    let relay_conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let relay_port = relay_conn.local_port().unwrap();
    let mut relay = Relay::new(&relay_conn, &format!("Tracker0@127.0.0.1:{port}"), None).unwrap();
    let remote = TrackerRemote::new(&format!("Tracker0@127.0.0.1:{relay_port}")).unwrap();
    let client = remote.connection().clone();
    let ping = client.register_type("vrpn_Base ping_message").unwrap();
    let me = client.register_sender("Tracker0").unwrap();
    let pong = client.register_type("vrpn_Base pong_message").unwrap();
    let pongs = std::rc::Rc::new(Cell::new(0u64));
    let p = pongs.clone();
    client.register_handler(pong, SenderFilter::Only(me), move |_| p.set(p.get() + 1));
    let pass = |relay: &mut Relay| {
        server.mainloop().unwrap();
        relay_conn.mainloop().unwrap();
        relay.mainloop(Now::read());
        remote.mainloop().unwrap();
    };
    let start = Instant::now();
    while !(client.connected() && relay.upstream().connected()) {
        assert!(start.elapsed() < Duration::from_secs(10));
        pass(&mut relay);
    }
    let quat = [0.0, 0.0, 0.0, 1.0];
    let step = |relay: &mut Relay, i: u64| {
        tracker
            .report_pose((i % 2) as i32, TimeVal::now(), [1.0, 2.0, 3.0], quat)
            .unwrap();
        if i % 10 == 0 {
            let _ = client.pack_message(TimeVal::now(), ping, me, &[], class::RELIABLE);
        }
        pass(relay);
    };
    // Warm up: every type and name seen, buffers at their working size.
    let mut i = 0;
    while remote.pose_count(1) < 500 || pongs.get() < 20 {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "relay warm-up stalled"
        );
        step(&mut relay, i);
        i += 1;
    }
    let (poses, pongs_before) = (remote.pose_count(0) + remote.pose_count(1), pongs.get());
    let allocs = allocations_in(|| {
        for j in 0..5_000 {
            step(&mut relay, i + j);
        }
        for _ in 0..200 {
            pass(&mut relay);
        }
    });
    let relayed = remote.pose_count(0) + remote.pose_count(1) - poses;
    assert!(relayed > 4_000, "only {relayed} poses relayed");
    assert!(pongs.get() > pongs_before + 100, "pongs did not come back");
    assert_eq!(allocs, 0, "{allocs} allocations relaying {relayed} poses");
}
