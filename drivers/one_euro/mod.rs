//! `vrpn_Tracker_FilterOneEuro`: another tracker's poses smoothed by the 1€ filter
//! ([`filter`]), sensor by sensor, and served under a name of its own.
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_FilterOneEuro NAME TRACKER SENSORS POS_MIN_CUTOFF POS_BETA POS_DCUTOFF QUAT_MIN_CUTOFF QUAT_BETA QUAT_DCUTOFF
//! ```
//!
//! `TRACKER` is `*NAME` (a device of this server) or `NAME@host`. Sensors `0..SENSORS` are
//! filtered; others are ignored. See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! For every pose of the source tracker (sensor below `SENSORS`), at once: a
//! `vrpn_Tracker Pos_Quat` (LOW_LATENCY) from `NAME` with the same sensor and time stamp, the
//! filtered position and the filtered orientation normalised, computed as C++ VRPN 07.38
//! does (the interval is the time since the sensor's previous report, 1 s when not positive;
//! the first report of a sensor counts from time 0, as C++'s zeroed times do).

pub mod filter;

#[cfg(test)]
mod tests;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

use self::filter::{quat_normalize, OrientationFilter, Params, PositionFilter};
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, DeviceRef};
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;
use crate::layered::{interval, TrackerSource};
use crate::time::{Now, TimeVal};
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_FilterOneEuro"],
    parse,
    hints: &[],
};

/// Most sensors a filter may serve.
pub const MAX_SENSORS: u32 = 1024;

/// The `vrpn_Tracker_FilterOneEuro` line.
#[derive(Clone, Debug, PartialEq)]
pub struct FilterOneEuro {
    /// Device name of the filtered tracker.
    pub name: String,
    /// The tracker read.
    pub source: DeviceRef,
    /// Sensors filtered (`0..sensors`).
    pub sensors: u32,
    /// Position filter parameters.
    pub position: Params,
    /// Orientation filter parameters.
    pub orientation: Params,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(
        9,
        "name, tracker (*NAME or NAME@host), sensors, position min_cutoff, beta, \
         derivative_cutoff, orientation min_cutoff, beta, derivative_cutoff",
    )?;
    let params = |i: usize| -> Result<Params, ConfigError> {
        Ok(Params {
            min_cutoff: line.f64(i, "min_cutoff")?,
            beta: line.f64(i + 1, "beta")?,
            derivative_cutoff: line.f64(i + 2, "derivative_cutoff")?,
        })
    };
    Ok(Box::new(FilterOneEuro {
        name: line.name(0)?,
        source: line
            .device_ref(1, "tracker", false)?
            .ok_or_else(|| line.err(ConfigErrorKind::BadName, "the tracker cannot be NULL"))?,
        sensors: line.uint(2, "sensors", 1, MAX_SENSORS)?,
        position: params(3)?,
        orientation: params(6)?,
    }))
}

impl DeviceSpec for FilterOneEuro {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(OneEuroDevice::new(self, cx.conn())?)])
    }
}

/// One sensor's filters and the time of its last report.
#[derive(Clone, Copy, Debug)]
struct Sensor {
    position: PositionFilter,
    orientation: OrientationFilter,
    last: TimeVal,
}

struct State {
    tracker: TrackerServer,
    sensors: Vec<Sensor>,
}

impl State {
    /// One source pose: filtered and reported at once, as C++ does in its callback.
    fn pose(&mut self, sensor: usize, time: TimeVal, pos: [f64; 3], quat: [f64; 4]) {
        let Some(s) = self.sensors.get_mut(sensor) else {
            return;
        };
        let mut dt = interval(time, s.last);
        if dt <= 0.0 {
            dt = 1.0;
        }
        let p = s.position.filter(dt, &pos);
        let q = quat_normalize(&s.orientation.filter(dt, &quat));
        s.last = time;
        let _ = self.tracker.report_pose(sensor, time, p, q);
    }
}

/// The running filter.
pub struct OneEuroDevice {
    name: String,
    source: TrackerSource,
    _state: Rc<RefCell<State>>,
}

impl OneEuroDevice {
    /// The filter `cfg` describes, serving on `conn` (the server's connection).
    pub fn new(cfg: &FilterOneEuro, conn: &Connection) -> Result<OneEuroDevice, Error> {
        let sensor = Sensor {
            position: PositionFilter::new(cfg.position),
            orientation: OrientationFilter::new(cfg.orientation),
            last: TimeVal::ZERO,
        };
        let state = Rc::new(RefCell::new(State {
            tracker: TrackerServer::new(&cfg.name, conn, cfg.sensors as usize)?,
            sensors: vec![sensor; cfg.sensors as usize],
        }));
        let source = TrackerSource::open(&cfg.source, conn)?;
        let s = state.clone();
        source.remote.on_pose(move |p| {
            let q = p.quat.quaternion();
            // A pose reported while this filter reports is impossible (different senders);
            // a busy state is skipped rather than panicking.
            if let Ok(mut st) = s.try_borrow_mut() {
                st.pose(
                    p.sensor,
                    p.time,
                    [p.pos.x, p.pos.y, p.pos.z],
                    [q.i, q.j, q.k, q.w],
                );
            }
        });
        Ok(OneEuroDevice {
            name: cfg.name.clone(),
            source,
            _state: state,
        })
    }
}

impl ServerDevice for OneEuroDevice {
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
