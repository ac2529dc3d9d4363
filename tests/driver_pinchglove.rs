//! The Pinch Glove driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_Button_PinchGlove`, and a TCP client of its Button. Checked against
//! the simulator's own log: exact changes in order with first-byte stamps, garbage and
//! damaged messages, silence (the idle probe resets the glove; nothing is invented), and
//! unplugging (reported, reopened, reset, resumed).

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::pinchglove::sim::{expected_changes, PinchSim, SimConfig};
use vrpn::sim::rig::{Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

#[path = "common/events.rs"]
mod events;
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

fn logged(sim: &SimulatedDevice<PinchSim>) -> usize {
    sim.model(|m| m.sent().len())
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
    let t0 = Now::read();
    let line = format!(
        "vrpn_Button_PinchGlove Pinch0 {} 9600\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect("Pinch0", server.port(), &[Interface::Button]).unwrap();
    let changes = |c: &Client| heard(c, 0).len();

    // 1. Start-up (T0 answered) and exact changes.
    client.wait_until(Duration::from_secs(10), "a first change", &server, |c| {
        changes(c) >= 1
    });
    let startup = heard(&client, 0)[0].1.seconds_since(t0.wall);
    eprintln!(
        "PinchGlove: vrpn_server start to first report {:.0} ms",
        startup * 1e3
    );
    client.wait_until(Duration::from_secs(10), "60 changes", &server, |c| {
        changes(c) >= 60
    });
    let (w, at) = want(&sim);
    check_run(&heard(&client, 0), &w, &at, 0, true, t0, "PinchGlove");

    // 2. Garbage and damaged messages between messages: reported, nothing else lost.
    let junk: [&[u8]; 4] = [&[0x33, 0x44], &[0x8F], &[0x80, 0x10], &[0x85, 0x20, 0x8F]];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(10), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let n = changes(&client);
    client.wait_until(
        Duration::from_secs(5),
        "changes after garbage",
        &server,
        |c| changes(c) >= n + 30,
    );
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        true,
        t0,
        "PinchGlove after garbage",
    );
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);
    client.wait_text(
        0,
        "wrong message start byte (0x85)",
        Duration::from_secs(1),
        &server,
    );

    // 3. Silence: probed after 2 s, reset after 3 s; the changes resume, none invented.
    let (from, before) = (client.len(), logged(&sim));
    sim.model(|m| m.mute = true);
    client.wait_text(
        from,
        "no answer to a T0 probe, resetting",
        Duration::from_secs(5),
        &server,
    );
    let quiet = heard(&client, from).len();
    sim.model(|m| m.mute = false);
    client.wait_until(
        Duration::from_secs(5),
        "changes after silence",
        &server,
        |c| heard(c, from).len() >= quiet + 30,
    );
    let (w, at) = want(&sim);
    let after = first_from(&w, before.saturating_sub(10));
    check_run(
        &heard(&client, from),
        &w,
        &at,
        after,
        false,
        t0,
        "PinchGlove after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened when back, resumed.
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
    client.wait_text(from, "is open again", Duration::from_secs(3), &server);
    let fresh = after_text(&client, from, "is open again");
    client.wait_until(
        Duration::from_secs(6),
        "changes after plugging back",
        &server,
        |c| heard(c, fresh).len() >= 30,
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
        "PinchGlove after unplugging",
    );
}
