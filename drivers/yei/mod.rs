//! YEI Technology 3-Space Sensor units on a serial line: wired (`vrpn_YEI_3Space_Sensor`,
//! the unit's own USB serial port) and wireless (`vrpn_YEI_3Space_Sensor_Wireless`, units
//! paired with a wireless dongle on one port). Commands in [`command`], the streamed record
//! in [`record`], the wired stream's framing in [`framing`], the dongle's in [`dongle`]; a
//! simulator in `sim` (with the `sim` feature).
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_YEI_3Space_Sensor NAME PORT BAUD CALIBRATE TARE FPS RED GREEN BLUE LED_MODE [\]
//! ```
//!
//! `CALIBRATE` and `TARE` (0 or 1) calibrate the gyroscopes and tare the orientation once at
//! start-up; `FPS` is the streaming rate asked for (0: as fast as the unit can); the LED colour
//! (each 0–1) and mode (0 standard, 1 static) are set at start-up too. A trailing `\` is
//! followed by a line holding one ASCII command (decimal, without its `:`, e.g.
//! `238,1,1,0`), sent at every reset; that line may end in `\` again.
//!
//! ```text
//! vrpn_YEI_3Space_Sensor_Wireless NAME ID PORT BAUD CALIBRATE TARE FPS RED GREEN BLUE LED_MODE [\ | /]
//! vrpn_YEI_3Space_Sensor_Wireless NAME ID CALIBRATE TARE FPS RED GREEN BLUE LED_MODE [\ | /]
//! ```
//!
//! A wireless unit at logical id `ID` (0–14) of the dongle on `PORT`, with the same fields;
//! its `\` command lines may end in `/`, as its first line may, and then a line of the second
//! form describes another unit on the same dongle (no port). Each unit is served as a wired
//! one is, under its own name; one driver runs the dongle ([`wireless`]).
//!
//! # What is sent
//!
//! `NAME` is a Tracker with two sensors (0: untared orientation, 1: tared orientation;
//! position always 0; sensor 1 also reports the tared linear acceleration, gravity removed,
//! in m/s²), an Analog with 11 channels (gyro rates x y z in rad/s, gravity x y z in g,
//! compass x y z in gauss, temperature in °C, confidence 0–1) and a Button with 8 buttons.
//! Each record is stamped with the arrival of its first byte.
//!
//! # Supervision
//!
//! Two seconds without a record (from any unit on a dongle): C++'s timeout text and a reset;
//! a unit of a dongle without a record for two seconds (silent, or left out at the reset
//! because it failed) resets the dongle too, which tries it again.

pub mod command;
pub mod config;
pub mod dongle;
pub mod framing;
pub mod record;
#[cfg(any(test, feature = "sim"))]
pub mod sim;
pub mod wired;
pub mod wireless;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_wireless;

use std::time::Duration;

use self::record::{Record, BUTTONS, CHANNELS, GRAVITY};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Recovery, Supervision};
use crate::time::Now;
use crate::{AnalogServer, ButtonServer, Connection, Error, TrackerServer};

pub use self::config::{Unit, Yei, YeiWireless};

/// The registry entry: `vrpn_YEI_3Space_Sensor` and `vrpn_YEI_3Space_Sensor_Wireless`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_YEI_3Space_Sensor", config::WIRELESS_KEYWORD],
    parse: config::parse,
    hints: &[],
};

/// Silence after which a unit is reset (C++'s).
pub const TIMEOUT: Duration = Duration::from_secs(2);

/// How long the unit is given to stop streaming before the input is flushed (C++'s).
pub const SETTLE: Duration = Duration::from_millis(50);

/// The wait for the answer to the LED read-back that proves the unit is there (C++'s).
pub const ANSWER_WAIT: Duration = Duration::from_secs(2);

/// How a unit is watched: C++'s 2 s timeout, then a reset.
pub fn supervision() -> Supervision {
    Supervision {
        watchdog: Some(TIMEOUT),
        on_silence: Recovery::Reset,
        pause: None,
        skip_note_interval: Duration::from_secs(1),
    }
}

/// C++'s timeout text.
pub fn say_timeout(last_record: Now, cx: &mut Cx<'_>) {
    let (cur, ts) = (cx.now.wall, last_record.wall);
    cx.say(
        TextSeverity::Error,
        format_args!(
            "vrpn_YEI_3Space::mainloop: Timeout... current_time={}:{}, timestamp={}:{}",
            cur.sec, cur.usec, ts.sec, ts.usec
        ),
    );
}

/// One unit's servers: a Tracker (2 sensors), an Analog (11 channels), a Button (8).
pub struct UnitServers {
    tracker: TrackerServer,
    analog: AnalogServer,
    buttons: ButtonServer,
}

impl UnitServers {
    /// The servers of the unit named `name` on `conn`.
    pub fn new(name: &str, conn: &Connection) -> Result<UnitServers, Error> {
        Ok(UnitServers {
            tracker: TrackerServer::new(name, conn, 2)?,
            analog: AnalogServer::new(name, conn, CHANNELS)?,
            buttons: ButtonServer::new(name, conn, BUTTONS)?,
        })
    }

    /// Reports a record as C++ does: both poses, the acceleration on sensor 1 (in m/s², with
    /// an identity rotation over 1 s), the channels if they changed, the buttons that changed.
    pub fn report(&mut self, r: &Record, at: Now) {
        let t = at.wall;
        let _ = self.tracker.report_pose(0usize, t, [0.0; 3], r.untared);
        let _ = self.tracker.report_pose(1usize, t, [0.0; 3], r.tared);
        let acc = r.accel_g.map(|g| g * GRAVITY);
        let _ = self
            .tracker
            .report_acceleration(1usize, t, acc, [0.0, 0.0, 0.0, 1.0], 1.0);
        for (i, &v) in r.channels.iter().enumerate() {
            self.analog.set_channel(i, v);
        }
        let _ = self.analog.report_changes(Some(t));
        for i in 0..BUTTONS {
            self.buttons.set_button(i, r.buttons & (1 << i) != 0);
        }
        self.buttons.set_timestamp(t);
        let _ = self.buttons.report_changes();
    }
}
