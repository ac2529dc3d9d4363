//! The publishing side: `vrpn.Server` (a server connection on a port) and the device servers
//! a script reports through (`TrackerServer`, `ButtonServer`, `AnalogServer`, `DialServer`,
//! `TextSender`). C++ and Rust clients read them like any VRPN server.

use std::net::Ipv4Addr;

use pyo3::exceptions::PyValueError;
use pyo3::gc::PyVisit;
use pyo3::prelude::*;
use pyo3::PyTraverseError;

use super::callbacks::{run, Owner, Registry};
use super::remote::state_name;
use super::remote::{on_event, on_notice, on_state_change, remove_connection_handlers, wait};
use super::{time_or_now, to_py};
use crate::devices::text::TextSeverity;
use crate::Connection;

/// A server connection: UDP and TCP on one port, for any number of clients.
#[pyclass(unsendable, module = "vrpn", name = "Server")]
pub(crate) struct Server {
    conn: Connection,
    reg: Registry,
}

impl Drop for Server {
    fn drop(&mut self) {
        remove_connection_handlers(&self.conn, &self.reg);
    }
}

#[pymethods]
impl Server {
    /// Listens on `port` (3883 by default; 0 picks a free one, see `port`), on every
    /// interface or only on the one with IPv4 address `nic`.
    #[new]
    #[pyo3(signature = (port = 3883, nic = None))]
    fn new(port: u16, nic: Option<&str>) -> PyResult<Self> {
        let nic = match nic {
            None => None,
            Some(text) => Some(text.parse::<Ipv4Addr>().map_err(|e| {
                PyValueError::new_err(format!("nic must be an IPv4 address, got {text:?}: {e}"))
            })?),
        };
        let conn = Connection::server(nic, port).map_err(to_py)?;
        Ok(Server {
            conn,
            reg: Registry::default(),
        })
    }

    /// Accepts clients, answers them and sends what the devices reported. Call it often.
    /// Raises the first exception a callback raised.
    fn mainloop(&self) -> PyResult<()> {
        run(|| self.conn.mainloop())
    }

    /// Sleeps until a client sends something, the connection has work due, or `timeout`
    /// seconds pass, letting other Python threads run; returns whether data arrived. Call
    /// `mainloop()` next.
    fn wait(&self, py: Python<'_>, timeout: f64) -> PyResult<bool> {
        wait(py, &self.conn, timeout)
    }

    /// The port the server listens on.
    #[getter]
    fn port(&self) -> Option<u16> {
        self.conn.local_port()
    }

    /// True while at least one client is connected.
    #[getter]
    fn connected(&self) -> bool {
        self.conn.connected()
    }

    /// Number of connected clients.
    #[getter]
    fn connected_peers(&self) -> usize {
        self.conn.connected_peers()
    }

    /// "listening" (no client) or "connected".
    #[getter]
    fn state(&self) -> &'static str {
        state_name(self.conn.state())
    }

    /// Calls `f()` on a connection event ("got_first_connection", "got_connection",
    /// "dropped_connection", "dropped_last_connection"). Returns a handle.
    fn on_event(&self, event: &str, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_event(&self.conn, &self.reg, event, f)
    }

    /// Calls `f(state)` whenever `state` changes. Returns a handle.
    fn on_state_change(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_state_change(&self.conn, &self.reg, f)
    }

    /// Calls `f(notice)` with the connection's diagnostics. Returns a handle.
    fn on_notice(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_notice(&self.conn, &self.reg, f)
    }

    /// Removes a callback by its handle.
    fn remove_callback(&self, handle: u64) -> PyResult<()> {
        let (id, owner) = self.reg.take(handle)?;
        debug_assert!(owner == Owner::Connection);
        self.conn.remove_handler(id);
        Ok(())
    }

    fn __repr__(&self) -> String {
        let port = self.conn.local_port().unwrap_or(0);
        format!(
            "<vrpn.Server port={port} {}>",
            state_name(self.conn.state())
        )
    }

    fn __traverse__(&self, visit: PyVisit<'_>) -> Result<(), PyTraverseError> {
        self.reg.traverse(&visit)
    }

    fn __clear__(&self) {
        self.reg.clear();
    }
}

fn parse_severity(s: &str) -> PyResult<TextSeverity> {
    match s {
        "normal" => Ok(TextSeverity::Normal),
        "warning" => Ok(TextSeverity::Warning),
        "error" => Ok(TextSeverity::Error),
        _ => Err(PyValueError::new_err(format!(
            "severity must be \"normal\", \"warning\" or \"error\", got {s:?}"
        ))),
    }
}

/// A tracker on a `Server`: `TrackerServer(server, "Tracker0", sensors=1)`.
#[pyclass(unsendable, module = "vrpn", name = "TrackerServer")]
pub(crate) struct TrackerServer {
    inner: crate::TrackerServer,
}

#[pymethods]
impl TrackerServer {
    #[new]
    #[pyo3(signature = (server, name, sensors = 1))]
    fn new(server: PyRef<'_, Server>, name: &str, sensors: usize) -> PyResult<Self> {
        let inner = crate::TrackerServer::new(name, &server.conn, sensors).map_err(to_py)?;
        Ok(TrackerServer { inner })
    }

    /// Reports a pose: position (x, y, z) in metres and quaternion (x, y, z, w), stamped
    /// `time` (seconds since the epoch; now when None).
    #[pyo3(signature = (sensor, pos, quat, time = None))]
    fn report_pose(
        &self,
        sensor: i32,
        pos: [f64; 3],
        quat: [f64; 4],
        time: Option<f64>,
    ) -> PyResult<()> {
        let t = time_or_now(time, self.inner.connection())?;
        run(|| self.inner.report_pose(sensor, t, pos, quat))
    }

    /// Reports a velocity: linear (x, y, z) m/s and the rotation `vel_quat` the sensor
    /// undergoes during `dt` seconds.
    #[pyo3(signature = (sensor, vel, vel_quat = [0.0, 0.0, 0.0, 1.0], dt = 1.0, time = None))]
    fn report_velocity(
        &self,
        sensor: i32,
        vel: [f64; 3],
        vel_quat: [f64; 4],
        dt: f64,
        time: Option<f64>,
    ) -> PyResult<()> {
        let t = time_or_now(time, self.inner.connection())?;
        run(|| self.inner.report_velocity(sensor, t, vel, vel_quat, dt))
    }

    /// Sends a text message from this device ("normal", "warning" or "error").
    #[pyo3(signature = (text, severity = "normal", level = 0))]
    fn send_text(&self, text: &str, severity: &str, level: u32) -> PyResult<()> {
        let s = parse_severity(severity)?;
        run(|| self.inner.send_text(s, level, text))
    }

    /// Number of sensors.
    #[getter]
    fn num_sensors(&self) -> usize {
        self.inner.num_sensors()
    }
}

/// Buttons on a `Server`: `ButtonServer(server, "Button0", buttons=1)`.
#[pyclass(unsendable, module = "vrpn", name = "ButtonServer")]
pub(crate) struct ButtonServer {
    inner: crate::ButtonServer,
}

#[pymethods]
impl ButtonServer {
    #[new]
    #[pyo3(signature = (server, name, buttons = 1))]
    fn new(server: PyRef<'_, Server>, name: &str, buttons: usize) -> PyResult<Self> {
        let inner = crate::ButtonServer::new(name, &server.conn, buttons).map_err(to_py)?;
        Ok(ButtonServer { inner })
    }

    /// Sets whether button `i` is pressed; `report_changes()` sends it.
    fn set_button(&self, i: usize, pressed: bool) -> PyResult<()> {
        if i >= self.inner.num_buttons() {
            return Err(PyValueError::new_err(format!(
                "button {i} out of range: this server has {} buttons",
                self.inner.num_buttons()
            )));
        }
        self.inner.set_button(i, pressed);
        Ok(())
    }

    /// Sends one change per button whose state changed, stamped `time` (now when None).
    #[pyo3(signature = (time = None))]
    fn report_changes(&self, time: Option<f64>) -> PyResult<()> {
        self.inner
            .set_timestamp(time_or_now(time, self.inner.connection())?);
        run(|| self.inner.report_changes())
    }

    /// Sends the state of every button now.
    fn report_states(&self) -> PyResult<()> {
        run(|| self.inner.report_states())
    }

    /// Number of buttons.
    #[getter]
    fn num_buttons(&self) -> usize {
        self.inner.num_buttons()
    }
}

/// Analog channels on a `Server`: `AnalogServer(server, "Analog0", channels=1)`.
#[pyclass(unsendable, module = "vrpn", name = "AnalogServer")]
pub(crate) struct AnalogServer {
    inner: crate::AnalogServer,
}

#[pymethods]
impl AnalogServer {
    #[new]
    #[pyo3(signature = (server, name, channels = 1))]
    fn new(server: PyRef<'_, Server>, name: &str, channels: usize) -> PyResult<Self> {
        let inner = crate::AnalogServer::new(name, &server.conn, channels).map_err(to_py)?;
        Ok(AnalogServer { inner })
    }

    /// Sets channel `i`; `report()` or `report_changes()` sends it.
    fn set_channel(&mut self, i: usize, value: f64) -> PyResult<()> {
        let n = self.inner.num_channels();
        match self.inner.channels_mut().get_mut(i) {
            Some(c) => *c = value,
            None => {
                return Err(PyValueError::new_err(format!(
                    "channel {i} out of range: this server has {n} channels"
                )))
            }
        }
        Ok(())
    }

    /// Sends every channel, stamped `time` (now when None). With `values`, sets the
    /// channels from it first (as many as given, at most the channel count).
    #[pyo3(signature = (values = None, time = None))]
    fn report(&mut self, values: Option<Vec<f64>>, time: Option<f64>) -> PyResult<()> {
        if let Some(v) = values {
            let n = self.inner.num_channels();
            if v.len() > n {
                return Err(PyValueError::new_err(format!(
                    "{} values given for {n} channels",
                    v.len()
                )));
            }
            self.inner.channels_mut()[..v.len()].copy_from_slice(&v);
        }
        let t = time_or_now(time, self.inner.connection())?;
        run(|| self.inner.report(Some(t)))
    }

    /// Sends every channel if any changed since the last report; returns whether it sent.
    #[pyo3(signature = (time = None))]
    fn report_changes(&mut self, time: Option<f64>) -> PyResult<bool> {
        let t = time_or_now(time, self.inner.connection())?;
        run(|| self.inner.report_changes(Some(t)))
    }

    /// Number of channels.
    #[getter]
    fn num_channels(&self) -> usize {
        self.inner.num_channels()
    }
}

/// Dials on a `Server`: `DialServer(server, "Dial0", dials=1)`.
#[pyclass(unsendable, module = "vrpn", name = "DialServer")]
pub(crate) struct DialServer {
    inner: crate::DialServer,
    conn: Connection,
}

#[pymethods]
impl DialServer {
    #[new]
    #[pyo3(signature = (server, name, dials = 1))]
    fn new(server: PyRef<'_, Server>, name: &str, dials: usize) -> PyResult<Self> {
        let inner = crate::DialServer::new(name, &server.conn, dials).map_err(to_py)?;
        Ok(DialServer {
            inner,
            conn: server.conn.clone(),
        })
    }

    /// Sends one update: dial `i` turned `revolutions` since the last one, at `time`.
    #[pyo3(signature = (i, revolutions, time = None))]
    fn report_rotation(&mut self, i: usize, revolutions: f64, time: Option<f64>) -> PyResult<()> {
        if i >= self.inner.num_dials() {
            return Err(PyValueError::new_err(format!(
                "dial {i} out of range: this server has {} dials",
                self.inner.num_dials()
            )));
        }
        self.inner.set_timestamp(time_or_now(time, &self.conn)?);
        self.inner.set_dial(i, revolutions);
        run(|| self.inner.report_changes())
    }

    /// Number of dials.
    #[getter]
    fn num_dials(&self) -> usize {
        self.inner.num_dials()
    }
}

/// Sends text messages as a device: `TextSender(server, "Tracker0")`.
#[pyclass(unsendable, module = "vrpn", name = "TextSender")]
pub(crate) struct TextSender {
    inner: crate::TextSender,
}

#[pymethods]
impl TextSender {
    #[new]
    fn new(server: PyRef<'_, Server>, name: &str) -> PyResult<Self> {
        let inner = crate::TextSender::new(name, &server.conn).map_err(to_py)?;
        Ok(TextSender { inner })
    }

    /// Sends `text` (at most 1023 bytes) with a severity ("normal", "warning", "error").
    #[pyo3(signature = (text, severity = "normal", level = 0, time = None))]
    fn send(&self, text: &str, severity: &str, level: u32, time: Option<f64>) -> PyResult<()> {
        let s = parse_severity(severity)?;
        let t = time.map(super::header_time).transpose()?;
        run(|| self.inner.send_message(text, s, level, t))
    }
}

pub(crate) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Server>()?;
    m.add_class::<TrackerServer>()?;
    m.add_class::<ButtonServer>()?;
    m.add_class::<AnalogServer>()?;
    m.add_class::<DialServer>()?;
    m.add_class::<TextSender>()?;
    Ok(())
}
