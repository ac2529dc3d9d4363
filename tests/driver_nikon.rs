//! The Nikon microscope focus driver end to end: the simulator on a pseudo-terminal, a
//! `vrpn_server` child serving `vrpn_nikon_controls`, a TCP client of its Analog and an
//! Analog_Output remote asking for moves on 127.0.0.1: the focus and each move reported
//! exactly, in order, with first-byte stamps; garbage between answers; silence (a reset after
//! 10 s); unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::drivers::nikon::sim::{NikonSim, SimConfig};
use vrpn::sim::rig::{Client, Heard};
use vrpn::sim::SimulatedDevice;
use vrpn::TimeVal;

#[path = "common/output_rig.rs"]
mod output_rig;
use output_rig::{Device, OutputRig};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// `v` without runs of equal values (a client is told a position only when it changed).
fn changes<T: Copy>(v: impl IntoIterator<Item = (f64, T)>) -> (Vec<f64>, Vec<T>) {
    let mut out: Vec<(f64, T)> = Vec::new();
    for (x, t) in v {
        if out.last().map_or(true, |l| l.0 != x) {
            out.push((x, t));
        }
    }
    out.into_iter().unzip()
}

fn reports(client: &Client, from: usize) -> (Vec<f64>, Vec<TimeVal>) {
    changes(
        client
            .reports_from(from)
            .into_iter()
            .filter_map(|h| match h {
                Heard::Analog { channels, time } => Some((channels[0], time)),
                _ => None,
            }),
    )
}

fn sent(sim: &SimulatedDevice<NikonSim>) -> (Vec<f64>, Vec<Instant>) {
    sim.model(|m| changes(m.sent().iter().map(|s| (s.focus as f64, s.at))))
}

#[test]
fn nikon_focus_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("nikon", || {
        let mut cfg = SimConfig::new(9600);
        cfg.keep_log = true;
        NikonSim::new(cfg)
    })
    .unwrap();
    let device = Device {
        what: "Nikon focus",
        reports,
        sent,
        request: |k| (0, f64::from(k * 137 - 900)),
    };
    let mut r = OutputRig::start(
        sim,
        SERVER,
        "vrpn_nikon_controls Nikon0 {PATH}\n",
        "Nikon0",
        device,
    );

    // 1. Start-up: the focus; then moves.
    r.client
        .wait_until(Duration::from_secs(10), "the focus", &r.server, |c| {
            !reports(c, 0).0.is_empty()
        });
    let (first, stamps) = reports(&r.client, 0);
    eprintln!(
        "Nikon: vrpn_server start to the focus {:.0} ms",
        stamps[0].seconds_since(r.t0.wall) * 1e3
    );
    assert_eq!(first[0], 1234.0);
    r.client
        .wait_text(0, "reset complete", Duration::from_secs(1), &r.server);
    r.moves(20);
    r.check(0, 0);

    // 2. Garbage between answers.
    let junk: [&[u8]; 3] = [b"zz", b"\r\n", b"\x00"];
    r.sim.inject_between_records(&junk);
    r.sim.model(|m| m.turn_knob(-5));
    r.client.wait_until(
        Duration::from_secs(5),
        "the garbage sent",
        &r.server,
        |_| r.sim.injected() == junk.len(),
    );
    r.moves(10);
    r.check(0, 0);
    r.client
        .wait_text(0, "skipped", Duration::from_secs(2), &r.server);

    // 3. Silence: polled, then reset on the open port after 10 s; moves again.
    r.silence_and_move("Timeout...", Duration::from_secs(13), 10);

    // 4. Unplugged: reported, reopened when back, reset, moves again.
    r.unplug_and_move(10);
}
