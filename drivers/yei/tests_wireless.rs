//! The wireless YEI driver against a simulated dongle with two units on a virtual serial
//! line: the reset's bytes, exact reports of each unit in order with first-byte stamps, a
//! slow reader, garbage, silence, a unit that is not paired, configurations.

use std::time::{Duration, Instant};

use super::config::YeiWireless;
use super::sim::{SimConfig, YeiSim};
use super::tests::{heard_values, values_of};
use super::wireless::WirelessProtocol;
use crate::config::ConfigErrorKind;
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{Connection, Now, TimeVal};

const LINE: &str =
    "vrpn_YEI_3Space_Sensor_Wireless\tYEI0\t0\tCOM5\t115200\t0\t0\t50.0 0 0 1 1 \\\n\
                    238,1,1,0 /\n\
                    vrpn_YEI_3Space_Sensor_Wireless\tYEI1\t1\t1\t0\t50.0 0 1 0 1 \\\n\
                    238,0,1,1\n";

struct Rig {
    line: VirtualLine<Lifecycle<WirelessProtocol>, YeiSim>,
    start: Now,
    clients: [Client; 2],
    _conn: Connection,
}

fn rig(text: &str, paired: &[u8], seed: u64) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: YeiWireless = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let all = [Interface::Tracker, Interface::Analog, Interface::Button];
    let clients = [
        Client::on_connection("YEI0", &conn, &all).unwrap(),
        Client::on_connection("YEI1", &conn, &all).unwrap(),
    ];
    let mut sim = SimConfig::wireless(cfg.baud, paired);
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    Rig {
        line: VirtualLine::new(driver, YeiSim::new(sim), start, seed),
        start,
        clients,
        _conn: conn,
    }
}

impl Rig {
    fn texts_with(&self, needle: &str) -> usize {
        self.clients[0]
            .heard()
            .iter()
            .filter(|h| matches!(h, Heard::Text { text, .. } if text.contains(needle)))
            .count()
    }

    fn assert_all_heard(&self, min_records: usize, stamps: bool) {
        for (u, client) in self.clients.iter().enumerate() {
            let sent: Vec<_> = self
                .line
                .device
                .sent()
                .iter()
                .filter(|s| s.unit == u)
                .cloned()
                .collect();
            assert!(sent.len() >= min_records, "unit {u}: {} sent", sent.len());
            let want = values_of(&sent, 0);
            let got = heard_values(&client.heard());
            assert!(
                want.len() - got.len() <= 11,
                "{} of {}",
                got.len(),
                want.len()
            );
            for (i, ((g, gt), (w, wt))) in got.iter().zip(&want).enumerate() {
                assert_eq!(g, w, "unit {u} report {i}");
                if stamps {
                    let at = self
                        .start
                        .wall
                        .plus(*wt + self.line.latency - self.start.mono);
                    assert_eq!(*gt, at, "unit {u} stamp {i}");
                }
            }
            // Every record released, in order, without a gap.
            assert!(sent.windows(2).all(|w| w[1].k == w[0].k + 1), "unit {u}");
        }
    }
}

#[test]
fn two_units_on_a_dongle_are_set_up_and_stream_exactly() {
    let mut r = rig(LINE, &[0, 1], 1);
    r.line.run_for(Duration::from_secs(2));
    let d = &r.line.device;
    assert!(d.manual_flush);
    assert_eq!(d.bad_commands, 0);
    for (u, (rgb, ascii)) in [
        ([0.0, 0.0, 1.0], "238,1,1,0"),
        ([0.0, 1.0, 0.0], "238,0,1,1"),
    ]
    .into_iter()
    .enumerate()
    {
        let s = &d.units[u];
        assert_eq!((s.led_mode, s.led_color, s.starts), (1, rgb, 1));
        assert_eq!((s.interval_us, s.axes), (20_000, Some(1)));
        assert_eq!(s.ascii, [ascii]);
    }
    let w = &r.line.written;
    assert_eq!(
        w[0].1,
        [0xF7, 0xB0, 0, 0xB0, 0xF8, 0, 0x56, 0x56, 0xF8, 1, 0x56, 0x57]
    );
    assert_eq!(w[1].0 - w[0].0, Duration::from_millis(50));
    assert_eq!(w[1].1, [0xF8, 0, 0xC4, 1, 0xC5]);
    assert!(w.iter().any(|(_, b)| b == b">1,238,0,1,1\n\0"));
    r.assert_all_heard(80, true);
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several frames (and the answers that end the
    // reset) in one read: every record the dongle released is reported, from the first.
    let mut r = rig(LINE, &[0, 1], 2);
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_millis(1500));
    r.assert_all_heard(50, false);
    assert_eq!(r.line.driver.stats().skipped_bytes, 0);
    assert_eq!(r.line.driver.stats().resets, 1);
}

#[test]
fn split_reads_and_garbage_lose_nothing() {
    let mut r = rig(LINE, &[0, 1], 5);
    r.line.split_reads = true;
    r.line.run_for(Duration::from_millis(703));
    for junk in [&b"\x41"[..], &[0x00, 0x07, 0x59], &[0x01, 0x00]] {
        r.line.inject(junk);
        r.line.run_for(Duration::from_millis(150));
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_all_heard(50, false);
    assert_eq!(r.line.driver.stats().skipped_bytes, 6);
    assert!(r.texts_with("skipped") >= 1);
    assert_eq!(r.line.driver.stats().resets, 1);
}

#[test]
fn silence_resets_the_dongle_and_streaming_resumes() {
    let mut r = rig(LINE, &[0, 1], 3);
    r.line.run_for(Duration::from_millis(500));
    r.line.silent = true;
    r.line.run_for(Duration::from_millis(3500));
    let texts: Vec<_> = r.clients[0]
        .heard()
        .iter()
        .filter_map(|h| match h {
            Heard::Text { text, .. } => Some(text.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(
        r.texts_with("vrpn_YEI_3Space::mainloop: Timeout..."),
        1,
        "{texts:#?}"
    );
    // The dongle's answers are lost too: each unit fails its reset, 500 ms each.
    assert!(
        r.texts_with("Timeout waiting for command status (got 0 chars)") >= 2,
        "{texts:#?}"
    );
    assert!(r.texts_with("Cannot reset! (logical ID 1)") >= 1);
    // The attempt under way when it speaks again may leave a unit out: it is tried again 2 s
    // later.
    r.line.silent = false;
    let n = [r.clients[0].len(), r.clients[1].len()];
    r.line.run_for(Duration::from_secs(4));
    for (c, n) in r.clients.iter().zip(n) {
        assert!(c.len() > n + 100, "{} after {n}", c.len());
    }
    let d = &r.line.device;
    assert!(d.units.iter().all(|u| u.starts >= 2), "{:?}", d.units);
    // Set up once: the port never closed.
    assert_eq!(d.units[1].calibrations, 1);
}

#[test]
fn an_unpaired_unit_is_left_out_and_the_other_streams() {
    // Unit 1 is not paired with this dongle: the dongle answers its commands with a failure.
    // Unit 0 streams all the same; every 2 s without a record of unit 1 the dongle is reset
    // and unit 1 tried again.
    let mut r = rig(LINE, &[0], 4);
    r.line.run_for(Duration::from_millis(4500));
    assert_eq!(r.texts_with("Error (1) from ID 1"), 3);
    assert_eq!(r.texts_with("Cannot reset! (logical ID 1)"), 3);
    assert_eq!(r.texts_with("no record from logical ID 1"), 2);
    assert!(heard_values(&r.clients[1].heard()).is_empty());
    let got = heard_values(&r.clients[0].heard());
    let sent: Vec<_> = r.line.device.sent().to_vec();
    assert!(sent.len() > 150, "{}", sent.len());
    let want = values_of(&sent, 0);
    assert!(want.len() - got.len() <= 11);
    assert!(got.iter().zip(&want).all(|(g, w)| g.0 == w.0));
    // The records unit 0 made during the resets waited in the dongle: none is missing.
    assert!(sent.windows(2).all(|w| w[1].k == w[0].k + 1));
    assert_eq!(r.line.device.units[0].starts, 3);
}

#[test]
fn every_wireless_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let one: YeiWireless =
        parse_one("vrpn_YEI_3Space_Sensor_Wireless\tYEI0\t0\tCOM5\t115200\t0\t0\t200.0 0 0 1 1\n");
    assert_eq!(
        (one.port.as_str(), one.baud, one.units.len()),
        ("COM5", 115200, 1)
    );
    let two: YeiWireless = parse_one(LINE);
    assert_eq!(two.units.len(), 2);
    assert_eq!(
        (two.units[1].name.as_str(), two.units[1].logical_id),
        ("YEI1", 1)
    );
    assert_eq!(two.units[0].reset_commands, ["238,1,1,0"]);
    assert_eq!(two.units[1].reset_commands, ["238,0,1,1"]);
    assert_eq!(two.units[1].led_color, [0.0, 1.0, 0.0]);
    let text = format!(
        "{LINE}vrpn_YEI_3Space_Sensor_Wireless W2 14 /dev/ttyUSB0 115200 1 1 0 1 1 1 0 /\n\
         vrpn_YEI_3Space_Sensor_Wireless W3 3 0 0 100 0 0 0 0 /\n\
         vrpn_YEI_3Space_Sensor_Wireless W4 4 0 0 100 0 0 0 0\n"
    );
    let entries = parse_str(&text, "yei.cfg").unwrap();
    assert_eq!(entries.len(), 2);
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 2);
    assert_eq!(names, ["YEI0", "W2"]);
    assert_eq!(entries[1].spec::<YeiWireless>().unwrap().units.len(), 3);
    let head = "vrpn_YEI_3Space_Sensor_Wireless Y 0 /dev/ttyUSB0 115200";
    let more = "vrpn_YEI_3Space_Sensor_Wireless Z";
    for (bad, kind, why) in [
        (
            format!("{head} 0 0 200 0 0 1\n"),
            ConfigErrorKind::MissingArguments,
            "expected 11",
        ),
        (
            "vrpn_YEI_3Space_Sensor_Wireless Y 15 COM5 115200 0 0 200 0 0 1 1\n".to_owned(),
            ConfigErrorKind::OutOfRange,
            "logical_id",
        ),
        (
            format!("{head} 0 0 200 0 0 1 1 /\n{more} 0 0 0 200 0 0 1 1\n"),
            ConfigErrorKind::BadBlockLine,
            "clashes",
        ),
        (
            format!("{head} 0 0 200 0 0 1 1 /\n{more} 1 0 0 200 0 0 1\n"),
            ConfigErrorKind::MissingArguments,
            "expected 9",
        ),
        (
            format!("{head} 0 0 200 0 0 1 1 /\nvrpn_YEI_3Space_Sensor Z 1 0 0 200 0 0 1 1\n"),
            ConfigErrorKind::BadBlockLine,
            "promised",
        ),
        (
            format!("{head} 0 0 200 0 0 1 1 /\n"),
            ConfigErrorKind::UnclosedBlock,
            "further wireless unit",
        ),
        (
            format!("{head} 0 0 200 0 0 1 1 \\\n238,1,1,0 /\n{more} 1 0 0 200 0 0 1 1 \\\n"),
            ConfigErrorKind::UnclosedBlock,
            "reset command",
        ),
    ] {
        let e = parse_str(&format!("# c\n{bad}"), "bad.cfg").unwrap_err();
        assert_eq!(e.kind(), kind, "{bad}: {e}");
        let shown = e.to_string();
        assert!(
            shown.starts_with("bad.cfg:") && shown.contains(why),
            "{shown}"
        );
    }
}
