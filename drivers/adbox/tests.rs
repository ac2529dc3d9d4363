//! The AD-Box driver against its simulated box on a virtual serial line, with a Button and an
//! Analog remote on one in-process connection: detection of each layout, exact reports with
//! first-byte stamps, a slow reader, garbage, silence, an unplugged line, a box that does not
//! answer, C++'s flicker filter, the configuration line.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::AdBox;
use super::frame::{Filter, Layout};
use super::sim::{AdBoxSim, Sent, SimConfig};
use super::AdBoxProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, ButtonRemote, Connection, Now, SenderFilter, TimeVal};

#[derive(Clone, Debug, PartialEq)]
enum Report {
    Button(usize, bool, TimeVal),
    Analog(Vec<f64>, TimeVal),
}

type Shared<T> = Rc<RefCell<Vec<T>>>;

struct Rig {
    line: VirtualLine<Lifecycle<AdBoxProtocol>, AdBoxSim>,
    start: Now,
    heard: Shared<Report>,
    texts: Shared<String>,
    _remotes: (ButtonRemote, AnalogRemote),
    _conn: Connection,
}

fn rig(len: usize, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: AdBox = parse_one("vrpn_ADBox ADBox0 /dev/ttyS0 19200\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let heard: Shared<Report> = Rc::default();
    let b = ButtonRemote::on_connection("ADBox0", &conn).unwrap();
    let h = heard.clone();
    b.on_change(move |c| {
        h.borrow_mut()
            .push(Report::Button(c.button, c.state.is_pressed(), c.time))
    });
    let a = AnalogRemote::on_connection("ADBox0", &conn).unwrap();
    let h = heard.clone();
    a.on_report(move |r| {
        h.borrow_mut()
            .push(Report::Analog(r.channels().to_vec(), r.time))
    });
    let texts: Shared<String> = Rc::default();
    let sender = conn.register_sender("ADBox0").unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((_, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push(text.to_owned());
        }
    });
    let mut sim = SimConfig::new(19200);
    sim.len = len;
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, AdBoxSim::new(sim), start, seed),
        start,
        heard,
        texts,
        _remotes: (b, a),
        _conn: conn,
    }
}

fn untimed(r: &Report) -> Report {
    match r {
        Report::Button(i, p, _) => Report::Button(*i, *p, TimeVal::ZERO),
        Report::Analog(v, _) => Report::Analog(v.clone(), TimeVal::ZERO),
    }
}

impl Rig {
    fn texts_with(&self, needle: &str) -> usize {
        self.texts
            .borrow()
            .iter()
            .filter(|t| t.contains(needle))
            .count()
    }

    /// What the simulator logged, with the times the driver saw the first bytes.
    fn sent(&self) -> Vec<Report> {
        let at = |t: Instant| {
            self.start
                .wall
                .plus(t + self.line.latency - self.start.mono)
        };
        self.line
            .device
            .sent()
            .iter()
            .map(|s| match s {
                Sent::Button(i, p, t) => Report::Button(*i, *p, at(*t)),
                Sent::Analog(v, t) => Report::Analog(v.clone(), at(*t)),
            })
            .collect()
    }

    /// Everything heard from `from` on is one run of what was logged from `after` on.
    fn assert_run(&self, from: usize, after: usize, timed: bool) {
        let heard: Vec<Report> = self.heard.borrow()[from..]
            .iter()
            .map(|r| if timed { r.clone() } else { untimed(r) })
            .collect();
        let sent: Vec<Report> = self
            .sent()
            .iter()
            .map(|r| if timed { r.clone() } else { untimed(r) })
            .collect();
        assert!(heard.len() > 20, "{} reports", heard.len());
        let runs = crate::sim::rig::runs_in(&heard, &sent, after);
        if runs.is_empty() {
            let loose: Vec<Report> = heard.iter().map(untimed).collect();
            let all: Vec<Report> = sent.iter().map(untimed).collect();
            crate::sim::rig::assert_run_of(&loose, &all, after, "untimed");
            let untimed_runs = crate::sim::rig::runs_in(&loose, &all, after);
            let at = untimed_runs.first().copied().unwrap_or(0);
            let bad = heard.iter().zip(&sent[at..]).position(|(h, s)| h != s);
            panic!(
                "not a run (untimed runs at {untimed_runs:?}; first difference at {bad:?}: {:?})",
                bad.map(|b| (&heard[b], &sent[at + b]))
            );
        }
        // At most the answer on its way is missing at the end.
        assert!(sent.len() - (runs[0] + heard.len()) <= 30);
    }
}

#[test]
fn each_layout_is_detected_and_every_answer_reported_exactly() {
    for (len, buttons, channels) in [(14, 16, 6), (18, 16, 8), (19, 24, 8)] {
        let mut r = rig(len, len as u64);
        assert_eq!(
            r.line.driver.port_kind(),
            PortKind::Serial(PortSettings::n81(19200))
        );
        r.line.run_for(Duration::from_secs(3));
        let layout = r.line.driver.protocol().layout().unwrap();
        assert_eq!((layout.buttons(), layout.channels()), (buttons, channels));
        assert_eq!(
            r.texts_with(&format!(
                "ad-box with {buttons} digital and {channels} analog ports detected"
            )),
            1
        );
        // Nothing lost from the detection's answer on, each stamped with its first byte.
        r.assert_run(0, 0, true);
        assert_eq!(r.heard.borrow()[0], r.sent()[0]);
        // About 19200 / 10 / (len + 3 ms of turnaround) answers a second.
        let answers = r.line.device.answers();
        assert!(answers > 40, "{answers} answers in 2 s");
        assert_eq!(r.line.driver.stats().skipped_bytes, 0);
        let pressed: std::collections::BTreeSet<usize> = r
            .heard
            .borrow()
            .iter()
            .filter_map(|h| match h {
                Report::Button(b, true, _) => Some(*b),
                _ => None,
            })
            .collect();
        assert!(pressed.len() >= 6, "{pressed:?}");
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    let mut r = rig(19, 7);
    r.line.read_lag = Duration::from_millis(8);
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.driver.stats().resets, 1);
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
    r.assert_run(0, 0, false);
}

#[test]
fn garbage_is_dropped_and_the_answers_come_back_in_step() {
    let mut r = rig(19, 3);
    r.line.run_for(Duration::from_millis(500));
    for junk in [&[0x41u8][..], &[0x7F, 0x55], &[0x20, 0x20, 0x20]] {
        r.line.inject(junk);
        r.line.run_for(Duration::from_millis(300));
    }
    assert!(r.line.driver.stats().skipped_bytes >= 6);
    assert!(r.texts_with("out of step") >= 1);
    let from = r.heard.borrow().len();
    let logged = r.line.device.sent().len();
    r.line.run_for(Duration::from_secs(1));
    r.assert_run(from, logged.saturating_sub(40), true);
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
}

#[test]
fn silence_and_unplugging_detect_the_box_again() {
    let mut r = rig(18, 4);
    r.line.run_for(Duration::from_millis(500));
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(1500));
    assert_eq!(
        r.texts_with("no answer for 1 s, detecting the box again"),
        1
    );
    r.line.silent = false;
    r.line.run_for(Duration::from_millis(1500));
    assert_eq!(r.texts_with("analog ports detected"), 2);
    let from = r.heard.borrow().len();
    let logged = r.line.device.sent().len();
    r.line.run_for(Duration::from_secs(1));
    r.assert_run(from, logged.saturating_sub(10), true);
    r.line.close();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.opens, 2);
    assert_eq!(r.texts_with("analog ports detected"), 3);
    let from = r.heard.borrow().len();
    let logged = r.line.device.sent().len();
    r.line.run_for(Duration::from_secs(1));
    r.assert_run(from, logged.saturating_sub(10), true);
}

#[test]
fn a_box_that_does_not_answer_is_asked_again_each_second() {
    let mut r = rig(19, 5);
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(3100));
    // Asked at 0, 1.2, 2.4 s (200 ms of waiting, 1 s of pause).
    assert_eq!(
        r.texts_with("trying to detect ad-box (0 bytes answered)"),
        3
    );
    assert!(r.heard.borrow().is_empty());
    r.line.silent = false;
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.texts_with("analog ports detected"), 1);
    assert!(r.heard.borrow().len() > 40);
}

#[test]
fn the_flicker_filter_is_cpps() {
    let mut f = Filter::new();
    let mut out = Vec::new();
    for v in [500, 501, 500, 501, 501, 600, 601, 0, 1] {
        out.push(f.value(0, v));
        f.next_frame();
    }
    let m = |a: f64, b: f64| (a + b) / 2046.0;
    assert_eq!(
        out,
        [
            500.0 / 1023.0,
            501.0 / 1023.0,
            m(500.0, 501.0),
            m(501.0, 500.0),
            m(501.0, 500.0),
            600.0 / 1023.0,
            601.0 / 1023.0,
            0.0,
            1.0 / 1023.0,
        ]
    );
    let l = Layout::of_len(19).unwrap();
    let mut a = [0xFFu8; 19];
    a[3] = 3;
    a[4] = 0xFF;
    a[1] = 0xFE;
    assert!(l.pressed(&a, 8) && !l.pressed(&a, 9));
    assert_eq!(l.raw(&a, 0), 1023);
    assert!(!l.plausible(&a), "channel 1's high byte is 0xFF");
    assert_eq!(Layout::of_len(15), None);
}

#[test]
fn configuration_lines_and_their_errors() {
    let a: AdBox = parse_one("vrpn_ADBox ADBox0 /dev/ttyS0 9600\n");
    assert_eq!(
        (a.name.as_str(), a.port.as_str(), a.baud),
        ("ADBox0", "/dev/ttyS0", 9600)
    );
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err().kind();
    assert_eq!(
        err("vrpn_ADBox ADBox0 /dev/ttyS0\n"),
        ConfigErrorKind::MissingArguments
    );
    assert_eq!(
        err("vrpn_ADBox ADBox0 /dev/ttyS0 fast\n"),
        ConfigErrorKind::BadNumber
    );
}
