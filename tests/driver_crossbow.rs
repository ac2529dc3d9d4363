//! The Crossbow driver end to end: the simulator on a pseudo-terminal, a `vrpn_server` child
//! serving the driver's vrpn.cfg line, and a TCP client on 127.0.0.1. Checked against the
//! simulator's own log (see `common/tracker_e2e.rs`): exact orientations in order with
//! first-byte stamps, garbage between packets, silence and the watchdog's reset,
//! unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::drivers::crossbow::sim::{CrossbowSim, SimConfig};
use vrpn::sim::SimulatedDevice;

#[path = "common/tracker_e2e.rs"]
mod tracker_e2e;
use tracker_e2e::{serve, values, Rig, Values};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn sent(sim: &SimulatedDevice<CrossbowSim>) -> (Vec<Values>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .map(|p| ((0, [0.0; 3], p.values.0), p.first_byte))
            .unzip()
    })
}

#[test]
fn crossbow_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("crossbow", || {
        let mut cfg = SimConfig::new(38400);
        cfg.keep_log = true;
        cfg.ranges = (4.0, 200.0);
        CrossbowSim::new(cfg)
    })
    .unwrap();
    let (t0, server, client) = serve(
        SERVER,
        &sim,
        "vrpn_Tracker_Crossbow Tracker0 {PATH} 38400 4.0 200\n",
        "Tracker0",
    );
    let rig = Rig {
        sim: &sim,
        server: &server,
        client: &client,
        t0,
        what: "Crossbow",
        sent: &sent,
        seen: &values,
    };
    rig.start(60, 3.0);
    rig.garbage(
        &[&[0xAA, 0x55, 1, 2], &[0xAA], &[0x00, 0x55, 0xAA, 0xAA]],
        30,
    );
    rig.silence(
        "Tracker failed, trying to reset",
        30,
        Duration::from_secs(8),
    );
    rig.unplug(30, Duration::from_secs(8));
}
