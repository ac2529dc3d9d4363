//! The Python box on a fake port, with a client on the same in-process connection, on a
//! virtual clock: exact changes and their sample times, bouncing, a port that fails and comes
//! back, configurations.

use std::time::{Duration, Instant};

use super::config::Python;
use super::sim::{expected_changes, FakeParport, RELEASED};
use super::{PythonButtons, READS_PER_SAMPLE, REOPEN_INTERVAL, SAMPLE_PERIOD};
use crate::devices::base::set_print_threshold;
use crate::devices::text::TextSeverity;
use crate::devices::ServerDevice;
use crate::driver::Interface;
use crate::server::config::{parse_one, parse_str};
use crate::server::{build_devices, BuildNote};
use crate::sim::rig::{Client, Heard};
use crate::{Connection, Now, TimeVal};

struct Rig {
    device: PythonButtons<FakeParport>,
    port: FakeParport,
    now: Now,
    client: Client,
    _conn: Connection,
}

fn rig() -> Rig {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let conn = Connection::new_loopback();
    let port = FakeParport::new("/dev/parport0");
    let device = PythonButtons::new("Button0", port.clone(), &conn).unwrap();
    let client = Client::on_connection("Button0", &conn, &[Interface::Button]).unwrap();
    Rig {
        device,
        port,
        now: Now {
            mono: Instant::now(),
            wall: TimeVal::new(1_700_000_000, 0),
        },
        client,
        _conn: conn,
    }
}

impl Rig {
    /// Runs the device on the virtual clock for `d`, at each of its deadlines.
    fn run_for(&mut self, d: Duration) {
        let end = self.now.mono + d;
        // A deadline already due (the first sample right after an open) runs at once, as
        // the server's loop would; a device that is always due would be a bug.
        let mut due_now = 0;
        loop {
            self.device.mainloop(self.now);
            let next = self.device.next_deadline().unwrap_or(end).min(end);
            if next <= self.now.mono {
                if self.now.mono >= end {
                    break;
                }
                due_now += 1;
                assert!(due_now < 100, "the device is due again and again");
                continue;
            }
            due_now = 0;
            self.now = self.now.plus(next - self.now.mono);
        }
    }

    fn set(&self, status: u8) {
        self.port.set_at(status, self.now.mono);
    }

    fn changes(&self) -> Vec<(usize, bool, TimeVal)> {
        self.client
            .heard()
            .iter()
            .filter_map(|h| match h {
                Heard::Button {
                    button,
                    pressed,
                    time,
                } => Some((*button, *pressed, *time)),
                _ => None,
            })
            .collect()
    }

    fn texts_with(&self, needle: &str) -> usize {
        let t = self.client.texts_from(0);
        t.iter().filter(|t| t.contains(needle)).count()
    }

    fn wall(&self, t: Instant) -> TimeVal {
        self.now.wall.plus_secs(-(self.now.mono - t).as_secs_f64())
    }
}

#[test]
fn every_button_and_its_sample_time() {
    let mut r = rig();
    r.run_for(Duration::from_millis(20));
    assert_eq!(r.port.opens(), 1);
    // Each button pressed and released alone, then all at once, 13 ms apart.
    let mut values = Vec::new();
    for bit in [0x10u8, 0x80, 0x20, 0x08, 0x40] {
        values.push(RELEASED ^ bit);
        values.push(RELEASED);
    }
    values.extend([0x80, RELEASED]);
    for v in values {
        r.set(v);
        r.run_for(Duration::from_millis(13));
    }
    let log = r.port.log();
    let want = expected_changes(&log);
    let got = r.changes();
    assert_eq!(got.len(), want.len());
    assert_eq!(want.len(), 20);
    for (g, w) in got.iter().zip(&want) {
        assert_eq!((g.0, g.1), (w.1, w.2));
        // Seen at the first sample after the value was set: within one sample period.
        let set = r.wall(log[w.0].0);
        let lag = g.2.seconds_since(set);
        assert!(
            (0.0..=SAMPLE_PERIOD.as_secs_f64()).contains(&lag),
            "{lag} {w:?}"
        );
    }
    // 30 reads every 5 ms.
    let samples = r.device.stats().samples;
    assert_eq!(r.port.reads(), samples * READS_PER_SAMPLE as u64);
}

#[test]
fn a_bouncing_contact_is_reported_once_it_settles() {
    let mut r = rig();
    r.run_for(Duration::from_millis(20));
    r.set(RELEASED ^ 0x10);
    // Two samples' worth of bouncing reads.
    r.port.bounce(2 * READS_PER_SAMPLE as u32);
    r.run_for(Duration::from_millis(30));
    assert!(r.device.stats().bouncing >= 2);
    let got = r.changes();
    assert_eq!(got.len(), 1, "{got:?}");
    assert_eq!((got[0].0, got[0].1), (0, true));
}

#[test]
fn a_failing_port_is_reported_and_reopened_and_nothing_is_invented() {
    let mut r = rig();
    r.run_for(Duration::from_millis(20));
    r.set(RELEASED ^ 0x08);
    r.run_for(Duration::from_millis(10));
    assert_eq!(r.changes().len(), 1);
    r.port.fail_reads(true);
    r.port.fail_opens(true);
    r.run_for(Duration::from_millis(10));
    assert_eq!(r.texts_with("reading /dev/parport0 failed"), 1);
    // Gone for 3 s: one text, however many attempts.
    r.set(RELEASED);
    r.run_for(Duration::from_secs(3));
    assert_eq!(r.texts_with("cannot open /dev/parport0"), 0, "told already");
    assert_eq!(r.changes().len(), 1, "nothing while the port is gone");
    r.port.fail_reads(false);
    r.port.fail_opens(false);
    r.run_for(REOPEN_INTERVAL + Duration::from_millis(10));
    assert_eq!(r.texts_with("/dev/parport0 is open again"), 1);
    let got = r.changes();
    assert_eq!(got.len(), 2);
    assert_eq!((got[1].0, got[1].1), (3, false));
}

#[test]
fn a_port_that_never_opens_is_told_once() {
    let mut r = rig();
    r.port.fail_opens(true);
    r.run_for(Duration::from_millis(3500));
    assert_eq!(r.texts_with("cannot open /dev/parport0"), 1);
    assert!(r.changes().is_empty());
    r.port.fail_opens(false);
    r.run_for(Duration::from_millis(1100));
    assert_eq!(r.texts_with("is open again"), 1);
    assert_eq!(r.port.opens(), 1);
}

#[test]
fn every_config_variant_builds_and_bad_lines_are_named() {
    set_print_threshold(TextSeverity::Other(u32::MAX));
    let text = "vrpn_Button_Python\tButton0\t1\n\
                vrpn_Button_Python Button1 2 378\n\
                vrpn_Button_Python Button2 1 0x3BC\n";
    let entries = parse_str(text, "python.cfg").unwrap();
    let conn = Connection::new_loopback();
    let mut names = Vec::new();
    let devices = build_devices(&entries, &conn, false, None, |n| {
        if let BuildNote::Opened { name, .. } = n {
            names.push(name.to_string());
        }
    })
    .unwrap();
    assert_eq!(devices.len(), 3);
    assert_eq!(names, ["Button0", "Button1", "Button2"]);
    let p: Python = parse_one("vrpn_Button_Python B 2 378\n");
    assert_eq!(
        (p.device_path().as_str(), p.address),
        ("/dev/parport1", Some(0x378))
    );
    let p: Python = parse_one("vrpn_Button_Python B 1 0x3BC\n");
    assert_eq!(p.address, Some(0x3BC));
    for (bad, why) in [
        ("vrpn_Button_Python B\n", "parallel port"),
        ("vrpn_Button_Python B 0\n", "parallel port"),
        ("vrpn_Button_Python B 1 xyz\n", "hexadecimal"),
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
