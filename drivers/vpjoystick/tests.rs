//! The VP joystick driver against its simulator on a virtual serial line, with a client on
//! the same in-process connection: exact button changes with first-byte stamps, a slow
//! reader, garbage, silence, a closed port, configurations.

use std::time::{Duration, Instant};

use super::config::VpJoystick;
use super::sim::{expected, SimConfig, VpJoystickSim};
use super::VpJoystickProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{Connection, Now, TimeVal};

struct Rig {
    line: VirtualLine<Lifecycle<VpJoystickProtocol>, VpJoystickSim>,
    start: Now,
    client: Client,
    _conn: Connection,
}

fn rig(seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: VpJoystick = parse_one("vrpn_VPJoystick VPJoystick0 /dev/ttyS0 9600\n");
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client = Client::on_connection("VPJoystick0", &conn, &[Interface::Button]).unwrap();
    let mut sim = SimConfig::new(cfg.baud);
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let mut line = VirtualLine::new(driver, VpJoystickSim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        client,
        _conn: conn,
    }
}

type Change = (usize, bool, TimeVal);

impl Rig {
    fn heard(&self) -> Vec<Change> {
        self.client
            .heard()
            .iter()
            .filter_map(|h| match *h {
                Heard::Button {
                    button,
                    pressed,
                    time,
                } => Some((button, pressed, time)),
                _ => None,
            })
            .collect()
    }

    fn texts_with(&self, needle: &str) -> usize {
        let t = self.client.texts_from(0);
        t.iter().filter(|t| t.contains(needle)).count()
    }

    /// Every change the messages logged make, in order, each stamped with its message's
    /// `FF` (`timed`), or without times.
    fn assert_exact(&self, timed: bool, min: usize) {
        let log = self.line.device.sent();
        let at = |t: Instant| {
            self.start
                .wall
                .plus(t + self.line.latency - self.start.mono)
        };
        let want: Vec<Change> = expected(log)
            .iter()
            .map(|&(b, p, k)| (b, p, at(log[k].first_byte)))
            .collect();
        let untime =
            |v: &[Change]| -> Vec<(usize, bool)> { v.iter().map(|&(b, p, _)| (b, p)).collect() };
        let got = self.heard();
        assert!(got.len() >= min, "{} changes heard", got.len());
        assert!(
            want.len() - got.len() <= 8,
            "{} of {}",
            got.len(),
            want.len()
        );
        if timed {
            assert_eq!(got[..], want[..got.len()]);
        } else {
            assert_eq!(untime(&got), untime(&want[..got.len()]));
        }
    }
}

#[test]
fn every_change_arrives_exactly() {
    let mut r = rig(1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
    r.line.run_for(Duration::from_secs(3));
    assert!(r.line.driver.is_streaming());
    assert_eq!(r.line.written, Vec::new(), "the joystick takes no commands");
    r.assert_exact(true, 200);
    let heard = r.heard();
    for b in 0..8 {
        assert!(heard.iter().any(|h| (h.0, h.1) == (b, true)), "{b}");
    }
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
}

#[test]
fn a_slow_reader_loses_nothing() {
    let mut r = rig(2);
    r.line.split_reads = false;
    r.line.read_lag = Duration::from_millis(50);
    r.line.run_for(Duration::from_secs(2));
    r.line.device.set_idle(true);
    r.line.run_for(Duration::from_millis(200));
    r.assert_exact(false, 150);
    assert_eq!(r.heard().len(), expected(r.line.device.sent()).len());
}

#[test]
fn garbage_is_skipped_silence_is_normal_and_a_closed_port_comes_back() {
    let mut r = rig(3);
    r.line.run_for(Duration::from_millis(1005));
    r.line.inject(&[0x41, 0x7F, 0x20]);
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact(true, 100);
    assert_eq!(r.line.driver.stats().skipped_bytes, 3);
    assert!(r.texts_with("bytes to find the next record") >= 1);
    // Silence: nothing is reset or reopened.
    r.line.silent = true;
    r.line.run_for(Duration::from_secs(10));
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
    assert_eq!(r.line.opens, 1);
    r.line.silent = false;
    let n = r.heard().len();
    r.line.run_for(Duration::from_secs(1));
    assert!(r.heard().len() > n + 50);
    // Unplugged: reopened, read again.
    r.line.close();
    let n = r.heard().len();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.opens, 2);
    assert!(r.heard().len() > n + 50);
}

#[test]
fn configuration_lines_and_their_errors() {
    let j: VpJoystick = parse_one("vrpn_VPJoystick VPJoystick0 /dev/ttyS0 9600\n");
    assert_eq!(
        (j.name.as_str(), j.port.as_str(), j.baud),
        ("VPJoystick0", "/dev/ttyS0", 9600)
    );
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err().kind();
    assert_eq!(
        err("vrpn_VPJoystick VPJoystick0 /dev/ttyS0\n"),
        ConfigErrorKind::MissingArguments
    );
    assert_eq!(
        err("vrpn_VPJoystick VPJoystick0 /dev/ttyS0 fast\n"),
        ConfigErrorKind::BadNumber
    );
}
