//! The Immersion box driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_ImmersionBox`, and a TCP client of its Button, Analog and Dial.
//! Checked against the simulator's own log: the reset, exact changes in order with
//! first-byte stamps, garbage, silence (the watchdog resets the box; nothing is invented),
//! and unplugging (reported, reopened, reset, resumed).

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::immersionbox::sim::{expected_changes, IboxSim, SimConfig};
use vrpn::sim::rig::{Client, Heard};
use vrpn::sim::SimulatedDevice;
use vrpn::TimeVal;

#[path = "common/event_rig.rs"]
mod event_rig;
#[path = "common/events.rs"]
mod events;
use event_rig::{Device, EventRig};
use events::{check_run, first_from};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const BUTTONS: usize = 7;

type Change = (usize, bool);

fn heard(c: &Client, from: usize) -> Vec<(Change, TimeVal)> {
    c.heard()[from..]
        .iter()
        .filter_map(|h| match h {
            Heard::Button {
                button,
                pressed,
                time,
            } => Some(((*button, *pressed), *time)),
            Heard::Analog { .. } | Heard::Dial { .. } => panic!("not sent by C++: {h:?}"),
            _ => None,
        })
        .collect()
}

type Want = (Vec<(Change, Option<usize>)>, Vec<Instant>);

fn want(sim: &SimulatedDevice<IboxSim>) -> Want {
    sim.model(|m| {
        let sent = m.sent();
        let want = expected_changes(sent, BUTTONS, 0)
            .into_iter()
            .map(|(i, b, p)| ((b, p), Some(i)))
            .collect();
        (want, sent.iter().map(|s| s.first_byte).collect())
    })
}

/// The log index just after the last text containing `part` heard at `from` or later.
fn after_text(c: &Client, from: usize, part: &str) -> usize {
    from + 1
        + c.heard()[from..]
            .iter()
            .rposition(|h| matches!(h, Heard::Text { text, .. } if text.contains(part)))
            .unwrap()
}

#[test]
fn immersion_box_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("ibox", || {
        let mut cfg = SimConfig::new(38400);
        cfg.keep_log = true;
        IboxSim::new(cfg)
    })
    .unwrap();
    let device = Device {
        what: "vrpn_ImmersionBox",
        unit: "change",
        heard,
        want,
        skip_first: true,
    };
    let r = EventRig::start(
        sim,
        SERVER,
        &format!("vrpn_ImmersionBox ibox0 {{PATH}} 38400 {BUTTONS} 2 1\n"),
        "ibox0",
        &[Interface::Button, Interface::Analog, Interface::Dial],
        device,
    );

    // 1. Reset and exact changes.
    r.start_up("vrpn_ImmersionBox", 100);

    // 2. Garbage between records: reported, nothing lost.
    let junk: [&[u8]; 3] = [&[0x01, 0x7F], &[0xC0], &[0x55, 0x81, 0x22]];
    r.garbage(&junk, 50);

    // 3. Cut off: the watchdog resets the box after 2 s; records resume after a new reset.
    let (from, before) = (r.client.len(), r.logged());
    r.sim.model(|m| m.mute = true);
    r.client.wait_text(
        from,
        "Too long since last report, resetting",
        Duration::from_secs(5),
        &r.server,
    );
    r.sim.model(|m| m.mute = false);
    r.client.wait_text(
        from,
        "vrpn_ImmersionBox found",
        Duration::from_secs(5),
        &r.server,
    );
    let fresh = after_text(&r.client, from, "vrpn_ImmersionBox found");
    r.client.wait_until(
        Duration::from_secs(5),
        "changes after silence",
        &r.server,
        |c| heard(c, fresh).len() >= 50,
    );
    let (w, at) = want(&r.sim);
    let after = first_from(&w, before);
    check_run(
        &heard(&r.client, fresh),
        &w,
        &at,
        after,
        true,
        r.t0,
        "vrpn_ImmersionBox after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened and reset when back.
    let (from, before) = (r.client.len(), r.logged());
    r.sim.unplug();
    r.client
        .wait_text(from, "failed", Duration::from_secs(3), &r.server);
    let while_unplugged = heard(&r.client, from).len();
    r.client.pump_until(Duration::from_millis(500), |_| false);
    assert_eq!(
        heard(&r.client, from).len(),
        while_unplugged,
        "changes while unplugged"
    );
    r.sim.plug().unwrap();
    r.client.wait_text(
        from,
        "vrpn_ImmersionBox found",
        Duration::from_secs(5),
        &r.server,
    );
    let fresh = after_text(&r.client, from, "vrpn_ImmersionBox found");
    r.client.wait_until(
        Duration::from_secs(6),
        "changes after plugging back",
        &r.server,
        |c| heard(c, fresh).len() >= 50,
    );
    let (w, at) = want(&r.sim);
    let after = first_from(&w, before);
    check_run(
        &heard(&r.client, fresh),
        &w,
        &at,
        after,
        true,
        r.t0,
        "vrpn_ImmersionBox after unplugging",
    );
}
