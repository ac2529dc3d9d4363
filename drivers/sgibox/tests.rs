//! The raw SGI box driver against its simulator on a virtual serial line, with a client on
//! the same in-process connection: the reset's bytes and pacing, exact reports and stamps,
//! toggles and their lights, garbage, an unexpected reset answer, a failed reset, a reopen,
//! configurations.

use std::time::{Duration, Instant};

use super::config::SgiBox;
use super::record::{ACTIVATE_BUTTONS, ENABLE_BUTTONS, ENABLE_DIALS, LIGHTS, RESET};
use super::sim::{expected, Report, SgiSim, SimConfig};
use super::{SgiBoxProtocol, BYTE_GAP};
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::driver::{Interface, Lifecycle};
use crate::serial::{PortKind, PortSettings, SerialDriver};
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::sim::VirtualLine;
use crate::{ButtonRemote, Connection, Now, TimeVal};

const LINE: &str = "vrpn_raw_SGIBox Sgibox0 /dev/ttyS0 0 1 2 3\n";

struct Rig {
    line: VirtualLine<Lifecycle<SgiBoxProtocol>, SgiSim>,
    start: Now,
    client: Client,
    toggles: Vec<u32>,
    conn: Connection,
}

fn rig(text: &str, seed: u64) -> Rig {
    rig_with(text, seed, |_| {})
}

/// A rig whose simulated boxes are set up by `tweak` before the port opens.
fn rig_with(text: &str, seed: u64, tweak: impl FnOnce(&mut SgiSim)) -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let cfg: SgiBox = parse_one(text);
    let conn = Connection::new_loopback();
    let driver = cfg.lifecycle(&conn).unwrap();
    let client = Client::on_connection(
        &cfg.name,
        &conn,
        &[Interface::Button, Interface::Analog, Interface::Dial],
    )
    .unwrap();
    let mut sim = SimConfig::new();
    sim.keep_log = true;
    let start = Now {
        mono: Instant::now(),
        wall: TimeVal::new(1_700_000_000, 0),
    };
    let mut boxes = SgiSim::new(sim);
    tweak(&mut boxes);
    let mut line = VirtualLine::new(driver, boxes, start, seed);
    line.split_reads = true;
    Rig {
        line,
        start,
        client,
        toggles: cfg.toggles.clone(),
        conn,
    }
}

fn report(h: &Heard) -> Option<(Report, TimeVal)> {
    match h {
        Heard::Button {
            button,
            pressed,
            time,
        } => Some((Report::Button(*button, *pressed), *time)),
        Heard::Analog { channels, time } => {
            let mut a = [0.0; 8];
            a.copy_from_slice(&channels[..8]);
            Some((Report::Analog(a), *time))
        }
        Heard::Dial { dial, change, time } => Some((Report::Dial(*dial, *change), *time)),
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

    /// Everything heard is what the log says, in order and stamped with first-byte arrivals;
    /// the lights show the toggles that are on.
    fn assert_exact(&self) {
        let sent = self.line.device.sent();
        let (want, on) = expected(sent, &self.toggles);
        let got = self.heard();
        assert!(got.len() >= 20, "{} reports", got.len());
        assert!(
            want.len() - got.len() <= 3,
            "{} of {}",
            got.len(),
            want.len()
        );
        for (g, w) in got.iter().zip(&want) {
            assert_eq!(g.0, w.0);
            // A slow read's records all carry its wake time: values only.
            if self.line.read_lag.is_zero() {
                assert_eq!(g.1, self.arrival_wall(sent[w.1].first_byte), "{w:?}");
            }
        }
        if want.len() == got.len() {
            assert_eq!(self.line.device.lights(), on);
        }
    }

    fn writes(&self) -> Vec<(Instant, Vec<u8>)> {
        self.line.written.clone()
    }
}

#[test]
fn port_settings_and_servers() {
    let r = rig(LINE, 1);
    assert_eq!(
        r.line.driver.port_kind(),
        PortKind::Serial(PortSettings::n81(9600))
    );
    let p = r.line.driver.protocol();
    assert_eq!(p.buttons().num_buttons(), 32);
    assert_eq!(p.analog().num_channels(), 8);
    assert_eq!(p.dials().num_dials(), 8);
    assert_eq!(r.toggles, [0, 1, 2, 3]);
}

#[test]
fn reset_writes_cplusplus_bytes_a_millisecond_apart() {
    let mut r = rig(LINE, 2);
    r.line.run_for(Duration::from_millis(100));
    assert!(r.line.driver.is_streaming());
    let w = r.writes();
    let bytes: Vec<u8> = w.iter().flat_map(|(_, b)| b.clone()).collect();
    let mut want = vec![RESET, RESET];
    want.extend(ENABLE_DIALS);
    for _ in 0..2 {
        want.extend(ENABLE_BUTTONS);
        want.extend(ACTIVATE_BUTTONS);
    }
    want.extend([LIGHTS, 0, 0, 0, 0]);
    // (Later light commands follow the presses of toggles.)
    assert_eq!(bytes[..want.len()], want[..]);
    assert!(w.iter().all(|(_, b)| b.len() == 1), "one byte per write");
    for pair in w.windows(2) {
        assert!(pair[1].0 - pair[0].0 >= BYTE_GAP);
    }
    // Both answers in 2 ms, then 28 bytes 1 ms apart: about 30 ms, not C++'s 1 s sleep.
    let done = w[want.len() - 1].0 - r.start.mono;
    assert!(done < Duration::from_millis(35), "{done:?}");
}

#[test]
fn events_toggles_and_lights_arrive_exactly() {
    let mut r = rig(LINE, 3);
    r.line.run_for(Duration::from_secs(4));
    r.assert_exact();
    let got = r.heard();
    assert!(got.iter().any(|g| matches!(g.0, Report::Dial(..))));
    assert!(got
        .iter()
        .any(|g| matches!(g.0, Report::Analog(a) if a.contains(&0.5))));
    // Toggles are reported on presses only; the lights followed them.
    assert_ne!(r.line.device.lights(), 0);
    assert_eq!(
        r.line.driver.protocol().lights_sent(),
        Some(r.line.device.lights())
    );
}

#[test]
fn a_slow_reader_loses_nothing() {
    // A loaded machine reads late and takes several events at once: every report is made,
    // from the first.
    let mut r = rig(LINE, 21);
    r.line.read_lag = Duration::from_millis(12);
    r.line.run_for(Duration::from_secs(4));
    r.assert_exact();
}

#[test]
fn a_client_setting_a_toggle_lights_it() {
    let mut r = rig("vrpn_raw_SGIBox Sgibox0 /dev/ttyS0\n", 4);
    r.line.run_for(Duration::from_millis(100));
    let remote = ButtonRemote::on_connection("Sgibox0", &r.conn).unwrap();
    remote.set_toggle(20, true).unwrap();
    r.conn.mainloop().unwrap();
    r.line.run_for(Duration::from_millis(20));
    assert_eq!(r.line.device.lights(), 1 << 20);
}

#[test]
fn garbage_is_skipped_and_a_reset_answer_resets() {
    let mut r = rig(LINE, 5);
    r.line.run_for(Duration::from_millis(300));
    for j in [&[0x01u8, 0x7F][..], &[0x45], &[0xBF, 0x10]] {
        r.line.run_for(Duration::from_millis(40));
        // Between events (a dial's three bytes take 2 ms; one event every 25 ms).
        let n = r.line.device.sent().len();
        assert!(r
            .line
            .run_until(Duration::from_secs(1), |l| l.device.sent().len() > n));
        r.line.run_for(Duration::from_millis(8));
        let now = r.line.now().mono;
        r.line.device.inject(j, now);
    }
    r.line.run_for(Duration::from_millis(500));
    r.assert_exact();
    assert_eq!(r.line.driver.stats().skipped_bytes, 5);
    assert!(r.texts_with("skipped") >= 1);
    // The boxes were reset behind the driver's back: it resets and enables them again.
    let resets = r.line.device.resets();
    let now = r.line.now().mono;
    r.line.device.inject(&[RESET], now);
    r.line.run_for(Duration::from_millis(200));
    assert_eq!(r.texts_with("didn't expect it"), 1);
    assert_eq!(r.line.device.resets(), resets + 2);
    r.line.run_for(Duration::from_secs(1));
    r.assert_exact();
}

#[test]
fn silent_boxes_are_retried_every_two_seconds() {
    let mut r = rig_with(LINE, 6, |b| b.mute = true);
    // Attempts at 0, 2 and 4 s, each failing after 1 s.
    r.line.run_for(Duration::from_millis(5500));
    assert_eq!(r.texts_with("no answer to the reset command"), 3);
    assert!(r.heard().is_empty());
    r.line.device.mute = false;
    r.line.run_for(Duration::from_secs(3));
    r.assert_exact();
}

#[test]
fn a_closed_port_is_reopened_and_reset() {
    let mut r = rig(LINE, 7);
    r.line.run_for(Duration::from_millis(500));
    // Unplugged: the boxes' events go nowhere (a press lost there would leave a toggle
    // wrong for good, on any driver), so they make none.
    r.line.device.mute = true;
    r.line.close();
    let n = r.heard().len();
    r.line.run_for(Duration::from_millis(400));
    assert_eq!(r.heard().len(), n, "nothing while closed");
    assert!(r.line.run_until(Duration::from_secs(2), |l| l.opens == 2));
    // Plugged in again (the first reset byte went unanswered).
    r.line.device.mute = false;
    r.line.run_for(Duration::from_secs(3));
    assert_eq!(r.line.driver.stats().resets, 2);
    assert!(
        r.heard().len() > n + 40,
        "{} reports after {n}",
        r.heard().len()
    );
    r.assert_exact();
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_raw_SGIBox\tSgibox0\t/dev/ttyS0\t0 1 2 3\n\
                vrpn_raw_SGIBox Sgibox1 /dev/ttyS1\n\
                vrpn_raw_SGIBox Sgibox2 /dev/ttyS2 31\n";
    let entries = parse_str(text, "sgi.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 3);
    assert_eq!(names, ["Sgibox0", "Sgibox1", "Sgibox2"]);
    for (bad, why) in [
        ("vrpn_raw_SGIBox S\n", "port"),
        ("vrpn_raw_SGIBox S /dev/ttyS0 32\n", "32"),
        ("vrpn_raw_SGIBox S /dev/ttyS0 1 x\n", "x"),
    ] {
        let e = parse_str(&format!("# comment\n{bad}"), "bad.cfg")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.cfg") && e.contains(":2") && e.contains(why),
            "{e}"
        );
    }
    let e = parse_str("vrpn_SGIBOX Sgibox0 1 2\n", "h.cfg").unwrap()[0]
        .unknown_error()
        .expect("the GL keyword is not served")
        .to_string();
    assert!(e.contains("vrpn_raw_SGIBox"), "{e}");
}
