//! The Zaber driver against its simulated chain on a virtual serial line, with an Analog and an
//! Analog_Output remote on one in-process connection: the reset's bytes, moves asked for and
//! reported exactly, the idle poll, silence, garbage, bad requests, the configuration line.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Zaber;
use super::reply::command;
use super::sim::{SimConfig, ZaberSim};
use super::ZaberProtocol;
use crate::devices::analog_output::AnalogOutputRemote;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, Connection, Now, SenderFilter, TimeVal};

const LINE: &str = "vrpn_Zaber Analog0 /dev/ttyS0\n";

type Heard = Rc<RefCell<Vec<(Vec<f64>, TimeVal)>>>;

struct Rig {
    line: VirtualLine<Lifecycle<ZaberProtocol>, ZaberSim>,
    start: Now,
    heard: Heard,
    texts: Rc<RefCell<Vec<String>>>,
    out: AnalogOutputRemote,
    _analog: AnalogRemote,
    _conn: Connection,
}

fn rig(devices: usize, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Zaber = parse_one(LINE);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let heard: Heard = Rc::default();
    let analog = AnalogRemote::on_connection(&cfg.name, &conn).unwrap();
    let h = heard.clone();
    analog.on_report(move |a| {
        h.borrow_mut()
            .push((a.channel[..a.num_channel].to_vec(), a.time))
    });
    let out = AnalogOutputRemote::on_connection(&cfg.name, &conn).unwrap();
    let texts: Rc<RefCell<Vec<String>>> = Rc::default();
    let sender = conn.register_sender(&cfg.name).unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((_, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push(text.to_owned());
        }
    });
    let mut sim = SimConfig::new(devices);
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, ZaberSim::new(sim), start, seed),
        start,
        heard,
        texts,
        out,
        _analog: analog,
        _conn: conn,
    }
}

impl Rig {
    fn run_until_reports(&mut self, n: usize, max: Duration) {
        let h = self.heard.clone();
        assert!(
            self.line.run_until(max, |_| h.borrow().len() >= n),
            "{} of {n} reports; texts {:?}",
            self.heard.borrow().len(),
            self.texts.borrow()
        );
    }

    fn has_text(&self, part: &str) -> bool {
        self.texts.borrow().iter().any(|t| t.contains(part))
    }

    /// Asks for a move of `channel` to `value` and runs until it is reported.
    fn move_to(&mut self, channel: i32, value: f64) {
        let n = self.heard.borrow().len();
        self.out
            .request_change_channel_value(channel, value)
            .unwrap();
        self.run_until_reports(n + 1, Duration::from_secs(2));
    }

    /// Reports from `from` on are the moves logged from `after` on, in order, each stamped
    /// with its answer's first byte.
    fn check(&self, from: usize, after: usize) {
        let heard = self.heard.borrow();
        let got = &heard[from..];
        let sent = &self.line.device.sent()[after..];
        assert_eq!(got.len(), sent.len(), "{got:?} / {sent:?}");
        for (i, ((channels, time), s)) in got.iter().zip(sent).enumerate() {
            assert_eq!(channels[..], s.channels[..], "report {i}");
            if !self.line.read_lag.is_zero() {
                // A slow read's records all carry its wake time: values only.
                continue;
            }
            let want = self.start.wall.plus(s.first_byte - self.start.mono);
            let late = time.seconds_since(want);
            assert!((0.0..0.002).contains(&late), "report {i}: {late} s late");
        }
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several answers at once, during the reset and
    // after: the positions and every move are reported.
    let mut r = rig(2, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.run_until_reports(1, Duration::from_secs(3));
    assert_eq!(r.heard.borrow()[0].0, [1000.0, 2000.0]);
    assert_eq!(r.line.driver.protocol().devices(), 2);
    for k in 0..20 {
        r.move_to(k % 2, f64::from(k * 211 - 900));
    }
    r.check(1, 0);
}

#[test]
fn reset_renumbers_probes_each_device_and_reports_the_positions() {
    let mut r = rig(2, 1);
    r.run_until_reports(1, Duration::from_secs(2));
    // Renumbering answers, 100 ms of quiet, two devices answering, one probe unanswered: the
    // last command about 0.22 s after the port opened, the positions reported 0.1 s later
    // (stamped with the last answer's first byte).
    let last_write = r.line.written.last().unwrap().0 - r.start.mono;
    assert!(last_write < Duration::from_millis(250), "{last_write:?}");
    let stamp = r.heard.borrow()[0].1.seconds_since(r.start.wall);
    assert!(stamp < 0.2, "{stamp}");
    assert_eq!(r.line.driver.protocol().devices(), 2);
    assert_eq!(r.heard.borrow()[0].0, [1000.0, 2000.0]);
    let mut want = command(0, 2, 0).to_vec();
    for d in 1..=3u8 {
        for (c, v) in [(23, 0), (40, 16), (41, 128), (42, 128)] {
            want.extend_from_slice(&command(d, c, v));
        }
    }
    assert_eq!(r.line.device.heard(), want);
    assert!(r.has_text("found 2 devices"));
    assert!(r.has_text("reset complete"));
}

#[test]
fn moves_are_written_and_their_positions_reported_exactly() {
    let mut r = rig(3, 2);
    r.line.split_reads = true;
    r.run_until_reports(1, Duration::from_secs(2));
    let from = r.heard.borrow().len();
    for k in 0..30 {
        r.move_to(k % 3, f64::from(k * 137 - 1500) + 0.75);
    }
    r.out.request_change_channels(&[5.0, 6.0, 7.0]).unwrap();
    r.run_until_reports(from + 33, Duration::from_secs(2));
    r.check(from, 0);
    assert_eq!(r.line.device.positions(), [5, 6, 7]);
    // Truncated as C++ does: 0 * 137 - 1500 + 0.75 -> -1499.
    assert_eq!(r.line.device.sent()[0].channels[0], -1499.0);
}

#[test]
fn an_idle_chain_is_polled_and_never_reset() {
    let mut r = rig(1, 3);
    r.run_until_reports(1, Duration::from_secs(2));
    let before = r.line.device.heard().len();
    r.line.run_for(Duration::from_secs(5));
    let polls = r.line.device.heard()[before..]
        .chunks(6)
        .filter(|c| *c == command(1, 23, 0))
        .count();
    assert!((4..=6).contains(&polls), "{polls} polls");
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
    assert_eq!(r.line.driver.stats().resets, 1);
}

#[test]
fn a_silent_chain_is_reset_and_moves_again() {
    let mut r = rig(2, 4);
    r.run_until_reports(1, Duration::from_secs(2));
    r.move_to(0, 300.0);
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(3500));
    assert_eq!(r.line.driver.stats().watchdog_fired, 1);
    assert!(r.has_text("Tracker failed, trying to reset"));
    r.line.device.mute = false;
    let (from, after) = (r.heard.borrow().len(), r.line.device.sent().len());
    assert!(r
        .line
        .run_until(Duration::from_secs(4), |l| l.driver.is_streaming()));
    r.move_to(1, -42.0);
    r.move_to(0, 77.0);
    r.check(from, after);
    assert_eq!(r.line.driver.stats().opens, 1, "reset on the open port");
}

#[test]
fn garbage_costs_no_reply_and_bad_requests_move_nothing() {
    let mut r = rig(2, 5);
    r.run_until_reports(1, Duration::from_secs(2));
    let from = r.heard.borrow().len();
    for (k, junk) in [&[9u8, 9, 9][..], &[1, 99], &[0]].iter().enumerate() {
        let now = r.line.now().mono;
        r.line.device.inject(junk, now);
        r.move_to(k as i32 % 2, 5000.0 + k as f64);
    }
    r.check(from, 0);
    assert_eq!(r.line.driver.stats().skipped_bytes, 6);
    let written = r.line.device.heard().len();
    r.out.request_change_channel_value(2, 5.0).unwrap();
    r.line.run_for(Duration::from_millis(100));
    assert!(r.has_text("not active"));
    let moves = r.line.device.heard()[written..]
        .chunks(6)
        .filter(|c| c[1] == 20)
        .count();
    assert_eq!(moves, 0);
}

#[test]
fn an_empty_chain_is_reported_and_retried() {
    let mut r = rig(0, 6);
    r.line.run_for(Duration::from_millis(2500));
    assert!(r.has_text("found 0 devices"));
    assert!(r.line.driver.stats().reset_attempts >= 2);
    assert!(!r.line.driver.is_streaming());
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Zaber\tAnalog0\tCOM1\n\
                vrpn_Zaber z1 /dev/ttyUSB0\n";
    let entries = parse_str(text, "zaber.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["Analog0", "z1"]);
    let e = parse_str("# comment\nvrpn_Zaber z1\n", "bad.cfg").unwrap_err();
    let e = e.to_string();
    assert!(e.contains("bad.cfg") && e.contains(":2"), "{e}");
}
