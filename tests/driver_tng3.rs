//! The TNG-3 driver end to end: its simulator on a pseudo-terminal, a `vrpn_server` child
//! serving `vrpn_Tng3`, and a TCP client of its Analog and Button. Checked against the
//! simulator's own log: exact values in order with first-byte stamps, garbage (the step is
//! found again, nothing lost), silence (the watchdog looks for the step again; nothing is
//! invented), unplugging.

use std::time::Duration;

use vrpn::driver::Interface;
use vrpn::drivers::tng3::sim::{expected, Report, SimConfig, Tng3Sim};
use vrpn::sim::rig::{Client, Heard};
use vrpn::sim::SimulatedDevice;
use vrpn::TimeVal;

#[path = "common/event_rig.rs"]
mod event_rig;
#[path = "common/events.rs"]
mod events;
use event_rig::{Device, EventRig, Want};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn heard(c: &Client, from: usize) -> Vec<(Report, TimeVal)> {
    c.heard()[from..]
        .iter()
        .filter_map(|h| match h {
            Heard::Button {
                button,
                pressed,
                time,
            } => Some((Report::Button(*button, *pressed), *time)),
            Heard::Analog { channels, time } => Some((Report::Analog(channels.clone()), *time)),
            _ => None,
        })
        .collect()
}

fn want(sim: &SimulatedDevice<Tng3Sim>) -> Want<Report> {
    sim.model(|m| {
        let sent = m.sent();
        let want = expected(sent, 8, 8)
            .into_iter()
            .map(|(r, i)| (r, Some(i)))
            .collect();
        (want, sent.iter().map(|s| s.first_byte).collect())
    })
}

#[test]
fn tng3_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("tng3", || {
        let mut cfg = SimConfig::new();
        cfg.keep_log = true;
        Tng3Sim::new(cfg)
    })
    .unwrap();
    let device = Device {
        what: "TNG-3",
        unit: "report",
        heard,
        want,
        skip_first: true,
    };
    let r = EventRig::start(
        sim,
        SERVER,
        "vrpn_Tng3 tng3 {PATH} 8 8\n",
        "tng3",
        &[Interface::Analog, Interface::Button],
        device,
    );

    // 1. The step found, exact values.
    r.start_up("vrpn_Tng3", 200);

    // 2. Garbage between records: the step is lost and found again, nothing lost.
    // Noise, and false records of both start bytes after a byte that breaks the step. Each
    // piece starts with a byte that is no start byte: junk right where a record is due that
    // starts with the due start byte would be taken for a record (the protocol has no check;
    // docs/DRIVERS.md says so), and the byte after a false record is junk too, so that its
    // rejection does not depend on the data that follows.
    let junk: [&[u8]; 3] = [
        &[0x01, 0x02],
        &[0x13, 0x55, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0x13],
        &[0x33, 0xAA, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0x33],
    ];
    r.garbage(&junk, 100);

    // 3. Silence: reported after 2 s; records resume and nothing is invented.
    let from = r.client.len();
    r.sim.model(|m| m.mute = true);
    r.client.wait_text(
        from,
        "Too long since last report, resetting",
        Duration::from_secs(5),
        &r.server,
    );
    r.sim.model(|m| m.mute = false);
    r.client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &r.server,
        |c| heard(c, from).len() >= 100,
    );
    r.check(&r.heard(0), 0, "TNG-3 after silence");

    // 4. Unplugged: reported, nothing while unplugged, reopened, the step found again.
    r.unplug(100, Duration::from_secs(6), |_| {}, |_| {});
}
