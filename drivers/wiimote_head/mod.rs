//! `vrpn_Tracker_WiimoteHead`: a head tracker from a Wii Remote's IR camera watching two LEDs
//! on a pair of glasses (the "Johnny Lee" set-up), read from the Wiimote's Analog channels.
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_WiimoteHead NAME WIIMOTE [MIN_UPDATE_RATE [LED_SPACING]]
//! ```
//!
//! `WIIMOTE` is `*NAME` (an Analog of this server) or `NAME@host`, a `vrpn_WiiMote` or any
//! Analog with its channel layout (1-3 gravity, then x, y, size of up to four IR blobs from
//! channel 4). `MIN_UPDATE_RATE` (default 60, 0 for 60) is the least number of reports a
//! second; `LED_SPACING` the distance between the LEDs in metres (default 0.205). Both are read
//! in single precision as C++ reads them. See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! One `vrpn_Tracker Pos_Quat` (sensor 0) at the first server pass after each Wiimote report
//! (several reports in one pass give one), after a new client connects, and whenever
//! `1 / MIN_UPDATE_RATE` seconds pass without one: the pose as C++ VRPN 07.38 computes it
//! ([`head::HeadTracker`]), stamped with the latest Wiimote report's time.

mod head;
#[cfg(test)]
mod tests;

pub use head::{quat_from_two_vecs, quat_xform, Flip, HeadTracker, Pose};

use std::cell::RefCell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, DeviceRef};
use crate::connection::ConnectionEvent;
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;
use crate::layered::AnalogSource;
use crate::time::Now;
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_WiimoteHead"],
    parse,
    hints: &[],
};

/// The `vrpn_Tracker_WiimoteHead` line.
#[derive(Clone, Debug, PartialEq)]
pub struct WiimoteHead {
    /// Device name of the tracker.
    pub name: String,
    /// The Wiimote's Analog.
    pub source: DeviceRef,
    /// Least reports per second (0: 60, as C++).
    pub min_update_rate: f32,
    /// Distance between the two LEDs, metres.
    pub led_spacing: f32,
}

impl WiimoteHead {
    /// The longest time between two reports: `1 / MIN_UPDATE_RATE` seconds (double
    /// precision, as C++), 1/60 s for a rate of 0.
    pub fn max_interval(&self) -> f64 {
        if self.min_update_rate == 0.0 {
            1.0 / 60.0
        } else {
            1.0 / f64::from(self.min_update_rate)
        }
    }
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(
        2,
        "name, wiimote (*NAME or NAME@host) [, min update rate [, LED spacing]]",
    )?;
    let name = line.name(0)?;
    let source = line
        .device_ref(1, "wiimote", false)?
        .ok_or_else(|| line.err(ConfigErrorKind::BadName, "the wiimote cannot be NULL"))?;
    let min_update_rate = match line.arg(2) {
        Some(_) => line.rate_or_zero(2, "min update rate")?,
        None => 60.0,
    };
    let led_spacing = match line.arg(3) {
        Some(_) => line.f32(3, "LED spacing")?,
        None => 0.205,
    };
    Ok(Box::new(WiimoteHead {
        name,
        source,
        min_update_rate,
        led_spacing,
    }))
}

impl DeviceSpec for WiimoteHead {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(WiimoteHeadDevice::new(self, cx.conn())?)])
    }
}

/// The running tracker.
pub struct WiimoteHeadDevice {
    name: String,
    tracker: TrackerServer,
    source: AnalogSource,
    state: Rc<RefCell<HeadTracker>>,
    max_interval: f64,
    /// When the last report went out (start-up before the first).
    last_report: Option<Instant>,
}

impl WiimoteHeadDevice {
    /// The tracker `cfg` describes, serving on `conn` (the server's connection).
    pub fn new(cfg: &WiimoteHead, conn: &Connection) -> Result<WiimoteHeadDevice, Error> {
        let tracker = TrackerServer::new(&cfg.name, conn, 1)?;
        let state = Rc::new(RefCell::new(HeadTracker::new(f64::from(cfg.led_spacing))));
        let source = AnalogSource::open(&cfg.source, conn)?;
        let s = state.clone();
        source.remote.on_report(move |r| {
            if let Ok(mut st) = s.try_borrow_mut() {
                st.wiimote_report(r.sender_time, r.channels());
            }
        });
        let s = state.clone();
        conn.on_event(ConnectionEvent::GotConnection, move || {
            if let Ok(mut st) = s.try_borrow_mut() {
                st.updated = true;
            }
        });
        Ok(WiimoteHeadDevice {
            name: cfg.name.clone(),
            tracker,
            source,
            state,
            max_interval: cfg.max_interval(),
            last_report: None,
        })
    }
}

impl ServerDevice for WiimoteHeadDevice {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, now: Now) {
        self.source.poll();
        let mut st = self.state.borrow_mut();
        let interval_passed = match self.last_report {
            None => true,
            Some(last) => {
                now.mono.saturating_duration_since(last).as_secs_f64() >= self.max_interval
            }
        };
        if st.updated || interval_passed {
            st.update_pose();
            // Before the first Wiimote report C++ stamps 0 s 0 µs; the server's clock is used.
            let time = st.time.unwrap_or(now.wall);
            let p = st.reported;
            let _ = self.tracker.report_pose(0, time, p.xyz, p.quat);
            self.last_report = Some(now.mono);
            st.updated = false;
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let periodic = self
            .last_report
            .map(|last| last + Duration::from_secs_f64(self.max_interval.max(0.0)));
        match (periodic, self.source.next_deadline()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}
