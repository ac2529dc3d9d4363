//! The Magellan and CerealBox drivers end to end: the device simulator on a pseudo-terminal,
//! a `vrpn_server` child running the driver from its vrpn.cfg line, and a client over a real
//! socket on 127.0.0.1. The client must receive exactly the values the device sent, in order;
//! a corrupted stream resynchronises, a hung device is reset and resumes, an unplugged
//! device is reopened when it comes back.

mod common;
#[path = "common/pty_sim.rs"]
mod pty_sim;

use std::cell::RefCell;
use std::fmt::Debug;
use std::rc::Rc;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use pty_sim::Simulated;
use vrpn::devices::base::TEXT_MESSAGE;
use vrpn::devices::text::decode_text;
use vrpn::drivers::cerealbox::record::revolutions;
use vrpn::drivers::cerealbox::sim::{self as cereal, CerealSim};
use vrpn::drivers::magellan::record::{axis_value, RESET_NULL_RADIUS};
use vrpn::drivers::magellan::sim::{self as magellan, MagellanSim, Sent};
use vrpn::{AnalogRemote, ButtonRemote, Connection, DialRemote, SenderFilter};

type Shared<T> = Rc<RefCell<Vec<T>>>;

/// The tests run one at a time: a server started by one must not inherit the other's
/// pseudo-terminal in the moment before it is made close-on-exec (unplugging would then
/// not hang up), and the timings are steadier.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

/// Collects the texts `device` sends to the client on `conn`.
fn texts(conn: &Connection, device: &str) -> Shared<String> {
    let texts: Shared<String> = Rc::default();
    let t = texts.clone();
    let sender = conn.register_sender(device).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((_, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push(text.to_owned());
        }
    });
    texts
}

/// Runs the client until `done` or `limit`; returns whether `done` held.
fn pump(conn: &Connection, limit: Duration, mut done: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    while !done() {
        if start.elapsed() > limit {
            return false;
        }
        conn.mainloop().unwrap();
        let _ = conn.wait(Duration::from_millis(2));
    }
    true
}

/// `got` is a contiguous run of `want` (the client joined mid-stream and may lag behind).
fn assert_run_of<T: PartialEq + Debug>(got: &[T], want: &[T], what: &str) {
    assert!(!got.is_empty(), "no {what}");
    let found =
        (0..want.len()).any(|i| want.len() - i >= got.len() && want[i..i + got.len()] == *got);
    if found {
        return;
    }
    let start = want.iter().position(|w| *w == got[0]);
    let diverge = start.map(|s| {
        (0..got.len())
            .find(|&k| want.get(s + k) != Some(&got[k]))
            .map(|k| (k, got.get(k), want.get(s + k), want.get(s + k + 1)))
    });
    panic!(
        "{what}: the {} received are not a run of the {} sent; first at {start:?}, diverging \
         (index, got, want, want next) {diverge:?}",
        got.len(),
        want.len()
    );
}

/// `got` is `want` in order with at most `missing` left out between its first and last.
fn assert_nearly_run_of<T: PartialEq + Debug>(got: &[T], want: &[T], missing: usize, what: &str) {
    let start = want.iter().position(|w| *w == got[0]).expect(what);
    let mut i = start;
    for g in got {
        let Some(k) = want[i..].iter().position(|w| w == g) else {
            panic!("{what}: {g:?} not found in order");
        };
        i += k + 1;
    }
    let skipped = i - start - got.len();
    assert!(skipped <= missing, "{what}: {skipped} left out");
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum MagellanEvent {
    Axes([f64; 6]),
    Button(i32, i32),
}

/// What a client must see for the Magellan's records so far (from zeroed values).
fn magellan_expected(sim: &Simulated<MagellanSim>) -> Vec<MagellanEvent> {
    let log: Vec<magellan::SentRecord> = sim.with(|m, _| m.log.iter().copied().collect());
    let (mut chans, mut mask) = ([0.0; 6], 0u16);
    let mut out = Vec::new();
    for r in log {
        match r.sent {
            Sent::Axes(raw) => {
                let v = raw.map(|x| axis_value(x, RESET_NULL_RADIUS));
                if v != chans {
                    out.push(MagellanEvent::Axes(v));
                    chans = v;
                }
            }
            Sent::Keys(k) => {
                for i in 0..9 {
                    if (k ^ mask) & (1 << i) != 0 {
                        out.push(MagellanEvent::Button(i, i32::from(k & (1 << i) != 0)));
                    }
                }
                mask = k;
            }
        }
    }
    out
}

fn split<T: Copy, U>(events: &[T], pick: impl Fn(&T) -> Option<U>) -> Vec<U> {
    events.iter().filter_map(pick).collect()
}

#[test]
fn magellan_through_vrpn_server_to_a_client() {
    let _serial = one_at_a_time();
    let sim = Simulated::start(MagellanSim::new(magellan::SimConfig::default()), "magellan");
    let cfg = format!("vrpn_Magellan Magellan0 {} 9600\n", sim.path.display());
    let t0 = Instant::now();
    let server = common::start_server(&cfg, 0);
    // Over TCP only, so every message comes in the order sent (over UDP, the first
    // low-latency reports go by TCP until the UDP channel is up, and may be overtaken).
    let at = format!("Magellan0@tcp://127.0.0.1:{}", server.port);
    let analog = AnalogRemote::new(&at).unwrap();
    let buttons = ButtonRemote::new(&at).unwrap();
    let conn = analog.connection().clone();
    let texts = texts(&conn, "Magellan0");
    let events: Shared<(Instant, MagellanEvent)> = Rc::default();
    let e = events.clone();
    analog.on_report(move |r| {
        let mut v = [0.0; 6];
        v.copy_from_slice(r.channels());
        e.borrow_mut()
            .push((Instant::now(), MagellanEvent::Axes(v)));
    });
    let e = events.clone();
    buttons.on_change(move |c| {
        e.borrow_mut().push((
            Instant::now(),
            MagellanEvent::Button(c.button as i32, c.state.raw()),
        ))
    });
    let count = || events.borrow().len();
    let stderr = || server.stderr.lock().unwrap().clone();
    assert!(
        pump(&conn, Duration::from_secs(10), || count() >= 150),
        "{} reports in 10 s; server said: {}",
        count(),
        stderr()
    );
    let first = events.borrow()[0].0 - t0;
    let reset = sim.with(|m, _| m.last_command_at.unwrap() - m.first_byte_at.unwrap());
    eprintln!("magellan: port opened to reset answered {reset:?}; server start to first report at the client {first:?}");

    // Exactly what the device sent, in order.
    let want = magellan_expected(&sim);
    let got: Vec<MagellanEvent> = events.borrow().iter().map(|e| e.1).collect();
    let axes = |e: &MagellanEvent| matches!(e, MagellanEvent::Axes(_)).then_some(*e);
    let keys = |e: &MagellanEvent| matches!(e, MagellanEvent::Button(..)).then_some(*e);
    assert_run_of(&split(&got, axes), &split(&want, axes), "axis reports");
    assert_run_of(&split(&got, keys), &split(&want, keys), "button changes");

    // Garbage three times: at most those records are lost, and a note says so.
    for _ in 0..3 {
        sim.with(|m, now| m.send_raw(b"\x00\xffjunk\x00", now));
        pump(&conn, Duration::from_millis(150), || false);
    }
    let n = count();
    assert!(pump(&conn, Duration::from_secs(5), || count() >= n + 50));
    let want = magellan_expected(&sim);
    let got: Vec<MagellanEvent> = events.borrow().iter().map(|e| e.1).collect();
    assert_nearly_run_of(
        &split(&got, axes),
        &split(&want, axes),
        3,
        "axes after garbage",
    );
    assert!(
        texts.borrow().iter().any(|t| t.contains("skipped")),
        "{:?}",
        texts.borrow()
    );

    // A hung device: queried after 2 s of silence, reset, and resumed once it wakes.
    sim.with(|m, _| m.set_silent(true));
    let silent = |texts: &Shared<String>| {
        texts
            .borrow()
            .iter()
            .any(|t| t.contains("No answer to a mode query"))
    };
    assert!(pump(&conn, Duration::from_secs(6), || silent(&texts)));
    pump(&conn, Duration::from_millis(1500), || false);
    sim.with(|m, _| m.set_silent(false));
    let woke = Instant::now();
    let n = count();
    assert!(
        pump(&conn, Duration::from_secs(5), || count() >= n + 30),
        "no reports after waking; texts {:?}",
        texts.borrow()
    );
    eprintln!(
        "magellan: woken device reporting again after {:?}",
        woke.elapsed()
    );

    // Unplugged and plugged back: the server reopens the port and resets the device.
    sim.set_plugged(false);
    pump(&conn, Duration::from_millis(1500), || false);
    let n = count();
    sim.set_plugged(true);
    let plugged = Instant::now();
    assert!(
        pump(&conn, Duration::from_secs(6), || count() >= n + 30),
        "no reports after plugging back; server said: {}",
        stderr()
    );
    eprintln!(
        "magellan: replugged device reporting again after {:?}",
        plugged.elapsed()
    );
    assert!(sim.with(|m, _| m.zeroed()) >= 3);
}

#[derive(Clone, Debug, PartialEq)]
enum CerealEvent {
    Analogs(Vec<f64>),
    Button(i32, i32),
    Dial(i32, f64),
}

const CEREAL: (usize, usize, usize) = (24, 8, 8);

/// What a client must see for the box's records so far (from zeroed values).
fn cereal_expected(sim: &Simulated<CerealSim>) -> Vec<CerealEvent> {
    let log: Vec<cereal::SentRecord> = sim.with(|m, _| m.log.iter().copied().collect());
    let (nb, na, ne) = CEREAL;
    let (mut chans, mut mask) = (vec![0.0; na], 0u32);
    let mut out = Vec::new();
    for r in log {
        let v: Vec<f64> = (0..na)
            .map(|i| -1.0 + 2.0 * f64::from(cereal::analog(r.seq, i)) / 4095.0)
            .collect();
        if v != chans {
            out.push(CerealEvent::Analogs(v.clone()));
            chans = v;
        }
        let m = cereal::buttons(r.seq);
        for i in 0..nb {
            if (m ^ mask) & (1 << i) != 0 {
                out.push(CerealEvent::Button(i as i32, i32::from(m & (1 << i) != 0)));
            }
        }
        mask = m;
        for i in 0..ne {
            let ticks = (cereal::encoder(r.seq, i) << 8) >> 8;
            if ticks != 0 {
                out.push(CerealEvent::Dial(i as i32, revolutions(ticks)));
            }
        }
    }
    out
}

#[test]
fn cerealbox_through_vrpn_server_to_a_client() {
    let _serial = one_at_a_time();
    let sim = Simulated::start(CerealSim::new(cereal::SimConfig::default()), "cerealbox");
    let (nb, na, ne) = CEREAL;
    let cfg = format!(
        "vrpn_CerealBox Cereal0 {} 19200 {nb} {na} {ne}\n",
        sim.path.display()
    );
    let t0 = Instant::now();
    let server = common::start_server(&cfg, 0);
    let at = format!("Cereal0@tcp://127.0.0.1:{}", server.port);
    let analog = AnalogRemote::new(&at).unwrap();
    let buttons = ButtonRemote::new(&at).unwrap();
    let dials = DialRemote::new(&at).unwrap();
    let conn = analog.connection().clone();
    let texts = texts(&conn, "Cereal0");
    let events: Shared<(Instant, CerealEvent)> = Rc::default();
    let e = events.clone();
    analog.on_report(move |r| {
        e.borrow_mut()
            .push((Instant::now(), CerealEvent::Analogs(r.channels().to_vec())))
    });
    let e = events.clone();
    buttons.on_change(move |c| {
        e.borrow_mut().push((
            Instant::now(),
            CerealEvent::Button(c.button as i32, c.state.raw()),
        ))
    });
    let e = events.clone();
    dials.on_update(move |u| {
        e.borrow_mut()
            .push((Instant::now(), CerealEvent::Dial(u.dial as i32, u.change)))
    });
    let count = || events.borrow().len();
    let stderr = || server.stderr.lock().unwrap().clone();
    assert!(
        pump(&conn, Duration::from_secs(10), || count() >= 1000),
        "{} reports in 10 s; server said: {}",
        count(),
        stderr()
    );
    let first = events.borrow()[0].0 - t0;
    let reset = sim.with(|m, _| m.first_request_at.unwrap() - m.first_byte_at.unwrap());
    eprintln!("cerealbox: port opened to first record request {reset:?}; server start to first report at the client {first:?}");
    // (The box's type is announced before the client connects; the layout shows the
    // configuration command arrived.)
    let layout = sim.with(|m, _| m.layout()).unwrap();
    assert_eq!((layout.buttons, layout.analogs, layout.encoders), CEREAL);

    let kinds = |events: &[CerealEvent]| {
        let a: Vec<CerealEvent> = events
            .iter()
            .filter(|e| matches!(e, CerealEvent::Analogs(_)))
            .cloned()
            .collect();
        let b: Vec<CerealEvent> = events
            .iter()
            .filter(|e| matches!(e, CerealEvent::Button(..)))
            .cloned()
            .collect();
        let d: Vec<CerealEvent> = events
            .iter()
            .filter(|e| matches!(e, CerealEvent::Dial(..)))
            .cloned()
            .collect();
        (a, b, d)
    };
    let want = kinds(&cereal_expected(&sim));
    let got = kinds(
        &events
            .borrow()
            .iter()
            .map(|e| e.1.clone())
            .collect::<Vec<_>>(),
    );
    assert_run_of(&got.0, &want.0, "analog reports");
    assert_run_of(&got.1, &want.1, "button changes");
    assert_run_of(&got.2, &want.2, "dial updates");

    // Garbage three times: polling goes on, at most those records are lost.
    for _ in 0..3 {
        sim.with(|m, now| m.send_raw(b"\x00\xffjunk\x00", now));
        pump(&conn, Duration::from_millis(150), || false);
    }
    let n = count();
    assert!(pump(&conn, Duration::from_secs(5), || count() >= n + 500));
    let want = kinds(&cereal_expected(&sim));
    let got = kinds(
        &events
            .borrow()
            .iter()
            .map(|e| e.1.clone())
            .collect::<Vec<_>>(),
    );
    assert_nearly_run_of(&got.0, &want.0, 3, "analogs after garbage");
    assert!(
        texts.borrow().iter().any(|t| t.contains("skipped")),
        "{:?}",
        texts.borrow()
    );

    // A hung box: the 2 s watchdog resets it, and it reports again once it wakes.
    sim.with(|m, _| m.set_silent(true));
    let reset_text = |texts: &Shared<String>| {
        texts
            .borrow()
            .iter()
            .any(|t| t.contains("Too long since last report, resetting"))
    };
    assert!(pump(&conn, Duration::from_secs(5), || reset_text(&texts)));
    pump(&conn, Duration::from_millis(1000), || false);
    sim.with(|m, _| m.set_silent(false));
    let woke = Instant::now();
    let n = count();
    assert!(
        pump(&conn, Duration::from_secs(6), || count() >= n + 300),
        "no reports after waking; texts {:?}",
        texts.borrow()
    );
    eprintln!(
        "cerealbox: woken box reporting again after {:?}",
        woke.elapsed()
    );

    // Unplugged and plugged back: reopened and reset.
    sim.set_plugged(false);
    pump(&conn, Duration::from_millis(1500), || false);
    let n = count();
    sim.set_plugged(true);
    let plugged = Instant::now();
    assert!(
        pump(&conn, Duration::from_secs(6), || count() >= n + 300),
        "no reports after plugging back; server said: {}",
        stderr()
    );
    eprintln!(
        "cerealbox: replugged box reporting again after {:?}",
        plugged.elapsed()
    );
    assert!(sim.with(|m, _| m.banners()) >= 3);
}
