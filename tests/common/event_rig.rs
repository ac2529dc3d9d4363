//! An end-to-end rig for a change-reporting serial device (buttons, analog channels, dials):
//! its simulator on a pseudo-terminal, a `vrpn_server` child and a TCP client, with the
//! steps its test repeats: start-up with exact reports, garbage between records, and
//! unplugging; every check compares the client's reports with the simulator's log through
//! `events::check_run`. A test crate that includes this file also includes `events.rs` as
//! `mod events`.
#![allow(dead_code)]

use std::fmt::Debug;
use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::sim::rig::{Client, ServerProcess};
use vrpn::sim::{DeviceModel, SimulatedDevice};
use vrpn::{Now, TimeVal};

use super::events::{check_run, first_from};

/// The reports a simulator's log implies, each with its record, and the records' first-byte
/// times (see `events::check_run`).
pub type Want<T> = (Vec<(T, Option<usize>)>, Vec<Instant>);

/// How a device's test reads what the client heard and what the simulator logged.
pub struct Device<M: DeviceModel + 'static, T> {
    /// The device's name in the checks' messages.
    pub what: &'static str,
    /// What one report is called in the waits' messages ("report", "change").
    pub unit: &'static str,
    /// The reports the client heard from its log index `from` on, with their stamps.
    pub heard: fn(&Client, usize) -> Vec<(T, TimeVal)>,
    /// What the simulator's log implies.
    pub want: fn(&SimulatedDevice<M>) -> Want<T>,
    /// Whether the first record after a start-up is reported against the driver's own state
    /// (`events::check_run`'s `skip_first`).
    pub skip_first: bool,
}

/// The rig. See the module documentation.
pub struct EventRig<M: DeviceModel + 'static, T> {
    pub sim: SimulatedDevice<M>,
    pub server: ServerProcess,
    pub client: Client,
    pub t0: Now,
    device: Device<M, T>,
}

impl<M: DeviceModel + 'static, T: PartialEq + Debug + Clone> EventRig<M, T> {
    /// Starts `server_exe` on the config `line` (the simulator's path in it is `{PATH}`) and
    /// connects a client of `name`'s `interfaces`.
    pub fn start(
        sim: SimulatedDevice<M>,
        server_exe: &str,
        line: &str,
        name: &str,
        interfaces: &[Interface],
        device: Device<M, T>,
    ) -> Self {
        let t0 = Now::read();
        let line = line.replace("{PATH}", &sim.path().display().to_string());
        let server = ServerProcess::start(server_exe.as_ref(), &line).unwrap();
        let client = Client::connect(name, server.port(), interfaces).unwrap();
        EventRig {
            sim,
            server,
            client,
            t0,
            device,
        }
    }

    /// The reports heard from log index `from` on.
    pub fn heard(&self, from: usize) -> Vec<(T, TimeVal)> {
        (self.device.heard)(&self.client, from)
    }

    /// How many reports were heard from log index `from` on.
    pub fn count(&self, from: usize) -> usize {
        self.heard(from).len()
    }

    /// How many records the simulator logged.
    pub fn logged(&self) -> usize {
        (self.device.want)(&self.sim).1.len()
    }

    /// `heard` is a run of what the log implies from `want[after..]` on (`what` names the
    /// step in failures).
    pub fn check(&self, heard: &[(T, TimeVal)], after: usize, what: &str) {
        let (w, at) = (self.device.want)(&self.sim);
        check_run(heard, &w, &at, after, self.device.skip_first, self.t0, what);
    }

    /// Start-up: waits for a first report (printing the time from the server's start to it,
    /// as `kind`), then for `n` reports, and checks them all.
    pub fn start_up(&self, kind: &str, n: usize) {
        let unit = self.device.unit;
        self.client.wait_until(
            Duration::from_secs(10),
            &format!("a first {unit}"),
            &self.server,
            |_| self.count(0) >= 1,
        );
        let startup = self.heard(0)[0].1.seconds_since(self.t0.wall);
        eprintln!(
            "{kind}: vrpn_server start to first report {:.0} ms",
            startup * 1e3
        );
        self.client.wait_until(
            Duration::from_secs(10),
            &format!("{n} {unit}s"),
            &self.server,
            |_| self.count(0) >= n,
        );
        self.check(&self.heard(0), 0, self.device.what);
    }

    /// Garbage between records: waits until `junk` went out and `more` reports came after
    /// it, checks everything heard, and waits for the driver's "skipped" text.
    pub fn garbage(&self, junk: &[&[u8]], more: usize) {
        self.sim.inject_between_records(junk);
        self.client.wait_until(
            Duration::from_secs(10),
            "the garbage sent",
            &self.server,
            |_| self.sim.injected() == junk.len(),
        );
        let n = self.count(0);
        self.client.wait_until(
            Duration::from_secs(5),
            &format!("{}s after garbage", self.device.unit),
            &self.server,
            |_| self.count(0) >= n + more,
        );
        let what = format!("{} after garbage", self.device.what);
        self.check(&self.heard(0), 0, &what);
        self.client
            .wait_text(0, "skipped", Duration::from_secs(2), &self.server);
    }

    /// Unplugged: reported, nothing heard while unplugged, reopened when back; then `more`
    /// reports (within `back_within`), checked against the records logged since. `quiet`
    /// is called before unplugging and `speak` once the port is open again (a device that
    /// must make no events meanwhile mutes and unmutes its simulator there).
    pub fn unplug(
        &self,
        more: usize,
        back_within: Duration,
        quiet: impl FnOnce(&SimulatedDevice<M>),
        speak: impl FnOnce(&SimulatedDevice<M>),
    ) {
        let (from, before) = (self.client.len(), self.logged());
        quiet(&self.sim);
        self.sim.unplug();
        self.client
            .wait_text(from, "failed", Duration::from_secs(3), &self.server);
        let while_unplugged = self.count(from);
        self.client
            .pump_until(Duration::from_millis(500), |_| false);
        assert_eq!(self.count(from), while_unplugged, "reports while unplugged");
        self.sim.plug().unwrap();
        self.client
            .wait_text(from, "is open again", Duration::from_secs(3), &self.server);
        speak(&self.sim);
        self.client.wait_until(
            back_within,
            "reports after plugging back",
            &self.server,
            |_| self.count(from) >= while_unplugged + more,
        );
        let (w, _) = (self.device.want)(&self.sim);
        let after = first_from(&w, before);
        let what = format!("{} after unplugging", self.device.what);
        self.check(&self.heard(from)[while_unplugged..], after, &what);
    }
}
