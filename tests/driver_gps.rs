//! The NMEA GPS driver end to end: the simulated receiver on a pseudo-terminal, a
//! `vrpn_server` child serving the driver's vrpn.cfg line, and a TCP client on 127.0.0.1.
//! Checked against the simulator's own log (see `common/tracker_e2e.rs`): exact fixes in
//! order with first-byte stamps, garbage between sentences, silence and the watchdog,
//! unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::drivers::gps::sim::{GpsSim, SimConfig};
use vrpn::sim::SimulatedDevice;

#[path = "common/tracker_e2e.rs"]
mod tracker_e2e;
use tracker_e2e::{serve, values, Rig, Values};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn sent(sim: &SimulatedDevice<GpsSim>) -> (Vec<Values>, Vec<Instant>) {
    sim.model(|m| {
        m.sent()
            .iter()
            .map(|f| ((0, f.values, [0.0, 0.0, 0.0, 1.0]), f.first_byte))
            .unzip()
    })
}

#[test]
fn gps_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("gps", || {
        let mut cfg = SimConfig::new(38400);
        cfg.keep_log = true;
        cfg.no_fix_every = Some(5);
        GpsSim::new(cfg)
    })
    .unwrap();
    let (t0, server, client) = serve(
        SERVER,
        &sim,
        "vrpn_Tracker_GPS Tracker0 {PATH} 38400\n",
        "Tracker0",
    );
    let rig = Rig {
        sim: &sim,
        server: &server,
        client: &client,
        t0,
        what: "GPS",
        sent: &sent,
        seen: &values,
    };
    rig.start(10, 3.0);
    rig.garbage(&[b"$GPGGA,12", b"\x00\xFF\r\n", b"$GPRMC*00\r\n"], 5);
    rig.silence("Tracker failed, trying to reset", 5, Duration::from_secs(8));
    rig.unplug(5, Duration::from_secs(8));
}
