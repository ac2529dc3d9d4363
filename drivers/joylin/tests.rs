//! The joystick driver against the simulator on a virtual line, with the driver's Analog and
//! Button and a client's remotes on one in-process connection. What a client must receive is
//! computed from the simulator's log by a reference model written here, not by the driver.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config;
use super::event::{JsEvent, Kind};
use super::sim::{JoystickSim, SimConfig};
use super::{JoylinProtocol, DEFAULT_AXES, DEFAULT_BUTTONS, READ_ERROR};
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, ButtonRemote, Connection, Now, SenderFilter, TimeVal};

type Shared<T> = Rc<RefCell<Vec<T>>>;

/// An Analog message: time and channels.
type Channels = (TimeVal, Vec<f64>);
/// A Change message: time, button, state.
type Change = (TimeVal, i32, i32);

struct Rig {
    line: VirtualLine<Lifecycle<JoylinProtocol>, JoystickSim>,
    start: Now,
    analog: Shared<Channels>,
    changes: Shared<Change>,
    texts: Shared<(TextSeverity, String)>,
    _remotes: (AnalogRemote, ButtonRemote),
    _conn: Connection,
}

fn joylin_cfg(text: &str) -> config::Joylin {
    parse_one(text)
}

fn rig(sim: SimConfig, tweak: impl FnOnce(&mut JoystickSim), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg = joylin_cfg("vrpn_Joylin Joy0 /dev/input/js0\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let ar = AnalogRemote::on_connection("Joy0", &conn).unwrap();
    let br = ButtonRemote::on_connection("Joy0", &conn).unwrap();
    let (analog, changes): (Shared<Channels>, Shared<Change>) = Default::default();
    let a = analog.clone();
    ar.on_report(move |r| {
        let n = r.num_channel;
        a.borrow_mut().push((r.time, r.channel[..n].to_vec()));
    });
    let c = changes.clone();
    br.on_change(move |ch| {
        c.borrow_mut()
            .push((ch.time, ch.button as i32, ch.state.raw()))
    });
    let texts: Shared<(TextSeverity, String)> = Rc::default();
    let sender = conn.register_sender("Joy0").unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((sev, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push((sev, text.to_owned()));
        }
    });
    let mut model = JoystickSim::new(SimConfig {
        keep_log: true,
        ..sim
    });
    tweak(&mut model);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, model, start, seed),
        start,
        analog,
        changes,
        texts,
        _remotes: (ar, br),
        _conn: conn,
    }
}

/// What a client must receive for the events logged: the channels after each axis event (all
/// `axes` of them; initial-state events of one burst together) and one change per button
/// event that changes the button. Times are the events' arrival.
fn expected(r: &Rig, axes: usize, buttons: usize) -> (Vec<Channels>, Vec<Change>) {
    let mut chan = vec![0.0; axes];
    let mut pressed = vec![0i32; buttons];
    let (mut a, mut c) = (Vec::new(), Vec::new());
    let log = r.line.device.sent();
    let mut i = 0;
    while i < log.len() {
        // A burst: the initial-state events that left together, or one live event.
        let at = log[i].at;
        let burst_end = if log[i].event.init {
            i + log[i..]
                .iter()
                .take_while(|e| e.event.init && e.at == at)
                .count()
        } else {
            i + 1
        };
        let time = r.arrival_wall(at);
        let before = chan.clone();
        for e in &log[i..burst_end] {
            let JsEvent {
                kind,
                number,
                value,
                ..
            } = e.event;
            let n = usize::from(number);
            match kind {
                Kind::Axis => chan[n] = f64::from(value) / 32767.0,
                Kind::Button => {
                    let v = i32::from(value != 0);
                    if pressed[n] != v {
                        pressed[n] = v;
                        c.push((time, n as i32, v));
                    }
                }
            }
        }
        if chan != before {
            a.push((time, chan.clone()));
        }
        i = burst_end;
    }
    (a, c)
}

impl Rig {
    fn arrival_wall(&self, t: Instant) -> TimeVal {
        self.start
            .wall
            .plus(t + self.line.latency - self.start.mono)
    }

    fn texts_with(&self, needle: &str) -> usize {
        let t = self.texts.borrow();
        t.iter().filter(|(_, t)| t.contains(needle)).count()
    }

    /// Everything received equals the reference, but for messages still on the line.
    fn assert_exact(&self, axes: usize, buttons: usize) {
        let (a, c) = expected(self, axes, buttons);
        let got_a = self.analog.borrow();
        let got_c = self.changes.borrow();
        assert!(!got_a.is_empty() && !got_c.is_empty());
        assert!(a.len() - got_a.len() <= 1, "{} / {}", got_a.len(), a.len());
        assert!(c.len() - got_c.len() <= 1, "{} / {}", got_c.len(), c.len());
        assert_eq!(got_a[..], a[..got_a.len()]);
        assert_eq!(got_c[..], c[..got_c.len()]);
    }

    /// What was received from `from` on equals the reference from `from` on.
    fn assert_exact_since(&self, from: TimeVal, axes: usize, buttons: usize) {
        let (a, c) = expected(self, axes, buttons);
        let tail = |v: &[Channels]| {
            v.iter()
                .filter(|m| m.0 >= from)
                .cloned()
                .collect::<Vec<_>>()
        };
        let tail_c = |v: &[Change]| {
            v.iter()
                .filter(|m| m.0 >= from)
                .cloned()
                .collect::<Vec<_>>()
        };
        let (got_a, want_a) = (tail(&self.analog.borrow()), tail(&a));
        let (got_c, want_c) = (tail_c(&self.changes.borrow()), tail_c(&c));
        assert!(got_a.len() > 20 && got_c.len() > 5);
        assert_eq!(got_a[..], want_a[..got_a.len()]);
        assert_eq!(got_c[..], want_c[..got_c.len()]);
        assert!(want_a.len() - got_a.len() <= 1 && want_c.len() - got_c.len() <= 1);
    }
}

#[test]
fn port_kind_and_identity() {
    let r = rig(SimConfig::new(2, 2), |_| {}, 1);
    assert_eq!(r.line.driver.name(), "Joy0");
    assert_eq!(r.line.driver.protocol().device(), "/dev/input/js0");
    assert_eq!(r.line.driver.port_kind(), PortKind::InputDevice);
    // Nothing is ever written to a joystick, and nothing waits on a deadline.
    assert!(r.line.written.is_empty());
    assert_eq!(r.line.driver.next_deadline(), None);
}

#[test]
fn initial_state_is_learned_and_reported_once() {
    let mut r = rig(
        SimConfig::new(6, 12),
        |s| {
            s.running = false;
            s.set_axis(0, 16_000);
            s.set_axis(5, -32_767);
            s.set_button(3, true);
            s.set_button(11, true);
        },
        2,
    );
    r.line.run_for(Duration::from_millis(100));
    assert_eq!(r.line.driver.protocol().analog().num_channels(), 6);
    assert_eq!(r.line.driver.protocol().buttons().num_buttons(), 12);
    let a = r.analog.borrow().clone();
    assert_eq!(a.len(), 1, "{a:?}");
    assert_eq!(a[0].1, vec![16_000.0 / 32767.0, 0.0, 0.0, 0.0, 0.0, -1.0]);
    let c: Vec<(i32, i32)> = r.changes.borrow().iter().map(|c| (c.1, c.2)).collect();
    assert_eq!(c, vec![(3, 1), (11, 1)]);
    r.assert_exact(6, 12);
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several events at once: every value and change
    // is reported, from the first (times aside: a slow read's events carry its wake time).
    let mut r = rig(SimConfig::new(6, 12), |_| {}, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(2));
    let (a, c) = expected(&r, 6, 12);
    let values = |v: &[Channels]| v.iter().map(|m| m.1.clone()).collect::<Vec<_>>();
    let changes = |v: &[Change]| v.iter().map(|m| (m.1, m.2)).collect::<Vec<_>>();
    let (got_a, got_c) = (values(&r.analog.borrow()), changes(&r.changes.borrow()));
    assert!(got_a.len() >= 295 && got_c.len() >= 95);
    assert!(a.len() - got_a.len() <= 3 && c.len() - got_c.len() <= 3);
    assert_eq!(got_a[..], values(&a)[..got_a.len()]);
    assert_eq!(got_c[..], changes(&c)[..got_c.len()]);
}

#[test]
fn live_events_arrive_exactly_with_their_times() {
    for seed in [3, 4] {
        let mut r = rig(SimConfig::new(6, 12), |_| {}, seed);
        r.line.split_reads = true;
        r.line.run_for(Duration::from_secs(2));
        // One event every 5 ms: 300 axis and 100 button events in 2 s.
        assert!(
            r.analog.borrow().len() >= 295,
            "{}",
            r.analog.borrow().len()
        );
        assert!(r.changes.borrow().len() >= 95);
        r.assert_exact(6, 12);
        assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
    }
}

#[test]
fn counts_default_to_two_and_grow_without_an_initial_state() {
    // Fewer than C++'s defaults: the defaults stand.
    let mut r = rig(SimConfig::new(1, 1), |_| {}, 5);
    r.line.run_for(Duration::from_millis(200));
    assert_eq!(
        r.line.driver.protocol().analog().num_channels(),
        DEFAULT_AXES
    );
    assert_eq!(
        r.line.driver.protocol().buttons().num_buttons(),
        DEFAULT_BUTTONS
    );
    r.assert_exact(DEFAULT_AXES, DEFAULT_BUTTONS);
    // A stand-in that sends live events only: the counts grow as events name higher numbers.
    let mut r = rig(SimConfig::new(5, 9), |s| s.skip_initial_state(), 6);
    r.line.run_for(Duration::from_millis(22));
    assert!(r.line.driver.protocol().analog().num_channels() < 5);
    r.line.run_for(Duration::from_secs(1));
    assert_eq!(r.line.driver.protocol().analog().num_channels(), 5);
    assert_eq!(r.line.driver.protocol().buttons().num_buttons(), 9);
    let a = r.analog.borrow();
    assert!(a.first().unwrap().1.len() <= 3 && a.last().unwrap().1.len() == 5);
}

#[test]
fn numbers_beyond_the_limits_are_ignored_with_one_warning() {
    let mut r = rig(SimConfig::new(2, 2), |s| s.skip_initial_state(), 7);
    let bad = JsEvent {
        time_ms: 1,
        value: 100,
        kind: Kind::Axis,
        init: false,
        number: 200,
    };
    r.line.inject(&bad.encode());
    r.line.inject(&bad.encode());
    r.line.run_for(Duration::from_millis(100));
    assert_eq!(r.line.driver.protocol().ignored(), 2);
    assert_eq!(r.texts_with("axis 200 is beyond"), 1);
    assert_eq!(r.line.driver.protocol().analog().num_channels(), 2);
}

#[test]
fn a_damaged_stream_resyncs() {
    let mut r = rig(SimConfig::new(4, 4), |_| {}, 8);
    r.line.split_reads = true;
    r.line.run_for(Duration::from_millis(300));
    for junk in [&[0x10u8, 0x20, 0x30][..], &[0xFF; 13], &[0x02, 0x01, 0x81]] {
        r.line.inject(junk);
        r.line.run_for(Duration::from_millis(37));
    }
    let after = r.line.now();
    // Every axis moves and every button toggles twice within 100 ms of events.
    r.line.run_for(Duration::from_secs(1));
    assert!(r.line.driver.protocol().skipped_bytes() >= 19);
    r.assert_exact_since(after.wall.plus(Duration::from_millis(200)), 4, 4);
}

#[test]
fn silence_is_not_a_fault() {
    let mut r = rig(SimConfig::new(3, 3), |_| {}, 9);
    r.line.run_for(Duration::from_millis(200));
    r.line.device.running = false;
    r.line.run_for(Duration::from_secs(10));
    assert_eq!(r.line.opens, 1);
    assert!(r.texts.borrow().is_empty(), "{:?}", r.texts.borrow());
    r.line.device.running = true;
    r.line.run_for(Duration::from_millis(300));
    r.assert_exact(3, 3);
}

#[test]
fn a_vanished_device_is_reported_and_reopened() {
    let mut r = rig(SimConfig::new(3, 3), |_| {}, 10);
    r.line.run_for(Duration::from_millis(200));
    r.line.close();
    assert_eq!(r.texts_with(READ_ERROR), 1);
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    // The device comes back with its initial state, then live events. What it sent while
    // the line was closed is lost; from its return on, the client sees exactly what it sends.
    r.line.device.plugged();
    let back = r.line.now();
    r.line.run_for(Duration::from_millis(300));
    r.assert_exact_since(back.wall.plus(Duration::from_millis(1)), 3, 3);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Joylin Joy0 /dev/input/js0\nvrpn_Joylin\tJoy1\t/tmp/joystick.fifo\n";
    let entries = parse_str(text, "joy.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["Joy0", "Joy1"]);
    let e = parse_str("# joystick\nvrpn_Joylin Joy0\n", "bad.cfg")
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad.cfg") && e.contains('2'), "{e}");
}

#[test]
fn a_reopen_never_invents_data() {
    let mut r = rig(SimConfig::new(3, 3), |_| {}, 11);
    r.line.run_for(Duration::from_millis(200));
    let (analog, changes) = (r.analog.borrow().len(), r.changes.borrow().len());
    r.line.close();
    // Closed: nothing reported (no zeroed axes, no released buttons).
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    assert_eq!(r.analog.borrow().len(), analog);
    assert_eq!(r.changes.borrow().len(), changes);
    // Back: what the client sees is exactly what the device sends, its initial state first.
    r.line.device.plugged();
    let back = r.line.now();
    r.line.run_for(Duration::from_millis(300));
    r.assert_exact_since(back.wall.plus(Duration::from_millis(1)), 3, 3);
}
