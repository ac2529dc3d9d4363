//! `vrpn_IMU_SimpleCombiner`: an orientation tracker from an inertial unit's analog channels.
//! At every pass of the server loop it turns its orientation by the gyroscope's rotational
//! velocity over the wall time since the previous pass, then pulls it towards "the
//! accelerometer points down" (and, with a magnetometer, "north points along -Z"), the more the
//! closer the acceleration's length is to gravity ([`model::Combiner`]).
//!
//! # Configuration (four lines)
//!
//! ```text
//! vrpn_IMU_SimpleCombiner NAME UPDATE_RATE
//! ACCEL_DEVICE X_CHANNEL X_OFFSET X_SCALE Y_CHANNEL Y_OFFSET Y_SCALE Z_CHANNEL Z_OFFSET Z_SCALE
//! GYRO_DEVICE  X_CHANNEL X_OFFSET X_SCALE Y_CHANNEL Y_OFFSET Y_SCALE Z_CHANNEL Z_OFFSET Z_SCALE
//! MAGNETOMETER_DEVICE
//! ```
//!
//! Devices are `*NAME` (an analog of this server) or `NAME@host`; the magnetometer line may be
//! `NULL` (no north correction), else channels 0-2 of that device are the north vector (a
//! `vrpn_IMU_Magnetometer`, say). See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! When `1/UPDATE_RATE` seconds (single precision; 1 s for 0) have passed since the previous
//! report, at the end of a pass: a `vrpn_Tracker Pos_Quat` of sensor 0 (position 0) and a
//! `vrpn_Tracker Velocity` (velocity 0, the rotation over 0.01 s), both stamped with the
//! pass's time.

pub mod model;
#[cfg(test)]
mod tests;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use self::model::{Combiner, VELOCITY_DT};
use crate::config::{ConfigError, ConfigLine, DeviceRef};
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;
use crate::layered::imu::{axis_line, device_line, AxisParams};
use crate::layered::{interval, update_interval, AnalogSource};
use crate::time::{checked_duration, Now, TimeVal, MAX_PERIOD};
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_IMU_SimpleCombiner"],
    parse,
    hints: &[],
};

/// The shortest time between two passes this device asks the server loop for: C++'s server
/// sleeps 1 ms between passes by default, so a rate above 1000 reports once a pass there too.
pub const MIN_PASS_INTERVAL: Duration = Duration::from_millis(1);

/// The `vrpn_IMU_SimpleCombiner` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct SimpleCombiner {
    /// Device name of the tracker.
    pub name: String,
    /// Reports per second (0: one a second), single precision as C++ reads it.
    pub update_rate: f32,
    /// The accelerometer's axes (m/s²).
    pub accel: AxisParams,
    /// The gyroscope's axes (rad/s).
    pub rotation: AxisParams,
    /// The magnetometer (its channels 0-2), if any.
    pub magnetometer: Option<DeviceRef>,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(
        2,
        "name, update rate; then the accelerometer, rotation and magnetometer lines",
    )?;
    let name = line.name(0)?;
    let update_rate = line.non_negative(1, "update rate")?;
    let accel = axis_line(line, "accelerometer")?;
    let rotation = axis_line(line, "rotation")?;
    let magnetometer = device_line(line, "magnetometer")?;
    Ok(Box::new(SimpleCombiner {
        name,
        update_rate,
        accel,
        rotation,
        magnetometer,
    }))
}

impl DeviceSpec for SimpleCombiner {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(CombinerDevice::new(self, cx.conn())?)])
    }
}

/// Times of the loop the combiner keeps.
#[derive(Clone, Copy, Debug)]
struct Passes {
    /// Wall time of the previous pass (the integration's start).
    update: TimeVal,
    /// Wall time of the previous report.
    report: TimeVal,
    /// Monotonic times of the previous report and pass, for the next deadline.
    report_mono: Instant,
    pass_mono: Instant,
}

/// The running combiner.
pub struct CombinerDevice {
    name: String,
    tracker: TrackerServer,
    /// The accelerometer, gyroscope and magnetometer sources (in that order, those present).
    sources: Vec<AnalogSource>,
    state: Rc<RefCell<Combiner>>,
    update_interval: f64,
    period: Duration,
    passes: Option<Passes>,
}

/// Where an analog input of the combiner goes.
#[derive(Clone, Copy)]
enum Input {
    Accel,
    Rotation,
    North,
}

impl CombinerDevice {
    /// The combiner `cfg` describes, serving on `conn` (the server's connection).
    pub fn new(cfg: &SimpleCombiner, conn: &Connection) -> Result<CombinerDevice, Error> {
        let state = Rc::new(RefCell::new(Combiner::new(cfg.magnetometer.is_some())));
        let north = cfg.magnetometer.as_ref().map(|m| AxisParams {
            source: m.clone(),
            channels: [0, 1, 2],
            offsets: [0.0; 3],
            scales: [1.0; 3],
        });
        let inputs = [
            Some((&cfg.accel, Input::Accel)),
            Some((&cfg.rotation, Input::Rotation)),
            north.as_ref().map(|n| (n, Input::North)),
        ];
        let mut sources: Vec<AnalogSource> = Vec::with_capacity(3);
        let mut opened: Vec<&DeviceRef> = Vec::with_capacity(3);
        for (params, input) in inputs.into_iter().flatten() {
            let source = match opened.iter().position(|r| **r == params.source) {
                Some(i) => sources[i].alongside(&params.source)?,
                None => AnalogSource::open(&params.source, conn)?,
            };
            let s = state.clone();
            let axes = params.clone();
            source.remote.on_report(move |r| {
                // Reports of the sources cannot arrive while this device reports (other
                // senders); a busy state is skipped rather than panicking.
                if let Ok(mut st) = s.try_borrow_mut() {
                    let v = axes.vector(r.channels());
                    match input {
                        Input::Accel => st.accel = v,
                        Input::Rotation => st.rotation = v,
                        Input::North => st.north = Some(v),
                    }
                }
            });
            opened.push(&params.source);
            sources.push(source);
        }
        let update_interval = update_interval(cfg.update_rate);
        Ok(CombinerDevice {
            name: cfg.name.clone(),
            tracker: TrackerServer::new(&cfg.name, conn, 1)?,
            sources,
            state,
            update_interval,
            // A rate too small for a schedule (the parser's `non_negative` allows it) never reports.
            period: checked_duration(update_interval).unwrap_or(MAX_PERIOD),
            passes: None,
        })
    }
}

impl ServerDevice for CombinerDevice {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        for s in &self.sources {
            s.poll();
        }
        let Some(p) = self.passes.as_mut() else {
            // C++ starts its clocks when it is built; here the first pass starts them.
            self.passes = Some(Passes {
                update: now.wall,
                report: now.wall,
                report_mono: now.mono,
                pass_mono: now.mono,
            });
            return;
        };
        // A pass in the same microsecond as the previous one (the loop spins after traffic)
        // has no time to integrate over: C++ would turn the orientation by a rotation that is
        // the identity but for rounding; this one leaves it.
        let dt = interval(now.wall, p.update);
        if dt == 0.0 {
            return;
        }
        let Ok(mut st) = self.state.try_borrow_mut() else {
            return;
        };
        st.step(dt);
        p.update = now.wall;
        p.pass_mono = now.mono;
        if interval(now.wall, p.report) >= self.update_interval {
            let _ = self.tracker.report_pose(0, now.wall, [0.0; 3], st.quat);
            let _ = self
                .tracker
                .report_velocity(0, now.wall, [0.0; 3], st.vel_quat, VELOCITY_DT);
            p.report = now.wall;
            p.report_mono = now.mono;
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let own = self
            .passes
            .map(|p| (p.report_mono + self.period).max(p.pass_mono + MIN_PASS_INTERVAL));
        self.sources
            .iter()
            .filter_map(|s| s.next_deadline())
            .chain(own)
            .min()
    }
}
