//! `vrpn_IMU_Magnetometer`: three analog channels of a magnetometer turned into a unit
//! vector towards magnetic north that calibrates itself: each axis is mapped into -1..1 by
//! the smallest and largest value it has had ([`Calibration`]), and the vector normalised.
//!
//! # Configuration (two lines)
//!
//! ```text
//! vrpn_IMU_Magnetometer NAME UPDATE_RATE
//! DEVICE X_CHANNEL X_OFFSET X_SCALE Y_CHANNEL Y_OFFSET Y_SCALE Z_CHANNEL Z_OFFSET Z_SCALE
//! ```
//!
//! `DEVICE` is `*NAME` (an analog of this server) or `NAME@host`. See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! `UPDATE_RATE` times a second (once a second for 0): a `vrpn_Analog Channel` report of 3
//! channels from `NAME`, the unit vector, stamped with the time it is sent (C++ sets the input's
//! time stamp, then its report call replaces it with the current time).

#[cfg(test)]
mod tests;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

use crate::config::{ConfigError, ConfigLine};
use crate::devices::analog::AnalogServer;
use crate::devices::{Cadence, ServerDevice};
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;
use crate::layered::imu::{axis_line, AxisParams, ImuVector};
use crate::layered::{update_interval, AnalogSource};
use crate::time::{checked_duration, Now, TimeVal, MAX_PERIOD};
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_IMU_Magnetometer"],
    parse,
    hints: &[],
};

/// The `vrpn_IMU_Magnetometer` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Magnetometer {
    /// Device name of the unit vector (an Analog of 3 channels).
    pub name: String,
    /// Reports per second (0: one a second), single precision as C++ reads it.
    pub update_rate: f32,
    /// The magnetometer's axes.
    pub axes: AxisParams,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, update rate; then the axis line on the next line")?;
    let name = line.name(0)?;
    let update_rate = line.non_negative(1, "update rate")?;
    let axes = axis_line(line, "magnetometer")?;
    Ok(Box::new(Magnetometer {
        name,
        update_rate,
        axes,
    }))
}

impl DeviceSpec for Magnetometer {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Analog])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(MagnetometerDevice::new(self, cx.conn())?)])
    }
}

/// The self-calibrating normalisation, as C++ VRPN 07.38 computes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// The latest vector.
    pub vector: ImuVector,
    /// Smallest value of each axis so far.
    pub mins: [f64; 3],
    /// Largest value of each axis so far.
    pub maxes: [f64; 3],
}

impl Default for Calibration {
    /// The zero vector counts as seen: C++ takes its extremes at every pass of its loop,
    /// the passes before the first report included.
    fn default() -> Self {
        Calibration {
            vector: ImuVector::default(),
            mins: [0.0; 3],
            maxes: [0.0; 3],
        }
    }
}

impl Calibration {
    /// A new vector from the magnetometer.
    pub fn input(&mut self, values: [f64; 3], time: TimeVal) {
        self.vector = ImuVector { values, time };
        for (i, v) in values.iter().enumerate() {
            if *v < self.mins[i] {
                self.mins[i] = *v;
            }
            if *v > self.maxes[i] {
                self.maxes[i] = *v;
            }
        }
    }

    /// The unit vector: each axis mapped into -1..1 by its extremes (0 at its minimum), the
    /// whole normalised; (1, 0, 0) when all are 0.
    pub fn unit(&self) -> [f64; 3] {
        let mut c = [0.0; 3];
        for (i, out) in c.iter_mut().enumerate() {
            let diff = self.vector.values[i] - self.mins[i];
            *out = if diff == 0.0 {
                0.0
            } else {
                -1.0 + 2.0 * diff / (self.maxes[i] - self.mins[i])
            };
        }
        let len = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        if len == 0.0 {
            [1.0, 0.0, 0.0]
        } else {
            [c[0] / len, c[1] / len, c[2] / len]
        }
    }
}

/// The running magnetometer.
pub struct MagnetometerDevice {
    name: String,
    analog: AnalogServer,
    source: AnalogSource,
    cadence: Cadence,
    state: Rc<RefCell<Calibration>>,
}

impl MagnetometerDevice {
    /// The magnetometer `cfg` describes, serving on `conn` (the server's connection).
    pub fn new(cfg: &Magnetometer, conn: &Connection) -> Result<MagnetometerDevice, Error> {
        let state = Rc::new(RefCell::new(Calibration::default()));
        let source = AnalogSource::open(&cfg.axes.source, conn)?;
        let s = state.clone();
        let axes = cfg.axes.clone();
        source.remote.on_report(move |r| {
            if let Ok(mut st) = s.try_borrow_mut() {
                st.input(axes.vector(r.channels()), r.time);
            }
        });
        let period = checked_duration(update_interval(cfg.update_rate)).unwrap_or(MAX_PERIOD);
        Ok(MagnetometerDevice {
            name: cfg.name.clone(),
            analog: AnalogServer::new(&cfg.name, conn, 3)?,
            source,
            cadence: Cadence::every(Some(period)),
            state,
        })
    }
}

impl ServerDevice for MagnetometerDevice {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        self.source.poll();
        let Ok(st) = self.state.try_borrow_mut() else {
            return;
        };
        if !self.cadence.due(now.mono) {
            return;
        }
        let unit = st.unit();
        drop(st);
        self.analog.channels_mut().copy_from_slice(&unit);
        let _ = self.analog.report(Some(now.wall));
    }

    fn next_deadline(&self) -> Option<Instant> {
        match (self.cadence.deadline(), self.source.next_deadline()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}
