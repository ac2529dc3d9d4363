//! The Orb driver against the simulator on a virtual serial line, with the driver's servers
//! and a client's remotes on one in-process connection: the reset, exact button, analog and
//! dial reports in order with their stamps, the probe of an idle Orb, garbage, silence,
//! configurations.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::Orb;
use super::sim::{OrbSim, Sent, SimConfig};
use super::OrbProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, ButtonRemote, Connection, DialRemote, Now, SenderFilter, TimeVal};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Report {
    Button(usize, bool, TimeVal),
    Analog([f64; 3], TimeVal),
    Dial(usize, f64, TimeVal),
}

type Shared<T> = Rc<RefCell<Vec<T>>>;

struct Rig {
    line: VirtualLine<Lifecycle<OrbProtocol>, OrbSim>,
    start: Now,
    heard: Shared<Report>,
    texts: Shared<String>,
    _remotes: (ButtonRemote, AnalogRemote, DialRemote),
    _conn: Connection,
}

fn rig(tweak: impl FnOnce(&mut SimConfig), seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Orb = parse_one("vrpn_GlobalHapticsOrb Orb0 COM1 19200\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let heard: Shared<Report> = Rc::default();
    let b = ButtonRemote::on_connection("Orb0", &conn).unwrap();
    let h = heard.clone();
    b.on_change(move |c| {
        h.borrow_mut()
            .push(Report::Button(c.button, c.state.is_pressed(), c.time))
    });
    let a = AnalogRemote::on_connection("Orb0", &conn).unwrap();
    let h = heard.clone();
    a.on_report(move |r| {
        let mut v = [0.0; 3];
        v.copy_from_slice(&r.channels()[..3]);
        h.borrow_mut().push(Report::Analog(v, r.time))
    });
    let d = DialRemote::on_connection("Orb0", &conn).unwrap();
    let h = heard.clone();
    d.on_update(move |u| h.borrow_mut().push(Report::Dial(u.dial, u.change, u.time)));
    let texts: Shared<String> = Rc::default();
    let sender = conn.register_sender("Orb0").unwrap();
    let text_type = conn.register_type(TEXT_MESSAGE).unwrap();
    let t = texts.clone();
    conn.register_handler(text_type, SenderFilter::Only(sender), move |m| {
        if let Some((_, _, text)) = decode_text(m.payload) {
            t.borrow_mut().push(text.to_owned());
        }
    });
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, OrbSim::new(sim), start, seed),
        start,
        heard,
        texts,
        _remotes: (b, a, d),
        _conn: conn,
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

    /// Everything heard is what the simulator sent from its first event on (it starts once
    /// it has answered the reset), in order, with first-byte stamps.
    fn assert_all_heard(&self, min: usize) {
        let heard = self.heard.borrow();
        let at = |t: Instant| {
            self.start
                .wall
                .plus(t + self.line.latency - self.start.mono)
        };
        let sent: Vec<Report> = self
            .line
            .device
            .sent()
            .iter()
            .map(|s| match *s {
                Sent::Button(i, p, t) => Report::Button(i, p, at(t)),
                Sent::Analog(v, t) => Report::Analog(v, at(t)),
                Sent::Dial(i, r, t) => Report::Dial(i, r, at(t)),
            })
            .collect();
        assert!(heard.len() >= min, "{} reports", heard.len());
        let from = sent
            .iter()
            .position(|s| *s == heard[0])
            .expect("the first report was sent");
        assert_eq!(from, 0, "{from} reports lost at the start");
        let sent = &sent[from..];
        assert!(
            sent.len() - heard.len() <= 2,
            "{} sent, {} heard",
            sent.len(),
            heard.len()
        );
        for (h, s) in heard.iter().zip(sent) {
            assert_eq!(h, s);
        }
    }
}

#[test]
fn events_arrive_exactly_after_a_reset() {
    let mut r = rig(|_| {}, 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(19200))
    );
    r.line.run_for(Duration::from_secs(3));
    assert_eq!(r.texts_with("Reset complete (this is good)"), 1);
    assert_eq!(r.line.device.resets_heard(), 1);
    r.assert_all_heard(500);
    let heard = r.heard.borrow();
    for kind in 0..3 {
        assert!(heard.iter().any(|h| match (kind, h) {
            (0, Report::Button(29, false, _)) => true,
            (1, Report::Analog(v, _)) => v[0] == 1.0,
            (2, Report::Dial(2, _, _)) => true,
            _ => false,
        }));
    }
}

#[test]
fn events_in_the_read_of_the_reset_answer_are_reported() {
    // A slow reader takes the answer `FC` and the first events in one read (seen on a loaded
    // machine): they are events, not part of the reset.
    let mut r = rig(|_| {}, 4);
    r.line.read_lag = Duration::from_millis(4);
    r.line.run_for(Duration::from_secs(1));
    // Let what is on its way arrive.
    r.line.device.set_idle(true);
    r.line.run_for(Duration::from_millis(50));
    assert_eq!(r.texts_with("Reset complete (this is good)"), 1);
    // Every event, in order (a read's reports carry its wake time, so times are not compared).
    let untimed = |v: &Report| match *v {
        Report::Button(i, p, _) => Report::Button(i, p, TimeVal::ZERO),
        Report::Analog(c, _) => Report::Analog(c, TimeVal::ZERO),
        Report::Dial(i, d, _) => Report::Dial(i, d, TimeVal::ZERO),
    };
    let heard: Vec<Report> = r.heard.borrow().iter().map(untimed).collect();
    let sent: Vec<Report> = r
        .line
        .device
        .sent()
        .iter()
        .map(|s| match *s {
            Sent::Button(i, p, _) => Report::Button(i, p, TimeVal::ZERO),
            Sent::Analog(v, _) => Report::Analog(v, TimeVal::ZERO),
            Sent::Dial(i, d, _) => Report::Dial(i, d, TimeVal::ZERO),
        })
        .collect();
    assert!(sent.len() > 250, "{} sent", sent.len());
    assert_eq!(heard, sent);
}

#[test]
fn an_idle_orb_is_probed_and_not_reset() {
    let mut r = rig(|s| s.idle = true, 2);
    r.line.run_for(Duration::from_secs(23));
    // Probed at 5 s, 10 s, 15 s, 20 s of silence; each probe answered.
    assert_eq!(r.line.device.resets_heard(), 5);
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
    r.line.device.set_idle(false);
    r.line.run_for(Duration::from_secs(1));
    r.assert_all_heard(150);
}

#[test]
fn garbage_is_skipped_and_silence_resets() {
    let mut r = rig(|_| {}, 3);
    r.line.run_for(Duration::from_millis(502));
    for junk in [&[0x41u8][..], &[0x7F, 0x55], &[0x20]] {
        r.line.inject(junk);
        r.line.run_for(Duration::from_millis(100));
    }
    r.assert_all_heard(100);
    assert_eq!(r.line.driver.stats().skipped_bytes, 4);
    assert!(r.texts_with("unknown byte") >= 1);
    r.line.silent = true;
    r.line.run_for(Duration::from_secs(13));
    assert!(r.texts_with("Too long since last report, resetting") >= 1);
    assert!(r.texts_with("No response from Orb") >= 1);
    r.line.silent = false;
    let n = r.heard.borrow().len();
    let heard = r.heard.clone();
    assert!(r
        .line
        .run_until(Duration::from_secs(4), |_| heard.borrow().len() > n + 50));
}

#[test]
fn configuration_lines_and_their_errors() {
    let o: Orb = parse_one("vrpn_GlobalHapticsOrb Orb0 COM1 19200\n");
    assert_eq!(
        (o.name.as_str(), o.port.as_str(), o.baud),
        ("Orb0", "COM1", 19200)
    );
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err().kind();
    assert_eq!(
        err("vrpn_GlobalHapticsOrb Orb0 COM1\n"),
        ConfigErrorKind::MissingArguments
    );
    assert_eq!(
        err("vrpn_GlobalHapticsOrb Orb0 COM1 19200 1\n"),
        ConfigErrorKind::BadValue
    );
}
