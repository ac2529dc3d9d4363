//! The IDEA stepper drive end to end: the simulated drive and motor on a pseudo-terminal, a
//! `vrpn_server` child serving `vrpn_IDEA` (with a limit hunt in its reset), a TCP client of
//! its Analog and Button and an Analog_Output remote asking for moves on 127.0.0.1. Checked
//! against the simulator's own log:
//!
//! 1. the reset hunts for the high limit and sets the position; a move into the closed limit
//!    is refused; each move asked for is made, and the positions the motor passes are
//!    reported exactly, in order, stamped with the arrival of the answer's first byte;
//!    inputs pressed are button changes, likewise;
//! 2. garbage between answers: reported, and not one position lost;
//! 3. silence: the watchdog resets the drive on the open port; moves resume;
//! 4. unplugging: reported, the port is reopened under the same path, the drive reset, moves
//!    resume.

use std::time::{Duration, Instant};

use vrpn::devices::analog_output::AnalogOutputRemote;
use vrpn::driver::Interface;
use vrpn::drivers::idea::sim::{IdeaSim, SimConfig};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard};
use vrpn::sim::SimulatedDevice;
use vrpn::TimeVal;

#[path = "common/output_rig.rs"]
mod output_rig;
use output_rig::{Device, OutputRig};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// `v` without runs of equal values (a client is told of a change only).
fn changes<T: Copy + PartialEq, S: Copy>(v: impl IntoIterator<Item = (T, S)>) -> Vec<(T, S)> {
    let mut out: Vec<(T, S)> = Vec::new();
    for (x, t) in v {
        if out.last().map_or(true, |l| l.0 != x) {
            out.push((x, t));
        }
    }
    out
}

fn positions(client: &Client, from: usize) -> (Vec<f64>, Vec<TimeVal>) {
    changes(
        client
            .reports_from(from)
            .into_iter()
            .filter_map(|h| match h {
                Heard::Analog { channels, time } => Some((channels[0], time)),
                _ => None,
            }),
    )
    .into_iter()
    .unzip()
}

fn told(sim: &SimulatedDevice<IdeaSim>) -> (Vec<f64>, Vec<Instant>) {
    sim.model(|m| changes(m.positions().iter().map(|t| (t.value, t.at))))
        .into_iter()
        .unzip()
}

fn button_events(client: &Client, from: usize) -> (Vec<(usize, bool)>, Vec<TimeVal>) {
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
        .unzip()
}

/// The button changes the inputs the drive told make, from all released.
fn told_buttons(sim: &SimulatedDevice<IdeaSim>) -> (Vec<(usize, bool)>, Vec<Instant>) {
    let bits = sim.model(|m| changes(m.inputs_told().iter().map(|t| (t.value, t.at))));
    let mut prev = 0u8;
    let mut out = Vec::new();
    for (b, at) in bits {
        for i in 0..4 {
            if (b ^ prev) & (1 << i) != 0 {
                out.push(((i, b & (1 << i) != 0), at));
            }
        }
        prev = b;
    }
    out.into_iter().unzip()
}

#[test]
fn idea_drive_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("idea", || {
        IdeaSim::new(SimConfig {
            keep_log: true,
            ..SimConfig::new()
        })
    })
    .unwrap();
    // Answers come 2 ms after their request: a gap of 1 ms marks one.
    sim.set_junk_idle(Duration::from_millis(1));
    let device = Device {
        what: "IDEA positions",
        reports: positions,
        sent: told,
        request: |k| (0, -100.0 - f64::from(k * 73 % 400)),
    };
    let mut r = OutputRig::start_with(
        sim,
        SERVER,
        "vrpn_IDEA Idea0 {PATH} 3200 1200 2000 40000 100000 290 0 290 290 50 8 1 -1 0 0 0 0 50 \
         0.5 -60.0\n",
        "Idea0",
        &[Interface::Analog, Interface::Button],
        device,
        |at| AnalogOutputRemote::new(at).unwrap(),
    );
    let t0 = r.t0;
    // Each move is made once its target is reported.
    let reached = |p: &f64, to: f64| *p == to;

    // 1. Start-up: the hunt ends at the rail (input 1 closed), set to -60 steps.
    // (A report of 0 may come first: the answer to the remote's ping, before the reset.)
    r.client
        .wait_until(Duration::from_secs(10), "the position", &r.server, |c| {
            positions(c, 0).0.contains(&-60.0)
        });
    let (first, stamps) = positions(&r.client, 0);
    let i = first.iter().position(|&p| p == -60.0).unwrap();
    assert!(first[..i].iter().all(|&p| p == 0.0), "{first:?}");
    eprintln!(
        "IDEA: vrpn_server start to the first position {:.0} ms",
        stamps[i].seconds_since(t0.wall) * 1e3
    );
    r.client
        .wait_until(Duration::from_secs(2), "the limit input", &r.server, |c| {
            button_events(c, 0).0.contains(&(0, true))
        });
    let moved = r.sim.model(|m| m.moves());
    r.out.request_change_channel_value(0, 10.0).unwrap();
    let out = &r.out;
    r.client
        .wait_until(Duration::from_secs(2), "the refusal", &r.server, |c| {
            let _ = out.mainloop();
            c.texts_from(0)
                .iter()
                .any(|t| t.contains("Asked to move into limit"))
        });
    assert_eq!(r.sim.model(|m| m.moves()), moved);
    let from = r.client.len();
    r.moves_to(12, reached);
    r.check(from, 0);
    // Inputs 2 and 3 pressed, then released.
    for bits in [0b0110, 0] {
        r.sim.model(move |m| m.set_inputs(bits));
        let pressed = bits != 0;
        r.client
            .wait_until(Duration::from_secs(2), "the inputs", &r.server, |c| {
                button_events(c, 0)
                    .0
                    .ends_with(&[(1, pressed), (2, pressed)])
            });
    }
    let (want, at) = told_buttons(&r.sim);
    let (got, stamps) = button_events(&r.client, 0);
    let runs = assert_run_of(&got, &want, 0, "IDEA inputs");
    assert_first_byte_stamps(
        &stamps,
        &at[runs[0]..],
        r.t0,
        Duration::from_millis(250),
        "IDEA inputs",
    );

    // 2. Garbage between answers.
    let junk: [&[u8]; 4] = [b"zz", b"`", b"`l12\r`x", b"\r\n"];
    r.inject_garbage(&junk, Duration::from_secs(5));
    r.moves_to(6, reached);
    r.check(from, 0);
    r.client
        .wait_text(0, "skipped", Duration::from_secs(2), &r.server);

    // 3. Silence: reset on the open port, then moves again.
    r.silence_then(
        "Timeout, resetting",
        Duration::from_secs(5),
        "reset complete",
        Duration::from_secs(6),
        |r| r.moves_to(6, reached),
    );

    // 4. Unplugged: reported, reopened when back, reset, moves again.
    r.unplug_then("reset complete", |r| r.moves_to(6, reached));
}
