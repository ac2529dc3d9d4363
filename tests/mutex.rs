//! Mutex and PeerMutex through real sockets on 127.0.0.1: index assignment, request, grant,
//! deny, release, the time-out, drops, and peers breaking ties.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::mutex::{MutexRemote, MutexServer, MutexState};
use vrpn::devices::peer_mutex::PeerMutex;
use vrpn::Connection;

type Log = Rc<RefCell<Vec<String>>>;

fn logged(remote: &MutexRemote, tag: &str) -> Log {
    let log: Log = Rc::new(RefCell::new(Vec::new()));
    for (what, l) in [("granted", log.clone()), ("denied", log.clone())] {
        let t = format!("{tag} {what}");
        match what {
            "granted" => remote.on_granted(move || l.borrow_mut().push(t.clone())),
            _ => remote.on_denied(move || l.borrow_mut().push(t.clone())),
        };
    }
    let (l, t) = (log.clone(), format!("{tag} released"));
    remote.on_released(move || l.borrow_mut().push(t.clone()));
    let (l, t) = (log.clone(), format!("{tag} taken"));
    remote.on_taken(move || l.borrow_mut().push(t.clone()));
    log
}

fn run(step: &dyn Fn(), done: &dyn Fn() -> bool) -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(10) {
        step();
        if done() {
            return true;
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    false
}

#[test]
fn two_remotes_share_one_lock() {
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    srv.on_notice(|_| {});
    let port = srv.local_port().unwrap();
    let server = MutexServer::new("lock", &srv).unwrap();
    let a = MutexRemote::new(&format!("lock@127.0.0.1:{port}")).unwrap();
    // A private connection for the second remote (the same location text would share).
    let b_conn = Connection::client("127.0.0.1", port, false, Default::default()).unwrap();
    let b = MutexRemote::on_connection("lock", &b_conn).unwrap();
    let la = logged(&a, "a");
    let lb = logged(&b, "b");
    let step = || {
        srv.mainloop().unwrap();
        a.mainloop().unwrap();
        b.mainloop().unwrap();
    };
    // A request before the index is known waits for it (C++ rule).
    a.request().unwrap();
    assert!(run(&step, &|| a.index().is_some() && b.index().is_some()));
    assert_ne!(a.index(), b.index());
    assert!(run(&step, &|| a.is_held_locally() && b.is_held_remotely()));
    assert!(server.is_held());
    assert_eq!(server.holder(), a.index());
    assert_eq!(*la.borrow(), ["a granted", "a taken"]);
    assert_eq!(*lb.borrow(), ["b taken"]);
    // b asks while a holds: locally not available, so denied at once.
    b.request().unwrap();
    assert_eq!(lb.borrow().last().unwrap(), "b denied");
    a.release().unwrap();
    assert!(run(&step, &|| b.is_available() && !server.is_held()));
    assert_eq!(la.borrow().last().unwrap(), "a released");
    assert_eq!(lb.borrow().last().unwrap(), "b released");
    // Now b gets it; a's request reaches the server and is denied there.
    b.request().unwrap();
    assert!(run(&step, &|| b.is_held_locally()));
    a.release().unwrap(); // not held: nothing
    assert!(run(&step, &|| a.is_held_remotely()));
    assert_eq!(a.state(), MutexState::HeldRemotely);
    // Dropping the holder releases the lock (C++ destructor).
    drop(b);
    let step = || {
        srv.mainloop().unwrap();
        a.mainloop().unwrap();
        b_conn.mainloop().unwrap();
    };
    assert!(run(&step, &|| a.is_available() && !server.is_held()));
}

#[test]
fn the_server_denies_a_second_request_on_the_wire() {
    // Two remotes ask at once: the server grants the first it hears and denies the second.
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    srv.on_notice(|_| {});
    let port = srv.local_port().unwrap();
    let _server = MutexServer::new("lock", &srv).unwrap();
    let a = MutexRemote::new(&format!("lock@127.0.0.1:{port}")).unwrap();
    let b_conn = Connection::client("127.0.0.1", port, false, Default::default()).unwrap();
    let b = MutexRemote::on_connection("lock", &b_conn).unwrap();
    let la = logged(&a, "a");
    let lb = logged(&b, "b");
    let step = || {
        srv.mainloop().unwrap();
        a.mainloop().unwrap();
        b.mainloop().unwrap();
    };
    assert!(run(&step, &|| a.index().is_some() && b.index().is_some()));
    a.request().unwrap();
    b.request().unwrap();
    assert_eq!(a.state(), MutexState::Requesting);
    assert!(run(&step, &|| {
        a.state() != MutexState::Requesting && b.state() != MutexState::Requesting
    }));
    let winners = [a.is_held_locally(), b.is_held_locally()];
    assert_eq!(winners.iter().filter(|w| **w).count(), 1);
    let (win, lose) = if winners[0] { (&la, &lb) } else { (&lb, &la) };
    assert!(win.borrow().iter().any(|e| e.ends_with("granted")));
    assert!(lose.borrow().iter().any(|e| e.ends_with("denied")));
}

#[test]
fn an_unanswered_request_times_out_and_a_late_grant_is_given_back() {
    // A fake server that assigns the index but answers the request only when told to.
    let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
    srv.on_notice(|_| {});
    let port = srv.local_port().unwrap();
    let sender = srv.register_sender("lock").unwrap();
    let types: Vec<_> = vrpn::wire::payload::mutex::TYPE_NAMES
        .iter()
        .map(|t| srv.register_type(t).unwrap())
        .collect();
    let (req_index, req_mutex, release, grant, init) =
        (types[0], types[1], types[2], types[4], types[6]);
    let pending = Rc::new(RefCell::new(None));
    let releases = Rc::new(RefCell::new(0));
    srv.register_handler(req_index, vrpn::SenderFilter::Only(sender), move |m| {
        let mut p = m.payload.to_vec();
        p.extend_from_slice(&7i32.to_be_bytes());
        let c = m.connection();
        c.pack_message(c.now().wall, init, sender, &p, vrpn::ServiceClass::RELIABLE)
            .unwrap();
    });
    let p = pending.clone();
    srv.register_handler(req_mutex, vrpn::SenderFilter::Only(sender), move |m| {
        *p.borrow_mut() = Some(m.payload.to_vec());
    });
    let r = releases.clone();
    srv.register_handler(release, vrpn::SenderFilter::Only(sender), move |_| {
        *r.borrow_mut() += 1;
    });
    let a = MutexRemote::new(&format!("lock@127.0.0.1:{port}")).unwrap();
    let la = logged(&a, "a");
    a.set_request_timeout(Some(Duration::from_millis(200)));
    let step = || {
        srv.mainloop().unwrap();
        a.mainloop().unwrap();
    };
    assert!(run(&step, &|| a.index() == Some(7)));
    let asked = Instant::now();
    a.request().unwrap();
    assert!(run(&step, &|| la.borrow().iter().any(|e| e == "a denied")));
    assert!(asked.elapsed() >= Duration::from_millis(200));
    assert!(a.is_available());
    // The grant arrives late: the remote gives the lock back and tells nobody it held it.
    assert!(pending.borrow().is_some());
    srv.pack_message(
        srv.now().wall,
        grant,
        sender,
        &7i32.to_be_bytes(),
        vrpn::ServiceClass::RELIABLE,
    )
    .unwrap();
    assert!(run(&step, &|| *releases.borrow() == 1));
    assert!(!la.borrow().iter().any(|e| e == "a granted"));
    assert!(a.is_available());
}

#[test]
fn peers_grant_deny_and_release() {
    let lo = Some(Ipv4Addr::LOCALHOST);
    let a = PeerMutex::new("peerlock", 0, lo).unwrap();
    let b = PeerMutex::new("peerlock", 0, lo).unwrap();
    let c = PeerMutex::new("peerlock", 0, lo).unwrap();
    for c in [a.connection(), b.connection(), c.connection()] {
        c.on_notice(|_| {});
    }
    let all = [&a, &b, &c];
    for p in all {
        for q in all {
            if p.port() != q.port() {
                p.add_peer(&format!("127.0.0.1:{}\n", q.port())).unwrap();
            }
        }
    }
    let step = || {
        for p in all {
            p.mainloop().unwrap();
        }
    };
    assert!(run(&step, &|| all.iter().all(|p| p.peers_connected())));
    assert_eq!(a.num_peers(), 2);
    let granted = Rc::new(RefCell::new(Vec::new()));
    for (tag, p) in [("a", &a), ("b", &b), ("c", &c)] {
        let g = granted.clone();
        p.on_granted(move || g.borrow_mut().push(format!("{tag} granted")));
        let g = granted.clone();
        p.on_denied(move || g.borrow_mut().push(format!("{tag} denied")));
    }
    a.request().unwrap();
    assert!(run(&step, &|| a.is_held_locally()));
    assert!(run(&step, &|| b.is_held_remotely() && c.is_held_remotely()));
    // b asks while a holds: c refuses (its holder is a), b is denied.
    b.request().unwrap(); // b sees the lock held: denied at once, locally
    assert_eq!(granted.borrow().last().unwrap(), "b denied");
    a.release();
    assert!(run(&step, &|| all.iter().all(|p| p.is_available())));
    // Simultaneous requests: the lower port wins everywhere.
    b.request().unwrap();
    c.request().unwrap();
    let low_is_b = b.port() < c.port();
    assert!(run(&step, &|| {
        (b.is_held_locally() && c.is_held_remotely())
            || (c.is_held_locally() && b.is_held_remotely())
    }));
    assert_eq!(b.is_held_locally(), low_is_b);
    // A peer that is gone is forgotten.
    let holder = if low_is_b { &b } else { &c };
    holder.release();
    assert!(run(&step, &|| all.iter().all(|p| p.is_available())));
    drop(c);
    assert!(run(&step_two(&a, &b), &|| a.num_peers() == 1
        && b.num_peers() == 1));
    a.request().unwrap();
    assert!(run(&step_two(&a, &b), &|| a.is_held_locally()));
}

fn step_two<'a>(a: &'a PeerMutex, b: &'a PeerMutex) -> impl Fn() + 'a {
    move || {
        a.mainloop().unwrap();
        b.mainloop().unwrap();
    }
}

#[test]
fn a_peer_alone_gets_the_lock_at_once_and_unreachable_peers_are_an_error() {
    let a = PeerMutex::new("solo", 0, Some(Ipv4Addr::LOCALHOST)).unwrap();
    a.request().unwrap();
    assert!(a.is_held_locally());
    a.release();
    // A peer nobody serves: the request is refused instead of waiting forever.
    let unused = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = unused.local_addr().unwrap().port();
    drop(unused);
    a.add_peer(&format!("127.0.0.1:{port}")).unwrap();
    assert!(a.request().is_err());
    assert!(a.is_available());
}
