//! The Atmel driver against its simulated board on a virtual serial line, with an Analog
//! remote and an Analog_Output remote on one in-process connection: the reset's reads, exact
//! values cycle after cycle with first-byte stamps, writes and C++'s error values, a slow
//! reader, garbage, silence, an unplugged line, a board without readable channels, the
//! configuration lines.

use std::time::{Duration, Instant};

use super::command::reported;
use super::config::Atmel;
use super::sim::{input_value, AtmelSim, SimConfig};
use super::AtmelProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::analog_output::AnalogOutputRemote;
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::Interface;
use crate::driver::Lifecycle;
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{Connection, Now, TimeVal};

const LINES: &str = "vrpn_Atmel Atmel0 /dev/ttyS0 9600 5\n\
                     vrpn_Atmel 0 RO\n\
                     # a comment between the lines\n\
                     vrpn_Atmel 1 RO\n\
                     vrpn_Atmel 2 RW\n\
                     vrpn_Atmel 3 WO\n\
                     vrpn_Atmel -1 END\n";

struct Rig {
    line: VirtualLine<Lifecycle<AtmelProtocol>, AtmelSim>,
    start: Now,
    client: Client,
    output: AnalogOutputRemote,
    _conn: Connection,
}

fn rig(text: &str, seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Atmel = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client = Client::on_connection("Atmel0", &conn, &[Interface::Analog]).unwrap();
    let output = AnalogOutputRemote::on_connection("Atmel0", &conn).unwrap();
    let mut sim = SimConfig::new(9600);
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, AtmelSim::new(sim), start, seed),
        start,
        client,
        output,
        _conn: conn,
    }
}

impl Rig {
    fn reports(&self) -> Vec<(Vec<f64>, TimeVal)> {
        self.client
            .reports_from(0)
            .into_iter()
            .filter_map(|h| match h {
                Heard::Analog { channels, time } => Some((channels, time)),
                _ => None,
            })
            .collect()
    }

    fn texts_with(&self, part: &str) -> usize {
        self.client
            .texts_from(0)
            .iter()
            .filter(|t| t.contains(part))
            .count()
    }

    /// Register `r`'s answers, in order: value and when the driver saw the first byte.
    fn answers(&self, r: usize) -> Vec<(f64, TimeVal)> {
        self.line
            .device
            .answered()
            .iter()
            .filter(|a| a.register == r)
            .map(|a| {
                let at = a.at + self.line.latency - self.start.mono;
                (f64::from(a.value), self.start.wall.plus(at))
            })
            .collect()
    }

    /// Reports `from..` carry register `r`'s answers one for one, in order, from answer
    /// `after` on; with `stamped`, each report is stamped with that answer's first byte.
    fn assert_channel_is_answers(&self, r: usize, from: usize, stamped: bool) {
        let got: Vec<(f64, TimeVal)> = self.reports()[from..]
            .iter()
            .map(|(c, t)| (c[r], *t))
            .collect();
        assert!(got.len() > 20, "{} reports", got.len());
        let sent = self.answers(r);
        let values = |v: &[(f64, TimeVal)]| v.iter().map(|x| x.0).collect::<Vec<_>>();
        let runs = crate::sim::rig::assert_run_of(&values(&got), &values(&sent), 0, "channel");
        if stamped {
            let at = runs[0];
            for (i, (_, t)) in got.iter().enumerate() {
                assert_eq!(*t, sent[at + i].1, "report {} stamp", from + i);
            }
        }
    }
}

#[test]
fn the_reset_reads_and_every_cycle_reports_each_answer() {
    let mut r = rig(LINES, 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.texts_with("Atmel started"), 1);
    let reports = r.reports();
    // One register read: 3 bytes at 9600 baud, 2 character times to tell it is a read, 1 ms
    // to answer: ~6 ms; three reads a cycle.
    assert!(reports.len() > 80, "{} reports in 2 s", reports.len());
    // The reset's report: the first read of each register.
    assert_eq!(
        reports[0].0,
        [
            input_value(0, 0) as f64,
            input_value(1, 0) as f64,
            2.0,
            -1.0,
            -1.0
        ]
    );
    for (c, _) in &reports {
        assert_eq!(c.len(), 5);
        assert_eq!(&c[2..], [2.0, reported::NOT_VALID, reported::NOT_VALID]);
    }
    // Channel 0 stamps each report: its answer is the cycle's first.
    r.assert_channel_is_answers(0, 0, true);
    r.assert_channel_is_answers(1, 0, false);
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
    assert_eq!(r.line.driver.stats().resets, 1);
}

#[test]
fn writes_reach_the_board_and_errors_are_cpps_values() {
    let mut r = rig(LINES, 2);
    r.line.run_for(Duration::from_millis(300));
    let n = r.reports().len();
    r.output.request_change_channel_value(2, 200.0).unwrap();
    r.output.request_change_channel_value(3, 17.5).unwrap();
    r.line.run_for(Duration::from_millis(100));
    assert_eq!(r.line.device.writes(), [(2, 200), (3, 17)]);
    assert_eq!(r.line.device.register(2), 200);
    let after: Vec<Vec<f64>> = r.reports()[n..].iter().map(|x| x.0.clone()).collect();
    // The written values are reported (C++ reports the value asked for, 17.5), then channel
    // 2 is read back from the board and channel 3 keeps its value.
    let first = after.iter().position(|c| c[2] == 200.0).unwrap();
    assert_eq!(after[first][3], 17.5);
    assert!(after[first + 1..]
        .iter()
        .all(|c| c[2] == 200.0 && c[3] == 17.5));
    // A read-only channel and a value out of range: C++'s error values, once each.
    let n = r.reports().len();
    r.output.request_change_channel_value(0, 5.0).unwrap();
    r.output.request_change_channel_value(2, 300.0).unwrap();
    r.output.request_change_channel_value(4, 1.0).unwrap();
    r.line.run_for(Duration::from_millis(100));
    let after: Vec<Vec<f64>> = r.reports()[n..].iter().map(|x| x.0.clone()).collect();
    // The requests are taken when the next cycle begins.
    let e = after
        .iter()
        .position(|c| c[0] == reported::NOT_WRITABLE)
        .unwrap();
    assert!(e <= 1, "{after:?}");
    assert_eq!(after[e][2], reported::OUT_OF_RANGE);
    assert_eq!(after[e][4], reported::NOT_WRITABLE);
    // Then channel 0 is read again, channel 2 keeps the board's value, and the unused
    // channel 4 keeps its error (C++ only reads RW and RO channels).
    let next = &after[e + 1];
    assert!(next[0] >= 0.0 && next[2] == 200.0 && next[4] == reported::NOT_WRITABLE);
    assert_eq!(r.texts_with("not writable"), 2);
    assert_eq!(r.texts_with("out of range"), 1);
    assert_eq!(r.line.device.writes().len(), 2);
}

#[test]
fn a_slow_reader_loses_nothing() {
    let mut r = rig(LINES, 7);
    r.line.read_lag = Duration::from_millis(8);
    r.line.split_reads = true;
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.driver.stats().resets, 1);
    r.assert_channel_is_answers(0, 0, false);
    r.assert_channel_is_answers(1, 0, false);
    assert!(r.reports().iter().all(|(c, _)| c[0] >= 0.0 && c[1] >= 0.0));
}

#[test]
fn an_answer_later_than_the_wait_is_a_failed_read_and_is_not_taken_for_the_next() {
    // A loaded machine can hold the board's answer past REPLY_WAIT: that read reports -21
    // (as C++), the late answer is not taken for another read, and the values go on exact.
    let mut r = rig(LINES, 8);
    r.line.run_for(Duration::from_millis(300));
    let n = r.reports().len();
    r.line
        .device
        .set_reply_delay(super::REPLY_WAIT + Duration::from_millis(40));
    r.line.run_for(Duration::from_millis(170));
    r.line.device.set_reply_delay(Duration::from_millis(1));
    r.line.run_for(Duration::from_secs(1));
    let reports = r.reports();
    let failed: Vec<usize> = (n..reports.len())
        .filter(|&i| reports[i].0[..3].contains(&reported::READ_FAILED))
        .collect();
    assert!(!failed.is_empty() && failed.len() <= 2, "{failed:?}");
    let after = failed[failed.len() - 1] + 1;
    for reg in [0, 1] {
        r.assert_channel_is_answers(reg, after, reg == 0);
    }
    assert!(reports[after..].iter().all(|(c, _)| c[2] == 2.0));
    assert!(reports[..n].iter().all(|(c, _)| c[0] >= 0.0 && c[2] == 2.0));
}

#[test]
fn garbage_between_answers_is_skipped() {
    let mut r = rig(LINES, 3);
    r.line.run_for(Duration::from_millis(300));
    for junk in [&[0x00u8, 0x7F][..], &[0xFE], &[0x41, 0x42, 0x43]] {
        r.line.inject(junk);
        r.line.run_for(Duration::from_millis(200));
    }
    r.line.run_for(Duration::from_millis(500));
    assert!(r.line.driver.stats().skipped_bytes >= 1);
    r.assert_channel_is_answers(0, 0, true);
    r.assert_channel_is_answers(1, 0, false);
}

#[test]
fn silence_reports_failed_reads_then_resets_and_an_unplugged_line_comes_back() {
    let mut r = rig(LINES, 4);
    r.line.run_for(Duration::from_millis(500));
    let n = r.reports().len();
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(2500));
    // Each unanswered read reports -21 (C++), the cycle taking two time-outs.
    let quiet: Vec<Vec<f64>> = r.reports()[n + 1..].iter().map(|x| x.0.clone()).collect();
    assert!(quiet.len() >= 5, "{} reports", quiet.len());
    assert!(quiet
        .iter()
        .all(|c| c[0] == reported::READ_FAILED && c[1] == reported::READ_FAILED));
    r.line.run_for(Duration::from_millis(2000));
    assert_eq!(r.texts_with("connection timed out"), 1);
    r.line.run_for(Duration::from_secs(3));
    // Each attempt: one unanswered read, then a second's pause.
    assert!(r.texts_with("Atmel not connected") >= 2);
    r.line.silent = false;
    r.line.run_for(Duration::from_secs(3));
    assert_eq!(r.texts_with("Atmel started"), 2);
    let n = r.reports().len();
    r.line.run_for(Duration::from_secs(1));
    assert!(r.reports()[n..].iter().all(|(c, _)| c[0] >= 0.0));
    r.line.close();
    r.line.run_for(Duration::from_secs(2));
    assert_eq!(r.line.opens, 2);
    assert_eq!(r.texts_with("Atmel started"), 3);
    let n = r.reports().len();
    r.line.run_for(Duration::from_secs(1));
    assert!(r.reports().len() > n + 40);
}

#[test]
fn a_board_without_readable_channels_lives_on_its_own_bytes() {
    let text = "vrpn_Atmel Atmel0 /dev/ttyS0 38400 2\nvrpn_Atmel 0 WO\nvrpn_Atmel -1 END\n";
    let mut r = rig(text, 5);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(38400))
    );
    r.line.run_for(Duration::from_secs(5));
    assert_eq!(r.texts_with("Atmel started"), 1);
    assert_eq!(r.texts_with("timed out"), 0);
    let reports = r.reports();
    // A cycle every 10 ms, nothing to exchange.
    assert!((400..=501).contains(&reports.len()), "{}", reports.len());
    r.output.request_change_channel_value(0, 9.0).unwrap();
    r.line.run_for(Duration::from_millis(50));
    assert_eq!(r.line.device.writes(), [(0, 9)]);
    assert_eq!(r.reports().last().unwrap().0, [9.0, -1.0]);
}

#[test]
fn configuration_lines_and_their_errors() {
    let a: Atmel = parse_one(LINES);
    assert_eq!(
        (a.name.as_str(), a.port.as_str(), a.baud),
        ("Atmel0", "/dev/ttyS0", 9600)
    );
    use super::command::Mode::*;
    assert_eq!(a.modes, [ReadOnly, ReadOnly, ReadWrite, WriteOnly, Unused]);
    // Any speed but 38400 is 9600, as C++ opens the port.
    let b: Atmel = parse_one("vrpn_Atmel A /dev/ttyS0 19200 1\nvrpn_Atmel -1\n");
    assert_eq!((b.line_speed(), b.modes.as_slice()), (9600, &[Unused][..]));
    let err = |t: &str| {
        let e = parse_str(t, "t.cfg").unwrap_err();
        (e.kind(), e.to_string())
    };
    let (k, m) = err("vrpn_Atmel A /dev/ttyS0 9600 2\nvrpn_Atmel 2 RW\nvrpn_Atmel -1 END\n");
    assert_eq!(k, ConfigErrorKind::OutOfRange);
    assert!(m.starts_with("t.cfg:2:"), "{m}");
    let (k, m) = err("vrpn_Atmel A /dev/ttyS0 9600 2\nvrpn_Atmel 1 XX\nvrpn_Atmel -1 END\n");
    assert_eq!(k, ConfigErrorKind::BadValue);
    assert!(m.contains("unknown io-mode 'XX'"), "{m}");
    let (k, _) = err("vrpn_Atmel A /dev/ttyS0 9600 2\nvrpn_Atmel 1 RW\n");
    assert_eq!(k, ConfigErrorKind::UnclosedBlock);
    let (k, m) = err("vrpn_Atmel A /dev/ttyS0 9600 2\nvrpn_Tracker_NULL T 1 60\n");
    assert_eq!(k, ConfigErrorKind::BadBlockLine);
    assert!(m.contains("t.cfg:2:"), "{m}");
    assert_eq!(
        err("vrpn_Atmel A /dev/ttyS0 9600\n").0,
        ConfigErrorKind::MissingArguments
    );
    assert_eq!(
        err("vrpn_Atmel A /dev/ttyS0 9600 0\n").0,
        ConfigErrorKind::OutOfRange
    );
    assert_eq!(
        err("vrpn_Atmel A /dev/ttyS0 9600 129\n").0,
        ConfigErrorKind::OutOfRange
    );
    assert_eq!(
        err("vrpn_Atmel A /dev/ttyS0 9600 2\nvrpn_Atmel x RW\n").0,
        ConfigErrorKind::BadNumber
    );
}
