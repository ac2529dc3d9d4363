//! Device types: each has a server half (reports) and a remote half (callbacks), built on the
//! shared [`base`] behaviour.

use std::time::{Duration, Instant};

use crate::time::{period_of_rate, Now};

pub mod analog;
pub mod analog_output;
pub mod aux_logger;
pub mod base;
pub mod builder;
pub mod button;
pub mod dial;
pub mod examples;
pub mod force;
pub mod function_generator;
pub mod imager;
pub mod latest;
pub mod mutex;
pub mod peer_mutex;
pub mod poser;
pub mod redundant;
pub mod shared_object;
pub mod sound;
pub mod text;
pub mod text_device;
pub mod tracker;

pub use builder::{Remote, RemoteBuilder};
pub use latest::Index;

builder::remote_builder!(
    tracker::TrackerRemote,
    button::ButtonRemote,
    analog::AnalogRemote,
    dial::DialRemote,
    analog_output::AnalogOutputRemote,
    poser::PoserRemote,
    force::ForceDeviceRemote,
    text_device::TextReceiver,
    imager::ImagerRemote,
    imager::ImagerPoseRemote,
    aux_logger::AuxLoggerRemote,
    function_generator::FunctionGeneratorRemote,
    sound::SoundClient,
);

/// A device a server runs: polled from the server loop, which sleeps until the earliest
/// deadline any device asks for (or until a socket is ready).
pub trait ServerDevice {
    /// The device's name (its sender).
    fn name(&self) -> &str;
    /// Does the device's periodic work (read hardware, send reports). `now` is the loop
    /// pass's reading of the clock: devices stamp reports with `now.wall` and schedule with
    /// `now.mono`, never reading a clock themselves.
    fn mainloop(&mut self, now: Now);
    /// When the device next needs [`mainloop`](Self::mainloop), if it has a schedule.
    fn next_deadline(&self) -> Option<Instant>;
}

/// A fixed-rate schedule: due at the first pass, then every period. After a stall it restarts
/// from the current time instead of bursting to catch up.
#[derive(Clone, Copy, Debug)]
pub struct Cadence {
    period: Option<Duration>,
    next: Option<Instant>,
}

impl Cadence {
    /// `rate` times a second; never for a rate that is not finite or below one per
    /// [`MAX_PERIOD`](crate::time::MAX_PERIOD) (see [`period_of_rate`]).
    pub fn per_second(rate: f64) -> Cadence {
        Cadence {
            period: period_of_rate(rate),
            next: None,
        }
    }

    /// Every `period`; never for `None`.
    pub fn every(period: Option<Duration>) -> Cadence {
        Cadence { period, next: None }
    }

    /// Whether a tick is due at `now`; if so, schedules the next one.
    pub fn due(&mut self, now: Instant) -> bool {
        let Some(period) = self.period else {
            return false;
        };
        match self.next {
            Some(next) if now < next => false,
            Some(next) => {
                let after = next + period;
                self.next = Some(if after <= now { now + period } else { after });
                true
            }
            None => {
                self.next = Some(now + period);
                true
            }
        }
    }

    /// When the next tick is due (`None`: never, or not started — a first pass starts it).
    pub fn deadline(&self) -> Option<Instant> {
        self.period.and(self.next)
    }

    /// True before the first tick.
    pub fn is_first(&self) -> bool {
        self.next.is_none()
    }
}
