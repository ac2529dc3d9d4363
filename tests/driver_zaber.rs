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

use vrpn::devices::analog_output::AnalogOutputRemote;
use vrpn::driver::Interface;
use vrpn::drivers::zaber::sim::{SimConfig, ZaberSim};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

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

struct Rig {
    sim: SimulatedDevice<ZaberSim>,
    server: ServerProcess,
    client: Client,
    out: AnalogOutputRemote,
    t0: Now,
    moves: i32,
}

impl Rig {
    /// Asks for `n` moves, alternating the devices, each once the previous was reported.
    fn moves(&mut self, n: usize) {
        for _ in 0..n {
            let k = self.moves;
            self.moves += 1;
            let heard = reports(&self.client, 0).0.len();
            self.out
                .request_change_channel_value(k % 2, f64::from(k * 311 - 2000))
                .unwrap();
            let out = &self.out;
            self.client.wait_until(
                Duration::from_secs(5),
                "a move reported",
                &self.server,
                |c| {
                    let _ = out.mainloop();
                    reports(c, 0).0.len() > heard
                },
            );
        }
    }

    /// Reports from log index `from` on are a run of the moves logged from `after` on.
    fn check(&self, from: usize, after: usize) {
        let (want, at) = sent(&self.sim);
        let (got, stamps) = reports(&self.client, from);
        let runs = assert_run_of(&got, &want, after, "Zaber moves");
        assert_first_byte_stamps(
            &stamps,
            &at[runs[0]..],
            self.t0,
            Duration::from_millis(250),
            "Zaber",
        );
    }
}

#[test]
fn zaber_chain_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("zaber", || {
        let mut cfg = SimConfig::new(2);
        cfg.keep_log = true;
        ZaberSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!("vrpn_Zaber Zaber0 {}\n", sim.path().display());
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect("Zaber0", server.port(), &[Interface::Analog]).unwrap();
    let out =
        AnalogOutputRemote::new(&format!("Zaber0@tcp://127.0.0.1:{}", server.port())).unwrap();
    let mut r = Rig {
        sim,
        server,
        client,
        out,
        t0,
        moves: 0,
    };

    // 1. Start-up: the positions; then moves.
    r.client
        .wait_until(Duration::from_secs(10), "the positions", &r.server, |c| {
            !reports(c, 0).0.is_empty()
        });
    let (first, stamps) = reports(&r.client, 0);
    eprintln!(
        "Zaber: vrpn_server start to the positions {:.0} ms",
        stamps[0].seconds_since(t0.wall) * 1e3
    );
    assert_eq!(first[0], [1000.0, 2000.0]);
    r.client
        .wait_text(0, "found 2 devices", Duration::from_secs(1), &r.server);
    let from = r.client.len();
    r.moves(20);
    r.check(from, 0);

    // 2. Garbage between answers.
    let junk: [&[u8]; 3] = [&[9, 9, 9], &[1, 99], &[0]];
    r.sim.inject_between_records(&junk);
    r.client.wait_until(
        Duration::from_secs(5),
        "the garbage sent",
        &r.server,
        |_| r.sim.injected() == junk.len(),
    );
    r.moves(10);
    r.check(from, 0);
    r.client
        .wait_text(0, "skipped", Duration::from_secs(2), &r.server);

    // 3. Silence: reset on the open port, then moves again.
    let (from, logged) = (r.client.len(), sent(&r.sim).0.len());
    r.sim.set_mute(true);
    r.client.wait_text(
        from,
        "Tracker failed, trying to reset",
        Duration::from_secs(5),
        &r.server,
    );
    r.sim.set_mute(false);
    r.client
        .wait_text(from, "reset complete", Duration::from_secs(6), &r.server);
    let after_reset = r.client.len();
    r.moves(10);
    r.check(after_reset, logged);
    assert!(!r
        .client
        .texts_from(from)
        .iter()
        .any(|t| t.contains("is open again")));

    // 4. Unplugged: reported, reopened when back, reset, moves again.
    let (from, logged) = (r.client.len(), sent(&r.sim).0.len());
    r.sim.unplug();
    r.client
        .wait_text(from, "failed", Duration::from_secs(3), &r.server);
    r.sim.plug().unwrap();
    r.client
        .wait_text(from, "is open again", Duration::from_secs(6), &r.server);
    r.client
        .wait_text(from, "reset complete", Duration::from_secs(6), &r.server);
    let after_reset = r.client.len();
    r.moves(10);
    r.check(after_reset, logged);
}
