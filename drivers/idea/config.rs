//! The `vrpn_IDEA` line: its fields, its parser, what it serves and how it is built.

use super::IdeaProtocol;
use crate::config::{ConfigError, ConfigErrorKind, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Interface, Served};
use crate::driver::{serve, Lifecycle};
use crate::error::Error;
use crate::Connection;

/// The line speed (C++ opens the port at 57600 baud, 8N1).
pub const BAUD: u32 = 57600;

/// What the fields after the port say, in C++'s order and units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// Run speed, steps per second.
    pub run_speed: i32,
    /// Start speed, steps per second.
    pub start_speed: i32,
    /// End speed, steps per second.
    pub end_speed: i32,
    /// Acceleration, steps per second².
    pub accel: i32,
    /// Deceleration, steps per second².
    pub decel: i32,
    /// Run current, mA.
    pub run_current: i32,
    /// Hold current, mA.
    pub hold_current: i32,
    /// Acceleration current, mA.
    pub accel_current: i32,
    /// Deceleration current, mA.
    pub decel_current: i32,
    /// Delay before dropping to the hold current, ms.
    pub delay: i32,
    /// Microstepping (8: eighth steps).
    pub step: i32,
}

/// `vrpn_IDEA NAME PORT RUN START END ACCEL DECEL RUN_I HOLD_I ACCEL_I DECEL_I DELAY STEP
/// HIGH_LIMIT LOW_LIMIT OUT1 OUT2 OUT3 OUT4 INITIAL_MOVE FRACTION RESET_LOCATION`: a Haydon
/// Kerk IDEA stepper drive.
#[derive(Clone, Debug, PartialEq)]
pub struct Idea {
    /// Device name (an Analog, an Analog_Output and a Button).
    pub name: String,
    /// Serial port.
    pub port: String,
    /// Speeds, accelerations and currents of every move.
    pub motion: Motion,
    /// Input (1–4) wired to the high limit switch; `None` for none (C++: -1).
    pub high_limit: Option<u8>,
    /// Input (1–4) wired to the low limit switch; `None` for none.
    pub low_limit: Option<u8>,
    /// Outputs 1–4 set by the reset: `Some(on)`, or `None` to leave one as it is (C++: -1).
    pub outputs: [Option<bool>; 4],
    /// Move made by the reset (steps; 0 for none), repeated until the high limit switch
    /// closes when there is one and the move is forward.
    pub initial_move: f64,
    /// Fraction of the speeds, accelerations and currents used by the reset's moves.
    pub fraction: f64,
    /// Position (steps) the drive is set to at the end of the reset.
    pub reset_location: f64,
}

const USAGE: &str = "name, port, run_speed, start_speed, end_speed, accel_rate, decel_rate, \
                     run_current, hold_current, accel_current, decel_current, delay, step, \
                     high_limit_index, low_limit_index, output_1..output_4, initial_move, \
                     fractional_c_a, reset_location";

/// A limit-switch input: 1–4, or none (C++ takes any value below 1 as none).
fn limit(line: &ConfigLine<'_, '_>, i: usize, field: &str) -> Result<Option<u8>, ConfigError> {
    let v = line.int(i, field)?;
    match v {
        ..=0 => Ok(None),
        1..=4 => Ok(Some(v as u8)),
        _ => Err(line.err(
            ConfigErrorKind::OutOfRange,
            format!("{field} must be an input 1 to 4, or -1 for none, found {v}"),
        )),
    }
}

/// Parses a `vrpn_IDEA` line.
pub(super) fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    line.need(22, USAGE)?;
    let int = |i: usize, field: &str| line.int(i, field);
    let motion = Motion {
        run_speed: int(2, "run_speed_tics_sec")?,
        start_speed: int(3, "start_speed_tics_sec")?,
        end_speed: int(4, "end_speed_tics_sec")?,
        accel: int(5, "accel_rate_tics_sec_sec")?,
        decel: int(6, "decel_rate_tics_sec_sec")?,
        run_current: int(7, "run_current")?,
        hold_current: int(8, "hold_current")?,
        accel_current: int(9, "accel_current")?,
        decel_current: int(10, "decel_current")?,
        delay: int(11, "delay")?,
        step: int(12, "step")?,
    };
    let mut outputs = [None; 4];
    for (k, out) in outputs.iter_mut().enumerate() {
        // As C++: below 0 leaves the output alone, 0 turns it off, anything else on.
        let v = int(15 + k, &format!("output_{}_value", k + 1))?;
        *out = (v >= 0).then_some(v != 0);
    }
    Ok(Box::new(Idea {
        name: line.name(0)?,
        port: line.word(1)?.to_owned(),
        motion,
        high_limit: limit(line, 13, "high_limit_index")?,
        low_limit: limit(line, 14, "low_limit_index")?,
        outputs,
        initial_move: line.f64(19, "initial_move")?,
        fraction: line.f64(20, "fractional_c_a")?,
        reset_location: line.f64(21, "reset_location")?,
    }))
}

impl Idea {
    /// The driver for this entry, with its Analog, Analog_Output and Button served on `conn`.
    pub fn lifecycle(&self, conn: &Connection) -> Result<Lifecycle<IdeaProtocol>, Error> {
        Ok(Lifecycle::new(
            &self.name,
            IdeaProtocol::new(self, conn)?,
            conn,
        ))
    }
}

impl DeviceSpec for Idea {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        Served::all(
            &self.name,
            &[
                Interface::Analog,
                Interface::AnalogOutput,
                Interface::Button,
            ],
        )
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let protocol = IdeaProtocol::new(self, cx.conn())?;
        Ok(vec![serve(&self.name, &self.port, protocol, cx)])
    }
}
