//! The BiosciencesTools temperature controller end to end: the simulator on a pseudo-terminal,
//! a `vrpn_server` child serving `vrpn_BiosciencesTools`, a TCP client of its Analog (the six
//! temperatures) and Button (control on), and an Analog_Output remote setting the reference
//! temperatures and the control, on 127.0.0.1. Checked against the simulator's own log:
//!
//! 1. start-up: the readings polled in turn, each reported exactly, in order, stamped with
//!    the arrival of the answer's first byte; set points asked for reach the controller, and
//!    control on is reported as a button;
//! 2. garbage between answers: skipped and said, not one reading lost;
//! 3. silence: the watchdog sets the controller up again on the open port; readings resume;
//! 4. unplugging: reported, the port is reopened under the same path, readings resume.
//!
//! A client is told a reading when it changed its channel; the simulator logs every channel
//! as the host must know it. Both logs are compared as the sequence of changes (channel, new
//! value): a change the host never heard (an answer lost to silence or unplugging) then
//! cannot shift every later comparison.

use std::time::{Duration, Instant};

use vrpn::devices::analog_output::AnalogOutputRemote;
use vrpn::driver::Interface;
use vrpn::drivers::biosciences::sim::{BioSim, SimConfig};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// A channel and its new value.
type Change = (usize, f64);

/// The changes from one vector of channels to the next, in channel order.
fn diff(before: &[f64], after: &[f64]) -> Vec<Change> {
    after
        .iter()
        .enumerate()
        .filter(|&(i, v)| before.get(i) != Some(v))
        .map(|(i, &v)| (i, v))
        .collect()
}

/// The changes the client heard, each with its report's stamp and the number of Analog
/// reports heard up to it. The first report is the base (the client joined mid-stream).
fn heard(client: &Client) -> Vec<(Change, TimeVal, usize)> {
    let reports: Vec<(Vec<f64>, TimeVal)> = client
        .reports_from(0)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Analog { channels, time } => Some((channels, time)),
            _ => None,
        })
        .collect();
    let mut out = Vec::new();
    for (k, pair) in reports.windows(2).enumerate() {
        for c in diff(&pair[0].0, &pair[1].0) {
            out.push((c, pair[1].1, k + 2));
        }
    }
    out
}

/// Analog reports heard so far.
fn analog_reports(client: &Client) -> usize {
    client
        .reports_from(0)
        .iter()
        .filter(|h| matches!(h, Heard::Analog { .. }))
        .count()
}

/// The changes the simulator put on the line, with their answers' first bytes.
fn sent(sim: &SimulatedDevice<BioSim>) -> (Vec<Change>, Vec<Instant>) {
    sim.model(|m| {
        let mut before = vec![0.0; 6];
        let mut out = (Vec::new(), Vec::new());
        for s in m.sent() {
            for c in diff(&before, &s.channels) {
                out.0.push(c);
                out.1.push(s.first_byte);
            }
            before.clone_from(&s.channels);
        }
        out
    })
}

struct Rig {
    sim: SimulatedDevice<BioSim>,
    server: ServerProcess,
    client: Client,
    out: AnalogOutputRemote,
    t0: Now,
}

impl Rig {
    /// Waits for `n` more changes than the `reports` first Analog reports hold.
    fn wait_changes(&self, reports: usize, n: usize, what: &str) {
        self.client
            .wait_until(Duration::from_secs(8), what, &self.server, |c| {
                let _ = self.out.mainloop();
                heard(c).iter().filter(|h| h.2 > reports).count() >= n
            });
    }

    /// The changes heard after the first `reports` Analog reports are one run of the changes
    /// the simulator sent from `after` on, stamped with their answers' first bytes.
    fn check(&self, reports: usize, after: usize) {
        let (want, at) = sent(&self.sim);
        let (got, stamps): (Vec<Change>, Vec<TimeVal>) = heard(&self.client)
            .into_iter()
            .filter(|h| h.2 > reports)
            .map(|h| (h.0, h.1))
            .unzip();
        let runs = assert_run_of(&got, &want, after, "BiosciencesTools readings");
        assert_first_byte_stamps(
            &stamps,
            &at[runs[0]..],
            self.t0,
            Duration::from_millis(250),
            "BiosciencesTools",
        );
    }
}

#[test]
fn biosciences_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("biosciences", || {
        let mut cfg = SimConfig::new();
        cfg.keep_log = true;
        BioSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let line = format!(
        "vrpn_BiosciencesTools Bio0 {} 37.0 36.5 0\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &line).unwrap();
    let client = Client::connect(
        "Bio0",
        server.port(),
        &[Interface::Analog, Interface::Button],
    )
    .unwrap();
    let out = AnalogOutputRemote::new(&format!("Bio0@tcp://127.0.0.1:{}", server.port())).unwrap();
    let r = Rig {
        sim,
        server,
        client,
        out,
        t0,
    };

    // 1. Start-up: the readings in turn, the configured set points; then new set points and
    //    control on.
    r.client
        .wait_until(Duration::from_secs(10), "the readings", &r.server, |c| {
            analog_reports(c) > 0
        });
    let first = r
        .client
        .reports_from(0)
        .into_iter()
        .find_map(|h| match h {
            Heard::Analog { channels, time } => Some((channels, time)),
            _ => None,
        })
        .unwrap();
    eprintln!(
        "BiosciencesTools: vrpn_server start to the first reading {:.0} ms",
        first.1.seconds_since(t0.wall) * 1e3
    );
    assert_eq!(first.0.len(), 6);
    r.wait_changes(0, 60, "readings");
    r.check(0, 0);
    let s = r.sim.model(|m| m.settings());
    assert_eq!(s.reference, [Some(37.0), Some(36.5)]);
    assert!(!s.control);
    r.out.request_change_channel_value(0, 30.5).unwrap();
    r.out.request_change_channel_value(1, 31.5).unwrap();
    r.out.request_change_channel_value(2, 1.0).unwrap();
    r.client
        .wait_until(Duration::from_secs(5), "control on", &r.server, |c| {
            let _ = r.out.mainloop();
            c.reports_from(0).iter().any(|h| {
                matches!(
                    h,
                    Heard::Button {
                        button: 0,
                        pressed: true,
                        ..
                    }
                )
            })
        });
    // The button is reported as the command is written: the simulator may read it later.
    let set = |sim: &SimulatedDevice<BioSim>| {
        let s = sim.model(|m| m.settings());
        s.reference == [Some(30.5), Some(31.5)] && s.control
    };
    r.client.wait_until(
        Duration::from_secs(2),
        "the set points at the controller",
        &r.server,
        |_| set(&r.sim),
    );

    // 2. Garbage between answers.
    let junk: [&[u8]; 3] = [b"xyz", b"\r\r", b"\x00\xFF"];
    r.sim.inject_between_records(&junk);
    r.client.wait_until(
        Duration::from_secs(5),
        "the garbage sent",
        &r.server,
        |_| r.sim.injected() == junk.len(),
    );
    let reports = analog_reports(&r.client);
    r.wait_changes(reports, 30, "readings after garbage");
    r.check(0, 0);
    r.client
        .wait_text(0, "skipped", Duration::from_secs(2), &r.server);

    // 3. Silence: the watchdog sets the controller up again on the open port; readings
    //    resume (the answers lost meanwhile are in the simulator's log, not the client's).
    let from = r.client.len();
    r.sim.set_mute(true);
    r.client.wait_text(
        from,
        "Tracker failed, trying to reset",
        Duration::from_secs(5),
        &r.server,
    );
    let (reports, logged) = (analog_reports(&r.client), sent(&r.sim).0.len());
    r.sim.set_mute(false);
    r.wait_changes(reports, 30, "readings after silence");
    r.check(reports, logged);
    assert!(!r
        .client
        .texts_from(from)
        .iter()
        .any(|t| t.contains("is open again")));

    // 4. Unplugged: reported, reopened when back, set up again with the set points in force
    //    (not the configured ones), readings resume.
    let written = |sim: &SimulatedDevice<BioSim>| {
        sim.model(|m| m.heard().windows(8).filter(|w| w == b"S1 0305\r").count())
    };
    let before = written(&r.sim);
    let from = r.client.len();
    r.sim.unplug();
    r.client
        .wait_text(from, "failed", Duration::from_secs(3), &r.server);
    let (reports, logged) = (analog_reports(&r.client), sent(&r.sim).0.len());
    r.sim.plug().unwrap();
    r.client
        .wait_text(from, "is open again", Duration::from_secs(6), &r.server);
    r.wait_changes(reports, 30, "readings after plugging back");
    r.check(reports, logged);
    assert!(written(&r.sim) > before);
    assert!(set(&r.sim));
}
