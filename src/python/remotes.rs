//! The device remotes: `TrackerRemote`, `ButtonRemote`, `AnalogRemote`, `DialRemote`,
//! `TextReceiver`, each a subclass of `vrpn.Remote`, which holds the Rust remote for it.
//!
//! Latest-state calls come in two kinds, as in the Rust API: `pose(s)` & co. keep the last
//! value, `take_pose(s)` & co. give a value once per arrival (None in frames where nothing new
//! came), and every report carries `seq` and `arrival` to tell a new one from a stale one.

use pyo3::prelude::*;

use super::args::index;
use super::callbacks::Owner;
use super::remote::Remote;
use super::to_py;
use super::values::{
    Acceleration, AnalogReport, ButtonChange, ButtonStates, DialUpdate, Pose, TextMessage, Velocity,
};
use crate::wire::payload::analog::CHANNEL_MAX;

/// Client of a tracker: `TrackerRemote("Tracker0@host")`.
#[pyclass(extends = Remote, module = "vrpn", name = "TrackerRemote")]
pub(crate) struct TrackerRemote;

type Tracker = crate::TrackerRemote;

#[pymethods]
impl TrackerRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Tracker::new(name).map_err(to_py)?;
        Ok((TrackerRemote, Remote::new("TrackerRemote", inner)))
    }

    /// Calls `f(pose)` for every pose report (only sensor `sensor`'s when given). Returns a
    /// handle for `remove_callback`.
    #[pyo3(signature = (f, sensor = None))]
    fn on_pose(
        slf: PyRef<'_, Self>,
        f: &Bound<'_, PyAny>,
        sensor: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<u64> {
        let base = slf.as_super();
        let t = base.inner::<Tracker>()?;
        let sensor = sensor.map(|s| index(s, "sensor", None)).transpose()?;
        base.reg()?.add(f, Owner::Device, |slot| match sensor {
            Some(s) => t.on_sensor_pose(s, move |p| slot.call_with(|| Pose(*p))),
            None => t.on_pose(move |p| slot.call_with(|| Pose(*p))),
        })
    }

    /// Calls `f(velocity)` for every velocity report. Returns a handle.
    fn on_velocity(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let t = base.inner::<Tracker>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            t.on_velocity(move |v| slot.call_with(|| Velocity(*v)))
        })
    }

    /// Calls `f(acceleration)` for every acceleration report. Returns a handle.
    fn on_acceleration(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let t = base.inner::<Tracker>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            t.on_acceleration(move |a| slot.call_with(|| Acceleration(*a)))
        })
    }

    /// The latest pose of `sensor`, None until one arrived (it stays after the server went
    /// away: see `state` and the pose's `arrival`).
    #[pyo3(signature = (sensor = None), text_signature = "($self, sensor=0)")]
    fn pose(slf: PyRef<'_, Self>, sensor: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Pose>> {
        let s = sensor_arg(sensor)?;
        Ok(slf.as_super().inner::<Tracker>()?.pose(s).map(Pose))
    }

    /// The latest pose of `sensor` if it arrived since the last `take_pose(sensor)`, else None.
    #[pyo3(signature = (sensor = None), text_signature = "($self, sensor=0)")]
    fn take_pose(
        slf: PyRef<'_, Self>,
        sensor: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Option<Pose>> {
        let s = sensor_arg(sensor)?;
        Ok(slf.as_super().inner::<Tracker>()?.take_pose(s).map(Pose))
    }

    /// The latest velocity of `sensor`, None until one arrived.
    #[pyo3(signature = (sensor = None), text_signature = "($self, sensor=0)")]
    fn velocity(
        slf: PyRef<'_, Self>,
        sensor: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Option<Velocity>> {
        let s = sensor_arg(sensor)?;
        Ok(slf.as_super().inner::<Tracker>()?.velocity(s).map(Velocity))
    }

    /// The latest velocity of `sensor` if it arrived since the last `take_velocity(sensor)`.
    #[pyo3(signature = (sensor = None), text_signature = "($self, sensor=0)")]
    fn take_velocity(
        slf: PyRef<'_, Self>,
        sensor: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Option<Velocity>> {
        let s = sensor_arg(sensor)?;
        let t = slf.as_super().inner::<Tracker>()?;
        Ok(t.take_velocity(s).map(Velocity))
    }

    /// The latest acceleration of `sensor`, None until one arrived.
    #[pyo3(signature = (sensor = None), text_signature = "($self, sensor=0)")]
    fn acceleration(
        slf: PyRef<'_, Self>,
        sensor: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Option<Acceleration>> {
        let s = sensor_arg(sensor)?;
        let t = slf.as_super().inner::<Tracker>()?;
        Ok(t.acceleration(s).map(Acceleration))
    }

    /// The latest acceleration of `sensor` if it arrived since the last
    /// `take_acceleration(sensor)`.
    #[pyo3(signature = (sensor = None), text_signature = "($self, sensor=0)")]
    fn take_acceleration(
        slf: PyRef<'_, Self>,
        sensor: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Option<Acceleration>> {
        let s = sensor_arg(sensor)?;
        let t = slf.as_super().inner::<Tracker>()?;
        Ok(t.take_acceleration(s).map(Acceleration))
    }

    /// Sensor slots seen so far (highest sensor index + 1).
    #[getter]
    fn sensor_count(slf: PyRef<'_, Self>) -> PyResult<usize> {
        Ok(slf.as_super().inner::<Tracker>()?.sensor_count())
    }

    /// Asks the server for `hz` reports per second (servers that cannot, ignore it).
    fn set_update_rate(slf: PyRef<'_, Self>, hz: f64) -> PyResult<()> {
        let t = slf.as_super().inner::<Tracker>()?;
        t.set_update_rate(hz).map_err(to_py)
    }

    /// Asks the server to re-zero its origin (servers that cannot, ignore it).
    fn reset_origin(slf: PyRef<'_, Self>) -> PyResult<()> {
        let t = slf.as_super().inner::<Tracker>()?;
        t.reset_origin().map_err(to_py)
    }
}

/// A sensor argument (0 when omitted).
fn sensor_arg(sensor: Option<&Bound<'_, PyAny>>) -> PyResult<usize> {
    sensor.map_or(Ok(0), |s| index(s, "sensor", None))
}

/// Client of a button device: `ButtonRemote("Button0@host")`.
#[pyclass(extends = Remote, module = "vrpn", name = "ButtonRemote")]
pub(crate) struct ButtonRemote;

type Buttons = crate::ButtonRemote;

/// A button index below the device's count (256 until the server's full-state report).
fn button_arg(b: &Buttons, i: &Bound<'_, PyAny>) -> PyResult<usize> {
    index(i, "button", Some(b.num_buttons()))
}

#[pymethods]
impl ButtonRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Buttons::new(name).map_err(to_py)?;
        Ok((ButtonRemote, Remote::new("ButtonRemote", inner)))
    }

    /// Calls `f(change)` whenever a button is pressed or released. Returns a handle.
    fn on_change(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let b = base.inner::<Buttons>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            b.on_change(move |c| slot.call_with(|| ButtonChange(*c)))
        })
    }

    /// Calls `f(states)` with every full-state report (sent on connection). Returns a handle.
    fn on_states(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let b = base.inner::<Buttons>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            b.on_states(move |s| slot.call_with(|| ButtonStates(*s)))
        })
    }

    /// Latest state of button `i` (1 pressed, 0 released or unknown). (Not `state`: that is
    /// the connection state every remote has.)
    fn button_state(slf: PyRef<'_, Self>, i: &Bound<'_, PyAny>) -> PyResult<i32> {
        let b = slf.as_super().inner::<Buttons>()?;
        Ok(b.state(button_arg(&b, i)?).raw())
    }

    /// True when button `i` is pressed.
    fn pressed(slf: PyRef<'_, Self>, i: &Bound<'_, PyAny>) -> PyResult<bool> {
        let b = slf.as_super().inner::<Buttons>()?;
        Ok(b.pressed(button_arg(&b, i)?))
    }

    /// How many times button `i` went down since the last `take_presses(i)` (a click whose
    /// press and release both came between two frames is counted).
    fn take_presses(slf: PyRef<'_, Self>, i: &Bound<'_, PyAny>) -> PyResult<u32> {
        let b = slf.as_super().inner::<Buttons>()?;
        Ok(b.take_presses(button_arg(&b, i)?))
    }

    /// The latest change of button `i`, None until one arrived.
    fn last_change(slf: PyRef<'_, Self>, i: &Bound<'_, PyAny>) -> PyResult<Option<ButtonChange>> {
        let b = slf.as_super().inner::<Buttons>()?;
        Ok(b.last_change(button_arg(&b, i)?).map(ButtonChange))
    }

    /// The latest change of button `i` if it arrived since the last `take_change(i)`.
    fn take_change(slf: PyRef<'_, Self>, i: &Bound<'_, PyAny>) -> PyResult<Option<ButtonChange>> {
        let b = slf.as_super().inner::<Buttons>()?;
        Ok(b.take_change(button_arg(&b, i)?).map(ButtonChange))
    }

    /// Number of buttons (256 until the server's full-state report says).
    #[getter]
    fn num_buttons(slf: PyRef<'_, Self>) -> PyResult<usize> {
        Ok(slf.as_super().inner::<Buttons>()?.num_buttons())
    }
}

/// Client of an analog device: `AnalogRemote("Analog0@host")`.
#[pyclass(extends = Remote, module = "vrpn", name = "AnalogRemote")]
pub(crate) struct AnalogRemote;

type Analog = crate::AnalogRemote;

#[pymethods]
impl AnalogRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Analog::new(name).map_err(to_py)?;
        Ok((AnalogRemote, Remote::new("AnalogRemote", inner)))
    }

    /// Calls `f(report)` for every channel report. Returns a handle.
    fn on_report(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let a = base.inner::<Analog>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            a.on_report(move |r| slot.call_with(|| AnalogReport(*r)))
        })
    }

    /// The latest report, None until one arrived.
    fn latest(slf: PyRef<'_, Self>) -> PyResult<Option<AnalogReport>> {
        let a = slf.as_super().inner::<Analog>()?;
        Ok(a.got_report().then(|| AnalogReport(a.latest())))
    }

    /// The latest report if it arrived since the last `take_report()`, else None.
    fn take_report(slf: PyRef<'_, Self>) -> PyResult<Option<AnalogReport>> {
        let a = slf.as_super().inner::<Analog>()?;
        Ok(a.take_report().map(AnalogReport))
    }

    /// Latest value of channel `i` (0.0 before the first report). Once a report came, a
    /// channel beyond its count raises `vrpn.OutOfRangeError`, as one beyond 128 always does.
    fn channel(slf: PyRef<'_, Self>, i: &Bound<'_, PyAny>) -> PyResult<f64> {
        let a = slf.as_super().inner::<Analog>()?;
        let n = if a.got_report() {
            a.num_channels().min(CHANNEL_MAX)
        } else {
            CHANNEL_MAX
        };
        Ok(a.channel(index(i, "channel", Some(n))?))
    }

    /// Number of channels in the latest report (0 before the first one).
    #[getter]
    fn num_channels(slf: PyRef<'_, Self>) -> PyResult<usize> {
        let a = slf.as_super().inner::<Analog>()?;
        Ok(if a.got_report() { a.num_channels() } else { 0 })
    }
}

/// Client of a dial device: `DialRemote("Dial0@host")`.
#[pyclass(extends = Remote, module = "vrpn", name = "DialRemote")]
pub(crate) struct DialRemote;

type Dial = crate::DialRemote;

#[pymethods]
impl DialRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Dial::new(name).map_err(to_py)?;
        Ok((DialRemote, Remote::new("DialRemote", inner)))
    }

    /// Calls `f(update)` whenever a dial turns. Returns a handle.
    fn on_update(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let d = base.inner::<Dial>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            d.on_update(move |u| slot.call_with(|| DialUpdate(*u)))
        })
    }

    /// The last update of dial `i`, None until one arrived.
    fn last_update(slf: PyRef<'_, Self>, i: &Bound<'_, PyAny>) -> PyResult<Option<DialUpdate>> {
        let d = slf.as_super().inner::<Dial>()?;
        Ok(d.last_update(index(i, "dial", None)?).map(DialUpdate))
    }

    /// Revolutions dial `i` turned since the last `take_rotation(i)` (0.0 when none came).
    fn take_rotation(slf: PyRef<'_, Self>, i: &Bound<'_, PyAny>) -> PyResult<f64> {
        let d = slf.as_super().inner::<Dial>()?;
        Ok(d.take_rotation(index(i, "dial", None)?))
    }
}

/// Receives a device's text messages: `TextReceiver("Tracker0@host")`.
#[pyclass(extends = Remote, module = "vrpn", name = "TextReceiver")]
pub(crate) struct TextReceiver;

type Text = crate::TextReceiver;

#[pymethods]
impl TextReceiver {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Text::new(name).map_err(to_py)?;
        Ok((TextReceiver, Remote::new("TextReceiver", inner)))
    }

    /// Calls `f(message)` for every text message from the device. Returns a handle.
    fn on_message(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let x = base.inner::<Text>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            x.on_message(move |m| slot.call_with(|| TextMessage(*m)))
        })
    }

    /// Messages received so far.
    #[getter]
    fn received(slf: PyRef<'_, Self>) -> PyResult<u64> {
        Ok(slf.as_super().inner::<Text>()?.received())
    }
}

pub(crate) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<TrackerRemote>()?;
    m.add_class::<ButtonRemote>()?;
    m.add_class::<AnalogRemote>()?;
    m.add_class::<DialRemote>()?;
    m.add_class::<TextReceiver>()?;
    Ok(())
}
