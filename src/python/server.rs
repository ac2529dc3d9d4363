//! The publishing side: `vrpn.Server` (a server connection on a port) and the device servers
//! a script reports through (`TrackerServer`, `ButtonServer`, `AnalogServer`, `DialServer`,
//! `TextSender`). C++ and Rust clients read them like any VRPN server.
//!
//! A device server is made on a `Server` with the checks every binding applies
//! ([`crate::server::limits`]: counts as in `vrpn.cfg`, names clients can open, one device of
//! each interface per name). The `Server` keeps a weak handle on each: `close()` (or leaving
//! a `with` block, or dropping the `Server`) releases them all with the connection, so the
//! port is free again at once.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::rc::{Rc, Weak};

use pyo3::exceptions::PyValueError;
use pyo3::gc::PyVisit;
use pyo3::prelude::*;
use pyo3::PyTraverseError;

use super::args::{count, index};
use super::callbacks::{run, Owner, Registry};
use super::errors::{closed, limit, publish};
use super::owned::Owned;
use super::remote::{
    on_event, on_notice, on_peer_sender, on_state_change, remove_connection_handlers, state_name,
};
use super::waiting::{fileno, wait};
use super::{time_or_now, to_py};
use crate::devices::text::TextSeverity;
use crate::server::limits::{Claim, Interface, Published};
use crate::Connection;

/// Something the `Server` releases when it closes.
pub(crate) trait Release {
    fn release(&self);
}

/// A device server's Rust side, until its `close()` or its `Server`'s.
pub(crate) struct Held<T>(RefCell<Option<Rc<T>>>);

impl<T> Held<T> {
    /// The Rust side, until closed.
    pub(crate) fn get(&self) -> Option<Rc<T>> {
        self.0.borrow().clone()
    }
}

impl<T> Release for Held<T> {
    fn release(&self) {
        let gone = self.0.borrow_mut().take();
        drop(gone);
    }
}

/// What a `Server` holds on its thread.
struct ServerState {
    /// `None` once closed.
    conn: RefCell<Option<Connection>>,
    reg: Registry,
    published: Published,
    devices: RefCell<Vec<Weak<dyn Release>>>,
}

impl ServerState {
    fn close(&self) {
        let conn = self.conn.borrow_mut().take();
        if let Some(c) = conn {
            remove_connection_handlers(&c, &self.reg);
        }
        let devices = std::mem::take(&mut *self.devices.borrow_mut());
        for d in devices.iter().filter_map(Weak::upgrade) {
            d.release();
        }
        self.reg.clear();
    }
}

impl Drop for ServerState {
    fn drop(&mut self) {
        self.close();
    }
}

/// A server connection: UDP and TCP on one port, for any number of clients.
#[pyclass(module = "vrpn", name = "Server")]
pub(crate) struct Server {
    state: Owned<ServerState>,
}

impl Server {
    fn st(&self) -> PyResult<&ServerState> {
        self.state.get("Server")
    }

    fn conn(&self) -> PyResult<Connection> {
        self.st()?
            .conn
            .borrow()
            .clone()
            .ok_or_else(|| closed("Server"))
    }

    /// Makes an object on the server's connection that the server's `close()` releases with
    /// it, without a device name claim (mutexes, shared objects: `src/python/families/`).
    pub(crate) fn adopt<T: 'static>(
        &self,
        make: impl FnOnce(&Connection) -> Result<T, crate::Error>,
    ) -> PyResult<Owned<Rc<Held<T>>>> {
        let conn = self.conn()?;
        let st = self.st()?;
        let held = Rc::new(Held(RefCell::new(Some(Rc::new(
            make(&conn).map_err(to_py)?,
        )))));
        let weak: Weak<dyn Release> = Rc::downgrade(&held) as Weak<dyn Release>;
        let mut devices = st.devices.borrow_mut();
        devices.retain(|d| d.strong_count() > 0);
        devices.push(weak);
        Ok(Owned::new(held))
    }

    /// Makes a device server of `kind` named `name` with `n` elements (already checked).
    fn publish<T: 'static>(
        &self,
        kind: Interface,
        name: &str,
        n: usize,
        make: impl FnOnce(&Connection, usize, Claim) -> Result<T, crate::Error>,
    ) -> PyResult<Owned<Rc<Held<T>>>> {
        let conn = self.conn()?;
        let st = self.st()?;
        let claim = st.published.claim(kind, name).map_err(publish)?;
        let held = Rc::new(Held(RefCell::new(Some(Rc::new(
            make(&conn, n, claim).map_err(to_py)?,
        )))));
        let weak: Weak<dyn Release> = Rc::downgrade(&held) as Weak<dyn Release>;
        let mut devices = st.devices.borrow_mut();
        devices.retain(|d| d.strong_count() > 0);
        devices.push(weak);
        Ok(Owned::new(held))
    }
}

#[pymethods]
impl Server {
    /// Listens on `port` (3883 by default; 0 picks a free one, see `port`), on every
    /// interface or only on the one with IPv4 address `nic`.
    #[new]
    #[pyo3(signature = (port = None, nic = None), text_signature = "(port=3883, nic=None)")]
    fn new(port: Option<&Bound<'_, PyAny>>, nic: Option<&str>) -> PyResult<Self> {
        let port = port.map_or(Ok(3883), super::args::port)?;
        let nic = match nic {
            None => None,
            Some(text) => Some(text.parse::<Ipv4Addr>().map_err(|e| {
                PyValueError::new_err(format!("nic must be an IPv4 address, got {text:?}: {e}"))
            })?),
        };
        let conn = Connection::server(nic, port).map_err(to_py)?;
        Ok(Server {
            state: Owned::new(ServerState {
                conn: RefCell::new(Some(conn)),
                reg: Registry::default(),
                published: Published::default(),
                devices: RefCell::new(Vec::new()),
            }),
        })
    }

    /// Accepts clients, answers them and sends what the devices reported. Call it often.
    /// Raises the first exception a callback raised.
    fn mainloop(&self) -> PyResult<()> {
        let conn = self.conn()?;
        run(|| conn.mainloop())
    }

    /// Sleeps until a client sends something, the connection has work due, or `timeout`
    /// seconds pass, letting other Python threads run; returns whether data arrived. Call
    /// `mainloop()` next.
    fn wait(&self, py: Python<'_>, timeout: f64) -> PyResult<bool> {
        wait(py, &self.conn()?, timeout)
    }

    /// The descriptor to wait on in asyncio (`loop.add_reader(s.fileno(), s.mainloop)`) or
    /// `select`: readable when a client sends something or the server has timed work due.
    fn fileno(&self) -> PyResult<i32> {
        fileno(&self.conn()?)
    }

    /// The port the server listens on.
    #[getter]
    fn port(&self) -> PyResult<Option<u16>> {
        Ok(self.conn()?.local_port())
    }

    /// True while at least one client is connected.
    #[getter]
    fn connected(&self) -> PyResult<bool> {
        Ok(self.conn()?.connected())
    }

    /// Number of connected clients.
    #[getter]
    fn connected_peers(&self) -> PyResult<usize> {
        Ok(self.conn()?.connected_peers())
    }

    /// "listening" (no client) or "connected".
    #[getter]
    fn state(&self) -> PyResult<&'static str> {
        Ok(state_name(self.conn()?.state()))
    }

    /// True once `close()` was called.
    #[getter]
    fn closed(&self) -> PyResult<bool> {
        Ok(self.st()?.conn.borrow().is_none())
    }

    /// Calls `f()` on a connection event ("got_first_connection", "got_connection",
    /// "dropped_connection", "dropped_last_connection"). Returns a handle.
    fn on_event(&self, event: &str, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_event(&self.conn()?, &self.st()?.reg, event, f)
    }

    /// Calls `f(state)` whenever `state` changes. Returns a handle.
    fn on_state_change(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_state_change(&self.conn()?, &self.st()?.reg, f)
    }

    /// Calls `f(notice)` with the connection's diagnostics. Returns a handle.
    fn on_notice(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_notice(&self.conn()?, &self.st()?.reg, f)
    }

    /// Calls `f(name)` with each sender name a client describes (its remotes' device
    /// names). Returns a handle.
    fn on_peer_sender(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_peer_sender(&self.conn()?, &self.st()?.reg, f)
    }

    /// The sender names the connected clients have described.
    #[getter]
    fn peer_senders(&self) -> PyResult<Vec<String>> {
        Ok(self.conn()?.peer_senders())
    }

    /// Removes a callback by its handle.
    fn remove_callback(&self, handle: u64) -> PyResult<()> {
        let conn = self.conn()?;
        let (id, owner) = self.st()?.reg.take(handle)?;
        debug_assert!(owner == Owner::Connection);
        conn.remove_handler(id);
        Ok(())
    }

    /// Closes the server now: its port is released, its clients are dropped and every
    /// device server made on it is closed too. Later use raises `vrpn.ClosedError`; closing
    /// twice is fine. (Leaving a `with` block, or dropping the last reference, does the same.)
    fn close(&self) -> PyResult<()> {
        self.st()?.close();
        Ok(())
    }

    fn __enter__(slf: Bound<'_, Self>) -> Bound<'_, Self> {
        slf
    }

    fn __exit__(
        &self,
        _ty: &Bound<'_, PyAny>,
        _value: &Bound<'_, PyAny>,
        _traceback: &Bound<'_, PyAny>,
    ) -> PyResult<bool> {
        self.close()?;
        Ok(false)
    }

    fn __repr__(&self) -> String {
        let Some(st) = self.state.mine() else {
            return "<vrpn.Server of another thread>".to_owned();
        };
        match st.conn.borrow().as_ref() {
            None => "<vrpn.Server closed>".to_owned(),
            Some(c) => format!(
                "<vrpn.Server port={} {}>",
                c.local_port().unwrap_or(0),
                state_name(c.state())
            ),
        }
    }

    fn __traverse__(&self, visit: PyVisit<'_>) -> Result<(), PyTraverseError> {
        match self.state.mine() {
            Some(st) => st.reg.traverse(&visit),
            None => Ok(()),
        }
    }

    fn __clear__(&self) {
        if let Some(st) = self.state.mine() {
            st.reg.clear();
        }
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

/// The count argument of a device server (`default` when omitted), checked.
fn count_arg(obj: Option<&Bound<'_, PyAny>>, kind: Interface) -> PyResult<usize> {
    match obj {
        Some(o) => count(o, kind),
        None => Ok(1),
    }
}

/// A device server's Rust side as its Python object reaches it.
pub(crate) fn held<'a, T>(h: &'a Owned<Rc<Held<T>>>, class: &'static str) -> PyResult<Rc<T>> {
    let h: &'a Rc<Held<T>> = h.get(class)?;
    let inner = h.0.borrow();
    inner.clone().ok_or_else(|| closed(class))
}

/// Closes a device server (its name is free again on the server).
pub(crate) fn close_held<T>(h: &Owned<Rc<Held<T>>>, class: &'static str) -> PyResult<()> {
    h.get(class)?.release();
    Ok(())
}

/// A tracker on a `Server`, with what keeps its name.
struct TrackerDev {
    server: crate::TrackerServer,
    _name: Claim,
}

/// A tracker on a `Server`: `TrackerServer(server, "Tracker0", sensors=1)`.
#[pyclass(module = "vrpn", name = "TrackerServer")]
pub(crate) struct TrackerServer {
    held: Owned<Rc<Held<TrackerDev>>>,
}

impl TrackerServer {
    fn dev(&self) -> PyResult<Rc<TrackerDev>> {
        held(&self.held, "TrackerServer")
    }
}

#[pymethods]
impl TrackerServer {
    #[new]
    #[pyo3(
        signature = (server, name, sensors = None),
        text_signature = "(server, name, sensors=1)"
    )]
    fn new(
        server: PyRef<'_, Server>,
        name: &str,
        sensors: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let n = count_arg(sensors, Interface::Tracker)?;
        let held = server.publish(Interface::Tracker, name, n, |conn, n, claim| {
            Ok(TrackerDev {
                server: crate::TrackerServer::new(name, conn, n)?,
                _name: claim,
            })
        })?;
        Ok(TrackerServer { held })
    }

    /// Reports a pose: position (x, y, z) in metres and quaternion (x, y, z, w), stamped
    /// `time` (seconds since the epoch; now when None).
    #[pyo3(signature = (sensor, pos, quat, time = None))]
    fn report_pose(
        &self,
        sensor: &Bound<'_, PyAny>,
        pos: [f64; 3],
        quat: [f64; 4],
        time: Option<f64>,
    ) -> PyResult<()> {
        let d = self.dev()?;
        let s = index(sensor, "sensor", Some(d.server.num_sensors()))?;
        let t = time_or_now(time, d.server.connection())?;
        run(|| d.server.report_pose(s, t, pos, quat))
    }

    /// Reports a velocity: linear (x, y, z) m/s in the tracker's frame, and `vel_quat`, the
    /// rotation (x, y, z, w, in the tracker's frame) the sensor undergoes during `dt` seconds.
    #[pyo3(signature = (sensor, vel, vel_quat = [0.0, 0.0, 0.0, 1.0], dt = 1.0, time = None))]
    fn report_velocity(
        &self,
        sensor: &Bound<'_, PyAny>,
        vel: [f64; 3],
        vel_quat: [f64; 4],
        dt: f64,
        time: Option<f64>,
    ) -> PyResult<()> {
        let d = self.dev()?;
        let s = index(sensor, "sensor", Some(d.server.num_sensors()))?;
        let t = time_or_now(time, d.server.connection())?;
        run(|| d.server.report_velocity(s, t, vel, vel_quat, dt))
    }

    /// Sends a text message from this device ("normal", "warning" or "error").
    #[pyo3(signature = (text, severity = "normal", level = 0))]
    fn send_text(&self, text: &str, severity: &str, level: u32) -> PyResult<()> {
        let s = parse_severity(severity)?;
        let d = self.dev()?;
        run(|| d.server.send_text(s, level, text))
    }

    /// Number of sensors.
    #[getter]
    fn num_sensors(&self) -> PyResult<usize> {
        Ok(self.dev()?.server.num_sensors())
    }

    /// Stops serving this tracker (its name is free again on the server).
    fn close(&self) -> PyResult<()> {
        close_held(&self.held, "TrackerServer")
    }
}

/// Buttons on a `Server`, with what keeps their name.
struct ButtonDev {
    server: crate::ButtonServer,
    _name: Claim,
}

/// Buttons on a `Server`: `ButtonServer(server, "Button0", buttons=1)`.
#[pyclass(module = "vrpn", name = "ButtonServer")]
pub(crate) struct ButtonServer {
    held: Owned<Rc<Held<ButtonDev>>>,
}

impl ButtonServer {
    fn dev(&self) -> PyResult<Rc<ButtonDev>> {
        held(&self.held, "ButtonServer")
    }
}

#[pymethods]
impl ButtonServer {
    #[new]
    #[pyo3(
        signature = (server, name, buttons = None),
        text_signature = "(server, name, buttons=1)"
    )]
    fn new(
        server: PyRef<'_, Server>,
        name: &str,
        buttons: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let n = count_arg(buttons, Interface::Button)?;
        let held = server.publish(Interface::Button, name, n, |conn, n, claim| {
            Ok(ButtonDev {
                server: crate::ButtonServer::new(name, conn, n)?,
                _name: claim,
            })
        })?;
        Ok(ButtonServer { held })
    }

    /// Sets whether button `i` is pressed; `report_changes()` sends it.
    fn set_button(&self, i: &Bound<'_, PyAny>, pressed: bool) -> PyResult<()> {
        let d = self.dev()?;
        let i = index(i, "button", Some(d.server.num_buttons()))?;
        d.server.set_button(i, pressed);
        Ok(())
    }

    /// Sends one change per button whose state changed, stamped `time` (now when None).
    #[pyo3(signature = (time = None))]
    fn report_changes(&self, time: Option<f64>) -> PyResult<()> {
        let d = self.dev()?;
        d.server
            .set_timestamp(time_or_now(time, d.server.connection())?);
        run(|| d.server.report_changes())
    }

    /// Sends the state of every button now.
    fn report_states(&self) -> PyResult<()> {
        let d = self.dev()?;
        run(|| d.server.report_states())
    }

    /// Number of buttons.
    #[getter]
    fn num_buttons(&self) -> PyResult<usize> {
        Ok(self.dev()?.server.num_buttons())
    }

    /// Stops serving these buttons (their name is free again on the server).
    fn close(&self) -> PyResult<()> {
        close_held(&self.held, "ButtonServer")
    }
}

/// Analog channels on a `Server`, with what keeps their name.
struct AnalogDev {
    server: RefCell<crate::AnalogServer>,
    _name: Claim,
}

impl AnalogDev {
    fn server(&self) -> PyResult<std::cell::RefMut<'_, crate::AnalogServer>> {
        self.server.try_borrow_mut().map_err(|_| {
            super::errors::VrpnError::new_err("AnalogServer called again from its own report")
        })
    }
}

/// Analog channels on a `Server`: `AnalogServer(server, "Analog0", channels=1)`.
#[pyclass(module = "vrpn", name = "AnalogServer")]
pub(crate) struct AnalogServer {
    held: Owned<Rc<Held<AnalogDev>>>,
}

impl AnalogServer {
    fn dev(&self) -> PyResult<Rc<AnalogDev>> {
        held(&self.held, "AnalogServer")
    }
}

#[pymethods]
impl AnalogServer {
    #[new]
    #[pyo3(
        signature = (server, name, channels = None),
        text_signature = "(server, name, channels=1)"
    )]
    fn new(
        server: PyRef<'_, Server>,
        name: &str,
        channels: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let n = count_arg(channels, Interface::Analog)?;
        let held = server.publish(Interface::Analog, name, n, |conn, n, claim| {
            Ok(AnalogDev {
                server: RefCell::new(crate::AnalogServer::new(name, conn, n)?),
                _name: claim,
            })
        })?;
        Ok(AnalogServer { held })
    }

    /// Sets channel `i`; `report()` or `report_changes()` sends it.
    fn set_channel(&self, i: &Bound<'_, PyAny>, value: f64) -> PyResult<()> {
        let d = self.dev()?;
        let mut s = d.server()?;
        let i = index(i, "channel", Some(s.num_channels()))?;
        s.set_channel(i, value);
        Ok(())
    }

    /// Sends every channel, stamped `time` (now when None). With `values`, sets the
    /// channels from it first (as many as given, at most the channel count).
    #[pyo3(signature = (values = None, time = None))]
    fn report(&self, values: Option<Vec<f64>>, time: Option<f64>) -> PyResult<()> {
        let d = self.dev()?;
        let mut s = d.server()?;
        if let Some(v) = values {
            let n = s.num_channels();
            if v.len() > n {
                return Err(limit(format!("{} values given for {n} channels", v.len())));
            }
            s.channels_mut()[..v.len()].copy_from_slice(&v);
        }
        let t = time_or_now(time, s.connection())?;
        run(|| s.report(Some(t)))
    }

    /// Sends every channel if any changed since the last report; returns whether it sent.
    #[pyo3(signature = (time = None))]
    fn report_changes(&self, time: Option<f64>) -> PyResult<bool> {
        let d = self.dev()?;
        let mut s = d.server()?;
        let t = time_or_now(time, s.connection())?;
        run(|| s.report_changes(Some(t)))
    }

    /// Number of channels.
    #[getter]
    fn num_channels(&self) -> PyResult<usize> {
        Ok(self.dev()?.server()?.num_channels())
    }

    /// Stops serving these channels (their name is free again on the server).
    fn close(&self) -> PyResult<()> {
        close_held(&self.held, "AnalogServer")
    }
}

/// Dials on a `Server`, with what keeps their name.
struct DialDev {
    server: RefCell<crate::DialServer>,
    _name: Claim,
}

/// Dials on a `Server`: `DialServer(server, "Dial0", dials=1)`.
#[pyclass(module = "vrpn", name = "DialServer")]
pub(crate) struct DialServer {
    held: Owned<Rc<Held<DialDev>>>,
}

impl DialServer {
    fn dev(&self) -> PyResult<Rc<DialDev>> {
        held(&self.held, "DialServer")
    }
}

#[pymethods]
impl DialServer {
    #[new]
    #[pyo3(
        signature = (server, name, dials = None),
        text_signature = "(server, name, dials=1)"
    )]
    fn new(
        server: PyRef<'_, Server>,
        name: &str,
        dials: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let n = count_arg(dials, Interface::Dial)?;
        let held = server.publish(Interface::Dial, name, n, |conn, n, claim| {
            Ok(DialDev {
                server: RefCell::new(crate::DialServer::new(name, conn, n)?),
                _name: claim,
            })
        })?;
        Ok(DialServer { held })
    }

    /// Sends one update: dial `i` turned `revolutions` since the last one, at `time`.
    #[pyo3(signature = (i, revolutions, time = None))]
    fn report_rotation(
        &self,
        i: &Bound<'_, PyAny>,
        revolutions: f64,
        time: Option<f64>,
    ) -> PyResult<()> {
        let d = self.dev()?;
        let mut s = d.server.try_borrow_mut().map_err(|_| {
            super::errors::VrpnError::new_err("DialServer called again from its own report")
        })?;
        let i = index(i, "dial", Some(s.num_dials()))?;
        let t = time_or_now(time, s.connection())?;
        s.set_timestamp(t);
        s.set_dial(i, revolutions);
        run(|| s.report_changes())
    }

    /// Number of dials.
    #[getter]
    fn num_dials(&self) -> PyResult<usize> {
        Ok(self.dev()?.server.borrow().num_dials())
    }

    /// Stops serving these dials (their name is free again on the server).
    fn close(&self) -> PyResult<()> {
        close_held(&self.held, "DialServer")
    }
}

/// A text sender on a `Server`, with what keeps its name.
struct TextDev {
    sender: crate::TextSender,
    _name: Claim,
}

/// Sends text messages as a device: `TextSender(server, "Tracker0")`.
#[pyclass(module = "vrpn", name = "TextSender")]
pub(crate) struct TextSender {
    held: Owned<Rc<Held<TextDev>>>,
}

#[pymethods]
impl TextSender {
    #[new]
    fn new(server: PyRef<'_, Server>, name: &str) -> PyResult<Self> {
        let held = server.publish(Interface::Text, name, 0, |conn, _, claim| {
            Ok(TextDev {
                sender: crate::TextSender::new(name, conn)?,
                _name: claim,
            })
        })?;
        Ok(TextSender { held })
    }

    /// Sends `text` (at most 1023 bytes) with a severity ("normal", "warning", "error").
    #[pyo3(signature = (text, severity = "normal", level = 0, time = None))]
    fn send(&self, text: &str, severity: &str, level: u32, time: Option<f64>) -> PyResult<()> {
        let s = parse_severity(severity)?;
        let d = held(&self.held, "TextSender")?;
        let t = time.map(super::header_time).transpose()?;
        run(|| d.sender.send_message(text, s, level, t))
    }

    /// Stops sending as this device (its name is free again on the server).
    fn close(&self) -> PyResult<()> {
        close_held(&self.held, "TextSender")
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
