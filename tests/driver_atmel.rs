//! The Atmel board driver end to end: the simulator on a pseudo-terminal, a `vrpn_server`
//! child serving a `vrpn_Atmel` entry, a TCP client of its Analog and an Analog_Output remote
//! on 127.0.0.1: each cycle's values exactly, in order, with first-byte stamps; writes and
//! C++'s error values; garbage between answers; silence (failed reads reported, then the
//! board started again); unplugging and reopening.

use std::time::{Duration, Instant};

use vrpn::devices::analog_output::AnalogOutputRemote;
use vrpn::driver::Interface;
use vrpn::drivers::atmel::sim::{AtmelSim, SimConfig};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard, ServerProcess};
use vrpn::sim::SimulatedDevice;
use vrpn::{Now, TimeVal};

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

fn reports(client: &Client, from: usize) -> Vec<(Vec<f64>, TimeVal)> {
    client
        .reports_from(from)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Analog { channels, time } => Some((channels, time)),
            _ => None,
        })
        .collect()
}

/// Register `r`'s answers: values and when their first bytes left.
fn answers(sim: &SimulatedDevice<AtmelSim>, r: usize) -> (Vec<f64>, Vec<Instant>) {
    sim.model(move |m| {
        m.answered()
            .iter()
            .filter(|a| a.register == r)
            .map(|a| (f64::from(a.value), a.at))
            .unzip()
    })
}

/// What a channel reports for a read the board did not answer within 150 ms (C++'s value).
const READ_FAILED: f64 = -21.0;

/// Channel `ch` of every report is `value`, the register's contents, except for reads a
/// loaded machine held the simulator's thread past the driver's 150 ms wait for (their
/// answer came too late: `READ_FAILED`, as C++ reports), at most one in ten.
fn assert_reads(reports: &[(Vec<f64>, TimeVal)], ch: usize, value: f64) {
    let failed = reports.iter().filter(|(c, _)| c[ch] == READ_FAILED).count();
    assert!(
        failed * 10 <= reports.len(),
        "channel {ch}: {failed} failed reads"
    );
    if let Some((c, t)) = reports
        .iter()
        .find(|(c, _)| c[ch] != value && c[ch] != READ_FAILED)
    {
        panic!("channel {ch}: {c:?} at {t:?}, not {value}");
    }
}

struct Rig {
    sim: SimulatedDevice<AtmelSim>,
    server: ServerProcess,
    client: Client,
    out: AnalogOutputRemote,
    t0: Now,
}

impl Rig {
    /// Waits for `n` more reports.
    fn more(&self, n: usize, what: &str) {
        let have = reports(&self.client, 0).len();
        let out = &self.out;
        self.client
            .wait_until(Duration::from_secs(10), what, &self.server, |c| {
                let _ = out.mainloop();
                reports(c, 0).len() >= have + n
            });
    }

    /// Reports from log index `from` on carry registers 0 and 1's answers one for one (and
    /// are stamped with register 0's, the first of each cycle). A loaded machine can hold
    /// the simulator's thread past the driver's 150 ms wait: that read reports -21 (as C++)
    /// and its late answer, logged by the simulator, is never heard. So each -21 may stand
    /// for one logged answer; every other value must be the next answer, exactly.
    fn check(&self, from: usize) {
        let got = reports(&self.client, from);
        for r in [0, 1] {
            let (want, at) = answers(&self.sim, r);
            let values: Vec<f64> = got.iter().map(|(c, _)| c[r]).collect();
            let failed = values.iter().filter(|&&v| v == READ_FAILED).count();
            assert!(
                failed * 10 <= values.len(),
                "register {r}: {failed} failed reads"
            );
            // Where the first four reports in a row without a failed read stand in the log
            // (a failed read among them would stand for an answer missing from the run),
            // then each next one.
            let i0 = (0..values.len().saturating_sub(3))
                .find(|&i| !values[i..i + 4].contains(&READ_FAILED))
                .expect("four reads in a row answered");
            let runs = assert_run_of(
                &values[i0..i0 + 4],
                &want,
                0,
                &format!("Atmel register {r}"),
            );
            let mut p = runs[0];
            let mut matched = Vec::new();
            let mut may_skip = 0;
            for (i, &v) in values.iter().enumerate().skip(i0) {
                if v == READ_FAILED {
                    may_skip += 1;
                    continue;
                }
                while want.get(p) != Some(&v) && may_skip > 0 {
                    p += 1;
                    may_skip -= 1;
                }
                assert_eq!(
                    want.get(p),
                    Some(&v),
                    "register {r}: report {i} is not the next answer"
                );
                matched.push((i, p));
                p += 1;
            }
            if r == 0 && failed == 0 {
                let stamps: Vec<TimeVal> = got.iter().map(|(_, t)| *t).collect();
                assert_first_byte_stamps(
                    &stamps,
                    &at[matched[0].1..],
                    self.t0,
                    Duration::from_millis(250),
                    "Atmel",
                );
            }
        }
    }

    fn wait_text(&self, from: usize, part: &str, max: Duration) {
        self.client.wait_text(from, part, max, &self.server);
    }
}

#[test]
fn atmel_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("atmel", || {
        let mut cfg = SimConfig::new(9600);
        cfg.keep_log = true;
        cfg.burst = true;
        AtmelSim::new(cfg)
    })
    .unwrap();
    let t0 = Now::read();
    let lines = format!(
        "vrpn_Atmel Atmel0 {} 9600 5\nvrpn_Atmel 0 RO\nvrpn_Atmel 1 RO\nvrpn_Atmel 2 RW\n\
         vrpn_Atmel 3 WO\nvrpn_Atmel -1 END\n",
        sim.path().display()
    );
    let server = ServerProcess::start(SERVER.as_ref(), &lines).unwrap();
    let client = Client::connect("Atmel0", server.port(), &[Interface::Analog]).unwrap();
    let out =
        AnalogOutputRemote::new(&format!("Atmel0@tcp://127.0.0.1:{}", server.port())).unwrap();
    let r = Rig {
        sim,
        server,
        client,
        out,
        t0,
    };

    // 1. Start-up and exact values.
    r.more(150, "150 reports");
    let first = reports(&r.client, 0)[0].1;
    eprintln!(
        "Atmel: vrpn_server start to the first report {:.0} ms",
        first.seconds_since(t0.wall) * 1e3
    );
    let start = reports(&r.client, 0);
    assert!(start
        .iter()
        .all(|(c, _)| c.len() == 5 && c[3] == -1.0 && c[4] == -1.0));
    assert_reads(&start, 2, 2.0);
    r.check(0);

    // 2. Writes, and C++'s values for a channel that cannot be written.
    r.out.request_change_channel_value(2, 200.0).unwrap();
    r.out.request_change_channel_value(3, 17.5).unwrap();
    r.out.request_change_channel_value(0, 5.0).unwrap();
    let from = r.client.len();
    r.more(20, "reports after writes");
    let after = reports(&r.client, from);
    let at = after.iter().position(|(c, _)| c[2] == 200.0).unwrap();
    assert_eq!(after[at].0[3], 17.5);
    assert!(after[at + 1..].iter().all(|(c, _)| c[3] == 17.5));
    assert_reads(&after[at + 1..], 2, 200.0);
    assert!(after[at + 1..]
        .iter()
        .all(|(c, _)| c[0] >= 0.0 || c[0] == READ_FAILED));
    assert!(after.iter().any(|(c, _)| c[0] == -24.0));
    assert_eq!(r.sim.model(|m| m.writes().to_vec()), [(2, 200), (3, 17)]);
    r.wait_text(from, "channel 0 not writable", Duration::from_secs(1));

    // 3. Garbage between answers: skipped, the values exact.
    let junk: [&[u8]; 3] = [&[0x00, 0x7F], &[0xFE], &[0x41, 0x42]];
    r.sim.inject_between_records(&junk);
    r.client.wait_until(
        Duration::from_secs(5),
        "the garbage sent",
        &r.server,
        |_| r.sim.injected() == junk.len(),
    );
    let from = r.client.len();
    r.more(100, "reports after garbage");
    r.check(from);
    r.wait_text(0, "skipped", Duration::from_secs(2));

    // 4. Silence: unanswered reads report -21; 3 s without a byte starts the board again.
    let from = r.client.len();
    r.sim.set_mute(true);
    r.wait_text(from, "connection timed out", Duration::from_secs(6));
    assert!(reports(&r.client, from)
        .iter()
        .skip(2)
        .all(|(c, _)| c[0] == READ_FAILED && c[1] == READ_FAILED));
    r.wait_text(from, "Atmel not connected", Duration::from_secs(8));
    r.sim.set_mute(false);
    r.wait_text(from, "Atmel started", Duration::from_secs(4));
    r.more(10, "reports after silence");
    let from = r.client.len();
    r.more(100, "reports after silence");
    r.check(from);

    // 5. Unplugged: reported, reopened, started, resumed.
    let from = r.client.len();
    r.sim.unplug();
    r.wait_text(from, "failed", Duration::from_secs(3));
    r.sim.plug().unwrap();
    r.wait_text(from, "is open again", Duration::from_secs(8));
    r.wait_text(from, "Atmel started", Duration::from_secs(4));
    r.more(10, "reports after plugging back");
    let from = r.client.len();
    r.more(100, "reports after plugging back");
    r.check(from);
}
