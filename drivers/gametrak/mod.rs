//! `vrpn_Tracker_GameTrak`: the two tethers of a GameTrak, read as six analog axes of a
//! joystick device, become the positions of two tracker sensors.
//!
//! # Configuration lines served
//!
//! ```text
//! vrpn_Tracker_GameTrak NAME JOYSTICK
//! axis_mapping C0 C1 C2 C3 C4 C5        (or an empty line)
//! ```
//!
//! `JOYSTICK` is `*NAME` (an Analog of this server) or `NAME@host`. The line after the entry
//! is required, as in C++: an empty line keeps the default mapping `0 1 2 3 4 5`, an
//! `axis_mapping` line names the analog channels read as left x, y, z and right x, y, z
//! (missing trailing numbers keep their defaults). See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! After each report of the joystick, at the next server pass: two `vrpn_Tracker Pos_Quat`
//! (sensor 0 the left tether, sensor 1 the right one) stamped with the joystick report's time,
//! identity orientation, positions as C++ VRPN 07.38 computes them ([`tether_positions`]). Two
//! joystick reports within one pass give one pair of reports (the later one), as in C++.

#[cfg(test)]
mod tests;

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

use crate::config::lines::c_tokens;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine, DeviceRef};
use crate::devices::analog::CHANNEL_MAX;
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;
use crate::layered::AnalogSource;
use crate::time::{Now, TimeVal};
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_GameTrak"],
    parse,
    hints: &[],
};

/// The `vrpn_Tracker_GameTrak` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct GameTrak {
    /// Device name of the tracker.
    pub name: String,
    /// The joystick read.
    pub source: DeviceRef,
    /// Analog channels read as left x, y, z, right x, y, z.
    pub mapping: [usize; 6],
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(2, "name, joystick (*NAME or NAME@host)")?;
    let name = line.name(0)?;
    let source = line
        .device_ref(1, "joystick", false)?
        .ok_or_else(|| line.err(ConfigErrorKind::BadName, "the joystick cannot be NULL"))?;
    let next = line.block_line(
        "the line after it: an empty line or 'axis_mapping C0 C1 C2 C3 C4 C5' (add one)",
    )?;
    let mut mapping = [0, 1, 2, 3, 4, 5];
    let tokens = c_tokens(next.text);
    match tokens.first().copied() {
        None => {}
        Some("axis_mapping") => {
            if tokens.len() > 7 {
                return Err(line.ctx().at(next.number).err(
                    ConfigErrorKind::BadBlockLine,
                    "axis_mapping takes at most six channel numbers",
                ));
            }
            for (i, tok) in tokens[1..].iter().enumerate() {
                mapping[i] = crate::config::fields::uint_in(
                    &line.ctx().at(next.number),
                    "axis_mapping channel",
                    tok,
                    0,
                    CHANNEL_MAX as u32 - 1,
                )? as usize;
            }
        }
        Some(other) => {
            return Err(line.ctx().at(next.number).err(
                ConfigErrorKind::BadBlockLine,
                format!(
                    "'{other}' after a vrpn_Tracker_GameTrak line: expected an empty line or \
                     'axis_mapping C0 C1 C2 C3 C4 C5' (did you forget the empty line?)"
                ),
            ))
        }
    }
    Ok(Box::new(GameTrak {
        name,
        source,
        mapping,
    }))
}

impl DeviceSpec for GameTrak {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(&self.name, &[Interface::Tracker])
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        Ok(vec![Box::new(GameTrakDevice::new(self, cx.conn())?)])
    }
}

/// The two tether positions (left, right) for one joystick report, as C++ VRPN computes
/// them: each tether's x and y axes are angles of ±32.5° at ±1, its z axis the pulled length
/// (1.5 m at -1, 0 at 1); the tethers' bases sit 6.5 cm either side of the origin.
/// Channels the report does not have read as 0.
pub fn tether_positions(channels: &[f64], mapping: &[usize; 6]) -> [[f64; 3]; 2] {
    let ch = |i: usize| channels.get(mapping[i]).copied().unwrap_or(0.0);
    let coef = (32.5 / 180.0) * std::f64::consts::PI;
    let one = |x: f64, y: f64, z: f64, base: f64| {
        let distance = 1.5 * (1.0 - z);
        let ax = -x * coef;
        let ay = -y * coef;
        [
            ax.sin() * distance + base,
            ax.cos() * ay.sin() * distance,
            ax.cos() * ay.cos() * distance,
        ]
    };
    [
        one(ch(0), ch(1), ch(2), 0.065),
        one(ch(3), ch(4), ch(5), -0.065),
    ]
}

struct State {
    mapping: [usize; 6],
    sensors: [[f64; 3]; 2],
    time: TimeVal,
    should_report: bool,
}

/// The running tracker.
pub struct GameTrakDevice {
    name: String,
    tracker: TrackerServer,
    source: AnalogSource,
    state: Rc<RefCell<State>>,
}

impl GameTrakDevice {
    /// The tracker `cfg` describes, serving on `conn` (the server's connection).
    pub fn new(cfg: &GameTrak, conn: &Connection) -> Result<GameTrakDevice, Error> {
        let tracker = TrackerServer::new(&cfg.name, conn, 2)?;
        let state = Rc::new(RefCell::new(State {
            mapping: cfg.mapping,
            sensors: [[0.0; 3]; 2],
            time: TimeVal::ZERO,
            should_report: false,
        }));
        let source = AnalogSource::open(&cfg.source, conn)?;
        let s = state.clone();
        source.remote.on_report(move |r| {
            if let Ok(mut st) = s.try_borrow_mut() {
                st.sensors = tether_positions(r.channels(), &st.mapping);
                st.time = r.sender_time;
                st.should_report = true;
            }
        });
        Ok(GameTrakDevice {
            name: cfg.name.clone(),
            tracker,
            source,
            state,
        })
    }
}

impl ServerDevice for GameTrakDevice {
    fn name(&self) -> &str {
        &self.name
    }

    fn mainloop(&mut self, _now: Now) {
        self.source.poll();
        let mut st = self.state.borrow_mut();
        if st.should_report {
            st.should_report = false;
            let identity = [0.0, 0.0, 0.0, 1.0];
            for (sensor, pos) in st.sensors.iter().enumerate() {
                let _ = self.tracker.report_pose(sensor, st.time, *pos, identity);
            }
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        self.source.next_deadline()
    }
}
