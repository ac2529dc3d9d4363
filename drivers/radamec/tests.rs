//! The Radamec SPI driver against its simulator on a virtual serial line, with a client on
//! the same in-process connection: the reset's commands, exact values and stamps for every
//! block type, echoes, garbage and bad check bytes, unhandled blocks, the watchdog, a reopen,
//! configurations.

use std::time::{Duration, Instant};

use super::config::Radamec;
use super::record::{command, ASK_CAMERA, STREAM};
use super::sim::{RadamecSim, SimConfig};
use super::RadamecProtocol;
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::serial::{Parity, PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{Connection, Now, TimeVal};

const LINE: &str = "vrpn_Radamec_SPI Analog0 /dev/ttyS16 38400\n";

struct Rig {
    line: VirtualLine<Lifecycle<RadamecProtocol>, RadamecSim>,
    start: Now,
    client: Client,
    _conn: Connection,
}

fn rig(seed: u64, tweak: impl FnOnce(&mut SimConfig)) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: Radamec = parse_one(LINE);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client = Client::on_connection(&cfg.name, &conn, &[Interface::Analog]).unwrap();
    let mut sim = SimConfig::new();
    sim.keep_log = true;
    tweak(&mut sim);
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let mut line = VirtualLine::new(driver, RadamecSim::new(sim), start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        client,
        _conn: conn,
    }
}

impl Rig {
    fn reports(&self) -> Vec<(Vec<f64>, TimeVal)> {
        self.client
            .heard()
            .iter()
            .filter_map(|h| match h {
                Heard::Analog { channels, time } => Some((channels.clone(), *time)),
                _ => None,
            })
            .collect()
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

    /// The reports are exactly the blocks logged (but the last, perhaps still on the line),
    /// from the first, stamped with their first bytes' arrival.
    fn assert_exact(&self) {
        let sent = self.line.device.sent();
        let got = self.reports();
        assert!(got.len() >= 20, "{} reports", got.len());
        assert!(
            sent.len() - got.len() <= 1,
            "{} of {}",
            got.len(),
            sent.len()
        );
        for (g, s) in got.iter().zip(sent) {
            assert_eq!(g.0, s.expected(), "{s:?}");
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                assert_eq!(g.1, self.arrival_wall(s.first_byte), "{s:?}");
            }
        }
    }

    /// Runs until between blocks, then forgets what was sent and heard.
    fn forget(&mut self) {
        let n = self.line.device.sent().len();
        assert!(self
            .line
            .run_until(Duration::from_secs(1), |l| l.device.sent().len() > n + 1));
        self.line.run_for(Duration::from_millis(10));
        self.line.device.clear_log();
        self.client.clear();
    }
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several blocks at once: every block is reported,
    // from the first.
    let mut r = rig(21, |_| {});
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact();
}

#[test]
fn port_settings_are_odd_parity() {
    let r = rig(1, |_| {});
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings {
            baud: 38400,
            data_bits: 8,
            parity: Parity::Odd,
            stop_bits: 1,
            rts_cts: false
        })
    );
}

#[test]
fn reset_writes_cplusplus_commands_then_every_block_type_is_exact() {
    for (seed, kind, channels) in [(2, 0xA0, 4), (3, 0xA1, 5), (4, 0xA2, 8), (5, 0xA6, 8)] {
        let mut r = rig(seed, |s| s.kind = kind);
        r.line.run_for(Duration::from_secs(1));
        assert_eq!(
            r.line.device.heard_commands(),
            [ASK_CAMERA, command(0xFF, STREAM)]
        );
        assert_eq!(r.texts_with("reset complete (this is good)"), 1);
        r.assert_exact();
        assert_eq!(r.reports()[0].0.len(), channels);
        assert_eq!(r.line.driver.protocol().camera(), 3);
        assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
    }
}

#[test]
fn echoes_are_not_reported() {
    let mut r = rig(6, |s| s.echo_commands = true);
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact();
    assert_eq!(r.line.driver.protocol().skipped_bytes(), 0);
}

#[test]
fn garbage_and_false_starts_lose_nothing() {
    let mut r = rig(7, |_| {});
    r.line.run_for(Duration::from_millis(200));
    // Noise, stray type bytes (each makes a candidate that fails its check byte), a block
    // with a wrong check byte.
    let mut bad = super::sim::sample(99).block(0xA0, 3);
    bad[14] ^= 0x55;
    let junk: [&[u8]; 4] = [&[0x00, 0x41, 0x13], &[0xA1], &[0xA6, 0x20, 0xA0], &bad];
    for j in junk {
        r.line.run_for(Duration::from_millis(95));
        // Between blocks: 30 bytes take 7.8 ms at 38400 baud, one every 20 ms.
        let n = r.line.device.sent().len();
        assert!(r
            .line
            .run_until(Duration::from_secs(1), |l| l.device.sent().len() > n));
        r.line.run_for(Duration::from_millis(12));
        let now = r.line.now().mono;
        r.line.device.inject(j, now);
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_exact();
    assert!(r.line.driver.protocol().skipped_bytes() >= 3 + 1 + 3 + 15);
    assert!(r.texts_with("with a bad check byte") >= 1);
}

#[test]
fn an_unhandled_block_type_resets_the_device() {
    let mut r = rig(8, |_| {});
    r.line.run_for(Duration::from_millis(300));
    r.forget();
    let mut a5 = vec![0xA5, 3, 1, 2];
    a5.push(super::record::check_byte(&a5));
    let now = r.line.now().mono;
    r.line.device.inject(&a5, now);
    r.line.run_for(Duration::from_millis(500));
    assert_eq!(r.texts_with("Unhandled command (0xa5), resetting"), 1);
    // The second reset asks the camera it learned.
    assert_eq!(
        &r.line.device.heard_commands()[2..],
        [ASK_CAMERA, command(3, STREAM)]
    );
    assert_eq!(r.line.driver.stats().resets, 2);
    r.assert_exact();
}

#[test]
fn a_silent_device_is_reset_after_two_seconds_and_resumes() {
    let mut r = rig(9, |_| {});
    r.line.run_for(Duration::from_millis(500));
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(2500));
    assert_eq!(r.texts_with("Timeout... current_time="), 1);
    assert_eq!(r.line.driver.stats().watchdog_fired, 1);
    let commands = r.line.device.heard_commands().len();
    assert_eq!(commands, 4, "the reset's two commands again");
    assert_eq!(r.line.opens, 1, "reset on the open port");
    r.line.device.mute = false;
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact();
    // A watchdog that fires again on a device still silent: every 2 s.
    r.line.device.mute = true;
    r.line.run_for(Duration::from_millis(4100));
    assert_eq!(r.line.driver.stats().watchdog_fired, 3);
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig(10, |_| {});
    r.line.run_for(Duration::from_millis(500));
    let n = r.reports().len();
    r.line.close();
    r.line.run_for(Duration::from_millis(400));
    assert_eq!(r.reports().len(), n, "nothing while closed");
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    r.forget();
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact();
    assert_eq!(r.line.driver.stats().resets, 2);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Radamec_SPI\tAnalog0\t/dev/ttyS16\t38400\n\
                vrpn_Radamec_SPI Radamec1 COM3 9600\n";
    let entries = parse_str(text, "radamec.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["Analog0", "Radamec1"]);
    for (bad, why) in [
        ("vrpn_Radamec_SPI R /dev/ttyS0\n", "baud"),
        ("vrpn_Radamec_SPI R /dev/ttyS0 38401\n", "38401"),
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
