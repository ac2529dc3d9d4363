//! The end-to-end checks every streaming serial tracker gets, on its simulator (a
//! pseudo-terminal), a `vrpn_server` child and a TCP client: exact values in order with
//! first-byte stamps, garbage between records, silence with the watchdog's reset, unplugging
//! and reopening. Each driver's test supplies the simulator, the vrpn.cfg line and a function
//! that reads what the simulator logged as (values a client must see, first-byte times).
#![allow(dead_code)]

use std::fmt::Debug;
use std::time::{Duration, Instant};

use vrpn::driver::Interface;
use vrpn::sim::rig::{
    assert_first_byte_stamps, assert_run_of, resume_after, Client, Heard, ServerProcess,
};
use vrpn::sim::{DeviceModel, SimulatedDevice};
use vrpn::{Now, TrackerPose};

/// What a client must see of one pose: sensor, position, quaternion (x, y, z, w).
pub type Values = (usize, [f64; 3], [f64; 4]);

/// The values of a pose as a client received it.
pub fn values(p: &TrackerPose) -> Values {
    let q = p.quat.into_inner();
    (p.sensor, [p.pos.x, p.pos.y, p.pos.z], [q.i, q.j, q.k, q.w])
}

/// What the simulator logged: the values a client must see, and each record's first-byte
/// time.
pub type SentLog<M, V> = dyn Fn(&SimulatedDevice<M>) -> (Vec<V>, Vec<Instant>);

/// A tracker under test: the simulator, the server, the client, and how to read the log.
pub struct Rig<'a, M: DeviceModel + 'static, V> {
    pub sim: &'a SimulatedDevice<M>,
    pub server: &'a ServerProcess,
    pub client: &'a Client,
    pub t0: Now,
    pub what: &'a str,
    /// What the simulator logged.
    pub sent: &'a SentLog<M, V>,
    /// The values of a pose the client heard.
    pub seen: &'a dyn Fn(&TrackerPose) -> V,
}

impl<M: DeviceModel + 'static, V: PartialEq + Debug> Rig<'_, M, V> {
    /// Checks the poses heard from log index `from` against the records logged from `after`.
    pub fn check(&self, from: usize, after: usize) {
        let (want, at) = (self.sent)(self.sim);
        let poses = self.client.poses_from(from);
        let got: Vec<V> = poses.iter().map(self.seen).collect();
        let runs = assert_run_of(&got, &want, after, self.what);
        let stamps: Vec<_> = poses.iter().map(|p| p.time).collect();
        assert_first_byte_stamps(
            &stamps,
            &at[runs[0]..],
            self.t0,
            Duration::from_millis(250),
            self.what,
        );
    }

    /// Where in the log the records still to come start: after the last ones the client
    /// heard (a polled device always has one in flight; a starved server, many).
    fn logged_before(&self) -> usize {
        let want = (self.sent)(self.sim).0;
        let heard: Vec<V> = self.client.poses().iter().map(self.seen).collect();
        resume_after(&heard, &want, want.len())
    }

    fn poses(&self) -> usize {
        self.client.poses().len()
    }

    /// Start-up (from `t0` to the first pose's stamp, printed), then `n` poses checked.
    pub fn start(&self, n: usize, limit: f64) -> f64 {
        self.client
            .wait_until(Duration::from_secs(15), "a first pose", self.server, |c| {
                !c.poses().is_empty()
            });
        let startup = self.client.poses()[0].time.seconds_since(self.t0.wall);
        eprintln!(
            "{}: vrpn_server start to first report {:.0} ms",
            self.what,
            startup * 1e3
        );
        assert!(startup < limit, "{}: start-up {startup} s", self.what);
        self.client
            .wait_until(Duration::from_secs(10), "poses", self.server, |c| {
                c.poses().len() >= n
            });
        self.check(0, 0);
        startup
    }

    /// Garbage between records: reported, nothing lost.
    pub fn garbage(&self, junk: &[&[u8]], n: usize) {
        self.sim.inject_between_records(junk);
        self.client.wait_until(
            Duration::from_secs(5),
            "the garbage sent",
            self.server,
            |_| self.sim.injected() == junk.len(),
        );
        let have = self.poses();
        self.client.wait_until(
            Duration::from_secs(5),
            "poses after garbage",
            self.server,
            |c| c.poses().len() >= have + n,
        );
        self.check(0, 0);
        self.client
            .wait_text(0, "skipped", Duration::from_secs(2), self.server);
    }

    /// Silence: the watchdog's texts, then records again, nothing invented meanwhile.
    pub fn silence(&self, text: &str, n: usize, back_within: Duration) {
        let (from, logged) = (self.client.len(), self.logged_before());
        self.sim.set_mute(true);
        self.client
            .wait_text(from, text, Duration::from_secs(6), self.server);
        self.sim.set_mute(false);
        self.client
            .wait_until(back_within, "poses after silence", self.server, |c| {
                c.poses_from(from).len() >= n
            });
        self.check(from, logged);
    }

    /// Unplugged: reported, nothing while away, reopened under the same path, resumed.
    pub fn unplug(&self, n: usize, back_within: Duration) {
        let (from, logged) = (self.client.len(), self.logged_before());
        self.sim.unplug();
        self.client
            .wait_text(from, "failed", Duration::from_secs(3), self.server);
        let while_unplugged = self.client.poses_from(from).len();
        self.client
            .pump_until(Duration::from_millis(300), |_| false);
        assert_eq!(
            self.client.poses_from(from).len(),
            while_unplugged,
            "{}: poses while unplugged",
            self.what
        );
        self.sim.plug().unwrap();
        self.client
            .wait_until(back_within, "poses after plugging back", self.server, |c| {
                c.poses_from(from).len() >= while_unplugged + n
            });
        self.client
            .wait_text(from, "is open again", Duration::from_secs(1), self.server);
        self.check(from, logged);
    }
}

/// Starts `server_exe` on the vrpn.cfg `line` (`{PATH}` in it stands for the simulator's
/// path) and connects a client of `name`'s tracker; returns the moment before the start too.
pub fn serve<M: DeviceModel + 'static>(
    server_exe: &str,
    sim: &SimulatedDevice<M>,
    line: &str,
    name: &str,
) -> (Now, ServerProcess, Client) {
    let t0 = Now::read();
    let line = line.replace("{PATH}", &sim.path().display().to_string());
    let server = ServerProcess::start(server_exe.as_ref(), &line).unwrap();
    let client = tracker_client(name, &server);
    (t0, server, client)
}

/// Lets a client of a stylus (a Button) listen 300 ms more, then checks what it heard: at
/// least three changes, all of button 0, pressed and released in turn.
pub fn assert_stylus_toggles(pen: &Client) {
    pen.pump_until(Duration::from_millis(300), |_| false);
    let changes: Vec<(usize, bool)> = pen
        .reports_from(0)
        .iter()
        .filter_map(|h| match h {
            Heard::Button {
                button, pressed, ..
            } => Some((*button, *pressed)),
            _ => None,
        })
        .collect();
    assert!(changes.len() >= 3, "{changes:?}");
    assert!(changes.iter().all(|c| c.0 == 0), "{changes:?}");
    assert!(changes.windows(2).all(|w| w[0].1 != w[1].1), "{changes:?}");
}

/// A client of `name`'s tracker (and texts) on `server`.
pub fn tracker_client(name: &str, server: &ServerProcess) -> Client {
    Client::connect(name, server.port(), &[Interface::Tracker]).unwrap()
}
