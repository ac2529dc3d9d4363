//! Shared objects through real sockets on 127.0.0.1: the initial value on connection,
//! unserialized and serialized changes, the serializer policies and hand-over, old and
//! idempotent changes, strings and floats.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::shared_object::{
    SerializerPolicy, SharedChange, SharedFloat64, SharedInt32, SharedMode, SharedString,
};
use vrpn::{Connection, SenderFilter, TimeVal};

struct Pair {
    srv: Connection,
    cli: Connection,
}

impl Pair {
    fn new() -> Pair {
        let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        srv.on_notice(|_| {});
        let port = srv.local_port().unwrap();
        let cli = Connection::client("127.0.0.1", port, false, Default::default()).unwrap();
        Pair { srv, cli }
    }

    fn run(&self, done: impl Fn() -> bool) -> bool {
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            self.srv.mainloop().unwrap();
            self.cli.mainloop().unwrap();
            if done() {
                return true;
            }
            std::thread::sleep(Duration::from_micros(300));
        }
        false
    }

    /// A few passes for messages that should not arrive.
    fn settle(&self) {
        for _ in 0..50 {
            self.srv.mainloop().unwrap();
            self.cli.mainloop().unwrap();
            std::thread::sleep(Duration::from_micros(300));
        }
    }
}

fn record<V: vrpn::devices::shared_object::SharedValue>(
    o: &vrpn::devices::shared_object::SharedObject<V>,
) -> Rc<RefCell<Vec<SharedChange<V>>>> {
    let log = Rc::new(RefCell::new(Vec::new()));
    let l = log.clone();
    o.on_change(move |c| l.borrow_mut().push(c.clone()));
    log
}

#[test]
fn unserialized_int_follows_both_ways() {
    let p = Pair::new();
    let server = SharedInt32::server("a", &p.srv, 5, SharedMode::default()).unwrap();
    let remote = SharedInt32::remote("a", &p.cli, 0, SharedMode::default()).unwrap();
    let sl = record(&server);
    let rl = record(&remote);
    // The remote learns the server's value when it connects.
    assert!(p.run(|| remote.value() == 5));
    assert!(!rl.borrow()[0].is_local);
    assert_eq!(rl.borrow()[0].when, server.last_update());
    server.set(7).unwrap();
    assert!(p.run(|| remote.value() == 7));
    assert!(sl.borrow().last().unwrap().is_local);
    remote.set(-3).unwrap();
    assert_eq!(remote.value(), -3);
    assert!(p.run(|| server.value() == -3));
    let last = sl.borrow().last().unwrap().clone();
    assert_eq!((last.value, last.is_local), (-3, false));
    assert_eq!(last.when, remote.last_update());
}

#[test]
fn serialized_deny_remote_then_hand_over() {
    // The C++ test pair: both sides serialized, the server denies remote changes.
    let p = Pair::new();
    let server = SharedInt32::server("a", &p.srv, 0, SharedMode::SERIALIZED).unwrap();
    server.set_policy(SerializerPolicy::DenyRemote);
    let remote = SharedInt32::remote("a", &p.cli, 0, SharedMode::SERIALIZED).unwrap();
    let deferred = Rc::new(RefCell::new(0));
    let d = deferred.clone();
    remote.on_deferred_update(move || *d.borrow_mut() += 1);
    let sl = record(&server);
    assert!(p.run(|| p.cli.connected() && p.srv.connected()));
    p.settle();
    assert!(server.is_serializer() && !remote.is_serializer());
    // A remote change goes to the serializer, which denies it: nothing changes anywhere.
    remote.set(3).unwrap();
    assert_eq!(remote.value(), 0);
    assert_eq!(*deferred.borrow(), 1);
    p.settle();
    assert_eq!(server.value(), 0);
    assert!(sl.borrow().is_empty());
    // The server's own change is taken and reaches the remote.
    server.set(-3).unwrap();
    assert!(p.run(|| remote.value() == -3));
    // The remote becomes the serializer; then its changes are taken and sent.
    remote.become_serializer();
    assert!(p.run(|| remote.is_serializer() && !server.is_serializer()));
    remote.set(3).unwrap();
    assert_eq!(remote.value(), 3);
    assert!(p.run(|| server.value() == 3));
    // And the server's changes now go through the remote.
    server.set(9).unwrap();
    assert_eq!(server.value(), 3);
    assert!(p.run(|| server.value() == 9 && remote.value() == 9));
}

#[test]
fn serialized_accept_gives_everyone_the_same_sequence() {
    let p = Pair::new();
    let server = SharedInt32::server("n", &p.srv, 0, SharedMode::SERIALIZED).unwrap();
    let remote = SharedInt32::remote("n", &p.cli, 0, SharedMode::SERIALIZED).unwrap();
    let sl = record(&server);
    let rl = record(&remote);
    assert!(p.run(|| p.cli.connected() && p.srv.connected()));
    p.settle();
    sl.borrow_mut().clear();
    rl.borrow_mut().clear();
    remote.set(1).unwrap();
    server.set(2).unwrap();
    remote.set(3).unwrap();
    assert!(p.run(|| rl.borrow().len() == 3));
    p.settle();
    let values = |l: &Rc<RefCell<Vec<SharedChange<i32>>>>| -> Vec<i32> {
        l.borrow().iter().map(|c| c.value).collect()
    };
    assert_eq!(values(&sl), values(&rl));
    assert_eq!(values(&sl), [2, 1, 3]);
    assert_eq!(server.value(), remote.value());
}

#[test]
fn policy_callback_and_deny_local() {
    let p = Pair::new();
    let server = SharedFloat64::server("f", &p.srv, 0.0, SharedMode::SERIALIZED).unwrap();
    server.set_policy_callback(|v, _| *v >= 0.0);
    let remote = SharedFloat64::remote("f", &p.cli, 0.0, SharedMode::SERIALIZED).unwrap();
    assert!(p.run(|| p.cli.connected() && p.srv.connected()));
    p.settle();
    remote.set(-1.5).unwrap();
    remote.set(2.25).unwrap();
    assert!(p.run(|| remote.value() == 2.25 && server.value() == 2.25));
    server.set_policy(SerializerPolicy::DenyLocal);
    server.set(9.0).unwrap();
    assert_eq!(server.value(), 2.25);
    remote.set(4.0).unwrap();
    assert!(p.run(|| server.value() == 4.0 && remote.value() == 4.0));
}

#[test]
fn old_and_idempotent_changes_are_ignored_when_asked() {
    let conn = Connection::new_loopback();
    let mode = SharedMode {
        ignore_old: true,
        ignore_idempotent: true,
        defer_updates: false,
    };
    let s = SharedInt32::server("x", &conn, 1, mode).unwrap();
    let log = record(&s);
    let t = |sec| TimeVal { sec, usec: 0 };
    let base = s.last_update().sec;
    s.set_at(2, t(base + 10)).unwrap();
    s.set_at(3, t(base + 5)).unwrap(); // older: ignored
    s.set_at(2, t(base + 20)).unwrap(); // same value: ignored
    s.set_at(4, t(base + 10)).unwrap(); // same time, serializer: taken
    assert_eq!(s.value(), 4);
    let values: Vec<i32> = log.borrow().iter().map(|c| c.value).collect();
    assert_eq!(values, [2, 4]);
    assert_eq!(SharedMode::from_bits(0x101), mode);
    assert_eq!(mode.bits(), 0x101);
    assert!(SharedMode::from_bits(0x10).defer_updates);
}

#[test]
fn strings_cross_whole_and_echoes_are_not_answered() {
    let p = Pair::new();
    let server =
        SharedString::server("s", &p.srv, "initial".into(), SharedMode::default()).unwrap();
    let remote = SharedString::remote("s", &p.cli, String::new(), SharedMode::default()).unwrap();
    assert!(p.run(|| remote.value() == "initial"));
    let long = "a string longer than sixteen bytes, with ünïcode".to_string();
    remote.set(long.clone()).unwrap();
    assert!(p.run(|| server.value() == long));
    assert!(server.set("x".repeat(2000)).is_err());
    // Count the updates the server sends: an update carrying the value and time the server
    // already has is not answered (two serializers would bounce it forever).
    let update = p.srv.register_type("vrpn_Shared update").unwrap();
    let sent = Rc::new(RefCell::new(0));
    let n = sent.clone();
    p.srv
        .register_handler(update, SenderFilter::Any, move |_| *n.borrow_mut() += 1);
    let before = *sent.borrow();
    // Echo the server's own value back from the remote's sender.
    let peer = p.cli.register_sender("vrpn Shared peer String s").unwrap();
    let when = server.last_update();
    let mut payload = Vec::new();
    payload.extend_from_slice(&(when.sec as i32).to_be_bytes());
    payload.extend_from_slice(&(when.usec as i32).to_be_bytes());
    payload.extend_from_slice(long.as_bytes());
    let cu = p.cli.register_type("vrpn_Shared update").unwrap();
    p.cli
        .pack_message(when, cu, peer, &payload, vrpn::ServiceClass::RELIABLE)
        .unwrap();
    p.settle();
    // Only the echo itself arrived at the server; it sent nothing.
    assert_eq!(*sent.borrow() - before, 1);
    assert_eq!(server.value(), long);
}
