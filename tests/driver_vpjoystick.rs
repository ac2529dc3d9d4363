//! The Virtual Presence joystick end to end: the simulator on a pseudo-terminal, a
//! `vrpn_server` child serving `vrpn_VPJoystick`, and a TCP client of its Button on
//! 127.0.0.1: exact changes in order with first-byte stamps, garbage between messages,
//! silence (nothing to reset), unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::vpjoystick::sim::{expected, SimConfig, VpJoystickSim};
use vrpn::sim::rig::{assert_first_byte_stamps, Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

#[path = "common/faults.rs"]
mod faults;
use faults::{garbage_costs_nothing, silence_is_normal, unplugged_and_reopened};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn heard(client: &Client, from: usize) -> Vec<((usize, bool), TimeVal)> {
    client
        .reports_from(from)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Button {
                button,
                pressed,
                time,
            } => Some(((button, pressed), time)),
            _ => None,
        })
        .collect()
}

/// The server joined the stream at some message `k`: what it reported is what a driver
/// starting there must report, stamped with the messages' first bytes.
fn check(sim: &SimulatedDevice<VpJoystickSim>, client: &Client, t0: Now) {
    let log = sim.model(|m| m.sent().to_vec());
    let got = heard(client, 0);
    let values: Vec<(usize, bool)> = got.iter().map(|g| g.0).collect();
    let fits = (0..log.len()).find_map(|k| {
        let want = expected(&log[k..]);
        let w: Vec<(usize, bool)> = want.iter().map(|&(b, p, _)| (b, p)).collect();
        (w.len() >= values.len() && w[..values.len()] == values[..]).then_some((k, want))
    });
    let Some((k, want)) = fits else {
        panic!(
            "the {} changes received are not what the messages say from any start: {values:?}",
            values.len()
        );
    };
    let at: Vec<Instant> = want.iter().map(|c| log[k + c.2].first_byte).collect();
    let stamps: Vec<TimeVal> = got.iter().map(|g| g.1).collect();
    assert_first_byte_stamps(&stamps, &at, t0, Duration::from_millis(250), "VP joystick");
}

#[test]
fn vp_joystick_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("vpjoystick", || {
        let mut cfg = SimConfig::new(9600);
        cfg.keep_log = true;
        VpJoystickSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!(
        "vrpn_VPJoystick VPJoystick0 {} 9600\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect("VPJoystick0", server.port(), &[Interface::Button]).unwrap();
    let count = |c: &Client, from: usize| heard(c, from).len();
    client.wait_until(Duration::from_secs(10), "changes", &server, |c| {
        count(c, 0) >= 200
    });
    check(&sim, &client, t0);
    let junk: [&[u8]; 3] = [&[0x41], &[0x7F, 0x55], &[0x20]];
    garbage_costs_nothing(&sim, &client, &server, &junk, count, 100);
    check(&sim, &client, t0);
    silence_is_normal(&sim, &client, &server, count, 100);
    unplugged_and_reopened(&sim, &client, &server, count, 100);
}
