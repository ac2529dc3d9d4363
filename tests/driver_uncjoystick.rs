//! The UNC joystick driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_Joystick`, and a TCP client of its Analog and Button. Checked against
//! the simulator's own log: the rest positions and exact values in order with first-byte
//! stamps, garbage, silence (the state repeated at the minimum rate, nothing else), and
//! unplugging (reported, reopened, reset, resumed).

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::uncjoystick::sim::{expected, JoystickSim, Report, SimConfig};
use vrpn::sim::rig::{Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

#[path = "common/events.rs"]
mod events;
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

fn logged(sim: &SimulatedDevice<JoystickSim>) -> usize {
    sim.model(|m| m.sent().len())
}

#[test]
fn unc_joystick_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("joystick", || {
        let mut cfg = SimConfig::new(19200);
        cfg.keep_log = true;
        JoystickSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!("vrpn_Joystick Joy0 {} 19200 10.0\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect(
        "Joy0",
        server.port(),
        &[Interface::Analog, Interface::Button],
    )
    .unwrap();
    let reports = |c: &Client| heard(c, 0).len();

    // 1. Start-up (the rest positions) and exact values.
    client.wait_until(Duration::from_secs(10), "a first report", &server, |c| {
        reports(c) >= 1
    });
    let startup = heard(&client, 0)[0].1.seconds_since(t0.wall);
    eprintln!(
        "vrpn_Joystick: vrpn_server start to first report {:.0} ms",
        startup * 1e3
    );
    client.wait_until(Duration::from_secs(10), "100 reports", &server, |c| {
        reports(c) >= 100
    });
    let (w, at) = want(&sim);
    check_run(&heard(&client, 0), &w, &at, 0, true, t0, "vrpn_Joystick");

    // 2. Garbage between records: reported, nothing lost.
    let junk: [&[u8]; 3] = [&[0x85, 0xFF], &[0x12, 0x13], &[0x44]];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(10), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let n = reports(&client);
    client.wait_until(
        Duration::from_secs(5),
        "reports after garbage",
        &server,
        |c| reports(c) >= n + 50,
    );
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        true,
        t0,
        "vrpn_Joystick after garbage",
    );
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);

    // 3. Silence: the state is repeated 10 times a second, and nothing else is sent.
    let from = client.len();
    sim.model(|m| m.mute = true);
    client.pump_until(Duration::from_millis(1500), |_| false);
    let quiet: Vec<Heard> = client.heard()[from..].to_vec();
    let repeats = quiet
        .iter()
        .filter(|h| matches!(h, Heard::Analog { .. }))
        .count();
    assert!((10..=17).contains(&repeats), "{repeats} repeats in 1.5 s");
    sim.model(|m| m.mute = false);
    client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &server,
        |c| heard(c, from).len() >= 50,
    );
    // The repeats were the state before: the whole stream is still one run.
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        true,
        t0,
        "vrpn_Joystick after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened and reset when back.
    let (from, before) = (client.len(), logged(&sim));
    sim.unplug();
    client.wait_text(from, "failed", Duration::from_secs(3), &server);
    let while_unplugged = client.heard().len();
    client.pump_until(Duration::from_millis(500), |_| false);
    assert!(
        client.heard()[while_unplugged..]
            .iter()
            .all(|h| matches!(h, Heard::Text { .. })),
        "reports while unplugged"
    );
    sim.plug().unwrap();
    client.wait_text(from, "is open again", Duration::from_secs(3), &server);
    let fresh = from
        + 1
        + client.heard()[from..]
            .iter()
            .position(|h| matches!(h, Heard::Text { text, .. } if text.contains("is open again")))
            .unwrap();
    client.wait_until(
        Duration::from_secs(6),
        "reports after plugging back",
        &server,
        |c| heard(c, fresh).len() >= 50,
    );
    let (w, at) = want(&sim);
    let after = first_from(&w, before);
    check_run(
        &heard(&client, fresh),
        &w,
        &at,
        after,
        true,
        t0,
        "vrpn_Joystick after unplugging",
    );
}
