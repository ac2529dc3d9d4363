//! The inertia mouse driver against the simulator on a virtual serial line, with the
//! driver's servers and a client's remotes on one in-process connection: exact channels and
//! button changes in order with first-byte stamps, garbage, configurations.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::config::InertiaMouse;
use super::sim::{InertiaSim, Sent, SimConfig};
use super::InertiaMouseProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::sim::VirtualLine;
use crate::{AnalogRemote, ButtonRemote, Connection, Now, TimeVal};

/// What the client heard: channels or a button change, with the report's time stamp.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Report {
    Analog([f64; 6], TimeVal),
    Button(usize, bool, TimeVal),
}

type Heard = Rc<RefCell<Vec<Report>>>;

struct Rig {
    line: VirtualLine<Lifecycle<InertiaMouseProtocol>, InertiaSim>,
    start: Now,
    heard: Heard,
    _remotes: (AnalogRemote, ButtonRemote),
    _conn: Connection,
}

fn rig(seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: InertiaMouse = parse_one("vrpn_inertiamouse Mouse0 /dev/ttyS0 115200\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let heard: Heard = Rc::default();
    let analog = AnalogRemote::on_connection("Mouse0", &conn).unwrap();
    let h = heard.clone();
    analog.on_report(move |r| {
        let mut v = [0.0; 6];
        v.copy_from_slice(&r.channels()[..6]);
        h.borrow_mut().push(Report::Analog(v, r.time));
    });
    let buttons = ButtonRemote::on_connection("Mouse0", &conn).unwrap();
    let h = heard.clone();
    buttons.on_change(move |c| {
        h.borrow_mut()
            .push(Report::Button(c.button, c.state.is_pressed(), c.time))
    });
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    Rig {
        line: VirtualLine::new(driver, InertiaSim::new(sim), start, seed),
        start,
        heard,
        _remotes: (analog, buttons),
        _conn: conn,
    }
}

impl Rig {
    /// Everything heard is what the simulator logged, in order, each stamped with its
    /// record's first byte (plus the line's latency).
    fn assert_all_heard(&self) {
        let heard = self.heard.borrow();
        let sent = self.line.device.sent();
        assert!(heard.len() >= 100, "{} reports", heard.len());
        assert!(
            sent.len() - heard.len() <= 2,
            "{} sent, {} heard",
            sent.len(),
            heard.len()
        );
        let at = |t: Instant| {
            self.start
                .wall
                .plus(t + self.line.latency - self.start.mono)
        };
        // A slow read's records all carry its wake time: values only.
        let lag = !self.line.read_lag.is_zero();
        let untimed = |r: Report| match r {
            Report::Analog(v, _) if lag => Report::Analog(v, TimeVal::ZERO),
            Report::Button(i, p, _) if lag => Report::Button(i, p, TimeVal::ZERO),
            r => r,
        };
        for (h, s) in heard.iter().zip(sent) {
            let want = match *s {
                Sent::Analog(v, t) => Report::Analog(v, at(t)),
                Sent::Button(i, p, t) => Report::Button(i, p, at(t)),
            };
            assert_eq!(untimed(*h), untimed(want));
        }
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several records at once: every report is made,
    // from the first.
    let mut r = rig(21);
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(3));
    r.assert_all_heard();
}

#[test]
fn channels_and_buttons_arrive_exactly() {
    let mut r = rig(1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(115_200))
    );
    r.line.run_for(Duration::from_secs(3));
    r.assert_all_heard();
    let heard = r.heard.borrow();
    assert!(heard
        .iter()
        .any(|h| matches!(h, Report::Button(0, true, _))));
    // Channels 0-3 move only while button 0 is held; channel 4 or 5 is read each record.
    assert!(heard
        .iter()
        .any(|h| matches!(h, Report::Analog(v, _) if v[0] != 0.0)));
}

#[test]
fn garbage_costs_no_record() {
    let mut r = rig(2);
    r.line.split_reads = true;
    // 5 ms after a record starts (one every 10 ms, 2.6 ms long): between records.
    r.line.run_for(Duration::from_millis(5));
    for junk in [&b"Dxx\n"[..], b"B\x01", b"\n\nQ", b"BBBB"] {
        r.line.run_for(Duration::from_millis(200));
        r.line.inject(junk);
    }
    r.line.run_for(Duration::from_millis(500));
    assert!(r.line.driver.stats().skipped_bytes >= 10);
    r.assert_all_heard();
}

#[test]
fn configuration_lines_and_their_errors() {
    let m: InertiaMouse = parse_one("vrpn_inertiamouse Mouse0 /dev/ttyS0 19200\n");
    assert_eq!((m.port.as_str(), m.baud), ("/dev/ttyS0", 19200));
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err().kind();
    assert_eq!(
        err("vrpn_inertiamouse Mouse0 /dev/ttyS0\n"),
        ConfigErrorKind::MissingArguments
    );
    assert_eq!(
        err("vrpn_inertiamouse Mouse0 /dev/ttyS0 19200 x\n"),
        ConfigErrorKind::BadValue
    );
}
