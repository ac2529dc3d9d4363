//! An end-to-end rig for a device with an Analog_Output that moves something (the Zaber
//! positioners, the Nikon focus): its simulator on a pseudo-terminal, a `vrpn_server` child,
//! a TCP client of its Analog and an Analog_Output remote asking for moves, and the checks
//! against the simulator's log.
#![allow(dead_code)]

use std::time::{Duration, Instant};

use vrpn::devices::analog_output::AnalogOutputRemote;
use vrpn::driver::Interface;
use vrpn::sim::rig::{assert_first_byte_stamps, assert_run_of, Client, ServerProcess};
use vrpn::sim::{DeviceModel, SimulatedDevice};
use vrpn::{Now, TimeVal};

/// Values a client heard, with their report stamps.
pub type HeardValues<T> = (Vec<T>, Vec<TimeVal>);
/// Values a simulator sent, with the moments their first bytes left.
pub type SentValues<T> = (Vec<T>, Vec<Instant>);

/// What one device's rig reads and asks for.
pub struct Device<M: DeviceModel + 'static, T> {
    /// The device's name, in the checks' messages.
    pub what: &'static str,
    /// The values the client heard from its log index `from` on, with their stamps.
    pub reports: fn(&Client, usize) -> HeardValues<T>,
    /// The values the simulator sent, with the moments their first bytes left.
    pub sent: fn(&SimulatedDevice<M>) -> SentValues<T>,
    /// The channel and value of the `k`-th move.
    pub request: fn(i32) -> (i32, f64),
}

/// The rig. See the module documentation.
pub struct OutputRig<M: DeviceModel + 'static, T> {
    pub sim: SimulatedDevice<M>,
    pub server: ServerProcess,
    pub client: Client,
    pub out: AnalogOutputRemote,
    pub t0: Now,
    device: Device<M, T>,
    moves: i32,
}

impl<M: DeviceModel + 'static, T: PartialEq + std::fmt::Debug> OutputRig<M, T> {
    /// Starts `server_exe` serving `name` with `line` (the simulator's path in it is
    /// `{PATH}`), and connects the client and the output remote.
    pub fn start(
        sim: SimulatedDevice<M>,
        server_exe: &str,
        line: &str,
        name: &str,
        device: Device<M, T>,
    ) -> Self {
        let t0 = Now::read();
        let line = line.replace("{PATH}", &sim.path().display().to_string());
        let server = ServerProcess::start(server_exe.as_ref(), &line).unwrap();
        let client = Client::connect(name, server.port(), &[Interface::Analog]).unwrap();
        let out =
            AnalogOutputRemote::new(&format!("{name}@tcp://127.0.0.1:{}", server.port())).unwrap();
        OutputRig {
            sim,
            server,
            client,
            out,
            t0,
            device,
            moves: 0,
        }
    }

    /// The values heard from log index `from` on, with their stamps.
    pub fn reports(&self, from: usize) -> HeardValues<T> {
        (self.device.reports)(&self.client, from)
    }

    /// The values the simulator logged.
    pub fn sent(&self) -> SentValues<T> {
        (self.device.sent)(&self.sim)
    }

    /// Asks for `n` moves, each once the previous was reported.
    pub fn moves(&mut self, n: usize) {
        for _ in 0..n {
            let (channel, value) = (self.device.request)(self.moves);
            self.moves += 1;
            let heard = self.reports(0).0.len();
            self.out
                .request_change_channel_value(channel, value)
                .unwrap();
            let (out, reports) = (&self.out, self.device.reports);
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

    /// Reports from log index `from` on are a run of the values logged from `after` on,
    /// stamped with their first bytes.
    pub fn check(&self, from: usize, after: usize) {
        let (want, at) = self.sent();
        let (got, stamps) = self.reports(from);
        let runs = assert_run_of(&got, &want, after, self.device.what);
        assert_first_byte_stamps(
            &stamps,
            &at[runs[0]..],
            self.t0,
            Duration::from_millis(250),
            self.device.what,
        );
    }

    /// Silences the device until the driver says `alarm` (within `within`), lets it speak
    /// again, waits for the reset on the open port (no reopening), then asks for `n` moves
    /// and checks them.
    pub fn silence_and_move(&mut self, alarm: &str, within: Duration, n: usize) {
        let (from, logged) = (self.client.len(), self.sent().0.len());
        self.sim.set_mute(true);
        self.client.wait_text(from, alarm, within, &self.server);
        self.sim.set_mute(false);
        self.client
            .wait_text(from, "reset complete", Duration::from_secs(6), &self.server);
        let after_reset = self.client.len();
        self.moves(n);
        self.check(after_reset, logged);
        assert!(!self
            .client
            .texts_from(from)
            .iter()
            .any(|t| t.contains("is open again")));
    }

    /// Unplugs the device, waits for the failure and for the port to be open again with the
    /// device reset, then asks for `n` moves and checks them.
    pub fn unplug_and_move(&mut self, n: usize) {
        let (from, logged) = (self.client.len(), self.sent().0.len());
        self.sim.unplug();
        self.client
            .wait_text(from, "failed", Duration::from_secs(3), &self.server);
        self.sim.plug().unwrap();
        self.client
            .wait_text(from, "is open again", Duration::from_secs(6), &self.server);
        self.client
            .wait_text(from, "reset complete", Duration::from_secs(6), &self.server);
        let after_reset = self.client.len();
        self.moves(n);
        self.check(after_reset, logged);
    }
}
