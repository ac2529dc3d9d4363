//! A connection burst: a classroom of clients started together, all from one host, is not an
//! attack. 255 clients (the server's maximum) opened at once through real loopback sockets,
//! on the UDP path and on `tcp://`, must all get their first pose without a single notice on
//! either side.
//!
//! The clients retry only once a minute, so a request or call-back the server turned away
//! would leave its client without a pose for the whole test: every client must get in on its
//! first attempt. How long the last one took is printed, not asserted (the machine is shared).

mod common;

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::net::Reactor;
use vrpn::{Connection, Limits, TrackerRemote};

/// A NULL tracker at 50 Hz: enough to see a first pose soon, light for 255 clients.
const CFG: &str = "vrpn_Tracker_NULL Tracker0 1 50.0\n";

const CLIENTS: usize = 255;

/// File descriptors one test process needs: up to five per client (call-back listener,
/// request socket, TCP, two UDP) plus the test harness's own.
fn raise_fd_limit() -> usize {
    use nix::sys::resource::{getrlimit, setrlimit, Resource};
    let want = (CLIENTS * 5 + 64) as u64;
    if let Ok((soft, hard)) = getrlimit(Resource::RLIMIT_NOFILE) {
        if soft < want {
            let _ = setrlimit(Resource::RLIMIT_NOFILE, want.min(hard), hard);
        }
    }
    let soft = getrlimit(Resource::RLIMIT_NOFILE).map_or(1024, |(s, _)| s) as usize;
    CLIENTS.min(soft.saturating_sub(64) / 5)
}

struct Client {
    tracker: TrackerRemote,
    first_pose: Rc<Cell<Option<Instant>>>,
}

fn burst(tcp_only: bool) {
    let n = raise_fd_limit();
    assert!(n >= 128, "only {n} clients fit in the descriptor limit");
    let server = common::start_server(CFG, 0);
    let limits = Limits {
        // One attempt each: a request the server turns away is never repeated in the test.
        retry_interval: Duration::from_secs(60),
        no_answer_warning: Duration::from_secs(60),
        connect_timeout: Duration::from_secs(60),
        ..Limits::default()
    };
    let reactor = Reactor::new().unwrap();
    let notices: Rc<RefCell<Vec<String>>> = Rc::default();
    let started = Instant::now();
    let clients: Vec<Client> = (0..n)
        .map(|_| {
            let conn = Connection::client_in(&reactor, "127.0.0.1", server.port, tcp_only, limits)
                .unwrap();
            let seen = notices.clone();
            conn.on_notice(move |n| seen.borrow_mut().push(n.text.clone()));
            let tracker = TrackerRemote::on_connection("Tracker0", &conn).unwrap();
            let first_pose: Rc<Cell<Option<Instant>>> = Rc::default();
            let f = first_pose.clone();
            tracker.on_pose(move |_| {
                if f.get().is_none() {
                    f.set(Some(Instant::now()));
                }
            });
            Client {
                tracker,
                first_pose,
            }
        })
        .collect();
    let opened = started.elapsed();
    let deadline = started + Duration::from_secs(20);
    while Instant::now() < deadline && clients.iter().any(|c| c.first_pose.get().is_none()) {
        for c in &clients {
            c.tracker.mainloop().unwrap();
        }
        reactor.wait(None, Duration::from_millis(5)).unwrap();
    }
    let got = clients
        .iter()
        .filter(|c| c.first_pose.get().is_some())
        .count();
    let last = clients
        .iter()
        .filter_map(|c| c.first_pose.get())
        .max()
        .map(|t| t - started);
    let path = if tcp_only { "tcp://" } else { "UDP path" };
    eprintln!(
        "{n} clients on the {path} opened in {opened:?}: {got} got a first pose, the last \
         after {last:?}; {} client notices",
        notices.borrow().len()
    );
    // Let the server write whatever it has to say about the burst.
    for _ in 0..20 {
        for c in &clients {
            c.tracker.mainloop().unwrap();
        }
        reactor.wait(None, Duration::from_millis(5)).unwrap();
    }
    let stderr = server.stderr.lock().unwrap().clone();
    assert_eq!(
        got,
        n,
        "clients without a pose; client notices: {:?}; server: {stderr}",
        notices.borrow()
    );
    assert!(
        notices.borrow().is_empty(),
        "client notices: {:?}",
        notices.borrow()
    );
    assert!(
        !stderr.contains("ignored") && !stderr.contains("dropped"),
        "server notices: {stderr}"
    );
}

#[test]
fn a_burst_of_udp_path_clients_all_connect_at_once() {
    burst(false);
}

#[test]
fn a_burst_of_tcp_only_clients_all_connect_at_once() {
    burst(true);
}
