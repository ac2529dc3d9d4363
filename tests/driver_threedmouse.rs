//! The Logitech 3D mouse driver end to end: the simulator on a pseudo-terminal, a
//! `vrpn_server` child serving `vrpn_Tracker_3DMouse`, and TCP clients of its Tracker and
//! Button on 127.0.0.1. Checked against the simulator's own log (see `common/tracker_e2e.rs`):
//! exact poses in order with first-byte stamps, the button changes of the records sent,
//! garbage between records, silence and the watchdog's reset, unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::threedmouse::sim::{SimConfig, ThreeDMouseSim};
use vrpn::sim::rig::{assert_run_of, Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::Now;

#[path = "common/tracker_e2e.rs"]
mod tracker_e2e;
use tracker_e2e::{tracker_client, values, Rig, Values};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// The poses the simulator sent (records out of range send none).
fn sent(sim: &SimulatedDevice<ThreeDMouseSim>) -> (Vec<Values>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .filter_map(|r| r.sample.pose().map(|p| (p, r.first_byte)))
            .unzip()
    })
}

/// The button changes of every record the simulator sent, from all released.
fn changes(sim: &SimulatedDevice<ThreeDMouseSim>) -> Vec<(usize, bool)> {
    sim.model(|m| {
        let mut state = [false; 5];
        let mut out = Vec::new();
        for r in m.sent() {
            for (i, &p) in r.sample.buttons().iter().enumerate() {
                if p != state[i] {
                    out.push((i, p));
                    state[i] = p;
                }
            }
        }
        out
    })
}

fn heard_changes(client: &Client) -> Vec<(usize, bool)> {
    client
        .reports_from(0)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Button {
                button, pressed, ..
            } => Some((button, pressed)),
            _ => None,
        })
        .collect()
}

#[test]
fn threedmouse_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("threedmouse", || {
        let mut cfg = SimConfig::new(19_200);
        cfg.keep_log = true;
        ThreeDMouseSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!(
        "vrpn_Tracker_3DMouse Mouse0 {} 19200 2\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let buttons = Client::connect("Mouse0", server.port(), &[Interface::Button]).unwrap();
    let client = tracker_client("Mouse0", &server);
    let rig = Rig {
        sim: &sim,
        server: &server,
        client: &client,
        t0,
        what: "3DMouse",
        sent: &sent,
        seen: &values,
    };
    rig.start(60, 3.0);
    assert_eq!(sim.model(|m| m.filter_count()), 2);
    // The buttons: every change of the records sent, in order (the client may have joined
    // after the first ones).
    buttons.pump_until(Duration::from_millis(500), |c| heard_changes(c).len() >= 20);
    let got = heard_changes(&buttons);
    assert!(got.len() >= 10, "{} button changes", got.len());
    assert_run_of(&got, &changes(&sim), 0, "3DMouse buttons");
    rig.garbage(&[&[0x01, 0x7F, 0x41], &[0xC5, 0x12], &[0x80]], 30);
    rig.silence(
        "3DMouse failed, trying to reset",
        30,
        Duration::from_secs(8),
    );
    rig.unplug(30, Duration::from_secs(8));
}
