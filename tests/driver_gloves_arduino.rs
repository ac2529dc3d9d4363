//! The serial 5DT gloves (`vrpn_5dt` polled, `vrpn_5dt` wireless, `vrpn_5dt16`) and the
//! Streaming Arduino end to end: their simulators on pseudo-terminals, a `vrpn_server` child
//! serving the driver's vrpn.cfg line, and a TCP client of the Analog on 127.0.0.1. Checked against the simulators' logs:
//! exact values in order, stamped with their record's first byte; garbage between records
//! reported and costing no record; silence → watchdog → reset on the open port → records
//! resume with nothing invented; unplugging → reopened under the same path → records resume.

use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::drivers::glove5dt::sim::{GloveSim, SimConfig};
use vrpn::drivers::glove5dt16::sim::{Glove16Sim, SimConfig as Sim16Config};
use vrpn::drivers::streaming_arduino::sim::{ArduinoSim, SimConfig as ArduinoConfig};
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, Heard, ServerProcess};
use vrpn::sim::{DeviceModel, SimulatedDevice};
use vrpn::Now;

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");

/// A simulator's log: the channels of each record and when its first byte left.
type Log = (Vec<Vec<f64>>, Vec<Instant>);

/// The analog reports heard from log index `from` on, with their stamps.
fn reports(client: &Client, from: usize) -> (Vec<Vec<f64>>, Vec<vrpn::TimeVal>) {
    client
        .reports_from(from)
        .into_iter()
        .filter_map(|h| match h {
            Heard::Analog { channels, time } => Some((channels, time)),
            _ => None,
        })
        .unzip()
}

/// Runs the four checks on a glove simulator; `sent` reads its log.
fn analog_end_to_end<M: DeviceModel + 'static>(
    what: &str,
    sim: SimulatedDevice<M>,
    cfg_line: &str,
    junk: &[&[u8]],
    sent: fn(&M) -> Log,
) {
    let t0 = Now::read();
    let server = ServerProcess::start(SERVER.as_ref(), cfg_line).unwrap();
    let client = Client::connect("dev0", server.port(), &[Interface::Analog]).unwrap();
    let n = |c: &Client| reports(c, 0).0.len();
    let check = |from: usize, after: usize| {
        let (want, at) = sim.model(move |m| sent(m));
        let (got, stamps) = reports(&client, from);
        let runs = assert_run_of(&got, &want, after, what);
        assert_first_byte_stamps(
            &stamps,
            &at[runs[0]..],
            t0,
            Duration::from_millis(250),
            what,
        );
    };

    // 1. Start-up and exact values.
    client.wait_until(Duration::from_secs(10), "a first report", &server, |c| {
        n(c) >= 1
    });
    let (_, stamps) = reports(&client, 0);
    eprintln!(
        "{what}: vrpn_server start to first report {:.0} ms",
        stamps[0].seconds_since(t0.wall) * 1e3
    );
    client.wait_until(Duration::from_secs(5), "60 reports", &server, |c| {
        n(c) >= 60
    });
    check(0, 0);

    // 2. Garbage between records.
    sim.inject_between_records(junk);
    client.wait_until(Duration::from_secs(5), "the garbage sent", &server, |_| {
        sim.injected() == junk.len()
    });
    let k = n(&client);
    client.wait_until(
        Duration::from_secs(5),
        "reports after garbage",
        &server,
        |c| n(c) >= k + 30,
    );
    check(0, 0);
    client.wait_text(0, "skipped", Duration::from_secs(2), &server);

    // 3. Silence: the watchdog resets the glove on the open port; records resume.
    let from = client.len();
    let logged = sim.model(move |m| sent(m).0.len());
    sim.set_mute(true);
    client.wait_text(
        from,
        "Tracker failed, trying to reset",
        Duration::from_secs(5),
        &server,
    );
    sim.set_mute(false);
    client.wait_until(
        Duration::from_secs(8),
        "reports after silence",
        &server,
        |c| reports(c, from).0.len() >= 30,
    );
    check(from, logged);

    // 4. Unplugged: reported, reopened when back, resumed with nothing invented.
    let from = client.len();
    let logged = sim.model(move |m| sent(m).0.len());
    sim.unplug();
    client.wait_text(from, "failed", Duration::from_secs(3), &server);
    let while_unplugged = reports(&client, from).0.len();
    client.pump_until(Duration::from_millis(300), |_| false);
    assert_eq!(
        reports(&client, from).0.len(),
        while_unplugged,
        "reports while unplugged"
    );
    sim.plug().unwrap();
    client.wait_until(
        Duration::from_secs(8),
        "reports after plugging back",
        &server,
        |c| reports(c, from).0.len() >= while_unplugged + 30,
    );
    client.wait_text(from, "is open again", Duration::from_secs(1), &server);
    check(from, logged.saturating_sub(2));
}

/// Garbage with no record's first byte in it.
const GLOVE_JUNK: &[&[u8]] = &[&[1, 2, 3], &[0x55, 0x40], &[0xFF]];

fn glove_log(m: &GloveSim) -> Log {
    m.sent()
        .iter()
        .map(|r| (r.channels.to_vec(), r.first_byte))
        .unzip()
}

#[test]
fn polled_5dt_glove_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("5dt", || {
        let mut cfg = SimConfig::new(19200);
        cfg.keep_log = true;
        GloveSim::new(cfg)
    })
    .unwrap();
    let line = format!("vrpn_5dt dev0 {} 19200 1 0\n", sim.path().display());
    analog_end_to_end("5DT polled", sim, &line, GLOVE_JUNK, glove_log);
}

#[test]
fn wireless_5dt_glove_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("5dtw", || {
        let mut cfg = SimConfig::new(9600);
        // A record takes 10.4 ms at 9600 baud: leave gaps for the garbage.
        cfg.period = std::time::Duration::from_millis(20);
        cfg.keep_log = true;
        GloveSim::new(cfg)
    })
    .unwrap();
    let line = format!("vrpn_5dt dev0 {} 9600 2 1\n", sim.path().display());
    analog_end_to_end("5DT wireless", sim, &line, GLOVE_JUNK, glove_log);
}

#[test]
fn glove_16_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("5dt16", || {
        let mut cfg = Sim16Config::new(19200);
        cfg.keep_log = true;
        Glove16Sim::new(cfg)
    })
    .unwrap();
    let line = format!("vrpn_5dt16 dev0 {} 19200\n", sim.path().display());
    analog_end_to_end("5DT glove 16", sim, &line, GLOVE_JUNK, |m| {
        m.sent()
            .iter()
            .map(|r| (r.channels.to_vec(), r.first_byte))
            .unzip()
    });
}

#[test]
fn streaming_arduino_through_vrpn_server_to_a_client() {
    let sim = SimulatedDevice::start("arduino", || {
        let mut cfg = ArduinoConfig::new(115_200);
        cfg.keep_log = true;
        ArduinoSim::new(cfg)
    })
    .unwrap();
    let line = format!("vrpn_Streaming_Arduino dev0 {} 4\n", sim.path().display());
    // Garbage without digits or newlines (digits would merge with the next line).
    let junk: &[&[u8]] = &[b"xyz", &[0x00, 0xFF], b"a;b"];
    analog_end_to_end("Streaming Arduino", sim, &line, junk, |m| {
        m.sent()
            .iter()
            .map(|r| (r.values.clone(), r.first_byte))
            .unzip()
    });
}
