//! `vrpn_JoyFly`: seven axes of an analog joystick fly a tracker (the older form of
//! `vrpn_Tracker_AnalogFly`), with per-axis acceleration and power from a file of its own.
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_JoyFly NAME JOYSTICK CONFIG_FILE
//! ```
//!
//! `JOYSTICK` is `*NAME` (an Analog of this server) or `NAME@host`. `CONFIG_FILE` (opened
//! relative to the server's working directory, as C++) holds seven `ACCEL POWER` pairs, one
//! per channel, then the sixteen numbers of the initial matrix, row by row. Without the file
//! every channel has acceleration 1 and power 1 and the matrix is the identity, as in C++.
//! See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! Each joystick report whose seven channels are all within [-0.5, 0.5] moves the pose
//! ([`Flight::step`]); at the next server pass one `vrpn_Tracker Pos_Quat` (sensor 0) reports
//! it, stamped with that joystick report's time (C++ stamps 0). A new client connection resets
//! the pose to the initial matrix, as in C++.

#[cfg(test)]
mod tests;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, DeviceRef};
use crate::connection::ConnectionEvent;
use crate::devices::text::TextSeverity;
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;
use crate::layered::{euler_col_matrix, mat_mult, quat_from_row_matrix, AnalogSource, Mat4};
use crate::time::{Now, TimeVal};
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_JoyFly"],
    parse,
    hints: &[],
};

/// Channels read: x, z, y translation, roll, pitch, yaw, and a seventh that only gates.
pub const CHANNELS: usize = 7;

/// The contents of the JoyFly file.
#[derive(Clone, Debug, PartialEq)]
pub struct JoyFlyFile {
    /// Acceleration of each channel.
    pub accel: [f64; CHANNELS],
    /// Power each channel's value is raised to.
    pub power: [i32; CHANNELS],
    /// The initial (and reset) matrix, `m[row][col]`.
    pub init: Mat4,
}

impl Default for JoyFlyFile {
    /// C++'s values when the file cannot be opened.
    fn default() -> Self {
        JoyFlyFile {
            accel: [1.0; CHANNELS],
            power: [1; CHANNELS],
            init: crate::layered::IDENTITY,
        }
    }
}

impl JoyFlyFile {
    /// Reads the file's text: seven `ACCEL POWER` pairs, then sixteen numbers.
    pub fn parse(text: &str) -> Result<JoyFlyFile, String> {
        let mut t = text.split_ascii_whitespace();
        let mut f = JoyFlyFile::default();
        for i in 0..CHANNELS {
            let (Some(a), Some(p)) = (t.next(), t.next()) else {
                return Err(format!("channel {i}: missing acceleration and power"));
            };
            f.accel[i] = a
                .parse()
                .map_err(|_| format!("channel {i}: acceleration '{a}' is not a number"))?;
            f.power[i] = p
                .parse()
                .map_err(|_| format!("channel {i}: power '{p}' is not an integer"))?;
        }
        for k in 0..16 {
            let Some(v) = t.next() else {
                return Err(format!("the initial matrix has {k} of its 16 numbers"));
            };
            f.init[k / 4][k % 4] = v
                .parse()
                .map_err(|_| format!("initial matrix: '{v}' is not a number"))?;
        }
        Ok(f)
    }
}

/// The `vrpn_JoyFly` line (with its file read).
#[derive(Clone, Debug, PartialEq)]
pub struct JoyFly {
    /// Device name of the tracker.
    pub name: String,
    /// The joystick read.
    pub source: DeviceRef,
    /// The file named.
    pub file_name: String,
    /// Its contents; `None` when it could not be opened (C++'s defaults are used).
    pub file: Option<JoyFlyFile>,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(3, "name, joystick (*NAME or NAME@host), configuration file")?;
    let name = line.name(0)?;
    let source = line
        .device_ref(1, "joystick", false)?
        .ok_or_else(|| line.err(ConfigErrorKind::BadName, "the joystick cannot be NULL"))?;
    let file_name = line.word(2)?.to_string();
    let file = match std::fs::read_to_string(&file_name) {
        Ok(text) => Some(JoyFlyFile::parse(&text).map_err(|why| {
            line.err(
                ConfigErrorKind::BadValue,
                format!("JoyFly file '{file_name}': {why}"),
            )
        })?),
        Err(_) => None,
    };
    Ok(Box::new(JoyFly {
        name,
        source,
        file_name,
        file,
    }))
}

impl DeviceSpec for JoyFly {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(JoyFlyDevice::new(self, cx.conn())?)])
    }
}

/// The flying state: C++'s arithmetic, operation for operation.
#[derive(Clone, Debug)]
pub struct Flight {
    file: JoyFlyFile,
    current: Mat4,
    /// The previous report's time; `None` after a reset.
    prev: Option<TimeVal>,
}

impl Flight {
    /// At the initial matrix.
    pub fn new(file: JoyFlyFile) -> Flight {
        Flight {
            current: file.init,
            file,
            prev: None,
        }
    }

    /// Back to the initial matrix; the next report counts as 1 ms after the previous.
    pub fn reset(&mut self) {
        self.current = self.file.init;
        self.prev = None;
    }

    /// One joystick report at `time`. Returns the new position and quaternion (x, y, z, w),
    /// or `None` when a channel is outside [-0.5, 0.5] (the report is then only a time mark).
    /// The step's milliseconds are the previous report's time minus this one's (negative
    /// when time goes forward: C++ subtracts that way round), 1 after a reset.
    pub fn step(&mut self, time: TimeVal, channels: &[f64]) -> Option<([f64; 3], [f64; 4])> {
        let dt = match self.prev {
            None => 1.0,
            Some(p) => {
                ((p.sec * 1_000_000 + p.usec) - (time.sec * 1_000_000 + time.usec)) as f64 / 1000.0
            }
        };
        self.prev = Some(time);
        let mut temp = [1.0; CHANNELS];
        for (i, t) in temp.iter_mut().enumerate() {
            let c = channels.get(i).copied().unwrap_or(0.0);
            if !((-0.5..=0.5).contains(&c)) {
                return None;
            }
            for _ in 0..self.file.power[i] {
                *t *= c;
            }
            if c > 0.0 {
                *t *= self.file.accel[i];
            } else {
                *t = -t.abs() * self.file.accel[i];
            }
            *t *= dt;
        }
        let (rz, rx, ry) = (temp[3], temp[4], temp[5]);
        let (tx, ty, tz) = (-temp[0], temp[2], temp[1]);
        let mut m = euler_col_matrix(rz, ry, rx);
        m[3][0] = tx;
        m[3][1] = ty;
        m[3][2] = tz;
        self.current = mat_mult(&m, &self.current);
        let c = &self.current;
        Some(([c[3][0], c[3][1], c[3][2]], quat_from_row_matrix(c)))
    }
}

struct State {
    flight: Flight,
    ready: Option<(TimeVal, [f64; 3], [f64; 4])>,
}

/// The running tracker.
pub struct JoyFlyDevice {
    name: String,
    tracker: TrackerServer,
    source: AnalogSource,
    state: Rc<RefCell<State>>,
}

impl JoyFlyDevice {
    /// The tracker `cfg` describes, serving on `conn` (the server's connection).
    pub fn new(cfg: &JoyFly, conn: &Connection) -> Result<JoyFlyDevice, Error> {
        let tracker = TrackerServer::new(&cfg.name, conn, 1)?;
        if cfg.file.is_none() {
            let _ = tracker.send_text(
                TextSeverity::Warning,
                0,
                &format!(
                    "cannot open the JoyFly file '{}': acceleration 1, power 1, identity matrix",
                    cfg.file_name
                ),
            );
        }
        let state = Rc::new(RefCell::new(State {
            flight: Flight::new(cfg.file.clone().unwrap_or_default()),
            ready: None,
        }));
        let source = AnalogSource::open(&cfg.source, conn)?;
        let s = state.clone();
        source.remote.on_report(move |r| {
            if let Ok(mut st) = s.try_borrow_mut() {
                if let Some((p, q)) = st.flight.step(r.sender_time, r.channels()) {
                    st.ready = Some((r.sender_time, p, q));
                }
            }
        });
        let s = state.clone();
        conn.on_event(ConnectionEvent::GotConnection, move || {
            if let Ok(mut st) = s.try_borrow_mut() {
                st.flight.reset();
            }
        });
        Ok(JoyFlyDevice {
            name: cfg.name.clone(),
            tracker,
            source,
            state,
        })
    }
}

impl ServerDevice for JoyFlyDevice {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, _now: Now) {
        self.source.poll();
        if let Some((t, p, q)) = self.state.borrow_mut().ready.take() {
            let _ = self.tracker.report_pose(0, t, p, q);
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.source.next_deadline()
    }
}
