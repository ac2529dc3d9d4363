//! The Wanda driver end to end: its simulator on a pseudo-terminal at 1200 baud, a
//! `vrpn_server` child serving `vrpn_Wanda`, and a TCP client of its Analog and Button.
//! Checked against the simulator's own log: exact values in order with first-byte stamps,
//! garbage between records, silence (the channels are centred once, nothing else is
//! invented), and unplugging (reported, reopened, resumed).

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::wanda::sim::{expected, Report, SimConfig, WandaSim};
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

fn logged(sim: &SimulatedDevice<WandaSim>) -> usize {
    sim.model(|m| m.sent().len())
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
    let t0 = Now::read();
    let line = format!("vrpn_Wanda Wanda0 {} 1200 60.0\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect(
        "Wanda0",
        server.port(),
        &[Interface::Analog, Interface::Button],
    )
    .unwrap();
    let reports = |c: &Client| heard(c, 0).len();

    // 1. Start-up and exact values.
    client.wait_until(Duration::from_secs(10), "a first report", &server, |c| {
        reports(c) >= 1
    });
    let startup = heard(&client, 0)[0].1.seconds_since(t0.wall);
    eprintln!(
        "Wanda: vrpn_server start to first report {:.0} ms",
        startup * 1e3
    );
    client.wait_until(Duration::from_secs(10), "60 reports", &server, |c| {
        reports(c) >= 60
    });
    let (w, at) = want(&sim);
    check_run(&heard(&client, 0), &w, &at, 0, true, t0, "Wanda");

    // 2. Garbage between records: reported, nothing lost.
    let junk: [&[u8]; 4] = [&[0x85, 0xFF], &[0x41], &[0xC3, 0x52, 0x90], &[0x7F, 0x45]];
    sim.inject_between_records(&junk);
    client.wait_until(Duration::from_secs(10), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let n = reports(&client);
    client.wait_until(
        Duration::from_secs(5),
        "reports after garbage",
        &server,
        |c| reports(c) >= n + 30,
    );
    let (w, at) = want(&sim);
    check_run(
        &heard(&client, 0),
        &w,
        &at,
        0,
        true,
        t0,
        "Wanda after garbage",
    );
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);

    // 3. Silence: the channels are centred once; then the records resume.
    let (from, before) = (client.len(), logged(&sim));
    sim.model(|m| m.mute = true);
    client.pump_until(Duration::from_millis(800), |_| false);
    let quiet = heard(&client, from);
    assert!(
        quiet.iter().any(|r| r.0 == Report::Analog([0.0, 0.0])),
        "centred: {quiet:?}"
    );
    sim.model(|m| m.mute = false);
    client.wait_until(
        Duration::from_secs(5),
        "reports after silence",
        &server,
        |c| heard(c, from).len() >= quiet.len() + 30,
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
        "Wanda after silence",
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
        "reports while unplugged"
    );
    sim.plug().unwrap();
    client.wait_until(
        Duration::from_secs(6),
        "reports after plugging back",
        &server,
        |c| heard(c, from).len() >= while_unplugged + 30,
    );
    client.wait_text(from, "is open again", Duration::from_secs(1), &server);
    let (w, at) = want(&sim);
    let after = first_from(&w, before);
    let fresh = client
        .heard()
        .iter()
        .skip(from)
        .position(|h| matches!(h, Heard::Text { text, .. } if text.contains("is open again")))
        .unwrap();
    check_run(
        &heard(&client, from + fresh),
        &w,
        &at,
        after,
        true,
        t0,
        "Wanda after unplugging",
    );
}
