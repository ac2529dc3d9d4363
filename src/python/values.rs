//! The report objects handed to callbacks and returned by the latest-state calls.
//!
//! Each keeps the Rust report as it came (fixed-size, no heap of its own) and builds Python
//! tuples and strings only when an attribute is read, so a callback that reads one field
//! pays for one field.

use pyo3::prelude::*;
use pyo3::types::PyList;

use crate::devices::text::TextSeverity;
use crate::wire::payload::analog::CHANNEL_MAX;
use crate::wire::payload::button::MAX_BUTTONS;

fn vec3(v: &nalgebra::Vector3<f64>) -> (f64, f64, f64) {
    (v.x, v.y, v.z)
}

fn xyzw(q: &nalgebra::UnitQuaternion<f64>) -> (f64, f64, f64, f64) {
    (q.i, q.j, q.k, q.w)
}

fn fmt_time(t: f64) -> String {
    format!("{t:.6}")
}

/// The `#[pymethods]` of report class `$class`: `$methods`, and the stamps a report carries,
/// read from the Rust report in field 0: `time`, `sender_time`, `arrival` and, for the reports
/// of one sensor, button, dial or analog device (all but `no_seq` ones), `seq`.
macro_rules! stamped_report {
    ($class:ident, no_seq, $($methods:tt)*) => {
        stamped_report!(@impl $class, {}, $($methods)*);
    };
    ($class:ident, $($methods:tt)*) => {
        stamped_report!(@impl $class, {
            /// Which report of its sensor, button or dial this is (1 for the first this remote
            /// received): a frame loop that sees the same `seq` again saw nothing new.
            #[getter]
            fn seq(&self) -> u64 {
                self.0.seq
            }
        }, $($methods)*);
    };
    (@impl $class:ident, { $($seq:tt)* }, $($methods:tt)*) => {
        #[pymethods]
        impl $class {
            $($methods)*

            /// Time the server stamped on the report, seconds since the epoch.
            #[getter]
            fn time(&self) -> f64 {
                self.0.time.as_secs_f64()
            }
            /// The time exactly as the sender stamped it (its own clock, as logs keep it).
            #[getter]
            fn sender_time(&self) -> f64 {
                self.0.sender_time.as_secs_f64()
            }
            /// When it arrived here: the local wall clock (seconds since the epoch) of the
            /// `mainloop()` pass that read it. `time.time() - arrival` is how old the value is.
            #[getter]
            fn arrival(&self) -> f64 {
                self.0.arrival.as_secs_f64()
            }
            $($seq)*
        }
    };
}

/// A tracker pose report.
#[pyclass(frozen, module = "vrpn", name = "Pose")]
pub(crate) struct Pose(pub(crate) crate::TrackerPose);

stamped_report! { Pose,
    /// Sensor index.
    #[getter]
    fn sensor(&self) -> usize {
        self.0.sensor
    }
    /// Position (x, y, z), metres, in the tracker's frame.
    #[getter]
    fn pos(&self) -> (f64, f64, f64) {
        vec3(&self.0.pos)
    }
    /// Orientation quaternion (x, y, z, w): rotates the tracker's axes onto the sensor's.
    #[getter]
    fn quat(&self) -> (f64, f64, f64, f64) {
        xyzw(&self.0.quat)
    }
    fn __repr__(&self) -> String {
        format!(
            "Pose(sensor={}, seq={}, pos={:?}, quat={:?}, time={})",
            self.0.sensor,
            self.0.seq,
            self.pos(),
            self.quat(),
            fmt_time(self.time())
        )
    }
}

/// A tracker velocity report.
#[pyclass(frozen, module = "vrpn", name = "Velocity")]
pub(crate) struct Velocity(pub(crate) crate::TrackerVelocity);

stamped_report! { Velocity,
    /// Sensor index.
    #[getter]
    fn sensor(&self) -> usize {
        self.0.sensor
    }
    /// Linear velocity (x, y, z), m/s, in the tracker's frame.
    #[getter]
    fn vel(&self) -> (f64, f64, f64) {
        vec3(&self.0.vel)
    }
    /// Rotation (x, y, z, w) the sensor undergoes during `vel_quat_dt` seconds, expressed in
    /// the tracker's frame: the orientation `vel_quat_dt` later is `vel_quat * quat`.
    #[getter]
    fn vel_quat(&self) -> (f64, f64, f64, f64) {
        xyzw(&self.0.vel_quat)
    }
    /// Seconds `vel_quat` spans.
    #[getter]
    fn vel_quat_dt(&self) -> f64 {
        self.0.vel_quat_dt
    }
    /// Angular velocity (x, y, z), rad/s, in the tracker's frame: the rotation vector
    /// (axis times angle) of `vel_quat` divided by `vel_quat_dt`.
    #[getter]
    fn angular_velocity(&self) -> (f64, f64, f64) {
        vec3(&self.0.angular_velocity())
    }
    fn __repr__(&self) -> String {
        format!(
            "Velocity(sensor={}, vel={:?}, time={})",
            self.0.sensor,
            self.vel(),
            fmt_time(self.time())
        )
    }
}

/// A tracker acceleration report.
#[pyclass(frozen, module = "vrpn", name = "Acceleration")]
pub(crate) struct Acceleration(pub(crate) crate::TrackerAcceleration);

stamped_report! { Acceleration,
    /// Sensor index.
    #[getter]
    fn sensor(&self) -> usize {
        self.0.sensor
    }
    /// Linear acceleration (x, y, z), m/s², in the tracker's frame.
    #[getter]
    fn acc(&self) -> (f64, f64, f64) {
        vec3(&self.0.acc)
    }
    /// Change (x, y, z, w) of the velocity rotation over `acc_quat_dt` seconds (tracker's
    /// frame).
    #[getter]
    fn acc_quat(&self) -> (f64, f64, f64, f64) {
        xyzw(&self.0.acc_quat)
    }
    /// Seconds `acc_quat` spans.
    #[getter]
    fn acc_quat_dt(&self) -> f64 {
        self.0.acc_quat_dt
    }
    fn __repr__(&self) -> String {
        format!(
            "Acceleration(sensor={}, acc={:?}, time={})",
            self.0.sensor,
            self.acc(),
            fmt_time(self.time())
        )
    }
}

/// One button changed.
#[pyclass(frozen, module = "vrpn", name = "ButtonChange")]
pub(crate) struct ButtonChange(pub(crate) crate::ButtonChange);

stamped_report! { ButtonChange,
    /// Button index.
    #[getter]
    fn button(&self) -> usize {
        self.0.button
    }
    /// New state: 1 pressed, 0 released.
    #[getter]
    fn state(&self) -> i32 {
        self.0.state.raw()
    }
    /// True when the button is now pressed.
    #[getter]
    fn pressed(&self) -> bool {
        self.0.state.is_pressed()
    }
    fn __repr__(&self) -> String {
        format!(
            "ButtonChange(button={}, state={}, time={})",
            self.0.button,
            self.0.state.raw(),
            fmt_time(self.time())
        )
    }
}

/// The state of every button of a device.
#[pyclass(frozen, module = "vrpn", name = "ButtonStates")]
pub(crate) struct ButtonStates(pub(crate) crate::ButtonStates);

stamped_report! { ButtonStates, no_seq,
    /// State of each button (1 pressed, 0 released), as many as the device has.
    #[getter]
    fn states<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(py, self.0.as_slice().iter().map(|s| s.raw()))
    }
    /// Number of buttons.
    #[getter]
    fn num_buttons(&self) -> usize {
        self.0.num_buttons.min(MAX_BUTTONS)
    }
    fn __repr__(&self) -> String {
        format!(
            "ButtonStates(states={:?}, time={})",
            self.0
                .as_slice()
                .iter()
                .map(|s| s.raw())
                .collect::<Vec<_>>(),
            fmt_time(self.time())
        )
    }
}

/// An analog report: every channel's value.
#[pyclass(frozen, module = "vrpn", name = "AnalogReport")]
pub(crate) struct AnalogReport(pub(crate) crate::AnalogReport);

stamped_report! { AnalogReport,
    /// The channel values.
    #[getter]
    fn channels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(py, self.0.channels())
    }
    /// Number of channels.
    #[getter]
    fn num_channels(&self) -> usize {
        self.0.num_channel.min(CHANNEL_MAX)
    }
    fn __repr__(&self) -> String {
        format!(
            "AnalogReport(channels={:?}, time={})",
            self.0.channels(),
            fmt_time(self.time())
        )
    }
}

/// A dial moved.
#[pyclass(frozen, module = "vrpn", name = "DialUpdate")]
pub(crate) struct DialUpdate(pub(crate) crate::DialUpdate);

stamped_report! { DialUpdate,
    /// Dial index.
    #[getter]
    fn dial(&self) -> usize {
        self.0.dial
    }
    /// Revolutions since the previous report.
    #[getter]
    fn change(&self) -> f64 {
        self.0.change
    }
    fn __repr__(&self) -> String {
        format!(
            "DialUpdate(dial={}, change={}, time={})",
            self.0.dial,
            self.0.change,
            fmt_time(self.time())
        )
    }
}

/// Severity name of a text message.
pub(crate) fn severity_name(s: TextSeverity) -> &'static str {
    match s {
        TextSeverity::Normal => "normal",
        TextSeverity::Warning => "warning",
        TextSeverity::Error => "error",
        TextSeverity::Other(_) => "other",
    }
}

/// A text message from a device.
#[pyclass(frozen, module = "vrpn", name = "TextMessage")]
pub(crate) struct TextMessage(pub(crate) crate::TextMessage);

#[pymethods]
impl TextMessage {
    /// The text.
    #[getter]
    fn text(&self) -> &str {
        self.0.text()
    }
    /// "normal", "warning", "error" or "other".
    #[getter]
    fn severity(&self) -> &'static str {
        severity_name(self.0.severity)
    }
    /// The level (free-form number).
    #[getter]
    fn level(&self) -> u32 {
        self.0.level
    }
    /// Time the sender stamped on the message, seconds since the epoch.
    #[getter]
    fn time(&self) -> f64 {
        self.0.time.as_secs_f64()
    }
    /// The time exactly as the sender stamped it (its own clock, as logs keep it).
    #[getter]
    fn sender_time(&self) -> f64 {
        self.0.sender_time.as_secs_f64()
    }
    fn __repr__(&self) -> String {
        format!(
            "TextMessage(severity={:?}, text={:?}, time={})",
            self.severity(),
            self.0.text(),
            fmt_time(self.time())
        )
    }
}

/// A diagnostic from a connection (no answer from a server, a dropped peer, ...).
#[pyclass(frozen, module = "vrpn", name = "Notice")]
pub(crate) struct Notice(pub(crate) crate::Notice);

#[pymethods]
impl Notice {
    /// "info", "warning" or "error".
    #[getter]
    fn severity(&self) -> &'static str {
        match self.0.severity {
            crate::Severity::Info => "info",
            crate::Severity::Warning => "warning",
            crate::Severity::Error => "error",
        }
    }
    /// What happened and what to do.
    #[getter]
    fn text(&self) -> &str {
        &self.0.text
    }
    fn __repr__(&self) -> String {
        format!("Notice({:?}, {:?})", self.severity(), self.0.text)
    }
}

pub(crate) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Pose>()?;
    m.add_class::<Velocity>()?;
    m.add_class::<Acceleration>()?;
    m.add_class::<ButtonChange>()?;
    m.add_class::<ButtonStates>()?;
    m.add_class::<AnalogReport>()?;
    m.add_class::<DialUpdate>()?;
    m.add_class::<TextMessage>()?;
    m.add_class::<Notice>()?;
    Ok(())
}
