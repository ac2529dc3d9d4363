//! Redundant transmission through real sockets on 127.0.0.1: copies go out spaced by the
//! interval, the receiver uses each message once, and a client tunes the sender remotely.

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;
use std::time::{Duration, Instant};

use vrpn::devices::redundant::{
    RedundantController, RedundantReceiver, RedundantRemote, RedundantTransmission,
};
use vrpn::wire::class;
use vrpn::{Connection, SenderFilter, TimeVal};

struct Setup {
    srv: Connection,
    cli: Connection,
    sender: Rc<RedundantTransmission>,
    _control: RedundantController,
    receiver: RedundantReceiver,
    data_type: vrpn::TypeId,
    me: vrpn::SenderId,
    /// Every copy the client's connection received, and what the receiver passed on.
    raw: Rc<Cell<u32>>,
    once: Rc<RefCell<Vec<u8>>>,
}

impl Setup {
    fn new() -> Setup {
        let srv = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        srv.on_notice(|_| {});
        let port = srv.local_port().unwrap();
        let sender = Rc::new(RedundantTransmission::new(&srv));
        let control = RedundantController::new(&srv, &sender).unwrap();
        let data_type = srv.register_type("redundant test data").unwrap();
        let me = srv.register_sender("redundant test").unwrap();
        let cli = Connection::client("127.0.0.1", port, false, Default::default()).unwrap();
        let ct = cli.register_type("redundant test data").unwrap();
        let cs = cli.register_sender("redundant test").unwrap();
        let raw = Rc::new(Cell::new(0));
        let r = raw.clone();
        cli.register_handler(ct, SenderFilter::Only(cs), move |_| r.set(r.get() + 1));
        let receiver = RedundantReceiver::new(&cli);
        let once = Rc::new(RefCell::new(Vec::new()));
        let o = once.clone();
        receiver.register_handler(ct, SenderFilter::Only(cs), move |m| {
            o.borrow_mut().push(m.payload[0])
        });
        let s = Setup {
            srv,
            cli,
            sender,
            _control: control,
            receiver,
            data_type,
            me,
            raw,
            once,
        };
        // Up, with the client's UDP channel open (copies go over UDP).
        s.run_for(Duration::from_millis(300));
        assert!(s.cli.connected());
        s
    }

    fn run_for(&self, d: Duration) {
        let end = Instant::now() + d;
        while Instant::now() < end {
            self.srv.mainloop().unwrap();
            self.sender.mainloop();
            self.cli.mainloop().unwrap();
            std::thread::sleep(Duration::from_micros(200));
        }
    }

    fn send(&self, i: u8) {
        let t = TimeVal {
            sec: 1000 + i64::from(i),
            usec: 0,
        };
        self.sender
            .pack_message(t, self.data_type, self.me, &[i], class::LOW_LATENCY)
            .unwrap();
    }
}

#[test]
fn copies_arrive_and_are_used_once() {
    let s = Setup::new();
    s.sender.set_defaults(2, Duration::from_millis(20));
    s.sender.enable(true);
    let sent_at = Instant::now();
    for i in 0..5 {
        s.send(i);
    }
    assert_eq!(s.sender.queued(), 5);
    // The copies are due 20 ms and 40 ms later.
    let due = s.sender.next_deadline().unwrap();
    assert!(due >= sent_at + Duration::from_millis(19));
    s.run_for(Duration::from_millis(300));
    assert_eq!(s.sender.queued(), 0);
    assert_eq!(*s.once.borrow(), [0, 1, 2, 3, 4]);
    // On loopback nothing is lost: three of each.
    assert_eq!(s.raw.get(), 15);
    assert_eq!(s.receiver.duplicates(), 10);
}

#[test]
fn disabled_passes_through_and_zero_interval_sends_one_copy_per_pass() {
    let s = Setup::new();
    s.send(1);
    assert_eq!(s.sender.queued(), 0);
    s.run_for(Duration::from_millis(100));
    assert_eq!(s.raw.get(), 1);
    s.sender.set_defaults(3, Duration::ZERO);
    s.sender.enable(true);
    s.send(2);
    s.sender.mainloop();
    assert_eq!(s.sender.queued(), 1);
    s.sender.mainloop();
    s.sender.mainloop();
    assert_eq!(s.sender.queued(), 0);
    s.run_for(Duration::from_millis(100));
    assert_eq!(s.raw.get(), 1 + 4);
    assert_eq!(*s.once.borrow(), [1, 2]);
}

#[test]
fn a_client_tunes_the_sender_and_the_receiver_remembers_counts() {
    let s = Setup::new();
    let remote = RedundantRemote::new(&s.cli).unwrap();
    remote.set(1, Duration::from_millis(5)).unwrap();
    remote.enable(true).unwrap();
    s.run_for(Duration::from_millis(200));
    assert!(s.sender.is_enabled());
    assert_eq!(s.sender.default_retransmissions(), 1);
    assert_eq!(s.sender.default_interval(), Duration::from_millis(5));
    s.receiver.record(true);
    // More messages than the receiver remembers: the oldest leave its memory with their
    // counts. (A burst longer than the memory would let late copies of its first messages
    // through, as in C++: the memory is 8 timestamps per type.)
    for batch in 0..4 {
        for i in 0..3 {
            s.send(batch * 3 + i);
        }
        s.run_for(Duration::from_millis(100));
    }
    assert_eq!(s.once.borrow().len(), 12);
    let memory = s.receiver.memory();
    assert_eq!(memory.len(), 4);
    assert!(memory.iter().all(|&(_, n)| n == 2), "{memory:?}");
    assert_eq!(memory[0].0, TimeVal { sec: 1000, usec: 0 });
    remote.enable(false).unwrap();
    s.run_for(Duration::from_millis(200));
    assert!(!s.sender.is_enabled());
}
