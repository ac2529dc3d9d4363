//! The serial mouse's buttons end to end: the simulator on a pseudo-terminal, a `vrpn_server`
//! child serving `vrpn_Button_SerialMouse`, and a TCP client of its Button on 127.0.0.1:
//! exact changes in order with first-byte stamps (both protocols), garbage between packets,
//! silence (nothing to reset), unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::serialmouse::packet::MouseType;
use vrpn::drivers::serialmouse::sim::{expected, SerialMouseSim, SimConfig};
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

/// The server joined the mouse's stream at some packet: what it reported is what a driver
/// starting at one packet `k` must report (all but the last few, which may be on their
/// way), stamped with the packets' first bytes.
fn check(sim: &SimulatedDevice<SerialMouseSim>, client: &Client, kind: MouseType, t0: Now) {
    let log = sim.model(|m| m.sent().to_vec());
    let got = heard(client, 0);
    let values: Vec<(usize, bool)> = got.iter().map(|g| g.0).collect();
    let fits = (0..log.len()).find_map(|k| {
        let want = expected(kind, &log[k..]);
        let w: Vec<(usize, bool)> = want.iter().map(|c| (c.button, c.pressed)).collect();
        (w.len() >= values.len() && w[..values.len()] == values[..]).then_some((k, want))
    });
    let Some((k, want)) = fits else {
        panic!("{kind:?}: the {} changes received are not what the packets say from any start: {values:?}", values.len());
    };
    let at: Vec<Instant> = want.iter().map(|c| log[k + c.packet].first_byte).collect();
    let stamps: Vec<TimeVal> = got.iter().map(|g| g.1).collect();
    assert_first_byte_stamps(&stamps, &at, t0, Duration::from_millis(250), "serial mouse");
}

fn start(
    kind: MouseType,
    word: &str,
) -> (SimulatedDevice<SerialMouseSim>, ServerProcess, Client, Now) {
    let sim = SimulatedDevice::start("serialmouse", move || {
        let mut cfg = SimConfig::new(kind);
        cfg.keep_log = true;
        SerialMouseSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!(
        "vrpn_Button_SerialMouse Button0 {} {word}\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect("Button0", server.port(), &[Interface::Button]).unwrap();
    (sim, server, client, t0)
}

#[test]
fn three_button_mouse_through_vrpn_server_to_a_client() {
    let (sim, server, client, t0) = start(MouseType::ThreeButton, "3button");
    client.wait_until(Duration::from_secs(10), "changes", &server, |c| {
        heard(c, 0).len() >= 40
    });
    check(&sim, &client, MouseType::ThreeButton, t0);
}

#[test]
fn mouse_systems_mouse_through_vrpn_server_to_a_client() {
    let kind = MouseType::MouseSystems;
    let (sim, server, client, t0) = start(kind, "mousesystems");
    let count = |c: &Client, from: usize| heard(c, from).len();
    client.wait_until(Duration::from_secs(10), "changes", &server, |c| {
        count(c, 0) >= 30
    });
    check(&sim, &client, kind, t0);
    // Garbage between packets: skipped, said, nothing lost.
    let junk: [&[u8]; 3] = [&[0x41], &[0x7F, 0x55], &[0x20]];
    garbage_costs_nothing(&sim, &client, &server, &junk, count, 20);
    check(&sim, &client, kind, t0);
    // Silence is normal for a mouse: no text, then changes again.
    silence_is_normal(&sim, &client, &server, count, 20);
    unplugged_and_reopened(&sim, &client, &server, count, 20);
}
