//! The devices a client drives, remote side: Analog_Output (`vrpn_analog_output_*`), Poser
//! (`vrpn_poser_*`), ForceDevice (`vrpn_force_device_*`). Remotes send requests; the servers'
//! side is in `output_servers`.

use std::ffi::{c_char, c_void};

use super::client::{callback, connection_state, mainloop, open, Callbacks, Remote};
use super::handle::{self, Header, Object};
use super::server::{doubles, time_arg};
use super::types::VrpnTimeVal;
use super::{count, status, Failure, VrpnStatus};
use crate::devices::analog_output::AnalogOutputRemote;
use crate::devices::base::RemoteCore;
use crate::devices::force::{ForceDeviceRemote, ForceField};
use crate::devices::poser::PoserRemote;
use crate::wire::payload::analog::CHANNEL_MAX;

/// Capacity of `VrpnAnalogOutputValues::channels` (C++ `vrpn_CHANNEL_MAX`).
pub const VRPN_ANALOG_OUTPUT_CAPACITY: usize = 128;
const _: () = assert!(VRPN_ANALOG_OUTPUT_CAPACITY == CHANNEL_MAX);

/// Reads `n` floats from C.
///
/// # Safety
/// `p` is NULL or points to `N` readable floats.
unsafe fn floats<const N: usize>(p: *const f32, what: &str) -> Result<[f32; N], Failure> {
    if p.is_null() {
        return Err(Failure::new(
            VrpnStatus::NullArgument,
            format!("{what} is NULL"),
        ));
    }
    // SAFETY: non-null and `N` floats readable (caller's contract).
    Ok(unsafe { p.cast::<[f32; N]>().read_unaligned() })
}

/// A C array of `n` elements as a slice (an empty one for `n == 0`, whatever `p`).
///
/// # Safety
/// `p` points to `n` readable elements when `n > 0`.
unsafe fn slice<'a, T>(p: *const T, n: i32, what: &str) -> Result<&'a [T], Failure> {
    let n = usize::try_from(n)
        .map_err(|_| Failure::invalid(format!("{what} count {n} is negative")))?;
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(Failure::new(
            VrpnStatus::NullArgument,
            format!("{what} is NULL"),
        ));
    }
    // SAFETY: `n` readable elements (caller's contract).
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

// ------------------------------------------------------------------ Analog_Output remote

/// An analog output remote (C++ `vrpn_Analog_Output_Remote`).
pub struct VrpnAnalogOutput {
    header: Header,
    remote: AnalogOutputRemote,
}

impl Object for VrpnAnalogOutput {
    const TAG: u32 = 0x7672_0007;
    const NAME: &'static str = "VrpnAnalogOutput";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl Remote for VrpnAnalogOutput {
    fn core(&self) -> &RemoteCore {
        &self.remote
    }
}

/// Opens the analog output device `name` ("Out0@host", see `vrpn_tracker_open`); NULL on
/// failure.
#[no_mangle]
pub extern "C" fn vrpn_analog_output_open(name: *const c_char) -> *mut VrpnAnalogOutput {
    open(name, |n| {
        Ok(VrpnAnalogOutput {
            header: Header::new::<VrpnAnalogOutput>(),
            remote: AnalogOutputRemote::new(n)?,
        })
    })
}

/// Frees an analog output remote (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_analog_output_free(ao: *mut VrpnAnalogOutput) -> VrpnStatus {
    handle::free(ao)
}

/// Services the remote's connection without blocking.
#[no_mangle]
pub extern "C" fn vrpn_analog_output_mainloop(ao: *mut VrpnAnalogOutput) -> VrpnStatus {
    mainloop(ao)
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_analog_output_connection_state(ao: *const VrpnAnalogOutput) -> i32 {
    connection_state(ao)
}

/// Asks the server to set `channel` to `value`. `VRPN_STATUS_NOT_CONNECTED` before the
/// connection is up (nothing is queued).
#[no_mangle]
pub extern "C" fn vrpn_analog_output_request_channel(
    ao: *mut VrpnAnalogOutput,
    channel: i32,
    value: f64,
) -> VrpnStatus {
    status(handle::with(ao, |a| {
        a.remote.request_change_channel_value(channel, value)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Asks the server to set channels 0 to `n - 1` to `values[0..n]`.
#[no_mangle]
pub extern "C" fn vrpn_analog_output_request_channels(
    ao: *mut VrpnAnalogOutput,
    values: *const f64,
    n: i32,
) -> VrpnStatus {
    status(handle::with(ao, |a| {
        // SAFETY: C passes `n` readable doubles.
        let v = unsafe { slice(values, n, "values")? };
        a.remote.request_change_channels(v)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// The server's channel count as it last announced it (128 until it does), or a negative
/// status.
#[no_mangle]
pub extern "C" fn vrpn_analog_output_num_channels(ao: *const VrpnAnalogOutput) -> i32 {
    count(handle::with(ao, |a| {
        Ok(usize::try_from(a.remote.num_channels()).unwrap_or(0))
    }))
}

// ------------------------------------------------------------------ Poser remote

/// A poser remote (C++ `vrpn_Poser_Remote`).
pub struct VrpnPoser {
    header: Header,
    remote: PoserRemote,
}

impl Object for VrpnPoser {
    const TAG: u32 = 0x7672_0008;
    const NAME: &'static str = "VrpnPoser";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl Remote for VrpnPoser {
    fn core(&self) -> &RemoteCore {
        &self.remote
    }
}

/// Opens the poser `name`; NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_poser_open(name: *const c_char) -> *mut VrpnPoser {
    open(name, |n| {
        Ok(VrpnPoser {
            header: Header::new::<VrpnPoser>(),
            remote: PoserRemote::new(n)?,
        })
    })
}

/// Frees a poser remote (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_poser_free(poser: *mut VrpnPoser) -> VrpnStatus {
    handle::free(poser)
}

/// Services the remote's connection without blocking.
#[no_mangle]
pub extern "C" fn vrpn_poser_mainloop(poser: *mut VrpnPoser) -> VrpnStatus {
    mainloop(poser)
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_poser_connection_state(poser: *const VrpnPoser) -> i32 {
    connection_state(poser)
}

/// Asks for a pose: `pos` 3 doubles, `quat` 4 (x, y, z, w); `time` NULL for now. With
/// `relative` non-zero the step is added to the pose last asked for (positions add,
/// rotations compose) and the sum is sent as a relative request, as C++ does.
#[no_mangle]
pub extern "C" fn vrpn_poser_request_pose(
    poser: *mut VrpnPoser,
    time: *const VrpnTimeVal,
    pos: *const f64,
    quat: *const f64,
    relative: i32,
) -> VrpnStatus {
    status(handle::with(poser, |p| {
        // SAFETY: C passes 3 and 4 readable doubles and a readable time or NULL.
        let (pos, quat, time) = unsafe {
            (
                doubles::<3>(pos, "pos")?,
                doubles::<4>(quat, "quat")?,
                time_arg(p.remote.connection(), time)?,
            )
        };
        if relative != 0 {
            p.remote.request_pose_relative(time, pos, quat)?;
        } else {
            p.remote.request_pose(time, pos, quat)?;
        }
        Ok(VrpnStatus::Ok)
    }))
}

/// Asks for a velocity: `vel` 3 doubles, and the rotation `quat` (4 doubles, x, y, z, w)
/// done in `dt` seconds; `time` NULL for now.
#[no_mangle]
pub extern "C" fn vrpn_poser_request_velocity(
    poser: *mut VrpnPoser,
    time: *const VrpnTimeVal,
    vel: *const f64,
    quat: *const f64,
    dt: f64,
) -> VrpnStatus {
    status(handle::with(poser, |p| {
        // SAFETY: as in `vrpn_poser_request_pose`.
        let (vel, quat, time) = unsafe {
            (
                doubles::<3>(vel, "vel")?,
                doubles::<4>(quat, "quat")?,
                time_arg(p.remote.connection(), time)?,
            )
        };
        p.remote.request_pose_velocity(time, vel, quat, dt)?;
        Ok(VrpnStatus::Ok)
    }))
}

// ------------------------------------------------------------------ ForceDevice remote

/// A force the device reports.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VrpnForceReport {
    /// Time the server stamped on it.
    pub time: VrpnTimeVal,
    /// Force x, y, z.
    pub force: [f64; 3],
}

/// A surface contact point the device reports.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VrpnScpReport {
    /// Time the server stamped on it.
    pub time: VrpnTimeVal,
    /// Contact point.
    pub pos: [f64; 3],
    /// Orientation (x, y, z, w).
    pub quat: [f64; 4],
}

/// An error the device reports.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VrpnForceErrorReport {
    /// Time the server stamped on it.
    pub time: VrpnTimeVal,
    /// Error code (C++ `FD_*`).
    pub code: i32,
}

/// Receives force reports; `report` is valid during the call only.
pub type VrpnForceCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, report: *const VrpnForceReport)>;
/// Receives contact points.
pub type VrpnScpCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, report: *const VrpnScpReport)>;
/// Receives errors.
pub type VrpnForceErrorCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, report: *const VrpnForceErrorReport)>;

/// A force device remote (C++ `vrpn_ForceDevice_Remote`).
pub struct VrpnForceDevice {
    header: Header,
    remote: ForceDeviceRemote,
    callbacks: Callbacks,
}

impl Object for VrpnForceDevice {
    const TAG: u32 = 0x7672_0009;
    const NAME: &'static str = "VrpnForceDevice";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl Remote for VrpnForceDevice {
    fn core(&self) -> &RemoteCore {
        &self.remote
    }
}

/// Opens the force device `name`; NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_force_device_open(name: *const c_char) -> *mut VrpnForceDevice {
    open(name, |n| {
        Ok(VrpnForceDevice {
            header: Header::new::<VrpnForceDevice>(),
            remote: ForceDeviceRemote::new(n)?,
            callbacks: Callbacks::default(),
        })
    })
}

/// Frees a force device remote (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_force_device_free(fd: *mut VrpnForceDevice) -> VrpnStatus {
    handle::free(fd)
}

/// Services the remote's connection without blocking; runs callbacks.
#[no_mangle]
pub extern "C" fn vrpn_force_device_mainloop(fd: *mut VrpnForceDevice) -> VrpnStatus {
    mainloop(fd)
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_force_device_connection_state(fd: *const VrpnForceDevice) -> i32 {
    connection_state(fd)
}

/// Calls `callback(userdata, report)` for every force the device reports.
#[no_mangle]
pub extern "C" fn vrpn_force_device_on_force(
    fd: *mut VrpnForceDevice,
    callback: VrpnForceCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(fd, |f| {
        let cb = self::callback(callback, userdata)?;
        let id = f.remote.on_force(move |r| {
            cb.call(VrpnForceReport {
                time: r.time.into(),
                force: r.force,
            })
        });
        f.callbacks.add(id, id_out)
    }))
}

/// Calls `callback(userdata, report)` for every surface contact point.
#[no_mangle]
pub extern "C" fn vrpn_force_device_on_scp(
    fd: *mut VrpnForceDevice,
    callback: VrpnScpCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(fd, |f| {
        let cb = self::callback(callback, userdata)?;
        let id = f.remote.on_scp(move |r| {
            cb.call(VrpnScpReport {
                time: r.time.into(),
                pos: r.pos,
                quat: r.quat,
            })
        });
        f.callbacks.add(id, id_out)
    }))
}

/// Calls `callback(userdata, report)` for every error the device reports.
#[no_mangle]
pub extern "C" fn vrpn_force_device_on_error(
    fd: *mut VrpnForceDevice,
    callback: VrpnForceErrorCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(fd, |f| {
        let cb = self::callback(callback, userdata)?;
        let id = f.remote.on_error(move |r| {
            cb.call(VrpnForceErrorReport {
                time: r.time.into(),
                code: r.error_code,
            })
        });
        f.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by its id.
#[no_mangle]
pub extern "C" fn vrpn_force_device_remove_callback(
    fd: *mut VrpnForceDevice,
    id: u64,
) -> VrpnStatus {
    status(handle::with(fd, |f| {
        f.remote.remove_callback(f.callbacks.take(id)?);
        Ok(VrpnStatus::Ok)
    }))
}

/// Sends a force field: force = `force` + `jacobian` · (position − `origin`) within `radius`
/// of the origin; `origin` and `force` point to 3 floats, `jacobian` to 9 (row-major).
#[no_mangle]
pub extern "C" fn vrpn_force_device_send_force_field(
    fd: *mut VrpnForceDevice,
    origin: *const f32,
    force: *const f32,
    jacobian: *const f32,
    radius: f32,
) -> VrpnStatus {
    status(handle::with(fd, |f| {
        // SAFETY: C passes 3, 3 and 9 readable floats.
        let (origin, force, j) = unsafe {
            (
                floats::<3>(origin, "origin")?,
                floats::<3>(force, "force")?,
                floats::<9>(jacobian, "jacobian")?,
            )
        };
        let field = ForceField {
            origin,
            force,
            jacobian: [[j[0], j[1], j[2]], [j[3], j[4], j[5]], [j[6], j[7], j[8]]],
            radius,
        };
        f.remote.send_force_field(&field)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Stops the force field.
#[no_mangle]
pub extern "C" fn vrpn_force_device_stop_force_field(fd: *mut VrpnForceDevice) -> VrpnStatus {
    status(handle::with(fd, |f| {
        f.remote.stop_force_field()?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Sends custom effect `effect_id` with `n` parameters (`params` NULL when `n` is 0).
#[no_mangle]
pub extern "C" fn vrpn_force_device_send_custom_effect(
    fd: *mut VrpnForceDevice,
    effect_id: u32,
    params: *const f32,
    n: i32,
) -> VrpnStatus {
    status(handle::with(fd, |f| {
        // SAFETY: C passes `n` readable floats.
        let p = unsafe { slice(params, n, "params")? };
        f.remote.send_custom_effect(effect_id, p)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Stops the custom effect.
#[no_mangle]
pub extern "C" fn vrpn_force_device_stop_effect(fd: *mut VrpnForceDevice) -> VrpnStatus {
    status(handle::with(fd, |f| {
        f.remote.stop_effect()?;
        Ok(VrpnStatus::Ok)
    }))
}
