//! The Pinch Glove driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_Button_PinchGlove`, and a TCP client of its Button. Checked against
//! the simulator's own log: exact changes in order with first-byte stamps, garbage and
//! damaged messages, silence (the idle probe resets the glove; nothing is invented), and
//! unplugging (reported, reopened, reset, resumed).

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::pinchglove::sim::{expected_changes, PinchSim, SimConfig};
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
            _ => None,
        })
        .collect()
}

type Want = (Vec<(Change, Option<usize>)>, Vec<Instant>);

fn want(sim: &SimulatedDevice<PinchSim>) -> Want {
    sim.model(|m| {
        let sent = m.sent();
        let want = expected_changes(sent)
            .into_iter()
            .map(|(i, b, p)| ((b, p), Some(i)))
            .collect();
        (want, sent.iter().map(|s| s.first_byte).collect())
    })
}

/// The log index just after the first text containing `part` heard at `from` or later.
fn after_text(c: &Client, from: usize, part: &str) -> usize {
    from + 1
        + c.heard()[from..]
            .iter()
            .position(|h| matches!(h, Heard::Text { text, .. } if text.contains(part)))
            .unwrap()
}

#[test]
fn pinch_glove_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("pinch", || {
        let mut cfg = SimConfig::new(9600);
        cfg.keep_log = true;
        PinchSim::new(cfg)
    })
    .unwrap();
    let device = Device {
        what: "PinchGlove",
        unit: "change",
        heard,
        want,
        skip_first: true,
    };
    let r = EventRig::start(
        sim,
        SERVER,
        "vrpn_Button_PinchGlove Pinch0 {PATH} 9600\n",
        "Pinch0",
        &[Interface::Button],
        device,
    );

    // 1. Start-up (T0 answered) and exact changes.
    r.start_up("PinchGlove", 60);

    // 2. Garbage and damaged messages between messages: reported, nothing else lost.
    let junk: [&[u8]; 4] = [&[0x33, 0x44], &[0x8F], &[0x80, 0x10], &[0x85, 0x20, 0x8F]];
    r.garbage(&junk, 30);
    r.client.wait_text(
        0,
        "wrong message start byte (0x85)",
        Duration::from_secs(1),
        &r.server,
    );

    // 3. Silence: probed after 2 s, reset after 3 s; the changes resume, none invented.
    let (from, before) = (r.client.len(), r.logged());
    r.sim.model(|m| m.mute = true);
    r.client.wait_text(
        from,
        "no answer to a T0 probe, resetting",
        Duration::from_secs(5),
        &r.server,
    );
    let quiet = heard(&r.client, from).len();
    r.sim.model(|m| m.mute = false);
    r.client.wait_until(
        Duration::from_secs(5),
        "changes after silence",
        &r.server,
        |c| heard(c, from).len() >= quiet + 30,
    );
    let (w, at) = want(&r.sim);
    let after = first_from(&w, before.saturating_sub(10));
    check_run(
        &heard(&r.client, from),
        &w,
        &at,
        after,
        false,
        r.t0,
        "PinchGlove after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened when back, resumed.
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
    r.client
        .wait_text(from, "is open again", Duration::from_secs(3), &r.server);
    let fresh = after_text(&r.client, from, "is open again");
    r.client.wait_until(
        Duration::from_secs(6),
        "changes after plugging back",
        &r.server,
        |c| heard(c, fresh).len() >= 30,
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
        "PinchGlove after unplugging",
    );
}
