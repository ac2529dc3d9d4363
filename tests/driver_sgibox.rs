//! The raw SGI box driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_raw_SGIBox` with toggles, and a TCP client of its Button, Analog and
//! Dial. Checked against the simulator's own log: exact reports in order with first-byte
//! stamps, the lights following the toggles, garbage, a quiet line, unplugging.

use std::time::Duration;

use vrpn::driver::Interface;
use vrpn::drivers::sgibox::sim::{expected, Report, SgiSim, SimConfig};
use vrpn::sim::rig::{Client, Heard};
use vrpn::sim::SimulatedDevice;
use vrpn::TimeVal;

#[path = "common/event_rig.rs"]
mod event_rig;
#[path = "common/events.rs"]
mod events;
use event_rig::{Device, EventRig};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const TOGGLES: [u32; 4] = [0, 1, 2, 3];

fn heard(c: &Client, from: usize) -> Vec<(Report, TimeVal)> {
    c.heard()[from..]
        .iter()
        .filter_map(|h| match h {
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
        })
        .collect()
}

/// What the log implies, and the toggles that are on.
type Want = (Vec<(Report, Option<usize>)>, Vec<std::time::Instant>, u32);

fn want(sim: &SimulatedDevice<SgiSim>) -> Want {
    sim.model(|m| {
        let sent = m.sent();
        let (want, on) = expected(sent, &TOGGLES);
        (
            want.into_iter().map(|(r, i)| (r, Some(i))).collect(),
            sent.iter().map(|s| s.first_byte).collect(),
            on,
        )
    })
}

/// What the log implies, for the rig.
fn reports(sim: &SimulatedDevice<SgiSim>) -> event_rig::Want<Report> {
    let (w, at, _) = want(sim);
    (w, at)
}

#[test]
fn sgi_boxes_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("sgibox", || {
        let mut cfg = SimConfig::new();
        cfg.keep_log = true;
        SgiSim::new(cfg)
    })
    .unwrap();
    let device = Device {
        what: "SGI box",
        unit: "report",
        heard,
        want: reports,
        skip_first: false,
    };
    let r = EventRig::start(
        sim,
        SERVER,
        "vrpn_raw_SGIBox Sgibox0 {PATH} 0 1 2 3\n",
        "Sgibox0",
        &[Interface::Button, Interface::Analog, Interface::Dial],
        device,
    );

    // 1. Reset, enable, exact reports; the lights show the toggles that are on.
    r.start_up("vrpn_raw_SGIBox", 150);
    // The lights follow the toggles (the light command goes out a few ms after a press).
    assert!(
        r.client.pump_until(Duration::from_secs(1), |_| {
            let (_, _, on) = want(&r.sim);
            r.sim.model(|m| m.lights()) == on
        }),
        "the lights do not show the toggles"
    );

    // 2. Garbage between events: reported, nothing lost.
    let junk: [&[u8]; 3] = [&[0x01, 0x7F], &[0x45], &[0xBF, 0x10]];
    r.garbage(&junk, 60);

    // 3. A quiet line is no failure (the boxes send only on events): nothing is invented.
    let from = r.client.len();
    r.sim.model(|m| m.mute = true);
    r.client.pump_until(Duration::from_millis(1500), |_| false);
    assert!(
        heard(&r.client, from).len() <= 4,
        "at most the events in flight: {:?}",
        heard(&r.client, from)
    );
    r.sim.model(|m| m.mute = false);
    r.client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &r.server,
        |c| heard(c, from).len() >= 40,
    );
    r.check(&r.heard(0), 0, "SGI box after silence");

    // 4. Unplugged: reported, nothing while unplugged, reopened, reset, resumed. The boxes
    // make no events meanwhile (a press lost on the way would leave a toggle wrong for good,
    // on any driver); the reset sent when the port opens again goes unanswered, the next
    // one is answered.
    r.unplug(
        40,
        Duration::from_secs(8),
        |sim| sim.model(|m| m.mute = true),
        |sim| sim.model(|m| m.mute = false),
    );
}
