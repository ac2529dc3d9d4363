//! Device simulators and the rigs that test drivers against them (the `sim` feature; never
//! in the default library, the C library or the Python module).
//!
//! * [`DeviceModel`]: the device end of a line, what each driver's `sim.rs` implements.
//! * [`VirtualLine`] / [`VirtualLines`]: a driver and a model joined on a virtual clock, with
//!   faults on demand: a whole reset, watchdog and reopen in microseconds, repeatable from a
//!   seed. For a driver's unit tests (`drivers/NAME/tests.rs`).
//! * [`PtyDevice`]: a model on a real pseudo-terminal, which a driver opens like hardware;
//!   [`SimulatedDevice`] steps one in its own thread, with garbage between records, silence
//!   and unplugging on demand.
//! * [`Simulator`]: a simulator as the `vrpn_device_sim` program runs it (each driver's
//!   `sim.rs` exports one; the list is `crate::drivers::SIMULATORS`).
//! * [`FirstWrites`]: stamps a paced simulator's logged records with the step that hands
//!   their first byte to the line (for first-byte timing measurements).
//! * [`rig`]: a `vrpn_server` child process on a configuration line and a TCP client that
//!   records everything it receives, for the end-to-end tests every driver has (exact values
//!   through a real server to a real client, garbage, silence, unplugging).
//!
//! docs/DRIVERS.md ("Adding a driver") shows them together.

#[cfg(test)]
pub(crate) mod analog_rig;
mod catalog;
mod first_write;
mod line;
mod pty;
pub mod rig;
mod thread;

pub use catalog::Simulator;
pub use first_write::{FirstByteLogged, FirstWrites};
pub use line::{DeviceModel, Rng, VirtualLine, VirtualLines};
pub use pty::{PtyDevice, Written};
pub use thread::{Noisy, SimulatedDevice};
