//! Device types: each has a server half (reports) and a remote half (callbacks), built on the
//! shared [`base`] behaviour.

use std::time::Instant;

pub mod analog;
pub mod analog_output;
pub mod base;
pub mod button;
pub mod dial;
pub mod force;
pub mod poser;
pub mod text;
pub mod text_device;
pub mod tracker;

/// A device a server runs: polled from the server loop, which sleeps until the earliest
/// deadline any device asks for (or until a socket is ready).
pub trait ServerDevice {
    /// The device's name (its sender).
    fn name(&self) -> &str;
    /// Does the device's periodic work (read hardware, send reports).
    fn mainloop(&mut self, now: Instant);
    /// When the device next needs [`mainloop`](Self::mainloop), if it has a schedule.
    fn next_deadline(&self) -> Option<Instant>;
}
