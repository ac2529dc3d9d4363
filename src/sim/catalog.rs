//! What `vrpn_device_sim` knows of each simulator: its name, the `vrpn.cfg` line that serves
//! it, and how to build it. Each driver's `sim.rs` exports one [`Simulator`]; the list is
//! `crate::drivers::SIMULATORS`.

use std::fmt;

use super::DeviceModel;

/// A device simulator that can run on its own on a pseudo-terminal.
pub struct Simulator {
    /// The name it is chosen by: the driver's folder name.
    pub name: &'static str,
    /// One line about the simulated device and what it sends.
    pub about: &'static str,
    /// The baud rate used when none is given (the rate `vrpn.cfg.sample` uses); 0 for a
    /// device that is not a serial line.
    pub baud: u32,
    /// The `vrpn.cfg` line that serves it, with `{PATH}` and `{BAUD}` to fill in.
    pub line: &'static str,
    /// Builds the simulated device for `baud`.
    pub make: fn(baud: u32) -> Box<dyn DeviceModel>,
}

impl Simulator {
    /// The `vrpn.cfg` line that serves this simulator on `path` at `baud`.
    pub fn config_line(&self, path: &str, baud: u32) -> String {
        self.line
            .replace("{PATH}", path)
            .replace("{BAUD}", &baud.to_string())
    }
}

impl fmt::Debug for Simulator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Simulator")
            .field("name", &self.name)
            .field("baud", &self.baud)
            .finish_non_exhaustive()
    }
}

impl<M: DeviceModel + ?Sized> DeviceModel for Box<M> {
    fn receive(&mut self, bytes: &[u8], now: crate::Now) {
        (**self).receive(bytes, now);
    }
    fn set_rts(&mut self, on: bool, now: crate::Now) {
        (**self).set_rts(on, now);
    }
    fn set_dtr(&mut self, on: bool, now: crate::Now) {
        (**self).set_dtr(on, now);
    }
    fn transmit(&mut self, now: crate::Now, out: &mut Vec<u8>) {
        (**self).transmit(now, out);
    }
    fn next_deadline(&self) -> Option<std::time::Instant> {
        (**self).next_deadline()
    }
}
