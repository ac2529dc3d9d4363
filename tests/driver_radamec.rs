//! The Radamec SPI driver end to end: its simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_Radamec_SPI`, and a TCP client of its Analog. Checked against the
//! simulator's own log: exact values in order with first-byte stamps, garbage and false
//! starts, silence (the watchdog resets the device; nothing is invented), unplugging.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::radamec::sim::{RadamecSim, SimConfig};
use vrpn::sim::rig::{Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

#[path = "common/events.rs"]
mod events;
use events::check_run;

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

type Want = (Vec<(Vec<f64>, Option<usize>)>, Vec<Instant>);

fn want(sim: &SimulatedDevice<RadamecSim>) -> Want {
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

fn logged(sim: &SimulatedDevice<RadamecSim>) -> usize {
    sim.model(|m| m.sent().len())
}

#[test]
fn radamec_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("radamec", || {
        let mut cfg = SimConfig::new();
        cfg.keep_log = true;
        RadamecSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!("vrpn_Radamec_SPI Analog0 {} 38400\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect("Analog0", server.port(), &[Interface::Analog]).unwrap();
    let reports = |c: &Client| heard(c, 0).len();

    // 1. Start-up and exact values (every report, absolute: nothing to skip).
    client.wait_until(Duration::from_secs(10), "a first report", &server, |c| {
        reports(c) >= 1
    });
    let startup = heard(&client, 0)[0].1.seconds_since(t0.wall);
    eprintln!(
        "vrpn_Radamec_SPI: vrpn_server start to first report {:.0} ms",
        startup * 1e3
    );
    client.wait_until(Duration::from_secs(10), "100 reports", &server, |c| {
        reports(c) >= 100
    });
    let (w, at) = want(&sim);
    check_run(&heard(&client, 0), &w, &at, 0, false, t0, "Radamec");
    assert_eq!(heard(&client, 0)[0].0.len(), 8);

    // 2. Garbage and stray type bytes between blocks: reported, nothing lost.
    let junk: [&[u8]; 3] = [&[0x00, 0x41, 0x13], &[0xA1], &[0xA6, 0x20, 0xA0]];
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
        false,
        t0,
        "Radamec after garbage",
    );
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);

    // 3. Silence: the watchdog resets the device; what follows is what it sends.
    let (from, before) = (client.len(), logged(&sim));
    sim.model(|m| m.mute = true);
    client.wait_text(
        from,
        "Timeout... current_time=",
        Duration::from_secs(5),
        &server,
    );
    sim.model(|m| m.mute = false);
    client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &server,
        |c| heard(c, from).len() >= 50,
    );
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, from),
        &w,
        &at,
        before.saturating_sub(5),
        false,
        t0,
        "Radamec after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened when back.
    let (from, before) = (client.len(), logged(&sim));
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
    client.wait_until(
        Duration::from_secs(6),
        "reports after plugging back",
        &server,
        |c| heard(c, from).len() >= while_unplugged + 50,
    );
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, from)[while_unplugged..],
        &w,
        &at,
        before,
        false,
        t0,
        "Radamec after unplugging",
    );
}
