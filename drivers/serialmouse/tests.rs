//! The serial mouse driver against its simulator on a virtual serial line, with a client on
//! the same in-process connection: exact button changes with first-byte stamps in both
//! protocols, a slow reader, garbage, silence, a closed port, configurations.

use std::time::{Duration, Instant};

use super::config::SerialMouse;
use super::packet::MouseType;
use super::sim::{expected, SerialMouseSim, SimConfig};
use super::SerialMouseProtocol;
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
    line: VirtualLine<Lifecycle<SerialMouseProtocol>, SerialMouseSim>,
    kind: MouseType,
    start: Now,
    client: Client,
    _conn: Connection,
}

fn rig(kind: &str, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: SerialMouse = parse_one(&format!(
        "vrpn_Button_SerialMouse Button0 /dev/ttyS0 {kind}\n"
    ));
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client = Client::on_connection("Button0", &conn, &[Interface::Button]).unwrap();
    let mut sim = SimConfig::new(cfg.kind);
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let mut line = VirtualLine::new(driver, SerialMouseSim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        kind: cfg.kind,
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

    /// Every change the packets logged make, in order, each stamped with its packet's first
    /// byte (`timed`), or without times.
    fn assert_exact(&self, timed: bool, min: usize) {
        let log = self.line.device.sent();
        let at = |t: Instant| {
            self.start
                .wall
                .plus(t + self.line.latency - self.start.mono)
        };
        let want: Vec<Change> = expected(self.kind, log)
            .iter()
            .map(|c| (c.button, c.pressed, at(log[c.packet].first_byte)))
            .collect();
        let untime =
            |v: &[Change]| -> Vec<(usize, bool)> { v.iter().map(|&(b, p, _)| (b, p)).collect() };
        let got = self.heard();
        assert!(got.len() >= min, "{} changes heard", got.len());
        assert!(
            want.len() - got.len() <= 3,
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
fn both_protocols_report_every_change_exactly() {
    for (kind, seed) in [("3button", 1), ("mousesystems", 2)] {
        let mut r = rig(kind, seed);
        assert_eq!(
            r.line.driver.port_kind(),
            PortKind::Serial(PortSettings::n81(1200))
        );
        r.line.run_for(Duration::from_secs(4));
        assert!(r.line.driver.is_streaming());
        assert_eq!(r.line.written, Vec::new(), "the mouse takes no commands");
        r.assert_exact(true, 40);
        // Each button was pressed and released.
        let heard = r.heard();
        for b in 0..3 {
            assert!(heard.iter().any(|h| (h.0, h.1) == (b, true)), "{kind} {b}");
            assert!(heard.iter().any(|h| (h.0, h.1) == (b, false)), "{kind} {b}");
        }
        assert_eq!(r.line.driver.stats().skipped_bytes, 0);
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine takes several packets in one read: each counts.
    for (kind, seed) in [("3button", 3), ("mousesystems", 4)] {
        let mut r = rig(kind, seed);
        r.line.split_reads = false;
        r.line.read_lag = Duration::from_millis(90);
        r.line.run_for(Duration::from_secs(3));
        r.line.device.set_idle(true);
        r.line.run_for(Duration::from_millis(300));
        r.assert_exact(false, 30);
        let want = expected(r.kind, r.line.device.sent()).len();
        assert_eq!(r.heard().len(), want, "{kind}");
    }
}

#[test]
fn garbage_is_skipped_silence_is_normal_and_a_closed_port_comes_back() {
    let mut r = rig("mousesystems", 5);
    r.line.run_for(Duration::from_millis(1010));
    r.line.device.set_idle(true);
    r.line.run_for(Duration::from_millis(100));
    r.line.inject(&[0x41, 0x7F, 0x20]);
    r.line.run_for(Duration::from_millis(100));
    r.line.device.set_idle(false);
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact(true, 20);
    assert_eq!(r.line.driver.stats().skipped_bytes, 3);
    assert!(r.texts_with("bytes to find the next record") >= 1);
    // Silence: nothing is reset or reopened.
    r.line.silent = true;
    r.line.run_for(Duration::from_secs(10));
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
    assert_eq!(r.line.opens, 1);
    r.line.silent = false;
    let n = r.heard().len();
    r.line.run_for(Duration::from_secs(2));
    assert!(r.heard().len() > n + 10);
    // Unplugged: said, reopened, read again.
    r.line.close();
    r.line.run_for(Duration::from_millis(100));
    assert_eq!(r.texts_with("vrpn_Button_SerialMouse failure!"), 1);
    let n = r.heard().len();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.opens, 2);
    assert!(r.heard().len() > n + 10);
}

#[test]
fn configuration_lines_and_their_errors() {
    for (line, kind) in [
        (
            "vrpn_Button_SerialMouse\tButton0 /dev/ttyd1 mousesystems\n",
            MouseType::MouseSystems,
        ),
        (
            "vrpn_Button_SerialMouse\tButton0 COM1 mousesystems\n",
            MouseType::MouseSystems,
        ),
        (
            "vrpn_Button_SerialMouse\tButton0 COM1 3button\n",
            MouseType::ThreeButton,
        ),
        (
            "vrpn_Button_SerialMouse\tButton0 /dev/ttyS0 3button\n",
            MouseType::ThreeButton,
        ),
        (
            "vrpn_Button_SerialMouse\tButton0 /dev/tty.USA49W3b12P1.1 3button\n",
            MouseType::ThreeButton,
        ),
    ] {
        let m: SerialMouse = parse_one(line);
        assert_eq!((m.name.as_str(), m.kind), ("Button0", kind));
    }
    let err = |t: &str| parse_str(t, "t.cfg").unwrap_err().kind();
    assert_eq!(
        err("vrpn_Button_SerialMouse Button0 COM1\n"),
        ConfigErrorKind::MissingArguments
    );
    assert_eq!(
        err("vrpn_Button_SerialMouse Button0 COM1 microsoft\n"),
        ConfigErrorKind::BadValue
    );
}
