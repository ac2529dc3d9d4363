//! The Wanda driver against its simulator on a virtual serial line, with a client on the same
//! in-process connection: the init message, exact values and stamps, the centring after
//! silence, garbage, a reopen, configurations.

use std::time::{Duration, Instant};

use super::config::Wanda;
use super::sim::{expected, Expected, Report, SimConfig, WandaSim};
use super::{WandaProtocol, CENTRE_AFTER};
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::serial::{Parity, PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{Connection, Now, TimeVal};

const LINE: &str = "vrpn_Wanda Wanda0 /dev/ttyS0 1200 60.0\n";

struct Rig {
    line: VirtualLine<Lifecycle<WandaProtocol>, WandaSim>,
    start: Now,
    client: Client,
    _conn: Connection,
}

fn rig(seed: u64, tweak: impl FnOnce(&mut SimConfig)) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Wanda = parse_one(LINE);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client =
        Client::on_connection(&cfg.name, &conn, &[Interface::Analog, Interface::Button]).unwrap();
    let mut sim = SimConfig::new();
    sim.keep_log = true;
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let mut line = VirtualLine::new(driver, WandaSim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        client,
        _conn: conn,
    }
}

/// A heard report as the simulator's [`Report`], with its time stamp.
fn report(h: &Heard) -> Option<(Report, TimeVal)> {
    match h {
        Heard::Button {
            button,
            pressed,
            time,
        } => Some((Report::Button(*button, *pressed), *time)),
        Heard::Analog { channels, time } => {
            Some((Report::Analog([channels[0], channels[1]]), *time))
        }
        _ => None,
    }
}

impl Rig {
    fn heard(&self) -> Vec<(Report, TimeVal)> {
        self.client.heard().iter().filter_map(report).collect()
    }

    fn texts_with(&self, needle: &str) -> usize {
        let t = self.client.texts_from(0);
        t.iter().filter(|t| t.contains(needle)).count()
    }

    fn arrival_wall(&self, t: Instant) -> TimeVal {
        self.start
            .wall
            .plus(t + self.line.latency - self.start.mono)
    }

    /// Everything heard is exactly what the simulator's log says a client receives, from the
    /// first report on, with every stamp the arrival of its record's first byte (or, for the
    /// centring, 0.2 s after the last record's).
    fn assert_exact(&self) {
        let sent = self.line.device.sent();
        let want: Vec<Expected> = expected(sent, self.line.now().mono);
        let got = self.heard();
        assert!(got.len() >= 20, "{} reports", got.len());
        assert_eq!(
            got.iter().map(|g| g.0).collect::<Vec<_>>(),
            want[..got.len()]
                .iter()
                .map(|w| w.report)
                .collect::<Vec<_>>()
        );
        assert!(
            want.len() - got.len() <= 3,
            "{} of {}",
            got.len(),
            want.len()
        );
        let mut last_record = None;
        for ((_, time), w) in got.iter().zip(&want) {
            let first = match w.record {
                Some(i) => {
                    last_record = Some(sent[i].first_byte);
                    sent[i].first_byte
                }
                None => last_record.unwrap() + CENTRE_AFTER,
            };
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                assert_eq!(*time, self.arrival_wall(first), "{w:?}");
            }
        }
    }
}

/// Runs `line` in 1 ms steps until `done` holds (at most `max`); returns whether it held.
fn run_in_steps<D: SerialDriver, M: crate::sim::DeviceModel>(
    line: &mut VirtualLine<D, M>,
    max: Duration,
    mut done: impl FnMut(&VirtualLine<D, M>) -> bool,
) -> bool {
    let end = line.now().mono + max;
    while line.now().mono < end {
        if done(line) {
            return true;
        }
        line.run_for(Duration::from_millis(1));
    }
    done(line)
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several records at once: every report is made,
    // from the first. (A lag well under the centring delay, which a late read may cross.)
    let mut r = rig(21, |_| {});
    r.line.read_lag = Duration::from_millis(4);
    r.line.run_for(Duration::from_secs(5));
    r.assert_exact();
}

#[test]
fn port_settings_are_seven_data_bits() {
    let r = rig(1, |_| {});
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings {
            baud: 1200,
            data_bits: 7,
            parity: Parity::None,
            stop_bits: 1,
            rts_cts: false
        })
    );
    assert_eq!(r.line.driver.protocol().analog().num_channels(), 2);
    assert_eq!(r.line.driver.protocol().buttons().num_buttons(), 3);
}

#[test]
fn init_message_then_exact_values_stamps_and_centring() {
    let mut r = rig(2, |_| {});
    r.line.run_for(Duration::from_secs(5));
    assert_eq!(r.line.driver.protocol().init_messages(), 1);
    assert_eq!(r.texts_with("init message"), 1);
    // The first record's reports arrive one record's transmission after it starts.
    let first = r.line.device.sent()[0].first_byte;
    assert!(first - r.start.mono <= Duration::from_millis(60));
    r.assert_exact();
    // Bursts of 20 records with pauses: the channels were centred after each burst.
    let centred = r
        .heard()
        .iter()
        .filter(|(rep, _)| *rep == Report::Analog([0.0, 0.0]))
        .count();
    assert!(centred >= 3, "{centred}");
    // Every button went down and up, the yellow one through its fourth byte.
    for b in 0..3 {
        for p in [true, false] {
            assert!(r
                .heard()
                .iter()
                .any(|(rep, _)| *rep == Report::Button(b, p)));
        }
    }
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
    assert_eq!(r.line.written, Vec::new(), "the driver writes nothing");
}

#[test]
fn garbage_between_records_loses_nothing() {
    let mut r = rig(3, |_| {});
    r.line.run_for(Duration::from_millis(300));
    // Bytes no seven-bit line delivers, and false starts (a sync byte followed by another).
    let junk: [&[u8]; 4] = [&[0x85, 0xFF], &[0x41], &[0xC3, 0x52, 0x90], &[0x7F, 0x45]];
    for j in junk {
        r.line.run_for(Duration::from_millis(230));
        // Between records: just after one ended (a record takes 25-33 ms at 1200 baud).
        assert!(run_in_steps(&mut r.line, Duration::from_secs(1), |l| {
            l.device.sent().last().is_some_and(|s| {
                let since = l.now().mono - s.first_byte;
                since > Duration::from_millis(36) && since < Duration::from_millis(45)
            })
        }));
        let now = r.line.now().mono;
        r.line.device.inject(j, now);
    }
    r.line.run_for(Duration::from_secs(2));
    r.assert_exact();
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 8);
    assert!(r.texts_with("skipped") >= 1);
}

#[test]
fn silence_centres_the_channels_once() {
    let mut r = rig(4, |_| {});
    r.line.run_for(Duration::from_millis(500));
    r.line.device.mute = true;
    r.line.run_for(Duration::from_secs(3));
    let n = r.heard().len();
    r.line.device.mute = false;
    r.line.run_for(Duration::from_secs(2));
    assert!(r.heard().len() > n);
    r.assert_exact();
    // No watchdog: silence is not a failure.
    assert_eq!(r.line.driver.stats().watchdog_fired, 0);
    assert_eq!(r.line.opens, 1);
}

#[test]
fn a_closed_port_is_reopened_and_nothing_is_invented() {
    let mut r = rig(5, |_| {});
    r.line.run_for(Duration::from_millis(700));
    let n = r.heard().len();
    r.line.close();
    r.line.run_for(Duration::from_millis(400));
    assert_eq!(r.heard().len(), n, "nothing while the port is closed");
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    r.line.run_for(Duration::from_secs(2));
    assert!(r.heard().len() > n + 10);
    // Everything after the reopen is exact from the first record on (the state carried over
    // the gap: no centring was reported for it).
    let got = r.heard();
    assert!(!got[n..]
        .iter()
        .take(2)
        .any(|(rep, _)| *rep == Report::Analog([0.0, 0.0])));
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Wanda Wanda /dev/ttyd2 1200 60.0\n\
                vrpn_Wanda\tWanda1\tCOM2\t1200\t60\n\
                vrpn_Wanda Wanda2 /dev/ttyUSB0 9600 0\n";
    let entries = parse_str(text, "wanda.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 3);
    assert_eq!(names, ["Wanda", "Wanda1", "Wanda2"]);
    let w: Wanda = parse_one("vrpn_Wanda W COM2 1200 60.0\n");
    assert_eq!(w.min_update_rate, 60.0);
    for (bad, why) in [
        ("vrpn_Wanda W /dev/ttyS0 1200\n", "minimum update rate"),
        ("vrpn_Wanda W /dev/ttyS0 1201 60\n", "1201"),
        ("vrpn_Wanda W /dev/ttyS0 1200 fast\n", "fast"),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.cfg") && e.contains(":2") && e.contains(why),
            "{e}"
        );
    }
}
