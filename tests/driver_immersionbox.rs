//! The Immersion box driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_ImmersionBox`, and a TCP client of its Button, Analog and Dial.
//! Checked against the simulator's own log: the reset, exact changes in order with
//! first-byte stamps, garbage, silence (the watchdog resets the box; nothing is invented),
//! and unplugging (reported, reopened, reset, resumed).

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::immersionbox::sim::{expected_changes, IboxSim, SimConfig};
use vrpn::sim::rig::{Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

#[path = "common/events.rs"]
mod events;
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

fn logged(sim: &SimulatedDevice<IboxSim>) -> usize {
    sim.model(|m| m.sent().len())
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
    let t0 = Now::read();
    let line = format!(
        "vrpn_ImmersionBox ibox0 {} 38400 {BUTTONS} 2 1\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let interfaces = [Interface::Button, Interface::Analog, Interface::Dial];
    let client = Client::connect("ibox0", server.port(), &interfaces).unwrap();
    let changes = |c: &Client| heard(c, 0).len();

    // 1. Reset and exact changes.
    client.wait_until(Duration::from_secs(10), "a first change", &server, |c| {
        changes(c) >= 1
    });
    let startup = heard(&client, 0)[0].1.seconds_since(t0.wall);
    eprintln!(
        "vrpn_ImmersionBox: vrpn_server start to first report {:.0} ms",
        startup * 1e3
    );
    client.wait_until(Duration::from_secs(10), "100 changes", &server, |c| {
        changes(c) >= 100
    });
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        true,
        t0,
        "vrpn_ImmersionBox",
    );

    // 2. Garbage between records: reported, nothing lost.
    let junk: [&[u8]; 3] = [&[0x01, 0x7F], &[0xC0], &[0x55, 0x81, 0x22]];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(10), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let n = changes(&client);
    client.wait_until(
        Duration::from_secs(5),
        "changes after garbage",
        &server,
        |c| changes(c) >= n + 50,
    );
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        true,
        t0,
        "vrpn_ImmersionBox after garbage",
    );
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);

    // 3. Cut off: the watchdog resets the box after 2 s; records resume after a new reset.
    let (from, before) = (client.len(), logged(&sim));
    sim.model(|m| m.mute = true);
    client.wait_text(
        from,
        "Too long since last report, resetting",
        Duration::from_secs(5),
        &server,
    );
    sim.model(|m| m.mute = false);
    client.wait_text(
        from,
        "vrpn_ImmersionBox found",
        Duration::from_secs(5),
        &server,
    );
    let fresh = after_text(&client, from, "vrpn_ImmersionBox found");
    client.wait_until(
        Duration::from_secs(5),
        "changes after silence",
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
        "vrpn_ImmersionBox after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened and reset when back.
    let (from, before) = (client.len(), logged(&sim));
    sim.unplug();
    client.wait_text(from, "failed", Duration::from_secs(3), &server);
    let while_unplugged = heard(&client, from).len();
    client.pump_until(Duration::from_millis(500), |_| false);
    assert_eq!(
        heard(&client, from).len(),
        while_unplugged,
        "changes while unplugged"
    );
    sim.plug().unwrap();
    client.wait_text(
        from,
        "vrpn_ImmersionBox found",
        Duration::from_secs(5),
        &server,
    );
    let fresh = after_text(&client, from, "vrpn_ImmersionBox found");
    client.wait_until(
        Duration::from_secs(6),
        "changes after plugging back",
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
        "vrpn_ImmersionBox after unplugging",
    );
}
