//! The raw SGI box driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_raw_SGIBox` with toggles, and a TCP client of its Button, Analog and
//! Dial. Checked against the simulator's own log: exact reports in order with first-byte
//! stamps, the lights following the toggles, garbage, a quiet line, unplugging.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::sgibox::sim::{expected, Report, SgiSim, SimConfig};
use vrpn::sim::rig::{Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

#[path = "common/events.rs"]
mod events;
use events::{check_run, first_from};

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

type Want = (Vec<(Report, Option<usize>)>, Vec<Instant>, u32);

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

fn logged(sim: &SimulatedDevice<SgiSim>) -> usize {
    sim.model(|m| m.sent().len())
}

#[test]
fn sgi_boxes_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("sgibox", || {
        let mut cfg = SimConfig::new();
        cfg.keep_log = true;
        SgiSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!("vrpn_raw_SGIBox Sgibox0 {} 0 1 2 3\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let interfaces = [Interface::Button, Interface::Analog, Interface::Dial];
    let client = Client::connect("Sgibox0", server.port(), &interfaces).unwrap();
    let reports = |c: &Client| heard(c, 0).len();

    // 1. Reset, enable, exact reports; the lights show the toggles that are on.
    client.wait_until(Duration::from_secs(10), "a first report", &server, |c| {
        reports(c) >= 1
    });
    let startup = heard(&client, 0)[0].1.seconds_since(t0.wall);
    eprintln!(
        "vrpn_raw_SGIBox: vrpn_server start to first report {:.0} ms",
        startup * 1e3
    );
    client.wait_until(Duration::from_secs(10), "150 reports", &server, |c| {
        reports(c) >= 150
    });
    let (w, at, _) = want(&sim);
    check_run(&heard(&client, 0), &w, &at, 0, false, t0, "SGI box");
    // The lights follow the toggles (the light command goes out a few ms after a press).
    assert!(
        client.pump_until(Duration::from_secs(1), |_| {
            let (_, _, on) = want(&sim);
            sim.model(|m| m.lights()) == on
        }),
        "the lights do not show the toggles"
    );

    // 2. Garbage between events: reported, nothing lost.
    let junk: [&[u8]; 3] = [&[0x01, 0x7F], &[0x45], &[0xBF, 0x10]];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(10), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let n = reports(&client);
    client.wait_until(
        Duration::from_secs(5),
        "reports after garbage",
        &server,
        |c| reports(c) >= n + 60,
    );
    let (w, at, _) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        false,
        t0,
        "SGI box after garbage",
    );
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);

    // 3. A quiet line is no failure (the boxes send only on events): nothing is invented.
    let from = client.len();
    sim.model(|m| m.mute = true);
    client.pump_until(Duration::from_millis(1500), |_| false);
    assert!(
        heard(&client, from).len() <= 4,
        "at most the events in flight: {:?}",
        heard(&client, from)
    );
    sim.model(|m| m.mute = false);
    client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &server,
        |c| heard(c, from).len() >= 40,
    );
    let (w, at, _) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        false,
        t0,
        "SGI box after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened, reset, resumed. The boxes
    // make no events meanwhile (a press lost on the way would leave a toggle wrong for good,
    // on any driver); the reset sent when the port opens again goes unanswered, the next
    // one is answered.
    let (from, before) = (client.len(), logged(&sim));
    sim.model(|m| m.mute = true);
    sim.unplug();
    client.wait_text(from, "failed", Duration::from_secs(3), &server);
    let while_unplugged = heard(&client, from).len();
    client.pump_until(Duration::from_millis(500), |_| false);
    assert_eq!(
        heard(&client, from).len(),
        while_unplugged,
        "reports while unplugged"
    );
    sim.plug().unwrap();
    client.wait_text(from, "is open again", Duration::from_secs(3), &server);
    sim.model(|m| m.mute = false);
    client.wait_until(
        Duration::from_secs(8),
        "reports after plugging back",
        &server,
        |c| heard(c, from).len() >= while_unplugged + 40,
    );
    let (w, at, _) = want(&sim);
    let after = first_from(&w, before);
    check_run(
        &heard(&client, from)[while_unplugged..],
        &w,
        &at,
        after,
        false,
        t0,
        "SGI box after unplugging",
    );
}
