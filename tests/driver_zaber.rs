//! The Zaber driver end to end: a simulated chain of two positioners on a pseudo-terminal, a
//! `vrpn_server` child serving the driver's vrpn.cfg line, a TCP client of its Analog and an
//! Analog_Output remote asking for moves. Checked against the simulator's own log:
//!
//! 1. the reset finds both devices; each move asked for is made and its position reported
//!    exactly, in order, stamped with the arrival of the answer's first byte;
//! 2. garbage between answers: reported, and not one move lost;
//! 3. silence: the watchdog resets the chain on the open port; moves resume;
//! 4. unplugging: reported, the port is reopened under the same path, the chain reset, moves
//!    resume.

use std::time::{Duration, Instant};

use vrpn::drivers::zaber::sim::{SimConfig, ZaberSim};
use vrpn::sim::rig::{Client, Heard};
use vrpn::sim::SimulatedDevice;
use vrpn::TimeVal;

#[path = "common/output_rig.rs"]
mod output_rig;
use output_rig::{Device, OutputRig};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn reports(client: &Client, from: usize) -> (Vec<Vec<f64>>, Vec<TimeVal>) {
    client
        .reports_from(from)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Analog { channels, time } => Some((channels, time)),
            _ => None,
        })
        .unzip()
}

fn sent(sim: &SimulatedDevice<ZaberSim>) -> (Vec<Vec<f64>>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .map(|s| (s.channels.clone(), s.first_byte))
            .unzip()
    })
}

#[test]
fn zaber_chain_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("zaber", || {
        let mut cfg = SimConfig::new(2);
        cfg.keep_log = true;
        ZaberSim::new(cfg)
    })
    .unwrap();
    let device = Device {
        what: "Zaber moves",
        reports,
        sent,
        // Alternating the devices.
        request: |k| (k % 2, f64::from(k * 311 - 2000)),
    };
    let mut r = OutputRig::start(sim, SERVER, "vrpn_Zaber Zaber0 {PATH}\n", "Zaber0", device);

    // 1. Start-up: the positions; then moves.
    r.client
        .wait_until(Duration::from_secs(10), "the positions", &r.server, |c| {
            !reports(c, 0).0.is_empty()
        });
    let (first, stamps) = reports(&r.client, 0);
    eprintln!(
        "Zaber: vrpn_server start to the positions {:.0} ms",
        stamps[0].seconds_since(r.t0.wall) * 1e3
    );
    assert_eq!(first[0], [1000.0, 2000.0]);
    r.client
        .wait_text(0, "found 2 devices", Duration::from_secs(1), &r.server);
    let from = r.client.len();
    r.moves(20);
    r.check(from, 0);

    // 2. Garbage between answers.
    let junk: [&[u8]; 3] = [&[9, 9, 9], &[1, 99], &[0]];
    r.inject_garbage(&junk, Duration::from_secs(5));
    r.moves(10);
    r.check(from, 0);
    r.client
        .wait_text(0, "skipped", Duration::from_secs(2), &r.server);

    // 3. Silence: reset on the open port, then moves again.
    r.silence_and_move(
        "Tracker failed, trying to reset",
        Duration::from_secs(5),
        10,
    );

    // 4. Unplugged: reported, reopened when back, reset, moves again.
    r.unplug_and_move(10);
}
