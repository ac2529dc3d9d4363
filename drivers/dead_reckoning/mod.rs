//! `vrpn_Tracker_DeadReckoning_Rotation`: another tracker's poses with their orientation
//! predicted a fixed time ahead ([`predict`]), from the source's angular velocity reports or,
//! until it sends one, from its two latest poses.
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_DeadReckoning_Rotation NAME TRACKER SENSORS PREDICTION_SECONDS
//! ```
//!
//! `TRACKER` is `*NAME` (a device of this server) or `NAME@host`. See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! For every pose of the source (sensor below `SENSORS`): a `vrpn_Tracker Pos_Quat`
//! (LOW_LATENCY) from `NAME`, same sensor, stamped the pose's time plus the prediction time,
//! the pose's position and the predicted orientation. For every velocity of the source: the
//! prediction again (with the new rate), then the velocity itself, unchanged.

pub mod predict;

#[cfg(test)]
mod tests;

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::time::Instant;

use self::predict::Sensor;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, DeviceRef};
use crate::devices::text::TextSeverity;
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;
use crate::layered::TrackerSource;
use crate::time::{Now, TimeVal};
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_DeadReckoning_Rotation"],
    parse,
    hints: &[],
};

/// Most sensors one predictor may serve.
pub const MAX_SENSORS: u32 = 1024;

/// The `vrpn_Tracker_DeadReckoning_Rotation` line.
#[derive(Clone, Debug, PartialEq)]
pub struct DeadReckoning {
    /// Device name of the predicting tracker.
    pub name: String,
    /// The tracker predicted for.
    pub source: DeviceRef,
    /// Sensors predicted (`0..sensors`).
    pub sensors: u32,
    /// How far ahead, in seconds (read in single precision, as C++ reads it).
    pub prediction: f32,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(
        4,
        "name, tracker (*NAME or NAME@host), sensors, prediction time in seconds",
    )?;
    Ok(Box::new(DeadReckoning {
        name: line.name(0)?,
        source: line
            .device_ref(1, "tracker", false)?
            .ok_or_else(|| line.err(ConfigErrorKind::BadName, "the tracker cannot be NULL"))?,
        sensors: line.uint(2, "sensors", 1, MAX_SENSORS)?,
        prediction: line.non_negative(3, "prediction time")?,
    }))
}

impl DeviceSpec for DeadReckoning {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(DeadReckoningDevice::new(self, cx.conn())?)])
    }
}

struct State {
    tracker: TrackerServer,
    sensors: Vec<Sensor>,
    prediction: f64,
    /// Whether a report of a sensor beyond `SENSORS` has been answered with a warning
    /// (C++ sends one per report; once is enough to tell the configuration is short).
    warned: Cell<bool>,
}

impl State {
    fn sensor(&mut self, sensor: usize, what: &str) -> Option<&mut Sensor> {
        if sensor >= self.sensors.len() {
            if !self.warned.replace(true) {
                let text = format!(
                    "{what} of sensor {sensor} but only {} sensors are predicted; ignored",
                    self.sensors.len()
                );
                let _ = self.tracker.send_text(TextSeverity::Warning, 0, &text);
            }
            return None;
        }
        self.sensors.get_mut(sensor)
    }

    fn send_prediction(&self, sensor: usize) {
        if let Some(p) = self.sensors[sensor].predict(self.prediction) {
            let _ = self.tracker.report_pose(sensor, p.time, p.pos, p.quat);
        }
    }

    fn pose(&mut self, sensor: usize, time: TimeVal, pos: [f64; 3], quat: [f64; 4]) {
        if let Some(s) = self.sensor(sensor, "a pose") {
            s.pose(time, pos, quat);
            self.send_prediction(sensor);
        }
    }

    fn velocity(&mut self, sensor: usize, time: TimeVal, vel: [f64; 3], q: [f64; 4], dt: f64) {
        if let Some(s) = self.sensor(sensor, "a velocity") {
            s.velocity(q, dt);
            self.send_prediction(sensor);
            let _ = self.tracker.report_velocity(sensor, time, vel, q, dt);
        }
    }
}

/// The running predictor.
pub struct DeadReckoningDevice {
    name: String,
    source: TrackerSource,
    _state: Rc<RefCell<State>>,
}

impl DeadReckoningDevice {
    /// The predictor `cfg` describes, serving on `conn` (the server's connection).
    pub fn new(cfg: &DeadReckoning, conn: &Connection) -> Result<DeadReckoningDevice, Error> {
        let state = Rc::new(RefCell::new(State {
            tracker: TrackerServer::new(&cfg.name, conn, cfg.sensors as usize)?,
            sensors: vec![Sensor::default(); cfg.sensors as usize],
            prediction: cfg.prediction as f64,
            warned: Cell::new(false),
        }));
        let source = TrackerSource::open(&cfg.source, conn)?;
        let s = state.clone();
        source.remote.on_pose(move |p| {
            let q = p.quat.quaternion();
            // Reports of the source cannot arrive while this device reports (different
            // senders); a busy state is skipped rather than panicking.
            if let Ok(mut st) = s.try_borrow_mut() {
                st.pose(
                    p.sensor,
                    p.time,
                    [p.pos.x, p.pos.y, p.pos.z],
                    [q.i, q.j, q.k, q.w],
                );
            }
        });
        let s = state.clone();
        source.remote.on_velocity(move |v| {
            let q = v.vel_quat.quaternion();
            if let Ok(mut st) = s.try_borrow_mut() {
                st.velocity(
                    v.sensor,
                    v.time,
                    [v.vel.x, v.vel.y, v.vel.z],
                    [q.i, q.j, q.k, q.w],
                    v.vel_quat_dt,
                );
            }
        });
        Ok(DeadReckoningDevice {
            name: cfg.name.clone(),
            source,
            _state: state,
        })
    }
}

impl ServerDevice for DeadReckoningDevice {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, _now: Now) {
        self.source.poll();
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.source.next_deadline()
    }
}
