//! Latency a relay adds: a client's ping to a tracker and the tracker's pong, straight to the
//! tracker's server (the baseline: `Tracker1`) and through a `Relay` that re-serves a tracker
//! of the same server (`Tracker0`), in the same run. Everything spins in one thread over loopback TCP, as `round_trip` does, so the
//! figures are the processing and the extra hop, without scheduler wake-ups.
//!
//! Rounds alternate between the two paths, so that load from other processes affects both.

mod common;

use std::cell::Cell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::Duration;

use common::{spin_until, Samples};
use vrpn::devices::ServerDevice;
use vrpn::forward::Relay;
use vrpn::wire::class;
use vrpn::{Connection, Limits, Now, SenderFilter, TimeVal, TrackerServer};

const N: usize = 5_000;
const ROUNDS: usize = 10;
const LIMIT: Duration = Duration::from_secs(5);

/// A client that pings `device` at `port` and notes each pong from it.
struct Pinger {
    conn: Connection,
    ping: (vrpn::TypeId, vrpn::SenderId),
    answered: Rc<Cell<bool>>,
}

impl Pinger {
    fn new(port: u16, device: &str) -> Pinger {
        let conn = Connection::client("127.0.0.1", port, true, Limits::default()).unwrap();
        let dev = conn.register_sender(device).unwrap();
        let ping = conn.register_type("vrpn_Base ping_message").unwrap();
        let pong = conn.register_type("vrpn_Base pong_message").unwrap();
        let answered = Rc::new(Cell::new(false));
        let a = answered.clone();
        conn.register_handler(pong, SenderFilter::Only(dev), move |_| a.set(true));
        Pinger {
            conn,
            ping: (ping, dev),
            answered,
        }
    }
}

struct Rig {
    server: Connection,
    _trackers: [TrackerServer; 2],
    relay_conn: Connection,
    relay: std::cell::RefCell<Relay>,
    direct: Pinger,
    relayed: Pinger,
}

impl Rig {
    fn new() -> Rig {
        let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let port = server.local_port().unwrap();
        // Two trackers, so that a pong of one path never ends a round trip of the other (a
        // server sends every message to every client, the relay included).
        let relayed_tracker = TrackerServer::new("Tracker0", &server, 1).unwrap();
        let direct_tracker = TrackerServer::new("Tracker1", &server, 1).unwrap();
        let relay_conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let relay_port = relay_conn.local_port().unwrap();
        let relay = Relay::new(
            &relay_conn,
            &format!("Tracker0@tcp://127.0.0.1:{port}"),
            None,
        )
        .unwrap();
        let rig = Rig {
            direct: Pinger::new(port, "Tracker1"),
            relayed: Pinger::new(relay_port, "Tracker0"),
            server,
            _trackers: [relayed_tracker, direct_tracker],
            relay_conn,
            relay: std::cell::RefCell::new(relay),
        };
        spin_until(LIMIT, || {
            rig.pass();
            rig.direct.conn.connected()
                && rig.relayed.conn.connected()
                && rig.relay.borrow().upstream().connected()
        });
        for _ in 0..500 {
            rig.round_trip(&rig.direct);
            rig.round_trip(&rig.relayed);
        }
        rig
    }

    /// One turn of every loop: the two clients, the relay, the tracker's server.
    fn pass(&self) {
        self.direct.conn.mainloop().unwrap();
        self.relayed.conn.mainloop().unwrap();
        self.relay_conn.mainloop().unwrap();
        self.relay.borrow_mut().mainloop(Now::read());
        self.server.mainloop().unwrap();
    }

    fn round_trip(&self, p: &Pinger) {
        p.answered.set(false);
        let (t, s) = p.ping;
        p.conn
            .pack_message(TimeVal::now(), t, s, &[], class::RELIABLE)
            .unwrap();
        spin_until(LIMIT, || {
            self.pass();
            p.answered.get()
        });
    }
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let rig = Rig::new();
    let mut direct = Vec::with_capacity(N * ROUNDS);
    let mut relayed = Vec::with_capacity(N * ROUNDS);
    for _ in 0..ROUNDS {
        for (pinger, out) in [(&rig.direct, &mut direct), (&rig.relayed, &mut relayed)] {
            for _ in 0..N {
                let t = std::time::Instant::now();
                rig.round_trip(pinger);
                out.push(t.elapsed().as_nanos() as u64);
            }
        }
    }
    let direct = Samples::from_ns("ping→pong straight to the server (TCP)", direct);
    let relayed = Samples::from_ns("ping→pong through a relay (TCP)", relayed);
    direct.print_us();
    relayed.print_us();
    let added = relayed.median() as f64 - direct.median() as f64;
    println!(
        "    relay adds p50 {:.2} µs per round trip ({:.2} µs each way); ratio p50 {:.2}×",
        added / 1e3,
        added / 2e3,
        relayed.median() as f64 / direct.median() as f64
    );
    let r = rig.relay.borrow();
    println!(
        "    relayed down {} messages, up {} (pings)",
        r.relayed_down().forwarded,
        r.relayed_up().forwarded
    );
}
