//! The TNG-3 driver end to end: its simulator on a pseudo-terminal, a `vrpn_server` child
//! serving `vrpn_Tng3`, and a TCP client of its Analog and Button. Checked against the
//! simulator's own log: exact values in order with first-byte stamps, garbage (the step is
//! found again, nothing lost), silence (the watchdog looks for the step again; nothing is
//! invented), unplugging.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::tng3::sim::{expected, Report, SimConfig, Tng3Sim};
use vrpn::sim::rig::{Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

#[path = "common/events.rs"]
mod events;
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
            Heard::Analog { channels, time } => Some((Report::Analog(channels.clone()), *time)),
            _ => None,
        })
        .collect()
}

type Want = (Vec<(Report, Option<usize>)>, Vec<Instant>);

fn want(sim: &SimulatedDevice<Tng3Sim>) -> Want {
    sim.model(|m| {
        let sent = m.sent();
        let want = expected(sent, 8, 8)
            .into_iter()
            .map(|(r, i)| (r, Some(i)))
            .collect();
        (want, sent.iter().map(|s| s.first_byte).collect())
    })
}

fn logged(sim: &SimulatedDevice<Tng3Sim>) -> usize {
    sim.model(|m| m.sent().len())
}

#[test]
fn tng3_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("tng3", || {
        let mut cfg = SimConfig::new();
        cfg.keep_log = true;
        Tng3Sim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!("vrpn_Tng3 tng3 {} 8 8\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect(
        "tng3",
        server.port(),
        &[Interface::Analog, Interface::Button],
    )
    .unwrap();
    let reports = |c: &Client| heard(c, 0).len();

    // 1. The step found, exact values.
    client.wait_until(Duration::from_secs(10), "a first report", &server, |c| {
        reports(c) >= 1
    });
    let startup = heard(&client, 0)[0].1.seconds_since(t0.wall);
    eprintln!(
        "vrpn_Tng3: vrpn_server start to first report {:.0} ms",
        startup * 1e3
    );
    client.wait_until(Duration::from_secs(10), "200 reports", &server, |c| {
        reports(c) >= 200
    });
    let (w, at) = want(&sim);
    check_run(&heard(&client, 0), &w, &at, 0, true, t0, "TNG-3");

    // 2. Garbage between records: the step is lost and found again, nothing lost.
    // Noise, and false records of both start bytes after a byte that breaks the step. Each
    // piece starts with a byte that is no start byte: junk right where a record is due that
    // starts with the due start byte would be taken for a record (the protocol has no check;
    // docs/DRIVERS.md says so), and the byte after a false record is junk too, so that its
    // rejection does not depend on the data that follows.
    let junk: [&[u8]; 3] = [
        &[0x01, 0x02],
        &[0x13, 0x55, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0x13],
        &[0x33, 0xAA, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0x33],
    ];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(10), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let n = reports(&client);
    client.wait_until(
        Duration::from_secs(5),
        "reports after garbage",
        &server,
        |c| reports(c) >= n + 100,
    );
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        true,
        t0,
        "TNG-3 after garbage",
    );
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);

    // 3. Silence: reported after 2 s; records resume and nothing is invented.
    let from = client.len();
    sim.model(|m| m.mute = true);
    client.wait_text(
        from,
        "Too long since last report, resetting",
        Duration::from_secs(5),
        &server,
    );
    sim.model(|m| m.mute = false);
    client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &server,
        |c| heard(c, from).len() >= 100,
    );
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        true,
        t0,
        "TNG-3 after silence",
    );

    // 4. Unplugged: reported, nothing while unplugged, reopened, the step found again.
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
        |c| heard(c, from).len() >= while_unplugged + 100,
    );
    let (w, at) = want(&sim);
    let after = first_from(&w, before);
    check_run(
        &heard(&client, from)[while_unplugged..],
        &w,
        &at,
        after,
        true,
        t0,
        "TNG-3 after unplugging",
    );
}
