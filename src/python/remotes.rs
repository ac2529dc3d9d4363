//! The device remotes: `TrackerRemote`, `ButtonRemote`, `AnalogRemote`, `DialRemote`,
//! `TextReceiver`, each a subclass of `vrpn.Remote` holding the Rust remote it shares with it.

use std::rc::Rc;

use pyo3::prelude::*;

use super::callbacks::Owner;
use super::remote::Remote;
use super::to_py;
use super::values::{
    Acceleration, AnalogReport, ButtonChange, ButtonStates, DialUpdate, Pose, TextMessage, Velocity,
};

/// Client of a tracker: `TrackerRemote("Tracker0@host")`.
#[pyclass(extends = Remote, unsendable, module = "vrpn", name = "TrackerRemote")]
pub(crate) struct TrackerRemote {
    inner: Rc<crate::TrackerRemote>,
}

#[pymethods]
impl TrackerRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Rc::new(crate::TrackerRemote::new(name).map_err(to_py)?);
        Ok((
            TrackerRemote {
                inner: inner.clone(),
            },
            Remote::new(inner),
        ))
    }

    /// Calls `f(pose)` for every pose report (only sensor `sensor`'s when given). Returns a
    /// handle for `remove_callback`.
    #[pyo3(signature = (f, sensor = None))]
    fn on_pose(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>, sensor: Option<usize>) -> PyResult<u64> {
        let inner = slf.inner.clone();
        slf.as_super()
            .reg
            .add(f, Owner::Device, |slot| match sensor {
                Some(s) => inner.on_sensor_pose(s, move |p| slot.call_with(|| Pose(*p))),
                None => inner.on_pose(move |p| slot.call_with(|| Pose(*p))),
            })
    }

    /// Calls `f(velocity)` for every velocity report. Returns a handle.
    fn on_velocity(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let inner = slf.inner.clone();
        slf.as_super().reg.add(f, Owner::Device, |slot| {
            inner.on_velocity(move |v| slot.call_with(|| Velocity(*v)))
        })
    }

    /// Calls `f(acceleration)` for every acceleration report. Returns a handle.
    fn on_acceleration(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let inner = slf.inner.clone();
        slf.as_super().reg.add(f, Owner::Device, |slot| {
            inner.on_acceleration(move |a| slot.call_with(|| Acceleration(*a)))
        })
    }

    /// The latest pose of `sensor`, None until one arrived.
    #[pyo3(signature = (sensor = 0))]
    fn pose(&self, sensor: usize) -> Option<Pose> {
        self.inner.pose(sensor).map(Pose)
    }

    /// The latest velocity of `sensor`, None until one arrived.
    #[pyo3(signature = (sensor = 0))]
    fn velocity(&self, sensor: usize) -> Option<Velocity> {
        self.inner.velocity(sensor).map(Velocity)
    }

    /// The latest acceleration of `sensor`, None until one arrived.
    #[pyo3(signature = (sensor = 0))]
    fn acceleration(&self, sensor: usize) -> Option<Acceleration> {
        self.inner.acceleration(sensor).map(Acceleration)
    }

    /// Sensor slots seen so far (highest sensor index + 1).
    #[getter]
    fn sensor_count(&self) -> usize {
        self.inner.sensor_count()
    }

    /// Asks the server for `hz` reports per second (servers that cannot, ignore it).
    fn set_update_rate(&self, hz: f64) -> PyResult<()> {
        self.inner.set_update_rate(hz).map_err(to_py)
    }

    /// Asks the server to re-zero its origin (servers that cannot, ignore it).
    fn reset_origin(&self) -> PyResult<()> {
        self.inner.reset_origin().map_err(to_py)
    }
}

/// Client of a button device: `ButtonRemote("Button0@host")`.
#[pyclass(extends = Remote, unsendable, module = "vrpn", name = "ButtonRemote")]
pub(crate) struct ButtonRemote {
    inner: Rc<crate::ButtonRemote>,
}

#[pymethods]
impl ButtonRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Rc::new(crate::ButtonRemote::new(name).map_err(to_py)?);
        Ok((
            ButtonRemote {
                inner: inner.clone(),
            },
            Remote::new(inner),
        ))
    }

    /// Calls `f(change)` whenever a button is pressed or released. Returns a handle.
    fn on_change(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let inner = slf.inner.clone();
        slf.as_super().reg.add(f, Owner::Device, |slot| {
            inner.on_change(move |c| slot.call_with(|| ButtonChange(*c)))
        })
    }

    /// Calls `f(states)` with every full-state report (sent on connection). Returns a handle.
    fn on_states(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let inner = slf.inner.clone();
        slf.as_super().reg.add(f, Owner::Device, |slot| {
            inner.on_states(move |s| slot.call_with(|| ButtonStates(*s)))
        })
    }

    /// Latest state of button `i` (1 pressed, 0 released or unknown). (Not `state`: that is
    /// the connection state every remote has.)
    fn button_state(&self, i: usize) -> i32 {
        self.inner.state(i).raw()
    }

    /// True when button `i` is pressed.
    fn pressed(&self, i: usize) -> bool {
        self.inner.pressed(i)
    }

    /// Number of buttons (256 until the server's full-state report says).
    #[getter]
    fn num_buttons(&self) -> usize {
        self.inner.num_buttons()
    }
}

/// Client of an analog device: `AnalogRemote("Analog0@host")`.
#[pyclass(extends = Remote, unsendable, module = "vrpn", name = "AnalogRemote")]
pub(crate) struct AnalogRemote {
    inner: Rc<crate::AnalogRemote>,
}

#[pymethods]
impl AnalogRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Rc::new(crate::AnalogRemote::new(name).map_err(to_py)?);
        Ok((
            AnalogRemote {
                inner: inner.clone(),
            },
            Remote::new(inner),
        ))
    }

    /// Calls `f(report)` for every channel report. Returns a handle.
    fn on_report(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let inner = slf.inner.clone();
        slf.as_super().reg.add(f, Owner::Device, |slot| {
            inner.on_report(move |r| slot.call_with(|| AnalogReport(*r)))
        })
    }

    /// The latest report, None until one arrived.
    fn latest(&self) -> Option<AnalogReport> {
        self.inner
            .got_report()
            .then(|| AnalogReport(self.inner.latest()))
    }

    /// Latest value of channel `i` (0.0 before any report or beyond the count).
    fn channel(&self, i: usize) -> f64 {
        self.inner.channel(i)
    }

    /// Number of channels in the latest report (0 before the first one).
    #[getter]
    fn num_channels(&self) -> usize {
        if self.inner.got_report() {
            self.inner.num_channels()
        } else {
            0
        }
    }
}

/// Client of a dial device: `DialRemote("Dial0@host")`.
#[pyclass(extends = Remote, unsendable, module = "vrpn", name = "DialRemote")]
pub(crate) struct DialRemote {
    inner: Rc<crate::DialRemote>,
}

#[pymethods]
impl DialRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Rc::new(crate::DialRemote::new(name).map_err(to_py)?);
        Ok((
            DialRemote {
                inner: inner.clone(),
            },
            Remote::new(inner),
        ))
    }

    /// Calls `f(update)` whenever a dial turns. Returns a handle.
    fn on_update(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let inner = slf.inner.clone();
        slf.as_super().reg.add(f, Owner::Device, |slot| {
            inner.on_update(move |u| slot.call_with(|| DialUpdate(*u)))
        })
    }
}

/// Receives a device's text messages: `TextReceiver("Tracker0@host")`.
#[pyclass(extends = Remote, unsendable, module = "vrpn", name = "TextReceiver")]
pub(crate) struct TextReceiver {
    inner: Rc<crate::TextReceiver>,
}

#[pymethods]
impl TextReceiver {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = Rc::new(crate::TextReceiver::new(name).map_err(to_py)?);
        Ok((
            TextReceiver {
                inner: inner.clone(),
            },
            Remote::new(inner),
        ))
    }

    /// Calls `f(message)` for every text message from the device. Returns a handle.
    fn on_message(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let inner = slf.inner.clone();
        slf.as_super().reg.add(f, Owner::Device, |slot| {
            inner.on_message(move |m| slot.call_with(|| TextMessage(*m)))
        })
    }

    /// Messages received so far.
    #[getter]
    fn received(&self) -> u64 {
        self.inner.received()
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
