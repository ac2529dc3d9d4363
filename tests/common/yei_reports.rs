//! What a client of a YEI 3-Space unit must hear (two poses, the Analog and the button
//! changes of each record), what it heard, and the check of one against the other, for the
//! wired and the wireless end-to-end tests.
#![allow(dead_code)]

use std::time::{Duration, Instant};

use vrpn::drivers::yei::sim::{Sent, YeiSim};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

/// One report as a client hears it.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Pose(usize, [f64; 4]),
    Analog(Vec<f64>),
    Button(usize, bool),
}

/// What the client of `unit` must hear for the records `sent`, from all buttons released on.
pub fn expected(sent: &[Sent], unit: usize) -> (Vec<Value>, Vec<Instant>) {
    let mut out = Vec::new();
    let mut buttons = 0u8;
    for s in sent.iter().filter(|s| s.unit == unit) {
        let t = s.first_byte;
        out.push((Value::Pose(0, s.quats[0]), t));
        out.push((Value::Pose(1, s.quats[1]), t));
        out.push((Value::Analog(s.channels.to_vec()), t));
        for i in 0..8 {
            if (buttons ^ s.buttons) & (1 << i) != 0 {
                out.push((Value::Button(i, s.buttons & (1 << i) != 0), t));
            }
        }
        buttons = s.buttons;
    }
    out.into_iter().unzip()
}

/// The reports `client` heard from its log index `from` on, with their stamps.
pub fn heard(client: &Client, from: usize) -> (Vec<Value>, Vec<TimeVal>) {
    client
        .reports_from(from)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Pose(p) => {
                let q = p.quat.coords;
                Some((Value::Pose(p.sensor, [q.x, q.y, q.z, q.w]), p.time))
            }
            Heard::Analog { channels, time } => Some((Value::Analog(channels), time)),
            Heard::Button {
                button,
                pressed,
                time,
            } => Some((Value::Button(button, pressed), time)),
            _ => None,
        })
        .unzip()
}

/// How many reports `c` heard from its log index `from` on.
pub fn count(c: &Client, from: usize) -> usize {
    heard(c, from).0.len()
}

/// Everything `client` heard is a run of what `unit`'s records imply, each report stamped
/// with its record's first byte (`what` names the unit in failures).
pub fn check(sim: &SimulatedDevice<YeiSim>, client: &Client, unit: usize, t0: Now, what: &str) {
    let (want, at) = sim.model(move |m| expected(m.sent(), unit));
    let (got, stamps) = heard(client, 0);
    let runs = assert_run_of(&got, &want, 0, what);
    assert_first_byte_stamps(
        &stamps,
        &at[runs[0]..],
        t0,
        Duration::from_millis(250),
        what,
    );
}
