//! Server side: a server connection on a port, and tracker, button, analog and dial servers
//! that report on it.

use std::cell::RefCell;
use std::ffi::c_char;
use std::net::Ipv4Addr;
use std::time::Duration;

use super::client::index;
use super::handle::{self, Header, Object};
use super::types::VrpnTimeVal;
use super::{count, status, text_arg, Failure, VrpnConnectionState, VrpnStatus};
use crate::devices::analog::AnalogServer;
use crate::devices::dial::DialServer;
use crate::time::TimeVal;
use crate::{ButtonServer, Connection, TrackerServer};

/// A server connection (C++ `vrpn_Connection` made by `vrpn_create_server_connection`).
pub struct VrpnServer {
    header: Header,
    conn: Connection,
}

impl Object for VrpnServer {
    const TAG: u32 = 0x7672_0101;
    const NAME: &'static str = "VrpnServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Opens a server on `port` (0 picks a free one: see `vrpn_server_port`; VRPN's usual port is
/// 3883), listening on every interface, or only on `nic` (a dotted-quad address) unless it is
/// NULL. NULL on failure (port in use, bad address); see `vrpn_last_error`.
#[no_mangle]
pub extern "C" fn vrpn_server_open(port: u16, nic: *const c_char) -> *mut VrpnServer {
    handle::into_handle(|| {
        let nic = if nic.is_null() {
            None
        } else {
            // SAFETY: non-null; C passes a NUL-terminated address.
            let text = unsafe { text_arg(nic, "nic")? };
            Some(text.parse::<Ipv4Addr>().map_err(|_| {
                Failure::invalid(format!("nic {text:?} is not a dotted-quad IPv4 address"))
            })?)
        };
        Ok(VrpnServer {
            header: Header::new::<VrpnServer>(),
            conn: Connection::server(nic, port)?,
        })
    })
}

/// Frees a server handle (NULL is ignored). The sockets close once the device servers made
/// on it are freed too.
#[no_mangle]
pub extern "C" fn vrpn_server_free(server: *mut VrpnServer) -> VrpnStatus {
    handle::free(server)
}

/// Services the server without blocking: accepts clients, reads requests, sends what the
/// device servers reported. Call it after reporting, once per loop.
#[no_mangle]
pub extern "C" fn vrpn_server_mainloop(server: *mut VrpnServer) -> VrpnStatus {
    status(handle::with(server, |s| {
        s.conn.mainloop()?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Sleeps until a client sends something, the server has work due, or `timeout_ms` pass,
/// instead of spinning; call `vrpn_server_mainloop` next.
#[no_mangle]
pub extern "C" fn vrpn_server_wait(server: *mut VrpnServer, timeout_ms: u32) -> VrpnStatus {
    status(handle::with(server, |s| {
        s.conn.wait(Duration::from_millis(u64::from(timeout_ms)))?;
        Ok(VrpnStatus::Ok)
    }))
}

/// The port the server listens on, or a negative status.
#[no_mangle]
pub extern "C" fn vrpn_server_port(server: *const VrpnServer) -> i32 {
    count(handle::with(server, |s| {
        Ok(usize::from(s.conn.local_port().unwrap_or(0)))
    }))
}

/// Number of connected clients, or a negative status.
#[no_mangle]
pub extern "C" fn vrpn_server_connected_clients(server: *const VrpnServer) -> i32 {
    count(handle::with(server, |s| Ok(s.conn.connected_peers())))
}

/// The server's state (`VRPN_CONNECTION_STATE_LISTENING` or `…_CONNECTED`), or a negative
/// status.
#[no_mangle]
pub extern "C" fn vrpn_server_connection_state(server: *const VrpnServer) -> i32 {
    match handle::with(server, |s| Ok(VrpnConnectionState::from(s.conn.state()))) {
        Ok(s) => s as i32,
        Err(f) => super::record(f) as i32,
    }
}

/// Makes a device server of kind `T` on `server`'s connection.
fn device<T: Object>(
    server: *mut VrpnServer,
    name: *const c_char,
    make: impl FnOnce(&Connection, &str) -> Result<T, Failure>,
) -> *mut T {
    handle::into_handle(|| {
        handle::with(server, |s| {
            // SAFETY: C passes a NUL-terminated device name (checked for NULL).
            let name = unsafe { text_arg(name, "device name")? };
            make(&s.conn, name)
        })
    })
}

/// A count argument from C, 1..=max.
fn size(n: i32, what: &str, max: usize) -> Result<usize, Failure> {
    match usize::try_from(n) {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(Failure::invalid(format!(
            "{what} count {n} is not between 1 and {max}"
        ))),
    }
}

/// A time argument from C: NULL means now; a time a message header cannot carry (before
/// 1970, after 2106) is refused.
///
/// # Safety
/// `time` is NULL or points to a readable `VrpnTimeVal`.
unsafe fn time_arg(conn: &Connection, time: *const VrpnTimeVal) -> Result<TimeVal, Failure> {
    if time.is_null() {
        return Ok(conn.now().wall);
    }
    // SAFETY: non-null and readable (caller's contract).
    let raw = unsafe { time.read() };
    let t = TimeVal::from(raw);
    if t.fits_header() {
        Ok(t)
    } else {
        Err(Failure::invalid(format!(
            "time {}.{:06} s is outside what a VRPN message carries (0 to 4294967295 s)",
            raw.sec, raw.usec
        )))
    }
}

/// Reads `N` doubles from C.
///
/// # Safety
/// `p` is NULL or points to `N` readable doubles.
unsafe fn doubles<const N: usize>(p: *const f64, what: &str) -> Result<[f64; N], Failure> {
    if p.is_null() {
        return Err(Failure::new(
            VrpnStatus::NullArgument,
            format!("{what} is NULL"),
        ));
    }
    // SAFETY: non-null and `N` doubles readable (caller's contract); read unaligned-safe.
    Ok(unsafe { p.cast::<[f64; N]>().read_unaligned() })
}

// ------------------------------------------------------------------------------ tracker

/// A tracker server (C++ `vrpn_Tracker_Server`).
pub struct VrpnTrackerServer {
    header: Header,
    server: TrackerServer,
}

impl Object for VrpnTrackerServer {
    const TAG: u32 = 0x7672_0102;
    const NAME: &'static str = "VrpnTrackerServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Serves tracker `name` with `sensors` sensors (1..=1024) on `server`; NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_tracker_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
    sensors: i32,
) -> *mut VrpnTrackerServer {
    device(server, name, |conn, name| {
        Ok(VrpnTrackerServer {
            header: Header::new::<VrpnTrackerServer>(),
            server: TrackerServer::new(name, conn, size(sensors, "sensor", 1024)?)?,
        })
    })
}

/// Frees a tracker server (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_tracker_server_free(tracker: *mut VrpnTrackerServer) -> VrpnStatus {
    handle::free(tracker)
}

/// Reports a pose of `sensor`: `pos` points to 3 doubles (metres), `quat` to 4 (x, y, z, w);
/// `time` is the time to stamp, or NULL for now. Sent at the next `vrpn_server_mainloop`.
#[no_mangle]
pub extern "C" fn vrpn_tracker_server_report_pose(
    tracker: *mut VrpnTrackerServer,
    sensor: i32,
    time: *const VrpnTimeVal,
    pos: *const f64,
    quat: *const f64,
) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        // SAFETY: C passes 3 and 4 readable doubles and a readable time or NULL.
        let (pos, quat, time) = unsafe {
            (
                doubles::<3>(pos, "pos")?,
                doubles::<4>(quat, "quat")?,
                time_arg(t.server.connection(), time)?,
            )
        };
        t.server.report_pose(sensor, time, pos, quat)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Reports a velocity of `sensor`: `vel` 3 doubles (m/s), `vel_quat` 4 (the rotation over
/// `dt` seconds, x, y, z, w); `time` NULL for now.
#[no_mangle]
pub extern "C" fn vrpn_tracker_server_report_velocity(
    tracker: *mut VrpnTrackerServer,
    sensor: i32,
    time: *const VrpnTimeVal,
    vel: *const f64,
    vel_quat: *const f64,
    dt: f64,
) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        // SAFETY: C passes 3 and 4 readable doubles and a readable time or NULL.
        let (vel, vel_quat, time) = unsafe {
            (
                doubles::<3>(vel, "vel")?,
                doubles::<4>(vel_quat, "vel_quat")?,
                time_arg(t.server.connection(), time)?,
            )
        };
        t.server.report_velocity(sensor, time, vel, vel_quat, dt)?;
        Ok(VrpnStatus::Ok)
    }))
}

// ------------------------------------------------------------------------------ button

/// A button server (C++ `vrpn_Button_Server`).
pub struct VrpnButtonServer {
    header: Header,
    server: ButtonServer,
}

impl Object for VrpnButtonServer {
    const TAG: u32 = 0x7672_0103;
    const NAME: &'static str = "VrpnButtonServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Serves button device `name` with `buttons` buttons (1..=256) on `server`; NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_button_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
    buttons: i32,
) -> *mut VrpnButtonServer {
    device(server, name, |conn, name| {
        Ok(VrpnButtonServer {
            header: Header::new::<VrpnButtonServer>(),
            server: ButtonServer::new(name, conn, size(buttons, "button", 256)?)?,
        })
    })
}

/// Frees a button server (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_button_server_free(button: *mut VrpnButtonServer) -> VrpnStatus {
    handle::free(button)
}

/// Sets the state of button `index` (nonzero is pressed); reported by
/// `vrpn_button_server_report_changes`.
#[no_mangle]
pub extern "C" fn vrpn_button_server_set(
    button: *mut VrpnButtonServer,
    index: i32,
    pressed: i32,
) -> VrpnStatus {
    status(handle::with(button, |b| {
        let i = self::index(index, "button")?;
        if i >= b.server.num_buttons() {
            return Err(Failure::invalid(format!(
                "button {i} is beyond this server's {}",
                b.server.num_buttons()
            )));
        }
        b.server.set_button(i, pressed != 0);
        Ok(VrpnStatus::Ok)
    }))
}

/// Sends one change report per button whose state changed, stamped `time` (NULL for now).
#[no_mangle]
pub extern "C" fn vrpn_button_server_report_changes(
    button: *mut VrpnButtonServer,
    time: *const VrpnTimeVal,
) -> VrpnStatus {
    status(handle::with(button, |b| {
        // SAFETY: `time` is a readable VrpnTimeVal or NULL.
        let time = unsafe { time_arg(b.server.connection(), time)? };
        b.server.set_timestamp(time);
        b.server.report_changes()?;
        Ok(VrpnStatus::Ok)
    }))
}

// ------------------------------------------------------------------------------ analog

/// An analog server (C++ `vrpn_Analog_Server`).
pub struct VrpnAnalogServer {
    header: Header,
    server: RefCell<AnalogServer>,
}

impl Object for VrpnAnalogServer {
    const TAG: u32 = 0x7672_0104;
    const NAME: &'static str = "VrpnAnalogServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl VrpnAnalogServer {
    fn server(&self) -> Result<std::cell::RefMut<'_, AnalogServer>, Failure> {
        self.server
            .try_borrow_mut()
            .map_err(|_| Failure::new(VrpnStatus::Busy, "analog server called from its own report"))
    }
}

/// Serves analog device `name` with `channels` channels (1..=128) on `server`; NULL on
/// failure.
#[no_mangle]
pub extern "C" fn vrpn_analog_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
    channels: i32,
) -> *mut VrpnAnalogServer {
    device(server, name, |conn, name| {
        let n = size(channels, "channel", super::types::VRPN_ANALOG_MAX_CHANNELS)?;
        Ok(VrpnAnalogServer {
            header: Header::new::<VrpnAnalogServer>(),
            server: RefCell::new(AnalogServer::new(name, conn, n)?),
        })
    })
}

/// Frees an analog server (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_analog_server_free(analog: *mut VrpnAnalogServer) -> VrpnStatus {
    handle::free(analog)
}

/// Sets channel `index` to `value`; sent by the next report call.
#[no_mangle]
pub extern "C" fn vrpn_analog_server_set(
    analog: *mut VrpnAnalogServer,
    index: i32,
    value: f64,
) -> VrpnStatus {
    status(handle::with(analog, |a| {
        let mut s = a.server()?;
        let i = self::index(index, "channel")?;
        if i >= s.num_channels() {
            return Err(Failure::invalid(format!(
                "channel {i} is beyond this server's {}",
                s.num_channels()
            )));
        }
        s.set_channel(i, value);
        Ok(VrpnStatus::Ok)
    }))
}

/// Sends every channel now, stamped `time` (NULL for now).
#[no_mangle]
pub extern "C" fn vrpn_analog_server_report(
    analog: *mut VrpnAnalogServer,
    time: *const VrpnTimeVal,
) -> VrpnStatus {
    status(handle::with(analog, |a| {
        let mut s = a.server()?;
        // SAFETY: `time` is a readable VrpnTimeVal or NULL.
        let time = unsafe { time_arg(s.connection(), time)? };
        s.report(Some(time))?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Sends every channel if any changed since the last report: `VRPN_STATUS_OK` when it sent,
/// `VRPN_STATUS_NO_DATA` when nothing changed.
#[no_mangle]
pub extern "C" fn vrpn_analog_server_report_changes(
    analog: *mut VrpnAnalogServer,
    time: *const VrpnTimeVal,
) -> VrpnStatus {
    status(handle::with(analog, |a| {
        let mut s = a.server()?;
        // SAFETY: `time` is a readable VrpnTimeVal or NULL.
        let time = unsafe { time_arg(s.connection(), time)? };
        Ok(if s.report_changes(Some(time))? {
            VrpnStatus::Ok
        } else {
            VrpnStatus::NoData
        })
    }))
}

// ------------------------------------------------------------------------------ dial

/// A dial server (C++ `vrpn_Dial_Server`).
pub struct VrpnDialServer {
    header: Header,
    conn: Connection,
    server: RefCell<DialServer>,
}

impl Object for VrpnDialServer {
    const TAG: u32 = 0x7672_0105;
    const NAME: &'static str = "VrpnDialServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Serves dial device `name` with `dials` dials (1..=128) on `server`; NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_dial_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
    dials: i32,
) -> *mut VrpnDialServer {
    device(server, name, |conn, name| {
        let n = size(dials, "dial", super::types::VRPN_DIAL_MAX_DIALS)?;
        Ok(VrpnDialServer {
            header: Header::new::<VrpnDialServer>(),
            conn: conn.clone(),
            server: RefCell::new(DialServer::new(name, conn, n)?),
        })
    })
}

/// Frees a dial server (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_dial_server_free(dial: *mut VrpnDialServer) -> VrpnStatus {
    handle::free(dial)
}

/// Adds `revolutions` to dial `index`'s rotation since its last report.
#[no_mangle]
pub extern "C" fn vrpn_dial_server_add(
    dial: *mut VrpnDialServer,
    index: i32,
    revolutions: f64,
) -> VrpnStatus {
    status(handle::with(dial, |d| {
        let mut s = d
            .server
            .try_borrow_mut()
            .map_err(|_| Failure::new(VrpnStatus::Busy, "dial server is busy"))?;
        let i = self::index(index, "dial")?;
        if i >= s.num_dials() {
            return Err(Failure::invalid(format!(
                "dial {i} is beyond this server's {}",
                s.num_dials()
            )));
        }
        s.add_rotation(i, revolutions);
        Ok(VrpnStatus::Ok)
    }))
}

/// Sends one update per dial that turned since its last report, stamped `time` (NULL for
/// now), and starts summing anew.
#[no_mangle]
pub extern "C" fn vrpn_dial_server_report_changes(
    dial: *mut VrpnDialServer,
    time: *const VrpnTimeVal,
) -> VrpnStatus {
    status(handle::with(dial, |d| {
        let mut s = d
            .server
            .try_borrow_mut()
            .map_err(|_| Failure::new(VrpnStatus::Busy, "dial server is busy"))?;
        // SAFETY: `time` is a readable VrpnTimeVal or NULL.
        s.set_timestamp(unsafe { time_arg(&d.conn, time)? });
        s.report_changes()?;
        Ok(VrpnStatus::Ok)
    }))
}
