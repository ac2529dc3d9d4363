//! Once a connection is up and its names are registered, sending, receiving and dispatching
//! allocate nothing: checked with a counting global allocator on every transport (in-process,
//! TCP-only, UDP+TCP), in both directions, and for idle `mainloop()` calls.

#[path = "common/counting_alloc.rs"]
mod counting_alloc;

use std::cell::Cell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use counting_alloc::allocations_in;
use vrpn::wire::class;
use vrpn::{Connection, SenderFilter, TimeVal, TrackerRemote, TrackerServer};

const N: u64 = 10_000;
const IDENTITY: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

fn counter() -> Rc<Cell<u64>> {
    Rc::new(Cell::new(0))
}

fn bump(c: &Rc<Cell<u64>>) -> impl FnMut() + 'static {
    let c = c.clone();
    move || c.set(c.get() + 1)
}

/// `OutDatagrams` of this network namespace (`/proc/net/snmp`): evidence that UDP was used.
fn udp_out_datagrams() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/net/snmp").ok()?;
    let mut lines = text.lines().filter(|l| l.starts_with("Udp:"));
    let names = lines.next()?;
    let values = lines.next()?;
    let col = names.split_whitespace().position(|n| n == "OutDatagrams")?;
    values.split_whitespace().nth(col)?.parse().ok()
}

#[test]
fn in_process_reports_do_not_allocate() {
    let conn = Connection::new_loopback();
    let server = TrackerServer::new("Tracker0", &conn, 2).unwrap();
    let remote = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let poses = counter();
    let mut hit = bump(&poses);
    remote.on_pose(move |_| hit());
    // A raw handler of a user type, sent with pack_message.
    let sender = conn.register_sender("raw sender").unwrap();
    let raw_type = conn.register_type("zero_alloc raw").unwrap();
    let raws = counter();
    let mut hit = bump(&raws);
    conn.register_handler(raw_type, SenderFilter::Only(sender), move |_| hit());

    for i in 0..500 {
        server
            .report_pose(i % 2, TimeVal::now(), [1.0, 2.0, 3.0], IDENTITY)
            .unwrap();
        conn.pack_message(TimeVal::now(), raw_type, sender, &[7; 16], class::RELIABLE)
            .unwrap();
        remote.mainloop().unwrap();
    }
    let (p0, r0) = (poses.get(), raws.get());
    let allocs = allocations_in(|| {
        for i in 0..N {
            server
                .report_pose((i % 2) as i32, TimeVal::now(), [1.0, 2.0, 3.0], IDENTITY)
                .unwrap();
            conn.pack_message(TimeVal::now(), raw_type, sender, &[7; 16], class::RELIABLE)
                .unwrap();
            if i % 10 == 0 {
                remote.mainloop().unwrap();
            }
        }
        for _ in 0..1000 {
            conn.mainloop().unwrap();
            remote.mainloop().unwrap();
        }
    });
    assert_eq!(poses.get() - p0, N, "every pose delivered");
    assert_eq!(raws.get() - r0, N, "every raw message delivered");
    assert_eq!(allocs, 0, "allocations while reporting in-process");
}

/// A tracker server and a remote on real sockets, plus a user type the client sends to the
/// server, so that both directions are exercised.
struct Net {
    server_conn: Connection,
    server: TrackerServer,
    remote: TrackerRemote,
    poses: Rc<Cell<u64>>,
    c2s: Rc<Cell<u64>>,
    c2s_type: vrpn::TypeId,
    c2s_sender: vrpn::SenderId,
    pongs: Rc<Cell<u64>>,
    ping_type: vrpn::TypeId,
    tracker: vrpn::SenderId,
}

impl Net {
    fn new(name_fmt: &str) -> Net {
        let server_conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let port = server_conn.local_port().unwrap();
        let server = TrackerServer::new("Tracker0", &server_conn, 2).unwrap();
        let s_type = server_conn.register_type("zero_alloc c2s").unwrap();
        let c2s = counter();
        let mut hit = bump(&c2s);
        server_conn.register_handler(s_type, SenderFilter::Any, move |m| {
            assert_eq!(m.payload.len(), 16);
            hit()
        });
        let remote = TrackerRemote::new(&name_fmt.replace("PORT", &port.to_string())).unwrap();
        let poses = counter();
        let mut hit = bump(&poses);
        remote.on_pose(move |_| hit());
        let c2s_sender = remote
            .connection()
            .register_sender("zero_alloc client")
            .unwrap();
        let c2s_type = remote.connection().register_type("zero_alloc c2s").unwrap();
        // Pings from the device's sender, answered by the server from inside its handler (the
        // deferred-delivery path), come back as pongs.
        let client = remote.connection();
        let tracker = client.register_sender("Tracker0").unwrap();
        let ping_type = client.register_type("vrpn_Base ping_message").unwrap();
        let pong_type = client.register_type("vrpn_Base pong_message").unwrap();
        let pongs = counter();
        let mut hit = bump(&pongs);
        client.register_handler(pong_type, SenderFilter::Only(tracker), move |_| hit());
        Net {
            server_conn,
            server,
            remote,
            poses,
            c2s,
            c2s_type,
            c2s_sender,
            pongs,
            ping_type,
            tracker,
        }
    }

    fn step(&self, i: u64, c2s_class: u32) {
        self.server
            .report_pose((i % 2) as i32, TimeVal::now(), [1.0, 2.0, 3.0], IDENTITY)
            .unwrap();
        self.remote
            .connection()
            .pack_message(
                TimeVal::now(),
                self.c2s_type,
                self.c2s_sender,
                &[9; 16],
                c2s_class,
            )
            .unwrap();
        if i % 100 == 0 {
            self.remote
                .connection()
                .pack_message(
                    TimeVal::now(),
                    self.ping_type,
                    self.tracker,
                    &[],
                    class::RELIABLE,
                )
                .unwrap();
        }
        self.server_conn.mainloop().unwrap();
        self.remote.mainloop().unwrap();
    }

    /// Connects, lets the ping cycle finish and exchanges a few hundred messages each way.
    fn warm_up(&self, c2s_class: u32) {
        let start = Instant::now();
        while !self.remote.connection().connected() {
            assert!(start.elapsed() < Duration::from_secs(10), "no connection");
            self.server_conn.mainloop().unwrap();
            self.remote.mainloop().unwrap();
            std::thread::sleep(Duration::from_micros(200));
        }
        // Unreliable messages keep to TCP for a while after the descriptions
        // (Limits::udp_after_descriptions, or until the peer answers a clock query): the
        // warm-up runs past that, so that the measurement covers the path under test (the UDP
        // test counts the datagrams that went out).
        let connected = Instant::now();
        let hold = vrpn::Limits::default().udp_after_descriptions + Duration::from_millis(50);
        let mut i = 0;
        while self.poses.get() < 500
            || self.c2s.get() < 500
            || self.remote.ping_cycle().waiting_for_pong()
            || connected.elapsed() < hold
        {
            assert!(start.elapsed() < Duration::from_secs(10), "warm-up stalled");
            self.step(i, c2s_class);
            i += 1;
        }
        // Let what is in flight arrive, so that the measurement starts from a quiet state.
        let quiet = Instant::now();
        while quiet.elapsed() < Duration::from_millis(50) {
            self.server_conn.mainloop().unwrap();
            self.remote.mainloop().unwrap();
        }
    }

    /// Sends N messages each way (with both mainloops per message) and a ping every hundred,
    /// then drains, and returns (poses, client-to-server messages) delivered and the
    /// allocations made.
    fn measure(&self, c2s_class: u32) -> (u64, u64, u64) {
        let (p0, c0, g0) = (self.poses.get(), self.c2s.get(), self.pongs.get());
        let allocs = allocations_in(|| {
            for i in 0..N {
                self.step(i, c2s_class);
            }
            // Drain what is in flight, then idle loops.
            let start = Instant::now();
            while (self.poses.get() - p0 < N
                || self.c2s.get() - c0 < N
                || self.pongs.get() - g0 < N / 100)
                && start.elapsed() < Duration::from_millis(500)
            {
                self.server_conn.mainloop().unwrap();
                self.remote.mainloop().unwrap();
            }
            for _ in 0..1000 {
                self.server_conn.mainloop().unwrap();
                self.remote.mainloop().unwrap();
            }
        });
        assert_eq!(self.pongs.get() - g0, N / 100, "every ping answered");
        (self.poses.get() - p0, self.c2s.get() - c0, allocs)
    }
}

#[test]
fn tcp_only_reports_do_not_allocate() {
    let net = Net::new("Tracker0@tcp://127.0.0.1:PORT");
    net.warm_up(class::RELIABLE);
    let (poses, c2s, allocs) = net.measure(class::RELIABLE);
    assert_eq!(poses, N, "every pose delivered over TCP");
    assert_eq!(c2s, N, "every client message delivered over TCP");
    assert_eq!(allocs, 0, "allocations on the TCP path");
}

#[test]
fn udp_reports_do_not_allocate() {
    let net = Net::new("Tracker0@127.0.0.1:PORT");
    net.warm_up(class::LOW_LATENCY);
    let before = udp_out_datagrams();
    let (poses, c2s, allocs) = net.measure(class::LOW_LATENCY);
    let after = udp_out_datagrams();
    // UDP may drop, but on loopback with both ends reading every pass it should not.
    assert!(poses >= N * 99 / 100, "poses delivered over UDP: {poses}");
    assert!(
        c2s >= N * 99 / 100,
        "client messages delivered over UDP: {c2s}"
    );
    if let (Some(b), Some(a)) = (before, after) {
        // One datagram per mainloop pass and direction: both directions went over UDP.
        assert!(a - b >= 2 * N, "only {} UDP datagrams went out", a - b);
    }
    assert_eq!(allocs, 0, "allocations on the UDP path");
}

#[test]
fn every_device_type_in_process_does_not_allocate() {
    use vrpn::devices::analog::{AnalogRemote, AnalogServer};
    use vrpn::devices::button::{ButtonRemote, ButtonServer};
    use vrpn::devices::dial::{DialRemote, DialServer};
    use vrpn::devices::text_device::{TextReceiver, TextSender};
    let conn = Connection::new_loopback();
    let buttons = ButtonServer::new("Buttons", &conn, 8).unwrap();
    let mut analog = AnalogServer::new("Analog", &conn, 16).unwrap();
    let mut dial = DialServer::new("Dial", &conn, 2).unwrap();
    let text = TextSender::new("Text", &conn).unwrap();
    let (b, a, d, t) = (counter(), counter(), counter(), counter());
    let br = ButtonRemote::on_connection("Buttons", &conn).unwrap();
    let mut bump_b = bump(&b);
    br.on_change(move |_| bump_b());
    let ar = AnalogRemote::on_connection("Analog", &conn).unwrap();
    let mut bump_a = bump(&a);
    ar.on_report(move |_| bump_a());
    let dr = DialRemote::on_connection("Dial", &conn).unwrap();
    let mut bump_d = bump(&d);
    dr.on_update(move |_| bump_d());
    let tr = TextReceiver::on_connection("Text", &conn).unwrap();
    let mut bump_t = bump(&t);
    tr.on_message(move |_| bump_t());
    let mut round = |i: u64| {
        buttons.set_button((i % 8) as usize, (i / 8) % 2 == 0);
        buttons.report_changes().unwrap();
        analog.set_channel((i % 16) as usize, i as f64);
        analog.report(None).unwrap();
        dial.add_rotation((i % 2) as usize, 0.25);
        dial.report_changes().unwrap();
        text.send_message("status ok", vrpn::TextSeverity::Normal, 0, None)
            .unwrap();
        conn.mainloop().unwrap();
    };
    for i in 0..100 {
        round(i);
    }
    let allocs = allocations_in(|| {
        for i in 100..100 + N {
            round(i);
        }
    });
    assert_eq!(
        allocs, 0,
        "allocations while sending and dispatching every type"
    );
    assert!(b.get() >= N && a.get() >= N + 100 && d.get() >= N && t.get() >= N + 100);
}

#[test]
fn log_replay_does_not_allocate_per_message() {
    let path = format!(
        "{}/tests/fixtures/golden/tracker_udp_lob.out.vrpn",
        env!("CARGO_MANIFEST_DIR")
    );
    let conn = Connection::replay_file(&path).unwrap();
    let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
    let n = counter();
    let mut bump_n = bump(&n);
    tracker.on_pose(move |_| bump_n());
    let r = conn.replay().unwrap();
    // The log describes five names at 0.73 s (echoes of a client's names): registering names
    // allocates, so measure from 1 s on, once every name is known.
    r.play_to_time(1.0);
    let before = n.get();
    let allocs = allocations_in(|| {
        r.play_to_time(r.length_secs() + 1.0);
    });
    assert_eq!(allocs, 0, "allocations while replaying");
    assert_eq!(n.get(), 410);
    assert!(
        n.get() - before > 250,
        "{} reports measured",
        n.get() - before
    );
}

/// A server fanning reports out to many clients on the UDP path: every client's datagrams of
/// a pass leave in one batched send, and that path allocates nothing either.
#[test]
fn udp_fan_out_to_many_clients_does_not_allocate() {
    const CLIENTS: usize = 16;
    const STEPS: u64 = 2_000;
    let server_conn = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    let port = server_conn.local_port().unwrap();
    let server = TrackerServer::new("Tracker0", &server_conn, 2).unwrap();
    let clients: Vec<(TrackerRemote, Rc<Cell<u64>>)> = (0..CLIENTS)
        .map(|_| {
            let conn =
                Connection::client("127.0.0.1", port, false, vrpn::Limits::default()).unwrap();
            let remote = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
            let poses = counter();
            let mut hit = bump(&poses);
            remote.on_pose(move |_| hit());
            (remote, poses)
        })
        .collect();
    let step = |i: u64| {
        for sensor in 0..2 {
            server
                .report_pose(sensor, TimeVal::now(), [i as f64, 2.0, 3.0], IDENTITY)
                .unwrap();
        }
        server_conn.mainloop().unwrap();
        for (remote, _) in &clients {
            remote.mainloop().unwrap();
        }
    };
    let start = Instant::now();
    let mut i = 0;
    // Past Limits::udp_after_descriptions, so that the measured reports go by UDP (the test
    // counts the datagrams).
    let hold = vrpn::Limits::default().udp_after_descriptions + Duration::from_millis(50);
    while clients.iter().any(|(_, p)| p.get() < 200) || start.elapsed() < hold {
        assert!(start.elapsed() < Duration::from_secs(20), "warm-up stalled");
        step(i);
        i += 1;
        std::thread::sleep(Duration::from_micros(100));
    }
    let before: Vec<u64> = clients.iter().map(|(_, p)| p.get()).collect();
    let datagrams_before = udp_out_datagrams();
    let allocs = allocations_in(|| {
        for k in 0..STEPS {
            step(i + k);
        }
        for _ in 0..200 {
            server_conn.mainloop().unwrap();
            for (remote, _) in &clients {
                remote.mainloop().unwrap();
            }
        }
    });
    let datagrams_after = udp_out_datagrams();
    for ((_, p), b) in clients.iter().zip(&before) {
        let got = p.get() - b;
        assert!(
            got >= 2 * STEPS * 99 / 100,
            "a client got {got} poses over UDP"
        );
    }
    if let (Some(b), Some(a)) = (datagrams_before, datagrams_after) {
        assert!(
            a - b >= STEPS * CLIENTS as u64,
            "only {} UDP datagrams went out",
            a - b
        );
    }
    assert_eq!(allocs, 0, "allocations fanning out over UDP");
}
