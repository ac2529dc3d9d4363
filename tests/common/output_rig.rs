//! An end-to-end rig for a device that something asks to move (the Zaber positioners, the
//! Nikon focus and the IDEA drive through an Analog_Output, the Tek4662 plotter's pen through
//! a Poser): its simulator on a pseudo-terminal, a `vrpn_server` child, a TCP client of what
//! it reports and the remote that asks for moves, and the checks against the simulator's log.
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
    /// The channel and value of the `k`-th move (for an Analog_Output; unused otherwise).
    pub request: fn(i32) -> (i32, f64),
}

/// The rig. See the module documentation. `O` is the remote that asks for moves.
pub struct OutputRig<M: DeviceModel + 'static, T, O = AnalogOutputRemote> {
    pub sim: SimulatedDevice<M>,
    pub server: ServerProcess,
    pub client: Client,
    pub out: O,
    pub t0: Now,
    device: Device<M, T>,
    /// How many moves were asked for so far.
    pub moves: i32,
}

impl<M: DeviceModel + 'static, T: PartialEq + std::fmt::Debug> OutputRig<M, T> {
    /// Starts `server_exe` serving `name` with `line` (the simulator's path in it is
    /// `{PATH}`), and connects the client (to the Analog) and the Analog_Output remote.
    pub fn start(
        sim: SimulatedDevice<M>,
        server_exe: &str,
        line: &str,
        name: &str,
        device: Device<M, T>,
    ) -> Self {
        Self::start_with(
            sim,
            server_exe,
            line,
            name,
            &[Interface::Analog],
            device,
            |at| AnalogOutputRemote::new(at).unwrap(),
        )
    }

    /// Asks for `n` moves, each once the previous was reported.
    pub fn moves(&mut self, n: usize) {
        self.ask(n, "a move reported", |got, heard, _| got.len() > heard);
    }

    /// Asks for `n` moves, each once the last value reported has `reached(value, target)`.
    pub fn moves_to(&mut self, n: usize, reached: fn(&T, f64) -> bool) {
        self.ask(n, "a move made", |got, _, to| {
            got.last().is_some_and(|v| reached(v, to))
        });
    }

    /// Asks for `n` moves, each once `done(values heard, how many were heard before, target)`.
    fn ask(&mut self, n: usize, what: &str, done: impl Fn(&[T], usize, f64) -> bool) {
        for _ in 0..n {
            let (channel, value) = (self.device.request)(self.moves);
            self.moves += 1;
            let heard = self.reports(0).0.len();
            self.out
                .request_change_channel_value(channel, value)
                .unwrap();
            let (out, reports) = (&self.out, self.device.reports);
            self.client
                .wait_until(Duration::from_secs(5), what, &self.server, |c| {
                    let _ = out.mainloop();
                    done(&reports(c, 0).0, heard, value)
                });
        }
    }

    /// [`Self::silence_then`] with `n` moves after the reset ("reset complete").
    pub fn silence_and_move(&mut self, alarm: &str, within: Duration, n: usize) {
        self.silence_then(
            alarm,
            within,
            "reset complete",
            Duration::from_secs(6),
            |r| r.moves(n),
        );
    }

    /// [`Self::unplug_then`] with `n` moves after the reset ("reset complete").
    pub fn unplug_and_move(&mut self, n: usize) {
        self.unplug_then("reset complete", |r| r.moves(n));
    }
}

impl<M: DeviceModel + 'static, T: PartialEq + std::fmt::Debug, O> OutputRig<M, T, O> {
    /// Starts `server_exe` serving `name` with `line` (the simulator's path in it is
    /// `{PATH}`), connects the client to `interfaces` and opens the remote that asks for
    /// moves with `open("name@tcp://127.0.0.1:PORT")`.
    pub fn start_with(
        sim: SimulatedDevice<M>,
        server_exe: &str,
        line: &str,
        name: &str,
        interfaces: &[Interface],
        device: Device<M, T>,
        open: impl FnOnce(&str) -> O,
    ) -> Self {
        let t0 = Now::read();
        let line = line.replace("{PATH}", &sim.path().display().to_string());
        let server = ServerProcess::start(server_exe.as_ref(), &line).unwrap();
        let client = Client::connect(name, server.port(), interfaces).unwrap();
        let out = open(&format!("{name}@tcp://127.0.0.1:{}", server.port()));
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

    /// Puts `junk` between the device's records and waits (`within`) until it all went out.
    pub fn inject_garbage(&self, junk: &[&[u8]], within: Duration) {
        self.sim.inject_between_records(junk);
        self.client
            .wait_until(within, "the garbage sent", &self.server, |_| {
                self.sim.injected() == junk.len()
            });
    }

    /// Silences the device until the driver says `alarm` (within `within`), lets it speak
    /// again, waits for the reset on the open port (`reset_done`, within `reset_within`; no
    /// reopening), then runs `then` (moves) and checks what was reported since.
    pub fn silence_then(
        &mut self,
        alarm: &str,
        within: Duration,
        reset_done: &str,
        reset_within: Duration,
        then: impl FnOnce(&mut Self),
    ) {
        let (from, logged) = (self.client.len(), self.sent().0.len());
        self.sim.set_mute(true);
        self.client.wait_text(from, alarm, within, &self.server);
        self.sim.set_mute(false);
        self.client
            .wait_text(from, reset_done, reset_within, &self.server);
        let after_reset = self.client.len();
        then(self);
        self.check(after_reset, logged);
        assert!(!self
            .client
            .texts_from(from)
            .iter()
            .any(|t| t.contains("is open again")));
    }

    /// Unplugs the device, waits for the failure and for the port to be open again with the
    /// device reset (`reset_done`), then runs `then` (moves) and checks what was reported
    /// since.
    pub fn unplug_then(&mut self, reset_done: &str, then: impl FnOnce(&mut Self)) {
        let (from, logged) = (self.client.len(), self.sent().0.len());
        self.sim.unplug();
        self.client
            .wait_text(from, "failed", Duration::from_secs(3), &self.server);
        self.sim.plug().unwrap();
        self.client
            .wait_text(from, "is open again", Duration::from_secs(6), &self.server);
        self.client
            .wait_text(from, reset_done, Duration::from_secs(6), &self.server);
        let after_reset = self.client.len();
        then(self);
        self.check(after_reset, logged);
    }
}
