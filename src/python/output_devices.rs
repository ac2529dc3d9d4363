//! The devices a client drives: Analog_Output, Poser and ForceDevice, both sides
//! (`AnalogOutputRemote` / `AnalogOutputServer`, `PoserRemote` / `PoserServer`,
//! `ForceDeviceRemote` / `ForceDeviceServer`), and the objects their callbacks receive.
//!
//! A remote sends requests to the server's device; a server hands each request to the
//! callbacks a script registered (`on_request`, `on_pose`, `on_force_field`, …) inside
//! `Server.mainloop()`.

use std::cell::RefCell;
use std::rc::Rc;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::callbacks::{run, Owner};
use super::owned::Owned;
use super::remote::{remote_like, Remote, RemoteLike};
use super::server::{close_held, count_arg, held, Held, Server};
use super::{time_or_now, to_py};
use crate::devices::analog_output::{AnalogOutputRemote as AoRemote, AnalogOutputValues};
use crate::devices::base::RemoteCore;
use crate::devices::force::{
    ForceDeviceRemote as FdRemote, ForceErrorReport, ForceField, ForceReport, Plane, ScpReport,
};
use crate::devices::poser::{PoserPose, PoserRemote as PsRemote};
use crate::dispatch::HandlerId;
use crate::server::limits::{Claim, Interface};
use crate::time::TimeVal;

remote_like!(AoRemote, FdRemote);

impl RemoteLike for PsRemote {
    fn core(&self) -> &RemoteCore {
        self
    }
    fn remove(&self, _: HandlerId) -> bool {
        false // a poser remote has no callbacks of its own
    }
}

fn secs(t: TimeVal) -> f64 {
    t.as_secs_f64()
}

/// A position or a force as Python's (x, y, z).
fn xyz<T: Copy>(v: [T; 3]) -> (T, T, T) {
    (v[0], v[1], v[2])
}

/// A quaternion (x, y, z, w) or a plane (a, b, c, d) as a Python tuple.
fn xyzw<T: Copy>(v: [T; 4]) -> (T, T, T, T) {
    (v[0], v[1], v[2], v[3])
}

// ------------------------------------------------------------------ report objects

/// The output values after a client's request (`AnalogOutputServer.on_request`).
#[pyclass(frozen, module = "vrpn", name = "AnalogOutputRequest")]
pub(crate) struct AnalogOutputRequest(AnalogOutputValues);

#[pymethods]
impl AnalogOutputRequest {
    /// Time the client stamped on the request, seconds since the epoch.
    #[getter]
    fn time(&self) -> f64 {
        secs(self.0.time)
    }
    /// Every channel's value after the request.
    #[getter]
    fn channels(&self) -> Vec<f64> {
        self.0.channels().to_vec()
    }
    fn __repr__(&self) -> String {
        format!("AnalogOutputRequest(channels={:?})", self.0.channels())
    }
}

/// A pose a client asked a poser for (`PoserServer.on_pose`, `on_relative_pose`).
#[pyclass(frozen, module = "vrpn", name = "PoserRequest")]
pub(crate) struct PoserRequest(PoserPose);

#[pymethods]
impl PoserRequest {
    /// Time the client stamped on the request.
    #[getter]
    fn time(&self) -> f64 {
        secs(self.0.time)
    }
    /// Position (x, y, z), after the server clamped it to its workspace.
    #[getter]
    fn pos(&self) -> (f64, f64, f64) {
        xyz(self.0.pos)
    }
    /// Orientation (x, y, z, w).
    #[getter]
    fn quat(&self) -> (f64, f64, f64, f64) {
        xyzw(self.0.quat)
    }
    fn __repr__(&self) -> String {
        format!("PoserRequest(pos={:?}, quat={:?})", self.0.pos, self.0.quat)
    }
}

/// A force report (`ForceDeviceRemote.on_force`).
#[pyclass(frozen, module = "vrpn", name = "ForceReport")]
pub(crate) struct PyForceReport(ForceReport);

#[pymethods]
impl PyForceReport {
    /// Time the server stamped on it.
    #[getter]
    fn time(&self) -> f64 {
        secs(self.0.time)
    }
    /// Force (x, y, z).
    #[getter]
    fn force(&self) -> (f64, f64, f64) {
        xyz(self.0.force)
    }
    fn __repr__(&self) -> String {
        format!("ForceReport(force={:?})", self.0.force)
    }
}

/// A surface contact point (`ForceDeviceRemote.on_scp`).
#[pyclass(frozen, module = "vrpn", name = "ScpReport")]
pub(crate) struct PyScpReport(ScpReport);

#[pymethods]
impl PyScpReport {
    /// Time the server stamped on it.
    #[getter]
    fn time(&self) -> f64 {
        secs(self.0.time)
    }
    /// Contact point (x, y, z).
    #[getter]
    fn pos(&self) -> (f64, f64, f64) {
        xyz(self.0.pos)
    }
    /// Orientation (x, y, z, w).
    #[getter]
    fn quat(&self) -> (f64, f64, f64, f64) {
        xyzw(self.0.quat)
    }
    fn __repr__(&self) -> String {
        format!("ScpReport(pos={:?})", self.0.pos)
    }
}

/// A force device's error (`ForceDeviceRemote.on_error`).
#[pyclass(frozen, module = "vrpn", name = "ForceErrorReport")]
pub(crate) struct PyForceError(ForceErrorReport);

#[pymethods]
impl PyForceError {
    /// Time the server stamped on it.
    #[getter]
    fn time(&self) -> f64 {
        secs(self.0.time)
    }
    /// The error code (C++ `FD_*`).
    #[getter]
    fn code(&self) -> i32 {
        self.0.error_code
    }
    fn __repr__(&self) -> String {
        format!("ForceErrorReport(code={})", self.0.error_code)
    }
}

/// A force field a client sent (`ForceDeviceServer.on_force_field`).
#[pyclass(frozen, module = "vrpn", name = "ForceFieldRequest")]
pub(crate) struct ForceFieldRequest(TimeVal, ForceField);

#[pymethods]
impl ForceFieldRequest {
    /// Time the client stamped on it.
    #[getter]
    fn time(&self) -> f64 {
        secs(self.0)
    }
    /// Field origin (x, y, z).
    #[getter]
    fn origin(&self) -> (f32, f32, f32) {
        xyz(self.1.origin)
    }
    /// Force at the origin.
    #[getter]
    fn force(&self) -> (f32, f32, f32) {
        xyz(self.1.force)
    }
    /// Jacobian, three rows of three.
    #[getter]
    fn jacobian(&self) -> Vec<Vec<f32>> {
        self.1.jacobian.iter().map(|r| r.to_vec()).collect()
    }
    /// Radius beyond which the field is off.
    #[getter]
    fn radius(&self) -> f32 {
        self.1.radius
    }
    /// True for the all-zero field that stops forces.
    #[getter]
    fn stops(&self) -> bool {
        self.1 == ForceField::default()
    }
}

/// A surface plane a client sent (`ForceDeviceServer.on_plane`).
#[pyclass(frozen, module = "vrpn", name = "PlaneRequest")]
pub(crate) struct PlaneRequest(TimeVal, Plane);

#[pymethods]
impl PlaneRequest {
    /// Time the client stamped on it.
    #[getter]
    fn time(&self) -> f64 {
        secs(self.0)
    }
    /// Plane equation (a, b, c, d): a·x + b·y + c·z + d = 0.
    #[getter]
    fn plane(&self) -> (f32, f32, f32, f32) {
        xyzw(self.1.plane)
    }
    /// Spring constant.
    #[getter]
    fn kspring(&self) -> f32 {
        self.1.kspring
    }
    /// Damping.
    #[getter]
    fn kdamp(&self) -> f32 {
        self.1.kdamp
    }
    /// Dynamic friction.
    #[getter]
    fn fdyn(&self) -> f32 {
        self.1.fdyn
    }
    /// Static friction.
    #[getter]
    fn fstat(&self) -> f32 {
        self.1.fstat
    }
}

/// A custom effect a client sent (`ForceDeviceServer.on_custom_effect`).
#[pyclass(frozen, module = "vrpn", name = "CustomEffect")]
pub(crate) struct PyCustomEffect {
    time: TimeVal,
    effect_id: u32,
    params: Vec<f32>,
}

#[pymethods]
impl PyCustomEffect {
    /// Time the client stamped on it.
    #[getter]
    fn time(&self) -> f64 {
        secs(self.time)
    }
    /// Effect id (0xFFFFFFFF stops the effect).
    #[getter]
    fn effect_id(&self) -> u32 {
        self.effect_id
    }
    /// Its parameters.
    #[getter]
    fn params(&self) -> Vec<f32> {
        self.params.clone()
    }
}

// ------------------------------------------------------------------ remotes

/// Client of an analog output device: `AnalogOutputRemote("Out0@host")`.
#[pyclass(extends = Remote, module = "vrpn", name = "AnalogOutputRemote")]
pub(crate) struct AnalogOutputRemote;

#[pymethods]
impl AnalogOutputRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = AoRemote::new(name).map_err(to_py)?;
        Ok((AnalogOutputRemote, Remote::new("AnalogOutputRemote", inner)))
    }

    /// Asks the server to set `channel` to `value`.
    fn request_change_channel_value(
        slf: PyRef<'_, Self>,
        channel: i32,
        value: f64,
    ) -> PyResult<()> {
        let r = slf.as_super().inner::<AoRemote>()?;
        run(|| r.request_change_channel_value(channel, value))
    }

    /// Asks the server to set channels 0, 1, … to `values`.
    fn request_change_channels(slf: PyRef<'_, Self>, values: Vec<f64>) -> PyResult<()> {
        let r = slf.as_super().inner::<AoRemote>()?;
        run(|| r.request_change_channels(&values))
    }

    /// The server's channel count as it last announced it (128 until it does).
    #[getter]
    fn num_channels(slf: PyRef<'_, Self>) -> PyResult<i32> {
        Ok(slf.as_super().inner::<AoRemote>()?.num_channels())
    }

    /// Calls `f(count)` each time the server announces its channel count. Returns a handle.
    fn on_num_channels(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let r = base.inner::<AoRemote>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            r.on_num_channels(move |n| slot.call_int(i64::from(*n)))
        })
    }
}

/// Client of a poser: `PoserRemote("Poser0@host")`.
#[pyclass(extends = Remote, module = "vrpn", name = "PoserRemote")]
pub(crate) struct PoserRemote;

#[pymethods]
impl PoserRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = PsRemote::new(name).map_err(to_py)?;
        Ok((PoserRemote, Remote::new("PoserRemote", inner)))
    }

    /// Asks for an absolute pose; `quat` is (x, y, z, w).
    #[pyo3(signature = (pos, quat = [0.0, 0.0, 0.0, 1.0], time = None))]
    fn request_pose(
        slf: PyRef<'_, Self>,
        pos: [f64; 3],
        quat: [f64; 4],
        time: Option<f64>,
    ) -> PyResult<()> {
        let r = slf.as_super().inner::<PsRemote>()?;
        let at = time_or_now(time, r.connection())?;
        run(|| r.request_pose(at, pos, quat))
    }

    /// Asks for a pose relative to the last one asked for (positions add, rotations compose).
    #[pyo3(signature = (dpos, dquat = [0.0, 0.0, 0.0, 1.0], time = None))]
    fn request_pose_relative(
        slf: PyRef<'_, Self>,
        dpos: [f64; 3],
        dquat: [f64; 4],
        time: Option<f64>,
    ) -> PyResult<()> {
        let r = slf.as_super().inner::<PsRemote>()?;
        let at = time_or_now(time, r.connection())?;
        run(|| r.request_pose_relative(at, dpos, dquat))
    }

    /// Asks for a velocity: `vel`, and the rotation `quat` done in `dt` seconds.
    #[pyo3(signature = (vel, quat = [0.0, 0.0, 0.0, 1.0], dt = 1.0, time = None))]
    fn request_pose_velocity(
        slf: PyRef<'_, Self>,
        vel: [f64; 3],
        quat: [f64; 4],
        dt: f64,
        time: Option<f64>,
    ) -> PyResult<()> {
        let r = slf.as_super().inner::<PsRemote>()?;
        let at = time_or_now(time, r.connection())?;
        run(|| r.request_pose_velocity(at, vel, quat, dt))
    }
}

/// Client of a force device: `ForceDeviceRemote("Phantom0@host")`.
#[pyclass(extends = Remote, module = "vrpn", name = "ForceDeviceRemote")]
pub(crate) struct ForceDeviceRemote;

#[pymethods]
impl ForceDeviceRemote {
    #[new]
    fn new(name: &str) -> PyResult<(Self, Remote)> {
        let inner = FdRemote::new(name).map_err(to_py)?;
        Ok((ForceDeviceRemote, Remote::new("ForceDeviceRemote", inner)))
    }

    /// Calls `f(report)` for every force the device reports. Returns a handle.
    fn on_force(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let r = base.inner::<FdRemote>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            r.on_force(move |x| slot.call_with(|| PyForceReport(*x)))
        })
    }

    /// Calls `f(report)` for every surface contact point. Returns a handle.
    fn on_scp(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let r = base.inner::<FdRemote>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            r.on_scp(move |x| slot.call_with(|| PyScpReport(*x)))
        })
    }

    /// Calls `f(error)` for every error the device reports. Returns a handle.
    fn on_error(slf: PyRef<'_, Self>, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        let base = slf.as_super();
        let r = base.inner::<FdRemote>()?;
        base.reg()?.add(f, Owner::Device, |slot| {
            r.on_error(move |x| slot.call_with(|| PyForceError(*x)))
        })
    }

    /// Sends a force field: force = `force` + `jacobian` · (position − `origin`), within
    /// `radius` of the origin.
    #[pyo3(signature = (origin, force, jacobian, radius))]
    fn send_force_field(
        slf: PyRef<'_, Self>,
        origin: [f32; 3],
        force: [f32; 3],
        jacobian: [[f32; 3]; 3],
        radius: f32,
    ) -> PyResult<()> {
        let r = slf.as_super().inner::<FdRemote>()?;
        let field = ForceField {
            origin,
            force,
            jacobian,
            radius,
        };
        run(|| r.send_force_field(&field))
    }

    /// Stops the force field.
    fn stop_force_field(slf: PyRef<'_, Self>) -> PyResult<()> {
        let r = slf.as_super().inner::<FdRemote>()?;
        run(|| r.stop_force_field())
    }

    /// Sends a surface plane (a, b, c, d) with its spring, damping and friction.
    #[pyo3(signature = (plane, kspring = 0.0, kdamp = 0.0, fdyn = 0.0, fstat = 0.0, plane_index = 0, recovery_cycles = 0))]
    #[allow(clippy::too_many_arguments)]
    fn start_surface(
        slf: PyRef<'_, Self>,
        plane: [f32; 4],
        kspring: f32,
        kdamp: f32,
        fdyn: f32,
        fstat: f32,
        plane_index: i32,
        recovery_cycles: i32,
    ) -> PyResult<()> {
        let r = slf.as_super().inner::<FdRemote>()?;
        let p = Plane {
            plane,
            kspring,
            kdamp,
            fdyn,
            fstat,
            plane_index,
            recovery_cycles,
        };
        run(|| r.start_surface(&p))
    }

    /// Sends a custom effect: an id and its parameters.
    fn send_custom_effect(slf: PyRef<'_, Self>, effect_id: u32, params: Vec<f32>) -> PyResult<()> {
        let r = slf.as_super().inner::<FdRemote>()?;
        run(|| r.send_custom_effect(effect_id, &params))
    }

    /// Stops the custom effect.
    fn stop_effect(slf: PyRef<'_, Self>) -> PyResult<()> {
        let r = slf.as_super().inner::<FdRemote>()?;
        run(|| r.stop_effect())
    }
}

// ------------------------------------------------------------------ servers

/// A device server on a `Server`: the Rust server, the callbacks Python registered on it, and
/// what keeps its name.
struct Dev<S> {
    callbacks: Callbacks,
    server: S,
    _name: Claim,
}

impl<S> Dev<S> {
    fn new(server: S, name: Claim) -> Dev<S> {
        Dev {
            callbacks: Callbacks::default(),
            server,
            _name: name,
        }
    }
}

/// The `#[pymethods]` of device server class `$class` (a `held` field holding a `$dev`):
/// `$methods`, and `remove_callback` and `close`, which every one has; and `dev()`, its
/// device or `ClosedError`.
macro_rules! device_server {
    ($class:ident, $dev:ty, $($methods:tt)*) => {
        impl $class {
            /// Its device, or `ClosedError` after `close()`.
            fn dev(&self) -> PyResult<Rc<$dev>> {
                held(&self.held, stringify!($class))
            }
        }

        #[pymethods]
        impl $class {
            $($methods)*

            /// Removes a callback an `on_*` method returned.
            fn remove_callback(&self, id: u64) -> PyResult<bool> {
                let d = self.dev()?;
                Ok(d.server.remove_callback(d.callbacks.take(id)?))
            }

            /// Stops serving this device (its name is free again on the server).
            fn close(&self) -> PyResult<()> {
                close_held(&self.held, stringify!($class))
            }
        }
    };
}

type AoDev = Dev<crate::devices::analog_output::AnalogOutputServer>;
type PoserDev = Dev<crate::devices::poser::PoserServer>;
type ForceDev = Dev<crate::devices::force::ForceDeviceServer>;

/// An analog output device on a `Server`: `AnalogOutputServer(server, "Out0", channels=1)`.
/// Clients' requests set its values; `on_request` hears each one.
#[pyclass(module = "vrpn", name = "AnalogOutputServer")]
pub(crate) struct AnalogOutputServer {
    held: Owned<Rc<Held<AoDev>>>,
}

device_server! { AnalogOutputServer, AoDev,
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
        let n = count_arg(channels, Interface::AnalogOutput)?;
        let held = server.publish(Interface::AnalogOutput, name, n, |conn, n, claim| {
            let server = crate::devices::analog_output::AnalogOutputServer::new(name, conn, n)?;
            Ok(Dev::new(server, claim))
        })?;
        Ok(AnalogOutputServer { held })
    }

    /// Calls `f(request)` after each client request has set the values (inside
    /// `Server.mainloop()`). Returns an id for `remove_callback`.
    fn on_request(&self, f: Py<PyAny>) -> PyResult<u64> {
        let d = self.dev()?;
        let id = d
            .server
            .on_request(move |v| call_in_python(&f, AnalogOutputRequest(*v)));
        Ok(d.callbacks.keep(id))
    }

    /// The current values of the channels.
    fn values(&self) -> PyResult<Vec<f64>> {
        let d = self.dev()?;
        Ok(d.server.values().channels().to_vec())
    }

    /// Announces the channel count to every client.
    fn report_num_channels(&self) -> PyResult<()> {
        let d = self.dev()?;
        run(|| d.server.report_num_channels())
    }
}

/// A poser on a `Server`: `PoserServer(server, "Poser0")`. Clients' pose requests reach
/// `on_pose` (absolute) and `on_relative_pose`.
#[pyclass(module = "vrpn", name = "PoserServer")]
pub(crate) struct PoserServer {
    held: Owned<Rc<Held<PoserDev>>>,
}

/// Calls the Python callable `f` with `v`; its exception is kept for the `mainloop()` that
/// ran it.
fn call_in_python<T: pyo3::PyClass + Into<pyo3::PyClassInitializer<T>>>(f: &Py<PyAny>, v: T) {
    Python::attach(|py| {
        let called = Py::new(py, v).and_then(|obj| f.call1(py, (obj,)));
        if let Err(e) = called {
            super::callbacks::stash(py, e, f.bind(py));
        }
    });
}

device_server! { PoserServer, PoserDev,
    #[new]
    fn new(server: PyRef<'_, Server>, name: &str) -> PyResult<Self> {
        let held = server.publish(Interface::Poser, name, 0, |conn, _, claim| {
            let server = crate::devices::poser::PoserServer::new(name, conn)?;
            Ok(Dev::new(server, claim))
        })?;
        Ok(PoserServer { held })
    }

    /// Calls `f(request)` for each absolute pose a client asks for. Returns an id.
    fn on_pose(&self, f: Py<PyAny>) -> PyResult<u64> {
        let d = self.dev()?;
        Ok(d.callbacks.keep(
            d.server
                .on_pose(move |p| call_in_python(&f, PoserRequest(*p))),
        ))
    }

    /// Calls `f(request)` for each relative pose (the resulting pose). Returns an id.
    fn on_relative_pose(&self, f: Py<PyAny>) -> PyResult<u64> {
        let d = self.dev()?;
        Ok(d.callbacks.keep(
            d.server
                .on_relative_pose(move |p| call_in_python(&f, PoserRequest(*p))),
        ))
    }

    /// The pose last requested (as a `PoserRequest`).
    fn pose(&self) -> PyResult<PoserRequest> {
        let d = self.dev()?;
        let s = d.server.state();
        Ok(PoserRequest(PoserPose {
            time: s.time,
            pos: s.pos,
            quat: s.quat,
        }))
    }
}

/// A force device on a `Server`: `ForceDeviceServer(server, "Phantom0")`. Reports forces
/// and contact points; hands clients' fields, planes and effects to callbacks.
#[pyclass(module = "vrpn", name = "ForceDeviceServer")]
pub(crate) struct ForceDeviceServer {
    held: Owned<Rc<Held<ForceDev>>>,
}

device_server! { ForceDeviceServer, ForceDev,
    #[new]
    fn new(server: PyRef<'_, Server>, name: &str) -> PyResult<Self> {
        let held = server.publish(Interface::ForceDevice, name, 0, |conn, _, claim| {
            let server = crate::devices::force::ForceDeviceServer::new(name, conn)?;
            Ok(Dev::new(server, claim))
        })?;
        Ok(ForceDeviceServer { held })
    }

    /// Reports a force (x, y, z), stamped `time` (default now).
    #[pyo3(signature = (force, time = None))]
    fn report_force(&self, force: [f64; 3], time: Option<f64>) -> PyResult<()> {
        let d = self.dev()?;
        let t = time.map_or_else(TimeVal::now, TimeVal::from_secs_f64);
        run(|| d.server.report_force(t, force))
    }

    /// Reports a surface contact point and orientation (x, y, z, w).
    #[pyo3(signature = (pos, quat = [0.0, 0.0, 0.0, 1.0], time = None))]
    fn report_scp(&self, pos: [f64; 3], quat: [f64; 4], time: Option<f64>) -> PyResult<()> {
        let d = self.dev()?;
        let t = time.map_or_else(TimeVal::now, TimeVal::from_secs_f64);
        run(|| d.server.report_scp(t, pos, quat))
    }

    /// Reports an error code (C++ `FD_*`).
    fn send_error(&self, code: i32) -> PyResult<()> {
        let d = self.dev()?;
        run(|| d.server.send_error(code))
    }

    /// Calls `f(field)` for every force field a client sends. Returns an id.
    fn on_force_field(&self, f: Py<PyAny>) -> PyResult<u64> {
        let d = self.dev()?;
        Ok(d.callbacks.keep(
            d.server
                .on_force_field(move |(t, x)| call_in_python(&f, ForceFieldRequest(*t, *x))),
        ))
    }

    /// Calls `f(plane)` for every surface plane a client sends. Returns an id.
    fn on_plane(&self, f: Py<PyAny>) -> PyResult<u64> {
        let d = self.dev()?;
        Ok(d.callbacks.keep(
            d.server
                .on_plane(move |(t, p)| call_in_python(&f, PlaneRequest(*t, *p))),
        ))
    }

    /// Calls `f(effect)` for every custom effect (and stop) a client sends. Returns an id.
    fn on_custom_effect(&self, f: Py<PyAny>) -> PyResult<u64> {
        let d = self.dev()?;
        Ok(d.callbacks.keep(d.server.on_custom_effect(move |m| {
            call_in_python(
                &f,
                PyCustomEffect {
                    time: m.time,
                    effect_id: m.effect.effect_id,
                    params: m.effect.params().collect(),
                },
            )
        })))
    }

    /// Calls `f(name, time)` for every trimesh, scene or constraint request, with the
    /// request's VRPN type name. Returns an id.
    fn on_request(&self, f: Py<PyAny>) -> PyResult<u64> {
        let d = self.dev()?;
        Ok(d.callbacks.keep(d.server.on_request(move |r| {
            let (name, t) = (r.request.type_name(), r.time.as_secs_f64());
            Python::attach(|py| {
                if let Err(e) = f.call1(py, (name, t)) {
                    super::callbacks::stash(py, e, f.bind(py));
                }
            });
        })))
    }
}

/// The callbacks a device server registered for Python, by the number Python holds.
#[derive(Default)]
struct Callbacks(RefCell<Vec<Option<HandlerId>>>);

impl Callbacks {
    /// Keeps `id`; returns the number Python gets for it (1, 2, …).
    fn keep(&self, id: HandlerId) -> u64 {
        let mut v = self.0.borrow_mut();
        v.push(Some(id));
        v.len() as u64
    }

    /// Takes back the id of `key`, once.
    fn take(&self, key: u64) -> PyResult<HandlerId> {
        let mut v = self.0.borrow_mut();
        usize::try_from(key)
            .ok()
            .and_then(|k| k.checked_sub(1))
            .and_then(|i| v.get_mut(i))
            .and_then(Option::take)
            .ok_or_else(|| PyValueError::new_err(format!("no callback {key} on this device")))
    }
}

pub(crate) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<AnalogOutputRequest>()?;
    m.add_class::<PoserRequest>()?;
    m.add_class::<PyForceReport>()?;
    m.add_class::<PyScpReport>()?;
    m.add_class::<PyForceError>()?;
    m.add_class::<ForceFieldRequest>()?;
    m.add_class::<PlaneRequest>()?;
    m.add_class::<PyCustomEffect>()?;
    m.add_class::<AnalogOutputRemote>()?;
    m.add_class::<PoserRemote>()?;
    m.add_class::<ForceDeviceRemote>()?;
    m.add_class::<AnalogOutputServer>()?;
    m.add_class::<PoserServer>()?;
    m.add_class::<ForceDeviceServer>()?;
    Ok(())
}
