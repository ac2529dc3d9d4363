//! The UNC joystick driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_Joystick`, and a TCP client of its Analog and Button. Checked against
//! the simulator's own log: the rest positions and exact values in order with first-byte
//! stamps, garbage, silence (the state repeated at the minimum rate, nothing else), and
//! unplugging (reported, reopened, reset, resumed).

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::uncjoystick::sim::{expected, JoystickSim, Report, SimConfig};
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

/// Reports heard from `from`, without the minimum rate's repeats (an analog report equal to
/// the one before it).
fn heard(c: &Client, from: usize) -> Vec<(Report, TimeVal)> {
    let all: Vec<(Report, TimeVal)> = c.heard()[from..]
        .iter()
        .filter_map(|h| match h {
            Heard::Button {
                button,
                pressed,
                time,
            } => Some((Report::Button(*button, *pressed), *time)),
            Heard::Analog { channels, time } => {
                let mut a = [0.0; 7];
                a.copy_from_slice(&channels[..7]);
                Some((Report::Analog(a), *time))
            }
            _ => None,
        })
        .collect();
    dedup(all, |r| r.0)
}

fn dedup<T, F: Fn(&T) -> Report>(items: Vec<T>, report: F) -> Vec<T> {
    let mut last = None;
    items
        .into_iter()
        .filter(|i| match report(i) {
            Report::Analog(a) => {
                let new = last != Some(a);
                last = Some(a);
                new
            }
            Report::Button(..) => true,
        })
        .collect()
}

type Want = (Vec<(Report, Option<usize>)>, Vec<Instant>);

fn want(sim: &SimulatedDevice<JoystickSim>) -> Want {
    sim.model(|m| {
        let sent = m.sent();
        let want = expected(sent)
            .into_iter()
            .map(|(r, i)| (r, Some(i)))
            .collect();
        (
            dedup(want, |w| w.0),
            sent.iter().map(|s| s.first_byte).collect(),
        )
    })
}

#[test]
fn unc_joystick_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("joystick", || {
        let mut cfg = SimConfig::new(19200);
        cfg.keep_log = true;
        JoystickSim::new(cfg)
    })
    .unwrap();
    let device = Device {
        what: "vrpn_Joystick",
        unit: "report",
        heard,
        want,
        skip_first: true,
    };
    let r = EventRig::start(
        sim,
        SERVER,
        "vrpn_Joystick Joy0 {PATH} 19200 10.0\n",
        "Joy0",
        &[Interface::Analog, Interface::Button],
        device,
    );

    // 1. Start-up (the rest positions) and exact values.
    r.start_up("vrpn_Joystick", 100);

    // 2. Garbage between records: reported, nothing lost.
    let junk: [&[u8]; 3] = [&[0x85, 0xFF], &[0x12, 0x13], &[0x44]];
    r.garbage(&junk, 50);

    // 3. Silence: the state is repeated 10 times a second, and nothing else is sent.
    let from = r.client.len();
    r.sim.model(|m| m.mute = true);
    r.client.pump_until(Duration::from_millis(1500), |_| false);
    let quiet: Vec<Heard> = r.client.heard()[from..].to_vec();
    let repeats = quiet
        .iter()
        .filter(|h| matches!(h, Heard::Analog { .. }))
        .count();
    assert!((10..=17).contains(&repeats), "{repeats} repeats in 1.5 s");
    r.sim.model(|m| m.mute = false);
    r.client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &r.server,
        |c| heard(c, from).len() >= 50,
    );
    // The repeats were the state before: the whole stream is still one run.
    let (w, at) = want(&r.sim);
    check_run(
        &heard(&r.client, 0),
        &w,
        &at,
        0,
        true,
        r.t0,
        "vrpn_Joystick after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened and reset when back.
    let (from, before) = (r.client.len(), r.logged());
    r.sim.unplug();
    r.client
        .wait_text(from, "failed", Duration::from_secs(3), &r.server);
    let while_unplugged = r.client.heard().len();
    r.client.pump_until(Duration::from_millis(500), |_| false);
    assert!(
        r.client.heard()[while_unplugged..]
            .iter()
            .all(|h| matches!(h, Heard::Text { .. })),
        "reports while unplugged"
    );
    r.sim.plug().unwrap();
    r.client
        .wait_text(from, "is open again", Duration::from_secs(3), &r.server);
    let fresh = from
        + 1
        + r.client.heard()[from..]
            .iter()
            .position(|h| matches!(h, Heard::Text { text, .. } if text.contains("is open again")))
            .unwrap();
    r.client.wait_until(
        Duration::from_secs(6),
        "reports after plugging back",
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
        "vrpn_Joystick after unplugging",
    );
}
