//! The Radamec SPI driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_Radamec_SPI`, and a TCP client of its Analog. Checked against the
//! simulator's own log: exact values in order with first-byte stamps, garbage and false
//! starts, silence (the watchdog resets the device; nothing is invented), unplugging.

use std::time::Duration;

use vrpn::driver::Interface;
use vrpn::drivers::radamec::sim::{RadamecSim, SimConfig};
use vrpn::sim::rig::{Client, Heard};
use vrpn::sim::SimulatedDevice;
use vrpn::TimeVal;

#[path = "common/event_rig.rs"]
mod event_rig;
#[path = "common/events.rs"]
mod events;
use event_rig::{Device, EventRig, Want};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn heard(c: &Client, from: usize) -> Vec<(Vec<f64>, TimeVal)> {
    c.heard()[from..]
        .iter()
        .filter_map(|h| match h {
            Heard::Analog { channels, time } => Some((channels.clone(), *time)),
            _ => None,
        })
        .collect()
}

fn want(sim: &SimulatedDevice<RadamecSim>) -> Want<Vec<f64>> {
    sim.model(|m| {
        let sent = m.sent();
        let want = sent
            .iter()
            .enumerate()
            .map(|(i, s)| (s.expected(), Some(i)))
            .collect();
        (want, sent.iter().map(|s| s.first_byte).collect())
    })
}

#[test]
fn radamec_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("radamec", || {
        let mut cfg = SimConfig::new();
        cfg.keep_log = true;
        RadamecSim::new(cfg)
    })
    .unwrap();
    let device = Device {
        what: "Radamec",
        unit: "report",
        heard,
        want,
        skip_first: false,
    };
    let r = EventRig::start(
        sim,
        SERVER,
        "vrpn_Radamec_SPI Analog0 {PATH} 38400\n",
        "Analog0",
        &[Interface::Analog],
        device,
    );

    // 1. Start-up and exact values (every report, absolute: nothing to skip).
    r.start_up("vrpn_Radamec_SPI", 100);
    assert_eq!(r.heard(0)[0].0.len(), 8);

    // 2. Garbage and stray type bytes between blocks: reported, nothing lost.
    let junk: [&[u8]; 3] = [&[0x00, 0x41, 0x13], &[0xA1], &[0xA6, 0x20, 0xA0]];
    r.garbage(&junk, 50);

    // 3. Silence: the watchdog resets the device; what follows is what it sends.
    let (from, before) = (r.client.len(), r.logged());
    r.sim.model(|m| m.mute = true);
    r.client.wait_text(
        from,
        "Timeout... current_time=",
        Duration::from_secs(5),
        &r.server,
    );
    r.sim.model(|m| m.mute = false);
    r.client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &r.server,
        |c| heard(c, from).len() >= 50,
    );
    r.check(
        &r.heard(from),
        before.saturating_sub(5),
        "Radamec after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened when back.
    r.unplug(50, Duration::from_secs(6), |_| {}, |_| {});
}
