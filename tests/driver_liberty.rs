//! The Polhemus Liberty / Patriot driver end to end: the simulator on a pseudo-terminal, a
//! `vrpn_server` child serving the driver's vrpn.cfg line, and a TCP client on 127.0.0.1.
//! Checked against the simulator's own log (see `common/tracker_e2e.rs`): exact values in
//! order with first-byte stamps (and a stylus switch as a button), garbage between records,
//! silence and the watchdog's reset, unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::liberty::sim::{Kind, LibertySim, SimConfig};
use vrpn::sim::rig::Client;
use vrpn::sim::SimulatedDevice;

#[path = "common/tracker_e2e.rs"]
mod tracker_e2e;
use tracker_e2e::{assert_stylus_toggles, serve, values, Rig, Values};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn sent(sim: &SimulatedDevice<LibertySim>) -> (Vec<Values>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .map(|r| (r.sample.expected(), r.first_byte))
            .unzip()
    })
}

fn run(kind: Kind, line: &str, stations: Vec<u8>, stylus: Option<&str>) {
    let sim = SimulatedDevice::start("liberty", move || {
        let mut cfg = SimConfig::new(kind, 115200);
        cfg.keep_log = true;
        cfg.stations = stations;
        LibertySim::new(cfg)
    })
    .unwrap();
    let (t0, server, client) = serve(SERVER, &sim, line, "Tracker0");
    let pen = stylus.map(|p| Client::connect(p, server.port(), &[Interface::Button]).unwrap());
    let what = format!("{kind:?}");
    let rig = Rig {
        sim: &sim,
        server: &server,
        client: &client,
        t0,
        what: &what,
        sent: &sent,
        seen: &values,
    };
    rig.start(60, 3.0);
    // The stylus changes every 5 records.
    if let Some(pen) = &pen {
        assert_stylus_toggles(pen);
    }
    rig.garbage(&[b"LYxx", b"PA\x09junk ", &[0x00, 0xFF, b' ']], 30);
    rig.silence(
        "Tracker failed, trying to reset",
        30,
        Duration::from_secs(8),
    );
    rig.unplug(30, Duration::from_secs(8));
}

#[test]
fn liberty_with_a_stylus_through_vrpn_server_to_a_client() {
    run(
        Kind::Liberty,
        "vrpn_Tracker_Liberty Tracker0 {PATH} 115200 /\nStylus Stylus0 1\n",
        vec![1, 2],
        Some("Stylus0"),
    );
}

#[test]
fn patriot_through_vrpn_server_to_a_client() {
    run(
        Kind::Patriot,
        "vrpn_Tracker_Liberty Tracker0 {PATH} 115200\n",
        vec![1, 2],
        None,
    );
}
