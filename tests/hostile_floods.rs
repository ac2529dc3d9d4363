//! Floods from one peer against a `vrpn_server` child process on loopback, beside a TCP
//! watcher reading a 200 Hz tracker (issue 29, items 2 and 9). A binary of their own, one test
//! at a time: each flood takes a core, and run beside the other hostile tests it would starve
//! them rather than the server under test.

mod common;

use std::cell::Cell;
use std::io::{ErrorKind, Read, Write};
use std::net::{Ipv4Addr, TcpStream};
use std::rc::Rc;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use vrpn::wire::{header::encode_message, system, Cookie, Header};
use vrpn::{Connection, Limits, TimeVal, TrackerRemote};

/// A NULL tracker reporting 200 poses a second.
const CFG: &str = "vrpn_Tracker_NULL Tracker0 1 200.0\n";

/// One flood at a time.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// A client counting poses.
struct Legit {
    tracker: TrackerRemote,
    poses: Rc<Cell<u64>>,
}

impl Legit {
    fn new(port: u16, tcp_only: bool) -> Legit {
        let conn = Connection::client("127.0.0.1", port, tcp_only, Limits::default()).unwrap();
        conn.on_notice(|_| {});
        let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
        let poses = Rc::new(Cell::new(0));
        let p = poses.clone();
        tracker.on_pose(move |_| p.set(p.get() + 1));
        Legit { tracker, poses }
    }

    /// Runs the client for `d`; returns the poses it received meanwhile.
    fn run_for(&self, d: Duration) -> u64 {
        let before = self.poses.get();
        let start = Instant::now();
        while start.elapsed() < d {
            self.tracker.mainloop().unwrap();
            let _ = self.tracker.connection().wait(Duration::from_millis(2));
        }
        self.poses.get() - before
    }

    /// Runs until the first pose or `max`; returns whether one came.
    fn wait_for_poses(&self, max: Duration) -> bool {
        let start = Instant::now();
        while start.elapsed() < max {
            self.tracker.mainloop().unwrap();
            if self.poses.get() > 0 {
                return true;
            }
            let _ = self.tracker.connection().wait(Duration::from_millis(2));
        }
        false
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

fn description(id: i32, is_sender: bool, name: &[u8]) -> Vec<u8> {
    let mut p = ((name.len() + 1) as u32).to_be_bytes().to_vec();
    p.extend_from_slice(name);
    p.push(0);
    let t = if is_sender {
        system::SENDER_DESCRIPTION
    } else {
        system::TYPE_DESCRIPTION
    };
    message(t, id, &p)
}

/// A raw TCP peer that sent its cookie.
fn raw_peer(port: u16) -> TcpStream {
    let mut s = TcpStream::connect((Ipv4Addr::LOCALHOST, port)).unwrap();
    s.set_nodelay(true).unwrap();
    s.write_all(&Cookie::ours(0).to_bytes()).unwrap();
    s
}

/// A raw TCP peer that describes `names` (sender or type, id) and then writes `one` as fast as
/// the server takes it for `secs`, reading (and counting) whatever the server sends back in a
/// second thread. Returns the messages written and the bytes read.
fn flood(port: u16, names: &[(i32, bool, &str)], one: Vec<u8>, secs: f64) -> (u64, u64) {
    let mut s = raw_peer(port);
    s.set_write_timeout(Some(Duration::from_millis(100)))
        .unwrap();
    let mut r = s.try_clone().unwrap();
    r.set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let reader = std::thread::spawn(move || {
        let (mut got, mut buf) = (0u64, vec![0u8; 65536]);
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs_f64(secs + 2.0) {
            match r.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => got += n as u64,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                Err(_) => break,
            }
        }
        got
    });
    for &(id, is_sender, name) in names {
        s.write_all(&description(id, is_sender, name.as_bytes()))
            .unwrap();
    }
    let batch: Vec<u8> = one.iter().copied().cycle().take(one.len() * 256).collect();
    let (start, mut sent) = (Instant::now(), 0u64);
    while start.elapsed() < Duration::from_secs_f64(secs) {
        match s.write(&batch) {
            Ok(n) => sent += (n / one.len()) as u64,
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
            Err(_) => break, // dropped by the server
        }
    }
    let _ = s.shutdown(std::net::Shutdown::Both);
    (sent, reader.join().unwrap())
}

/// Issue 29, item 2: one client's clock-query flood does not stall the server. Every message
/// counts against a peer's budget for a pass (1,024), clock queries too (they bring no
/// delivery, and used to keep the pass reading for up to 1.1 s): a TCP watcher beside the
/// flood keeps its poses.
#[test]
fn a_clock_query_flood_starves_nobody() {
    use vrpn::wire::payload::clock;
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let server = common::start_server(CFG, 0);
    let a = Legit::new(server.port, true);
    assert!(a.wait_for_poses(Duration::from_secs(5)));
    a.run_for(Duration::from_millis(300));
    let mut query = [0u8; clock::Query::LEN];
    clock::Query {
        id: 7,
        query_sent: TimeVal::now(),
    }
    .encode(&mut query);
    let port = server.port;
    let flooder = std::thread::spawn(move || {
        let names = [
            (0, true, clock::SENDER),
            (0, false, clock::QUERY),
            (1, false, clock::REPLY),
        ];
        flood(port, &names, message(0, 0, &query), 3.0)
    });
    let got = a.run_for(Duration::from_secs(3));
    let (sent, answered) = flooder.join().unwrap();
    eprintln!(
        "clock-query flood: {sent} queries in 3 s ({answered} bytes of replies); the TCP \
         watcher got {got} poses (200/s: ~600)"
    );
    assert!(sent > 20_000, "the flood itself fell short: {sent}");
    assert!(answered > 0, "the flooder's queries were never answered");
    assert!(
        got >= 480,
        "the watcher got {got} of ~600 poses during the flood"
    );
}

/// Issue 29, item 9: a flood of `Request_Tracker_To_Room` costs the requester only: the reply
/// goes to the peer that asked (it used to be broadcast, and a watcher was dropped for 4 MiB
/// of reliable output pending). The watcher sees no reply it did not ask for and keeps its
/// poses.
#[test]
fn a_request_flood_is_answered_to_the_requester_only() {
    use vrpn::wire::payload::tracker;
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let server = common::start_server(CFG, 0);
    let a = Legit::new(server.port, true);
    assert!(a.wait_for_poses(Duration::from_secs(5)));
    let conn = a.tracker.connection();
    let to_room = conn.register_type(tracker::TO_ROOM).unwrap();
    let replies = Rc::new(Cell::new(0u64));
    let r = replies.clone();
    conn.register_handler(to_room, vrpn::SenderFilter::Any, move |_| {
        r.set(r.get() + 1)
    });
    a.run_for(Duration::from_millis(300));
    let port = server.port;
    let flooder = std::thread::spawn(move || {
        let names = [
            (0, true, "Tracker0"),
            (0, false, tracker::REQUEST_TRACKER_TO_ROOM),
        ];
        flood(port, &names, message(0, 0, &[]), 3.0)
    });
    let got = a.run_for(Duration::from_secs(3));
    let (sent, answered) = flooder.join().unwrap();
    a.run_for(Duration::from_millis(300));
    eprintln!(
        "To_Room request flood: {sent} requests in 3 s ({answered} bytes of replies to the \
         requester); the TCP watcher got {got} poses (~600) and {} replies",
        replies.get()
    );
    assert!(sent > 20_000, "the flood itself fell short: {sent}");
    assert!(answered > 0, "the requester got no reply");
    assert_eq!(
        replies.get(),
        0,
        "replies reached a client that never asked"
    );
    assert!(
        a.tracker.connection().connected(),
        "the watcher was dropped"
    );
    assert!(
        got >= 480,
        "the watcher got {got} of ~600 poses during the flood"
    );
}
