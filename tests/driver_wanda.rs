//! The Wanda driver end to end: its simulator on a pseudo-terminal at 1200 baud, a
//! `vrpn_server` child serving `vrpn_Wanda`, and a TCP client of its Analog and Button.
//! Checked against the simulator's own log: exact values in order with first-byte stamps,
//! garbage between records, silence (the channels are centred once, nothing else is
//! invented), and unplugging (reported, reopened, resumed).

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::wanda::sim::{expected, Report, SimConfig, WandaSim};
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
                Some((Report::Analog([channels[0], channels[1]]), *time))
            }
            _ => None,
        })
        .collect()
}

type Want = (Vec<(Report, Option<usize>)>, Vec<Instant>);

fn want(sim: &SimulatedDevice<WandaSim>) -> Want {
    sim.model(|m| {
        let sent = m.sent();
        let want = expected(sent, Instant::now())
            .into_iter()
            .map(|e| (e.report, e.record))
            .collect();
        (want, sent.iter().map(|s| s.first_byte).collect())
    })
}

#[test]
fn wanda_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("wanda", || {
        let mut cfg = SimConfig::new();
        cfg.keep_log = true;
        WandaSim::new(cfg)
    })
    .unwrap();
    // A byte every 8.3 ms at 1200 baud: a gap between records is longer than that.
    sim.set_junk_idle(Duration::from_millis(12));
    let device = Device {
        what: "Wanda",
        unit: "report",
        heard,
        want,
        skip_first: true,
    };
    let r = EventRig::start(
        sim,
        SERVER,
        "vrpn_Wanda Wanda0 {PATH} 1200 60.0\n",
        "Wanda0",
        &[Interface::Analog, Interface::Button],
        device,
    );

    // 1. Start-up and exact values.
    r.start_up("Wanda", 60);

    // 2. Garbage between records: reported, nothing lost.
    let junk: [&[u8]; 4] = [&[0x85, 0xFF], &[0x41], &[0xC3, 0x52, 0x90], &[0x7F, 0x45]];
    r.garbage(&junk, 30);

    // 3. Silence: the channels are centred once; then the records resume.
    let (from, before) = (r.client.len(), r.logged());
    r.sim.model(|m| m.mute = true);
    r.client.pump_until(Duration::from_millis(800), |_| false);
    let quiet = heard(&r.client, from);
    assert!(
        quiet.iter().any(|r| r.0 == Report::Analog([0.0, 0.0])),
        "centred: {quiet:?}"
    );
    r.sim.model(|m| m.mute = false);
    r.client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &r.server,
        |c| heard(c, from).len() >= quiet.len() + 30,
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
        "Wanda after silence",
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
        "reports while unplugged"
    );
    r.sim.plug().unwrap();
    r.client.wait_until(
        Duration::from_secs(6),
        "reports after plugging back",
        &r.server,
        |c| heard(c, from).len() >= while_unplugged + 30,
    );
    r.client
        .wait_text(from, "is open again", Duration::from_secs(1), &r.server);
    let (w, at) = want(&r.sim);
    let after = first_from(&w, before);
    let fresh = r
        .client
        .heard()
        .iter()
        .skip(from)
        .position(|h| matches!(h, Heard::Text { text, .. } if text.contains("is open again")))
        .unwrap();
    check_run(
        &heard(&r.client, from + fresh),
        &w,
        &at,
        after,
        true,
        r.t0,
        "Wanda after unplugging",
    );
}
