//! The servers' side of the devices a client drives: Analog_Output
//! (`vrpn_analog_output_server_*`), Poser (`vrpn_poser_server_*`), ForceDevice
//! (`vrpn_force_device_server_*`), and a server's text sender (`vrpn_text_sender_*`). Each
//! request a client sends reaches the C callbacks registered on the device, inside
//! `vrpn_server_mainloop`.

use std::ffi::{c_char, c_void};

use super::client::{callback, out_arg, Callbacks};
use super::handle::{self, Header, Object};
use super::server::{device, doubles, time_arg, VrpnServer};
use super::types::VrpnTimeVal;
use super::{count, status, text_arg, Failure, VrpnStatus};
use crate::devices::analog_output::{AnalogOutputServer, AnalogOutputValues};
use crate::devices::force::ForceDeviceServer;
use crate::devices::poser::PoserServer;
use crate::devices::text::TextSeverity;
use crate::server::limits::{Claim, Interface};
use crate::TextSender;

use super::output_devices::VRPN_ANALOG_OUTPUT_CAPACITY;

// ------------------------------------------------------------------ servers

/// The output values after a client's request.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct VrpnAnalogOutputValues {
    /// Time the client stamped on the request.
    pub time: VrpnTimeVal,
    /// Channels in use: `channels[0..num_channels]`.
    pub num_channels: i32,
    /// The values.
    pub channels: [f64; VRPN_ANALOG_OUTPUT_CAPACITY],
}

impl From<&AnalogOutputValues> for VrpnAnalogOutputValues {
    fn from(v: &AnalogOutputValues) -> Self {
        VrpnAnalogOutputValues {
            time: v.time.into(),
            num_channels: v.num_channel,
            channels: v.channel,
        }
    }
}

/// Receives the values after each client request.
pub type VrpnAnalogOutputCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, values: *const VrpnAnalogOutputValues)>;

/// An analog output device on a server (C++ `vrpn_Analog_Output_Callback_Server`).
pub struct VrpnAnalogOutputServer {
    header: Header,
    server: AnalogOutputServer,
    callbacks: Callbacks,
    _name: Claim,
}

impl Object for VrpnAnalogOutputServer {
    const TAG: u32 = 0x7672_0106;
    const NAME: &'static str = "VrpnAnalogOutputServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Serves analog output device `name` with `channels` channels (1..=128) on `server`; NULL
/// on failure (as `vrpn_tracker_server_new`).
#[no_mangle]
pub extern "C" fn vrpn_analog_output_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
    channels: i32,
) -> *mut VrpnAnalogOutputServer {
    device(
        server,
        name,
        Interface::AnalogOutput,
        channels,
        |conn, name, n, claim| {
            Ok(VrpnAnalogOutputServer {
                header: Header::new::<VrpnAnalogOutputServer>(),
                server: AnalogOutputServer::new(name, conn, n)?,
                callbacks: Callbacks::default(),
                _name: claim,
            })
        },
    )
}

/// Frees an analog output server (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_analog_output_server_free(aos: *mut VrpnAnalogOutputServer) -> VrpnStatus {
    handle::free(aos)
}

/// Calls `callback(userdata, values)` after each client request (inside
/// `vrpn_server_mainloop`).
#[no_mangle]
pub extern "C" fn vrpn_analog_output_server_on_request(
    aos: *mut VrpnAnalogOutputServer,
    callback: VrpnAnalogOutputCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(aos, |a| {
        let cb = self::callback(callback, userdata)?;
        let id = a
            .server
            .on_request(move |v| cb.call(VrpnAnalogOutputValues::from(v)));
        a.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by its id.
#[no_mangle]
pub extern "C" fn vrpn_analog_output_server_remove_callback(
    aos: *mut VrpnAnalogOutputServer,
    id: u64,
) -> VrpnStatus {
    status(handle::with(aos, |a| {
        a.server.remove_callback(a.callbacks.take(id)?);
        Ok(VrpnStatus::Ok)
    }))
}

/// Copies the current values into `out` (room for `capacity` doubles); returns the number
/// of channels (which may exceed `capacity`: only `capacity` are copied), or a negative
/// status.
#[no_mangle]
pub extern "C" fn vrpn_analog_output_server_values(
    aos: *const VrpnAnalogOutputServer,
    out: *mut f64,
    capacity: i32,
) -> i32 {
    count(handle::with(aos, |a| {
        out_arg(out, "out")?;
        let cap = usize::try_from(capacity)
            .map_err(|_| Failure::invalid(format!("capacity {capacity} is negative")))?;
        let values = a.server.values();
        let ch = values.channels();
        let n = ch.len().min(cap);
        // SAFETY: `out` holds `capacity` writable doubles (caller's contract); n <= capacity.
        unsafe { std::ptr::copy_nonoverlapping(ch.as_ptr(), out, n) };
        Ok(ch.len())
    }))
}

/// Announces the channel count to every client.
#[no_mangle]
pub extern "C" fn vrpn_analog_output_server_report_num_channels(
    aos: *mut VrpnAnalogOutputServer,
) -> VrpnStatus {
    status(handle::with(aos, |a| {
        a.server.report_num_channels()?;
        Ok(VrpnStatus::Ok)
    }))
}

/// A pose a client asked a poser for.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VrpnPoserRequest {
    /// Time the client stamped on the request.
    pub time: VrpnTimeVal,
    /// Position.
    pub pos: [f64; 3],
    /// Orientation (x, y, z, w).
    pub quat: [f64; 4],
    /// 1 for a relative request (the step as sent), 0 for an absolute one.
    pub relative: i32,
}

/// Receives pose requests.
pub type VrpnPoserCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, request: *const VrpnPoserRequest)>;

/// A poser on a server (C++ `vrpn_Poser_Server`).
pub struct VrpnPoserServer {
    header: Header,
    server: PoserServer,
    callbacks: Callbacks,
    _name: Claim,
}

impl Object for VrpnPoserServer {
    const TAG: u32 = 0x7672_0107;
    const NAME: &'static str = "VrpnPoserServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Serves poser `name` on `server`; NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_poser_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
) -> *mut VrpnPoserServer {
    device(server, name, Interface::Poser, 0, |conn, name, _, claim| {
        Ok(VrpnPoserServer {
            header: Header::new::<VrpnPoserServer>(),
            server: PoserServer::new(name, conn)?,
            callbacks: Callbacks::default(),
            _name: claim,
        })
    })
}

/// Frees a poser server (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_poser_server_free(ps: *mut VrpnPoserServer) -> VrpnStatus {
    handle::free(ps)
}

/// Calls `callback(userdata, request)` for every pose request, absolute and relative.
#[no_mangle]
pub extern "C" fn vrpn_poser_server_on_request(
    ps: *mut VrpnPoserServer,
    callback: VrpnPoserCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(ps, |p| {
        let to_c = |relative: i32| -> Result<_, Failure> {
            let cb = self::callback(callback, userdata)?;
            Ok(move |r: &crate::devices::poser::PoserPose| {
                cb.call(VrpnPoserRequest {
                    time: r.time.into(),
                    pos: r.pos,
                    quat: r.quat,
                    relative,
                })
            })
        };
        let abs = p.server.on_pose(to_c(0)?);
        let rel = p.server.on_relative_pose(to_c(1)?);
        p.callbacks.add(abs, id_out)?;
        // The relative handler goes with the absolute one: one id removes both.
        p.callbacks.add(rel, std::ptr::null_mut())
    }))
}

/// Removes a callback by the id `vrpn_poser_server_on_request` gave.
#[no_mangle]
pub extern "C" fn vrpn_poser_server_remove_callback(
    ps: *mut VrpnPoserServer,
    id: u64,
) -> VrpnStatus {
    status(handle::with(ps, |p| {
        p.server.remove_callback(p.callbacks.take(id)?);
        if let Some(rel) = id.checked_add(1) {
            if let Ok(h) = p.callbacks.take(rel) {
                p.server.remove_callback(h);
            }
        }
        Ok(VrpnStatus::Ok)
    }))
}

/// A force field a client sent.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VrpnForceFieldRequest {
    /// Time the client stamped on it.
    pub time: VrpnTimeVal,
    /// Field origin.
    pub origin: [f32; 3],
    /// Force at the origin.
    pub force: [f32; 3],
    /// Jacobian, row-major.
    pub jacobian: [f32; 9],
    /// Radius beyond which the field is off.
    pub radius: f32,
}

/// Receives force fields.
pub type VrpnForceFieldCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, field: *const VrpnForceFieldRequest)>;

/// A force device on a server (C++ `vrpn_ForceDevice_Server`).
pub struct VrpnForceDeviceServer {
    header: Header,
    server: ForceDeviceServer,
    callbacks: Callbacks,
    _name: Claim,
}

impl Object for VrpnForceDeviceServer {
    const TAG: u32 = 0x7672_0108;
    const NAME: &'static str = "VrpnForceDeviceServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Serves force device `name` on `server`; NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_force_device_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
) -> *mut VrpnForceDeviceServer {
    device(
        server,
        name,
        Interface::ForceDevice,
        0,
        |conn, name, _, claim| {
            Ok(VrpnForceDeviceServer {
                header: Header::new::<VrpnForceDeviceServer>(),
                server: ForceDeviceServer::new(name, conn)?,
                callbacks: Callbacks::default(),
                _name: claim,
            })
        },
    )
}

/// Frees a force device server (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_force_device_server_free(fds: *mut VrpnForceDeviceServer) -> VrpnStatus {
    handle::free(fds)
}

/// Reports a force (`force` 3 doubles); `time` NULL for now.
#[no_mangle]
pub extern "C" fn vrpn_force_device_server_report_force(
    fds: *mut VrpnForceDeviceServer,
    time: *const VrpnTimeVal,
    force: *const f64,
) -> VrpnStatus {
    status(handle::with(fds, |f| {
        // SAFETY: C passes 3 readable doubles and a readable time or NULL.
        let (force, time) = unsafe {
            (
                doubles::<3>(force, "force")?,
                time_arg(f.server.connection(), time)?,
            )
        };
        f.server.report_force(time, force)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Reports a surface contact point (`pos` 3 doubles, `quat` 4: x, y, z, w).
#[no_mangle]
pub extern "C" fn vrpn_force_device_server_report_scp(
    fds: *mut VrpnForceDeviceServer,
    time: *const VrpnTimeVal,
    pos: *const f64,
    quat: *const f64,
) -> VrpnStatus {
    status(handle::with(fds, |f| {
        // SAFETY: C passes 3 and 4 readable doubles and a readable time or NULL.
        let (pos, quat, time) = unsafe {
            (
                doubles::<3>(pos, "pos")?,
                doubles::<4>(quat, "quat")?,
                time_arg(f.server.connection(), time)?,
            )
        };
        f.server.report_scp(time, pos, quat)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Reports an error code (C++ `FD_*`).
#[no_mangle]
pub extern "C" fn vrpn_force_device_server_send_error(
    fds: *mut VrpnForceDeviceServer,
    code: i32,
) -> VrpnStatus {
    status(handle::with(fds, |f| {
        f.server.send_error(code)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Calls `callback(userdata, field)` for every force field a client sends (an all-zero field
/// stops forces).
#[no_mangle]
pub extern "C" fn vrpn_force_device_server_on_force_field(
    fds: *mut VrpnForceDeviceServer,
    callback: VrpnForceFieldCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(fds, |f| {
        let cb = self::callback(callback, userdata)?;
        let id = f.server.on_force_field(move |(t, x)| {
            let j = x.jacobian;
            cb.call(VrpnForceFieldRequest {
                time: (*t).into(),
                origin: x.origin,
                force: x.force,
                jacobian: [
                    j[0][0], j[0][1], j[0][2], j[1][0], j[1][1], j[1][2], j[2][0], j[2][1], j[2][2],
                ],
                radius: x.radius,
            })
        });
        f.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by its id.
#[no_mangle]
pub extern "C" fn vrpn_force_device_server_remove_callback(
    fds: *mut VrpnForceDeviceServer,
    id: u64,
) -> VrpnStatus {
    status(handle::with(fds, |f| {
        f.server.remove_callback(f.callbacks.take(id)?);
        Ok(VrpnStatus::Ok)
    }))
}

// ------------------------------------------------------------------ text sender

/// A text sender on a server (C++ `vrpn_Text_Sender`): texts as a device.
pub struct VrpnTextSender {
    header: Header,
    sender: TextSender,
    _name: Claim,
}

impl Object for VrpnTextSender {
    const TAG: u32 = 0x7672_0109;
    const NAME: &'static str = "VrpnTextSender";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Sends text messages as device `name` on `server`; NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_text_sender_new(
    server: *mut VrpnServer,
    name: *const c_char,
) -> *mut VrpnTextSender {
    device(server, name, Interface::Text, 0, |conn, name, _, claim| {
        Ok(VrpnTextSender {
            header: Header::new::<VrpnTextSender>(),
            sender: TextSender::new(name, conn)?,
            _name: claim,
        })
    })
}

/// Frees a text sender (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_text_sender_free(ts: *mut VrpnTextSender) -> VrpnStatus {
    handle::free(ts)
}

/// Sends `text` (UTF-8, at most 1023 bytes) with `severity` 0 normal, 1 warning, 2 error and
/// a free-form `level`; `time` NULL for now.
#[no_mangle]
pub extern "C" fn vrpn_text_sender_send(
    ts: *mut VrpnTextSender,
    text: *const c_char,
    severity: u32,
    level: u32,
    time: *const VrpnTimeVal,
) -> VrpnStatus {
    status(handle::with(ts, |t| {
        // SAFETY: C passes a NUL-terminated text and a readable time or NULL.
        let (text, time) = unsafe {
            (
                text_arg(text, "text")?,
                time_arg(t.sender.connection(), time)?,
            )
        };
        t.sender
            .send_message(text, TextSeverity::from_code(severity), level, Some(time))?;
        Ok(VrpnStatus::Ok)
    }))
}
