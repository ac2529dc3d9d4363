//! The Magellan driver against the simulator on a virtual serial line, with a client's
//! remotes on the same in-process connection: the reset (both kinds, paced), exact values
//! and first-byte times, resynchronisation, the idle query, a hung device, mouse mode, a
//! reopened port, every configuration variant.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config;
use super::record::{axis_value, AXES, BUTTONS, RESET_NULL_RADIUS};
use super::reset::{BYTE_GAP, RETRY_PAUSE};
use super::sim::{MagellanSim, Sent, SentRecord, SimConfig};
use super::{MagellanProtocol, IDLE_PROBE, PROBE, PROBE_TIMEOUT};
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::SerialDriver;
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, ButtonRemote, Connection, Now, SenderFilter, TimeVal};

type Line = VirtualLine<Lifecycle<MagellanProtocol>, MagellanSim>;
type Shared<T> = Rc<RefCell<Vec<T>>>;

const START_WALL: TimeVal = TimeVal {
    sec: 1_700_000_000,
    usec: 0,
};

/// What the client saw, in order.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Event {
    Analog(TimeVal, [f64; AXES]),
    Button(TimeVal, i32, i32),
}

impl Event {
    fn time(&self) -> TimeVal {
        match self {
            Event::Analog(t, _) | Event::Button(t, _, _) => *t,
        }
    }
}

fn magellan_cfg(text: &str) -> config::Magellan {
    parse_one(text)
}

struct Rig {
    line: Line,
    start: Now,
    events: Shared<Event>,
    texts: Shared<(TextSeverity, String)>,
    _remotes: (AnalogRemote, ButtonRemote),
    _conn: Connection,
}

fn rig(cfg_text: &str, sim: SimConfig, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg = magellan_cfg(cfg_text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let analog = AnalogRemote::on_connection(&cfg.name, &conn).unwrap();
    let buttons = ButtonRemote::on_connection(&cfg.name, &conn).unwrap();
    let events: Shared<Event> = Rc::default();
    let e = events.clone();
    analog.on_report(move |r| {
        let mut v = [0.0; AXES];
        v.copy_from_slice(r.channels());
        e.borrow_mut().push(Event::Analog(r.time, v));
    });
    let e = events.clone();
    buttons.on_change(move |c| {
        e.borrow_mut()
            .push(Event::Button(c.time, c.button as i32, c.state.raw()))
    });
    let texts: Shared<(TextSeverity, String)> = Rc::default();
    let sender = conn.register_sender(&cfg.name).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((sev, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push((sev, text.to_owned()));
        }
    });
    let start = Now {
        mono: Instant::now(),
        wall: START_WALL,
    };
    let mut line = VirtualLine::new(driver, MagellanSim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        events,
        texts,
        _remotes: (analog, buttons),
        _conn: conn,
    }
}

impl Rig {
    /// Runs until the driver streams; returns the time it took.
    fn run_to_streaming(&mut self, max: Duration) -> Duration {
        let t0 = self.line.now().mono;
        assert!(
            self.line.run_until(max, |l| l.driver.is_streaming()),
            "not streaming within {max:?}; texts: {:?}",
            self.texts.borrow()
        );
        self.line.now().mono - t0
    }

    fn texts_with(&self, needle: &str) -> usize {
        self.texts
            .borrow()
            .iter()
            .filter(|(_, t)| t.contains(needle))
            .count()
    }

    /// The host time at which a byte sent at `at` arrives.
    fn arrival(&self, at: Instant) -> TimeVal {
        START_WALL.plus(at + self.line.latency - self.start.mono)
    }

    fn log(&self) -> Vec<SentRecord> {
        self.line.device.log.iter().copied().collect()
    }

    /// What a client must see for `log` (less the records `lost`), from all-zero values.
    fn expected(&self, log: &[SentRecord], lost: &[u64]) -> Vec<Event> {
        self.expected_from(log, lost, [0.0; AXES], 0)
    }

    /// What a client must see for `log` (less the records `lost`), from the channels `chans`
    /// and the keys `mask`.
    fn expected_from(
        &self,
        log: &[SentRecord],
        lost: &[u64],
        mut chans: [f64; AXES],
        mut mask: u16,
    ) -> Vec<Event> {
        let mut out = Vec::new();
        // Only records whose second half has reached the driver.
        let complete = |r: &&SentRecord| {
            r.at + SimConfig::default().second_half_after + self.line.latency
                <= self.line.now().mono
        };
        for r in log
            .iter()
            .filter(complete)
            .filter(|r| !lost.contains(&r.seq))
        {
            let t = self.arrival(r.at);
            match r.sent {
                Sent::Axes(raw) => {
                    let v = raw.map(|x| axis_value(x, RESET_NULL_RADIUS));
                    if v != chans {
                        out.push(Event::Analog(t, v));
                        chans = v;
                    }
                }
                Sent::Keys(k) => {
                    for i in 0..BUTTONS {
                        if (k ^ mask) & (1 << i) != 0 {
                            out.push(Event::Button(t, i as i32, i32::from(k & (1 << i) != 0)));
                        }
                    }
                    mask = k;
                }
            }
        }
        out
    }
}

/// Events equal, times within a microsecond (the line's wall clock is computed in floating
/// point). Reports only the first difference.
fn assert_same(got: &[Event], want: &[Event]) {
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        let dt = (g.time().as_micros() - w.time().as_micros()).abs();
        let same = dt <= 1
            && match (g, w) {
                (Event::Analog(_, a), Event::Analog(_, b)) => a == b,
                (Event::Button(_, a, s), Event::Button(_, b, t)) => (a, s) == (b, t),
                _ => false,
            };
        assert!(
            same,
            "event {i} of {}/{}: got {g:?}, want {w:?}",
            got.len(),
            want.len()
        );
    }
    assert_eq!(got.len(), want.len(), "event counts");
}

/// `got` is `want` from its start, values only (a slow read's records all carry its wake
/// time), but for at most the last two records still on their way.
fn assert_same_values(got: &[Event], want: &[Event]) {
    let untimed = |e: &Event| {
        let mut e = *e;
        match &mut e {
            Event::Analog(t, _) | Event::Button(t, _, _) => *t = TimeVal::ZERO,
        }
        e
    };
    assert!(
        got.len() <= want.len() && got.len() + 2 >= want.len(),
        "{}/{}",
        got.len(),
        want.len()
    );
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(
            untimed(g),
            untimed(w),
            "event {i} of {}/{}",
            got.len(),
            want.len()
        );
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several records at once, during the reset (a
    // puck in motion) and with the answer that ends it: every record is reported.
    let sim = SimConfig {
        stream_at_power_on: true,
        ..SimConfig::default()
    };
    let mut r = rig("vrpn_Magellan M /dev/ttyS0 9600\n", sim, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.run_to_streaming(Duration::from_millis(500));
    r.line.run_for(Duration::from_secs(1));
    let log = r.log();
    assert!(log.len() > 40, "{} records", log.len());
    assert_same_values(&r.events.borrow(), &r.expected(&log, &[]));
}

#[test]
fn paced_reset_then_exact_values_stamped_with_the_first_byte() {
    let sim = SimConfig {
        // A device that loses characters coming faster than 4 ms apart.
        min_byte_gap: Some(Duration::from_millis(4)),
        ..SimConfig::default()
    };
    let mut r = rig("vrpn_Magellan Magellan0 /dev/ttyS0 9600\n", sim, 1);
    let took = r.run_to_streaming(Duration::from_secs(2));
    // 15 bytes 5 ms apart, then the answer to the beep.
    assert!(took < Duration::from_millis(100), "reset took {took:?}");
    assert_eq!(r.line.device.lost_chars(), 0);
    let writes = &r.line.written;
    assert_eq!(
        writes.iter().flat_map(|w| w.1.clone()).collect::<Vec<u8>>(),
        b"z\rm3\rc30\rnH\rbH\r"
    );
    assert!(writes.iter().all(|w| w.1.len() == 1));
    assert!(writes.windows(2).all(|p| p[1].0 - p[0].0 >= BYTE_GAP));
    let cmds: Vec<&[u8]> = r.line.device.commands.iter().map(Vec::as_slice).collect();
    assert_eq!(cmds, [&b"z"[..], b"m3", b"c30", b"nH", b"bH"]);
    r.line.run_for(Duration::from_secs(2));
    let log = r.log();
    assert!(log.len() > 90, "{} records", log.len());
    // Every record arrives in two reads 13.5 ms apart, yet carries its first byte's time.
    assert_same(&r.events.borrow(), &r.expected(&log, &[]));
    assert!(r
        .events
        .borrow()
        .iter()
        .any(|e| matches!(e, Event::Button(..))));
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
    assert!(r.texts.borrow().is_empty(), "{:?}", r.texts.borrow());
}

#[test]
fn alternative_reset_works_where_the_normal_one_cannot() {
    let old = SimConfig {
        old_unit: true,
        ..SimConfig::default()
    };
    let mut r = rig("vrpn_Magellan M /dev/ttyS0 9600 altreset\n", old.clone(), 2);
    r.run_to_streaming(Duration::from_secs(1));
    let cmds: Vec<&[u8]> = r.line.device.commands.iter().map(Vec::as_slice).collect();
    assert_eq!(cmds, [&b"z"[..], b"m3", b"nH", b"p?0", b"q00"]);
    r.line.run_for(Duration::from_secs(1));
    assert_same(&r.events.borrow(), &r.expected(&r.log(), &[]));

    // The normal reset gets `nH` where `c30` belongs, says so, and retries.
    let mut r = rig("vrpn_Magellan M /dev/ttyS0 9600\n", old, 3);
    r.line.run_for(Duration::from_secs(3));
    assert!(!r.line.driver.is_streaming());
    let bad = r.texts_with("Bad reset string (expected c30\\r, got nH\\r)");
    assert!(bad >= 3, "{:?}", r.texts.borrow());
    // One attempt every (75 ms of writing + the pause).
    assert!(r.line.driver.protocol().resets() == 1 && r.line.device.zeroed() >= 3);
    assert!(r.line.device.zeroed() as u32 <= 3_000 / RETRY_PAUSE.as_millis() as u32 + 1);
}

#[test]
fn a_puck_in_motion_during_the_reset_does_not_upset_it() {
    let sim = SimConfig {
        stream_at_power_on: true,
        ..SimConfig::default()
    };
    let mut r = rig("vrpn_Magellan M /dev/ttyS0 9600\n", sim, 4);
    r.run_to_streaming(Duration::from_millis(500));
    assert!(r.texts.borrow().is_empty(), "{:?}", r.texts.borrow());
    r.line.run_for(Duration::from_secs(1));
    // Records sent during the reset are reported too: nothing is lost.
    let log = r.log();
    assert!(log[0].at < r.start.mono + Duration::from_millis(80));
    assert_same(&r.events.borrow(), &r.expected(&log, &[]));
}

#[test]
fn garbage_costs_only_the_record_it_hits() {
    let mut r = rig("vrpn_Magellan M /dev/ttyS0 9600\n", SimConfig::default(), 5);
    r.run_to_streaming(Duration::from_secs(1));
    r.line.run_for(Duration::from_millis(300));
    let mut lost = Vec::new();
    let next_record = |r: &mut Rig| {
        let before = r.line.device.log.back().unwrap().seq;
        assert!(r.line.run_until(Duration::from_millis(30), |l| {
            l.device.log.back().unwrap().seq > before
        }));
        before + 1
    };
    for round in 0..6u64 {
        // Between records (after one's second half, before the next): nothing lost.
        next_record(&mut r);
        r.line.run_for(Duration::from_millis(16));
        r.line.inject(b"\x00\xffxyz\rd12");
        // Inside a record (after its first half arrived): that record is lost.
        let seq = next_record(&mut r);
        r.line.run_for(Duration::from_millis(4));
        lost.push(seq);
        r.line.inject(if round % 2 == 0 { b"?" } else { b"\n" });
    }
    r.line.run_for(Duration::from_millis(100));
    assert_same(&r.events.borrow(), &r.expected(&r.log(), &lost));
    assert!(r.line.driver.protocol().skipped_bytes() > 6 * 10);
    // Noted at most once a second.
    let notes = r.texts_with("skipped");
    assert!((1..=2).contains(&notes), "{:?}", r.texts.borrow());
    assert!(r.texts_with("first: a byte that starts no record, 0x00") == 1);
}

#[test]
fn an_idle_device_is_queried_and_left_alone_while_it_answers() {
    let mut r = rig("vrpn_Magellan M /dev/ttyS0 9600\n", SimConfig::default(), 6);
    r.run_to_streaming(Duration::from_secs(1));
    let now = r.line.now();
    r.line.device.set_moving(false, now);
    r.line.run_for(Duration::from_millis(10_500));
    let d = r.line.driver.protocol();
    // One query per 2 s of silence (each answer restarts the count).
    assert!((4..=5).contains(&d.probes()), "{} probes", d.probes());
    assert_eq!(d.resets(), 1);
    let queries = r
        .line
        .device
        .commands
        .iter()
        .filter(|c| c == &b"mQ")
        .count();
    assert_eq!(queries as u64, d.probes());
    assert!(r.texts.borrow().is_empty(), "{:?}", r.texts.borrow());
    assert_eq!(PROBE, b"mQ\r");
    // Moving again: reports resume at once.
    let n = r.events.borrow().len();
    let now = r.line.now();
    r.line.device.set_moving(true, now);
    r.line.run_for(Duration::from_millis(200));
    assert!(r.events.borrow().len() > n + 5);
}

#[test]
fn a_hung_device_is_reset_until_it_answers_and_resumes() {
    let mut r = rig("vrpn_Magellan M /dev/ttyS0 9600\n", SimConfig::default(), 7);
    r.run_to_streaming(Duration::from_secs(1));
    r.line.run_for(Duration::from_millis(500));
    r.line.device.set_silent(true);
    let hung = r.line.now().mono;
    assert!(r
        .line
        .run_until(Duration::from_secs(5), |l| !l.driver.is_streaming()));
    let noticed = r.line.now().mono - hung;
    // Counted from the last record's first byte, up to one period before the hang.
    let expect = IDLE_PROBE + PROBE_TIMEOUT;
    assert!(
        noticed <= expect && noticed + Duration::from_millis(25) >= expect,
        "{noticed:?}"
    );
    assert_eq!(r.texts_with("No answer to a mode query, resetting"), 1);
    // The keys the driver holds (the device's last key record), and the events so far.
    let held = r.line.driver.protocol().buttons();
    let mask = (0..BUTTONS)
        .filter(|&i| held.button(i).is_pressed())
        .fold(0u16, |m, i| m | 1 << i);
    let seen = r.events.borrow().len();
    r.line.run_for(Duration::from_secs(4));
    assert!(r.texts_with("No response from device") >= 2);
    // A reset invents nothing: no zeroed channels, no released keys while the device is mute.
    assert_eq!(
        r.events.borrow().len(),
        seen,
        "events while the device was silent"
    );
    r.line.device.set_silent(false);
    let woke = r.line.now().mono;
    let took = r.run_to_streaming(Duration::from_secs(3));
    assert!(took < RETRY_PAUSE + Duration::from_millis(1200), "{took:?}");
    r.line.run_for(Duration::from_secs(1));
    let log: Vec<SentRecord> = r.log().into_iter().filter(|s| s.at > woke).collect();
    let after: Vec<Event> = r
        .events
        .borrow()
        .iter()
        .copied()
        .filter(|e| e.time() > r.arrival(woke))
        .collect();
    // The device's answers to the zeroing command set the axes to 0 (it says so): each shows
    // as an all-zero report between the records, at the answer's arrival. The keys stay as
    // the device last sent them; otherwise exactly the records.
    let zeroed: Vec<TimeVal> = after
        .iter()
        .filter_map(|e| match e {
            Event::Analog(t, v) if *v == [0.0; AXES] => Some(*t),
            _ => None,
        })
        .collect();
    assert!(!zeroed.is_empty(), "the device's zeroing answer");
    let mut want = Vec::new();
    let mut chans = r
        .events
        .borrow()
        .iter()
        .rev()
        .find_map(|e| match e {
            Event::Analog(t, v) if *t <= r.arrival(woke) => Some(*v),
            _ => None,
        })
        .unwrap_or([0.0; AXES]);
    let mut keys = mask;
    let mut rest = &log[..];
    for z in &zeroed {
        let n = rest.iter().take_while(|s| r.arrival(s.at) < *z).count();
        let part = r.expected_from(&rest[..n], &[], chans, keys);
        for e in &part {
            match e {
                Event::Analog(_, v) => chans = *v,
                Event::Button(_, i, on) => {
                    keys = if *on != 0 {
                        keys | 1 << i
                    } else {
                        keys & !(1 << i)
                    }
                }
            }
        }
        want.extend(part);
        if chans != [0.0; AXES] {
            want.push(Event::Analog(*z, [0.0; AXES]));
            chans = [0.0; AXES];
        }
        rest = &rest[n..];
    }
    want.extend(r.expected_from(rest, &[], chans, keys));
    assert!(want.len() > 30);
    assert_same(&after, &want);
}

#[test]
fn mouse_mode_resets_the_device() {
    let mut r = rig("vrpn_Magellan M /dev/ttyS0 9600\n", SimConfig::default(), 8);
    r.run_to_streaming(Duration::from_secs(1));
    r.line.run_for(Duration::from_millis(105));
    let now = r.line.now();
    r.line.device.send_raw(b"mH\r", now);
    r.line.run_for(Duration::from_millis(20));
    assert_eq!(r.texts_with("Was put into mouse mode, resetting"), 1);
    assert_eq!(r.line.driver.protocol().resets(), 2);
    r.run_to_streaming(Duration::from_millis(500));
    assert_eq!(r.line.device.zeroed(), 2);
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig("vrpn_Magellan M /dev/ttyS0 9600\n", SimConfig::default(), 9);
    r.run_to_streaming(Duration::from_secs(1));
    r.line.run_for(Duration::from_millis(300));
    r.line.close();
    assert!(!r.line.driver.is_streaming());
    assert_eq!(r.line.driver.next_deadline(), None);
    r.run_to_streaming(Duration::from_secs(2));
    assert_eq!(r.line.opens, 2);
    assert_eq!(r.line.driver.protocol().resets(), 2);
    let n = r.line.driver.stats().records;
    r.line.run_for(Duration::from_millis(500));
    assert!(r.line.driver.stats().records > n + 15);
}

#[test]
fn every_variant_parses_and_builds() {
    for (text, alt) in [
        ("vrpn_Magellan Magellan0 /dev/ttyS0 9600\n", false),
        (
            "vrpn_Magellan Magellan0 /dev/ttyUSB1 19200 altreset\n",
            true,
        ),
    ] {
        let cfg = magellan_cfg(text);
        assert_eq!(cfg.alt_reset, alt);
        let conn = Connection::new_loopback();
        let d = MagellanProtocol::new(&cfg, &conn).unwrap();
        assert_eq!(d.reset.plan() == super::reset::ALTERNATIVE, alt);
        assert_eq!(d.analog().num_channels(), AXES);
        assert_eq!(d.buttons().num_buttons(), BUTTONS);
        assert_eq!(d.port(), cfg.port);
        let entries = parse_str(text, "test.cfg").unwrap();
        let mut opened = Vec::new();
        let devices = build_devices(&entries, &Connection::new_loopback(), false, None, |n| {
            if let BuildNote::Opened { name, .. } = n {
                opened.push(name.to_owned());
            }
        })
        .unwrap();
        assert_eq!(devices.len(), 1);
        assert_eq!(opened, ["Magellan0"]);
    }
}

#[test]
fn toggle_requests_do_not_filter_the_reports() {
    let mut r = rig(
        "vrpn_Magellan M /dev/ttyS0 9600\n",
        SimConfig::default(),
        11,
    );
    // A client asks for toggles; as in C++, the Magellan still reports every press and
    // release.
    r._remotes.1.set_all_toggle(false).unwrap();
    r.run_to_streaming(Duration::from_secs(1));
    r.line.run_for(Duration::from_secs(1));
    assert_eq!(
        r.line.driver.protocol().buttons().mode(4),
        crate::devices::button::TOGGLE_OFF
    );
    let want = r.expected(&r.log(), &[]);
    assert!(want.iter().any(|e| matches!(e, Event::Button(_, _, 0))));
    assert_same(&r.events.borrow(), &want);
}
