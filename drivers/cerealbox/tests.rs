//! The CerealBox driver against the simulated box on a virtual serial line, with a client's
//! remotes on the same in-process connection: the reset, exact values and first-byte times
//! for several layouts, resynchronisation and repolling, the watchdog, a wrong EEPROM, a
//! reopened port, every configuration variant.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config;
use super::record::{revolutions, Layout};
use super::reset::RETRY_PAUSE;
use super::sim::{analog, buttons, encoder, CerealSim, SentRecord, SimConfig};
use super::{CerealBoxProtocol, WATCHDOG};
use crate::devices::base::{set_print_threshold, TEXT_MESSAGE};
use crate::devices::text::{decode_text, TextSeverity};
use crate::driver::Lifecycle;
use crate::serial::SerialDriver;
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, ButtonRemote, Connection, DialRemote, Now, SenderFilter, TimeVal};

type Line = VirtualLine<Lifecycle<CerealBoxProtocol>, CerealSim>;
type Shared<T> = Rc<RefCell<Vec<T>>>;

const START_WALL: TimeVal = TimeVal {
    sec: 1_700_000_000,
    usec: 0,
};

/// What the client saw, in order.
#[derive(Clone, Debug, PartialEq)]
enum Event {
    Analog(TimeVal, Vec<f64>),
    Button(TimeVal, i32, i32),
    Dial(TimeVal, i32, f64),
}

impl Event {
    fn time(&self) -> TimeVal {
        match self {
            Event::Analog(t, _) | Event::Button(t, _, _) | Event::Dial(t, _, _) => *t,
        }
    }
}

fn cereal_cfg(text: &str) -> config::CerealBox {
    parse_one(text)
}

struct Rig {
    line: Line,
    start: Now,
    layout: Layout,
    events: Shared<Event>,
    texts: Shared<(TextSeverity, String)>,
    _remotes: (AnalogRemote, ButtonRemote, DialRemote),
    _conn: Connection,
}

fn rig(cfg_text: &str, sim: SimConfig, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg = cereal_cfg(cfg_text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let layout = driver.protocol().layout();
    let a = AnalogRemote::on_connection(&cfg.name, &conn).unwrap();
    let b = ButtonRemote::on_connection(&cfg.name, &conn).unwrap();
    let d = DialRemote::on_connection(&cfg.name, &conn).unwrap();
    let events: Shared<Event> = Rc::default();
    let e = events.clone();
    a.on_report(move |r| {
        e.borrow_mut()
            .push(Event::Analog(r.time, r.channels().to_vec()))
    });
    let e = events.clone();
    b.on_change(move |c| {
        e.borrow_mut()
            .push(Event::Button(c.time, c.button as i32, c.state.raw()))
    });
    let e = events.clone();
    d.on_update(move |u| {
        e.borrow_mut()
            .push(Event::Dial(u.time, u.dial as i32, u.change))
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
    let mut line = VirtualLine::new(driver, CerealSim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        layout,
        events,
        texts,
        _remotes: (a, b, d),
        _conn: conn,
    }
}

impl Rig {
    fn run_to_first_record(&mut self, max: Duration) -> Duration {
        let t0 = self.line.now().mono;
        assert!(
            self.line.run_until(max, |l| l.driver.stats().records > 0),
            "no record within {max:?}; texts: {:?}",
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

    fn arrival(&self, at: Instant) -> TimeVal {
        START_WALL.plus(at + self.line.latency - self.start.mono)
    }

    fn log(&self) -> Vec<SentRecord> {
        self.line.device.log.iter().copied().collect()
    }

    /// What a client must see for the complete records of `log` less `lost`, from zeroes.
    fn expected(&self, log: &[SentRecord], lost: &[u64]) -> Vec<Event> {
        self.expected_from(log, lost, vec![0.0; self.layout.analogs], 0)
    }

    /// What a client must see for the complete records of `log` less `lost`, from the channels
    /// `chans` and the buttons `mask`.
    fn expected_from(
        &self,
        log: &[SentRecord],
        lost: &[u64],
        mut chans: Vec<f64>,
        mut mask: u32,
    ) -> Vec<Event> {
        let l = self.layout;
        let mut out = Vec::new();
        let half = SimConfig::default().second_half_after;
        let now = self.line.now().mono;
        for r in log
            .iter()
            .filter(|r| r.at + half + self.line.latency <= now && !lost.contains(&r.seq))
        {
            let t = self.arrival(r.at);
            let v: Vec<f64> = (0..l.analogs)
                .map(|i| -1.0 + 2.0 * f64::from(analog(r.seq, i)) / 4095.0)
                .collect();
            if v != chans {
                out.push(Event::Analog(t, v.clone()));
                chans = v;
            }
            let m = buttons(r.seq);
            for i in 0..l.buttons {
                if (m ^ mask) & (1 << i) != 0 {
                    out.push(Event::Button(t, i as i32, i32::from(m & (1 << i) != 0)));
                }
            }
            mask = m;
            for i in 0..l.encoders {
                let ticks = encoder(r.seq, i);
                // The box counts 24 bits.
                let ticks = (ticks << 8) >> 8;
                if ticks != 0 {
                    out.push(Event::Dial(t, i as i32, revolutions(ticks)));
                }
            }
        }
        out
    }
}

/// Events equal, times within a microsecond; reports only the first difference.
fn assert_same(got: &[Event], want: &[Event]) {
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        let dt = (g.time().as_micros() - w.time().as_micros()).abs();
        let same = dt <= 1
            && match (g, w) {
                (Event::Analog(_, a), Event::Analog(_, b)) => a == b,
                (Event::Button(_, a, s), Event::Button(_, b, t)) => (a, s) == (b, t),
                (Event::Dial(_, a, x), Event::Dial(_, b, y)) => (a, x) == (b, y),
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
        let mut e = e.clone();
        match &mut e {
            Event::Analog(t, _) | Event::Button(t, _, _) | Event::Dial(t, _, _) => {
                *t = TimeVal::ZERO
            }
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
    // A loaded machine reads late and takes several replies at once (the first record with
    // the acknowledgement that ends the reset): every input is reported, from the first.
    let mut r = rig(
        "vrpn_CerealBox Cereal0 /dev/ttyS0 19200 24 8 8\n",
        SimConfig::default(),
        21,
    );
    r.line.read_lag = Duration::from_millis(12);
    r.run_to_first_record(Duration::from_secs(1));
    r.line.run_for(Duration::from_secs(1));
    let log = r.log();
    assert!(log.len() > 40, "{} records", log.len());
    assert_same_values(&r.events.borrow(), &r.expected(&log, &[]));
}

#[test]
fn every_input_exact_and_stamped_with_the_first_byte() {
    let mut r = rig(
        "vrpn_CerealBox Cereal0 /dev/ttyS0 19200 24 8 8\n",
        SimConfig::default(),
        1,
    );
    let took = r.run_to_first_record(Duration::from_secs(1));
    // Banner, configuration, acknowledgement and the first record, at 1 ms a reply.
    assert!(
        took < Duration::from_millis(15),
        "first record after {took:?}"
    );
    let written: Vec<u8> = r.line.written.iter().flat_map(|w| w.1.clone()).collect();
    assert_eq!(&written[..13], b"Tc0\xa0!!0000\npE");
    assert_eq!(r.line.device.layout(), Some(r.layout));
    assert_eq!(r.line.driver.protocol().box_type(), Some(b'L'));
    assert_eq!(
        *r.texts.borrow(),
        [(
            TextSeverity::Normal,
            "vrpn_CerealBox: Box of type 'L' found".into()
        )]
    );
    r.line.run_for(Duration::from_secs(2));
    let log = r.log();
    // Polled: about one record per 6 ms (1 ms reply, second half 5 ms later).
    assert!(log.len() > 300, "{} records", log.len());
    assert_same(&r.events.borrow(), &r.expected(&log, &[]));
    let kinds = |f: fn(&Event) -> bool| r.events.borrow().iter().filter(|e| f(e)).count();
    assert!(kinds(|e| matches!(e, Event::Dial(..))) > 1000);
    assert!(kinds(|e| matches!(e, Event::Button(..))) > 1000);
    assert_eq!(r.line.driver.protocol().repolls(), 0);
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
}

#[test]
fn partial_layouts_configure_the_box_and_decode() {
    for (i, (b, a, e)) in [(5usize, 3, 0), (0, 0, 2), (9, 5, 2), (17, 1, 5), (0, 0, 0)]
        .into_iter()
        .enumerate()
    {
        let text = format!("vrpn_CerealBox C /dev/ttyS0 19200 {b} {a} {e}\n");
        let mut r = rig(&text, SimConfig::default(), 10 + i as u64);
        r.run_to_first_record(Duration::from_secs(1));
        let want = Layout {
            buttons: b.div_ceil(8) * 8,
            analogs: a,
            encoders: e,
        };
        assert_eq!(r.line.device.layout(), Some(want), "{text}");
        r.line.run_for(Duration::from_millis(500));
        assert!(r.line.driver.stats().records > 50);
        assert_same(&r.events.borrow(), &r.expected(&r.log(), &[]));
    }
}

#[test]
fn garbage_costs_only_the_records_it_hits_and_polling_goes_on() {
    let mut r = rig(
        "vrpn_CerealBox C /dev/ttyS0 19200 16 4 4\n",
        SimConfig::default(),
        2,
    );
    r.run_to_first_record(Duration::from_secs(1));
    let half = SimConfig::default().second_half_after;
    let mut injected = Vec::new();
    for round in 0..150u64 {
        // Odd steps, so garbage lands at every phase of the polling cycle.
        r.line
            .run_for(Duration::from_micros(7_300 + 1_100 * (round % 7)));
        injected.push(r.line.now().mono);
        r.line.inject(match round % 4 {
            0 => b"\x00\xff",
            1 => b"\n",
            2 => b"xp",
            _ => b"\x7f\x7f\x7f",
        });
    }
    r.line.run_for(Duration::from_millis(300));
    // A record is hit when garbage arrives between its halves.
    let lost: Vec<u64> = r
        .log()
        .iter()
        .filter(|s| injected.iter().any(|&x| x > s.at && x < s.at + half))
        .map(|s| s.seq)
        .collect();
    assert!(lost.len() >= 8, "{} records hit", lost.len());
    assert_same(&r.events.borrow(), &r.expected(&r.log(), &lost));
    // Each hit record left the box waiting: the request was repeated.
    assert_eq!(r.line.driver.protocol().repolls(), lost.len() as u64);
    assert!(r.texts_with("skipped") >= 1 && r.texts_with("skipped") <= 2);
    assert_eq!(r.texts_with("resetting"), 0);
}

#[test]
fn a_lost_request_is_repeated() {
    let mut r = rig(
        "vrpn_CerealBox C /dev/ttyS0 19200 8 2 1\n",
        SimConfig::default(),
        3,
    );
    r.run_to_first_record(Duration::from_secs(1));
    r.line.device.ignore_requests(3);
    r.line.run_for(Duration::from_secs(1));
    assert_eq!(r.line.driver.protocol().repolls(), 3);
    assert_same(&r.events.borrow(), &r.expected(&r.log(), &[]));
    assert!(r.texts.borrow().len() == 1, "{:?}", r.texts.borrow());
}

#[test]
fn a_hung_box_is_reset_until_it_answers_and_resumes() {
    let mut r = rig(
        "vrpn_CerealBox C /dev/ttyS0 19200 8 2 2\n",
        SimConfig::default(),
        4,
    );
    r.run_to_first_record(Duration::from_secs(1));
    r.line.run_for(Duration::from_millis(300));
    r.line.device.set_silent(true);
    let hung = r.line.now().mono;
    assert!(r
        .line
        .run_until(Duration::from_secs(5), |l| !l.driver.is_streaming()));
    // The banner request of the new reset is the last write.
    let (at, bytes) = r.line.written.last().unwrap().clone();
    assert_eq!(bytes, b"T");
    let noticed = at - hung;
    assert!(
        noticed <= WATCHDOG && noticed + Duration::from_millis(10) >= WATCHDOG,
        "{noticed:?}"
    );
    assert_eq!(r.texts_with("Too long since last report, resetting"), 1);
    // What the box last sent, as the driver holds it.
    let (held_chans, held_mask) = {
        let p = r.line.driver.protocol();
        let mask = (0..r.layout.buttons)
            .filter(|&i| p.buttons().button(i).is_pressed())
            .fold(0u32, |m, i| m | 1 << i);
        (p.analog().channels().to_vec(), mask)
    };
    let seen = r.events.borrow().len();
    r.line.run_for(Duration::from_secs(6));
    // A reset never invents data: no zeroed channels, no released buttons meanwhile.
    assert_eq!(
        r.events.borrow().len(),
        seen,
        "events while the box was silent"
    );
    let failures = r.texts_with("No response from box");
    // One attempt per 2 s time-out and pause.
    assert!((2..=3).contains(&failures), "{:?}", r.texts.borrow());
    r.line.device.set_silent(false);
    let woke = r.line.now().mono;
    let before = r.line.driver.stats().records;
    assert!(r
        .line
        .run_until(Duration::from_secs(3), |l| l.driver.stats().records
            > before));
    let took = r.line.now().mono - woke;
    assert!(took <= Duration::from_secs(2) + RETRY_PAUSE + Duration::from_millis(20));
    r.line.run_for(Duration::from_secs(1));
    let log: Vec<SentRecord> = r.log().into_iter().filter(|s| s.at > woke).collect();
    let after: Vec<Event> = r
        .events
        .borrow()
        .iter()
        .filter(|e| e.time() > r.arrival(woke))
        .cloned()
        .collect();
    // From the values the box last sent, exactly what it sends after the reset.
    let want = r.expected_from(&log, &[], held_chans, held_mask);
    assert!(want.len() > 100);
    assert_same(&after, &want);
    // The first reset, the watchdog's, and the attempts that failed.
    let failed = r.texts_with("No response from box") + r.texts_with("expected characters");
    assert_eq!(r.line.driver.stats().reset_attempts, 2 + failed as u64);
}

#[test]
fn garbage_before_the_banner_is_passed_over() {
    let mut r = rig(
        "vrpn_CerealBox C /dev/ttyS0 19200 8 1 0\n",
        SimConfig::default(),
        5,
    );
    r.line.inject(b"p!!!\nCopy\x00");
    r.run_to_first_record(Duration::from_millis(100));
    assert_eq!(r.texts.borrow().len(), 1, "{:?}", r.texts.borrow());
}

#[test]
fn a_box_with_another_eeprom_is_refused() {
    let sim = SimConfig {
        version: *b"3.06",
        ..SimConfig::default()
    };
    let mut r = rig("vrpn_CerealBox C /dev/ttyS0 19200 8 1 1\n", sim, 6);
    r.line.run_for(Duration::from_secs(2));
    assert!(!r.line.driver.is_streaming());
    let n = r.texts_with("Bad EEPROM version (want 3.07, got 3.06)");
    assert!(n >= 3, "{:?}", r.texts.borrow());
    // (The last banner may still be on its way.)
    assert!((n as u32..=n as u32 + 1).contains(&r.line.device.banners()));
    assert_eq!(r.line.device.layout(), None);
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig(
        "vrpn_CerealBox C /dev/ttyS0 19200 8 1 1\n",
        SimConfig::default(),
        7,
    );
    r.run_to_first_record(Duration::from_secs(1));
    r.line.run_for(Duration::from_millis(100));
    r.line.close();
    assert_eq!(r.line.driver.next_deadline(), None);
    let n = r.line.driver.stats().records;
    assert!(r
        .line
        .run_until(Duration::from_secs(2), |l| l.driver.stats().records
            > n + 10));
    assert_eq!(r.line.opens, 2);
    assert_eq!(r.line.driver.stats().reset_attempts, 2);
    assert_eq!(r.line.device.banners(), 2);
}

#[test]
fn every_variant_parses_and_builds() {
    for (b, a, e) in [
        (0, 0, 0),
        (24, 8, 8),
        (1, 0, 0),
        (0, 1, 0),
        (0, 0, 1),
        (12, 7, 3),
    ] {
        let text = format!("vrpn_CerealBox Cereal0 /dev/ttyUSB0 9600 {b} {a} {e}\n");
        let cfg = cereal_cfg(&text);
        let conn = Connection::new_loopback();
        let d = CerealBoxProtocol::new(&cfg, &conn).unwrap();
        assert_eq!(d.analog().num_channels(), a);
        assert_eq!(d.buttons().num_buttons(), b);
        assert_eq!(d.dials().num_dials(), e);
        assert_eq!(d.port(), "/dev/ttyUSB0");
        let entries = parse_str(&text, "test.cfg").unwrap();
        let mut opened = Vec::new();
        let devices = build_devices(&entries, &Connection::new_loopback(), false, None, |n| {
            if let BuildNote::Opened { name, .. } = n {
                opened.push(name.to_owned());
            }
        })
        .unwrap();
        assert_eq!((devices.len(), opened), (1, vec!["Cereal0".to_owned()]));
    }
    let over = config::CerealBox {
        name: "C".into(),
        port: "/dev/x".into(),
        baud: 19200,
        buttons: 25,
        analogs: 0,
        encoders: 0,
    };
    assert!(CerealBoxProtocol::new(&over, &Connection::new_loopback()).is_err());
}
