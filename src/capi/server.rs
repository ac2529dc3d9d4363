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
use crate::server::limits::{self, Claim, Interface, PublishError, Published};
use crate::time::TimeVal;
use crate::{ButtonServer, Connection, TrackerServer};

/// A server connection (C++ `vrpn_Connection` made by `vrpn_create_server_connection`).
pub struct VrpnServer {
    header: Header,
    conn: Connection,
    /// The device names published on it (one device per interface and name).
    published: Published,
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
            published: Published::default(),
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

/// The server's descriptor for the program's own `poll`/`select`/`epoll` loop (see
/// `vrpn_tracker_fd`): readable when a client sends something or the server has timed work
/// due. Never read it or close it. A negative status on failure.
#[no_mangle]
pub extern "C" fn vrpn_server_fd(server: *const VrpnServer) -> i32 {
    match handle::with(server, |s| super::waiting::fd_of(&s.conn)) {
        Ok(fd) => fd,
        Err(f) => super::record(f) as i32,
    }
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

/// Makes a device server of interface `kind` with `count` elements on `server`'s connection,
/// after the checks every binding applies ([`crate::server::limits`]): the count within the
/// bounds `vrpn.cfg` has, a name clients can open, no other device of the interface under it.
fn device<T: Object>(
    server: *mut VrpnServer,
    name: *const c_char,
    kind: Interface,
    count: i32,
    make: impl FnOnce(&Connection, &str, usize, Claim) -> Result<T, Failure>,
) -> *mut T {
    handle::into_handle(|| {
        handle::with(server, |s| {
            // SAFETY: C passes a NUL-terminated device name (checked for NULL).
            let name = unsafe { text_arg(name, "device name")? };
            let n = if kind == Interface::Text {
                0
            } else {
                limits::check_count(kind, Some(count.into()), &count.to_string())
                    .map_err(publish_failure)?
            };
            let claim = s.published.claim(kind, name).map_err(publish_failure)?;
            make(&s.conn, name, n, claim)
        })
    })
}

/// A refused device server as a C status: a bad name is `VRPN_STATUS_NAME`, a bad count or
/// a name already taken `VRPN_STATUS_INVALID_ARGUMENT`.
fn publish_failure(e: PublishError) -> Failure {
    let status = match e {
        PublishError::Name(_) => VrpnStatus::Name,
        PublishError::Count(_) | PublishError::Duplicate(_) => VrpnStatus::InvalidArgument,
    };
    Failure::new(status, e.to_string())
}

/// A time argument from C: NULL means now; otherwise microseconds must be 0..=999999 (a
/// `struct timeval` in its normal form), as C++ VRPN and every reader of the stamp expect,
/// and the time must be one a message header can carry (1970 to 2106).
///
/// # Safety
/// `time` is NULL or points to a readable `VrpnTimeVal`.
unsafe fn time_arg(conn: &Connection, time: *const VrpnTimeVal) -> Result<TimeVal, Failure> {
    if time.is_null() {
        return Ok(conn.now().wall);
    }
    // SAFETY: non-null and readable (caller's contract).
    let t = unsafe { time.read() };
    if !(0..1_000_000).contains(&t.usec) {
        return Err(Failure::invalid(format!(
            "time {{sec {}, usec {}}}: usec must be between 0 and 999999",
            t.sec, t.usec
        )));
    }
    let time = TimeVal::from(t);
    if !time.fits_header() {
        return Err(Failure::invalid(format!(
            "time {{sec {}, usec {}}} is outside what a VRPN message carries (0 to 4294967295 s)",
            t.sec, t.usec
        )));
    }
    Ok(time)
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
    _name: Claim,
}

impl Object for VrpnTrackerServer {
    const TAG: u32 = 0x7672_0102;
    const NAME: &'static str = "VrpnTrackerServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Serves tracker `name` with `sensors` sensors (1..=1024, as in `vrpn.cfg`) on `server`;
/// NULL on failure: a count out of range or a name already serving a tracker on this server
/// (`VRPN_STATUS_INVALID_ARGUMENT`), a name with `@` or empty (`VRPN_STATUS_NAME`).
#[no_mangle]
pub extern "C" fn vrpn_tracker_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
    sensors: i32,
) -> *mut VrpnTrackerServer {
    device(
        server,
        name,
        Interface::Tracker,
        sensors,
        |conn, name, n, claim| {
            Ok(VrpnTrackerServer {
                header: Header::new::<VrpnTrackerServer>(),
                server: TrackerServer::new(name, conn, n)?,
                _name: claim,
            })
        },
    )
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

/// Reports a velocity of `sensor`: `vel` 3 doubles (m/s, tracker frame), `vel_quat` 4 (the
/// rotation over `dt` seconds in the tracker's frame, x, y, z, w: the orientation `dt` later
/// is `vel_quat * quat`); `time` NULL for now.
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
    _name: Claim,
}

impl Object for VrpnButtonServer {
    const TAG: u32 = 0x7672_0103;
    const NAME: &'static str = "VrpnButtonServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Serves button device `name` with `buttons` buttons (1..=256) on `server`; NULL on failure
/// (see `vrpn_tracker_server_new`).
#[no_mangle]
pub extern "C" fn vrpn_button_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
    buttons: i32,
) -> *mut VrpnButtonServer {
    device(
        server,
        name,
        Interface::Button,
        buttons,
        |conn, name, n, claim| {
            Ok(VrpnButtonServer {
                header: Header::new::<VrpnButtonServer>(),
                server: ButtonServer::new(name, conn, n)?,
                _name: claim,
            })
        },
    )
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
    _name: Claim,
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
/// failure (see `vrpn_tracker_server_new`).
#[no_mangle]
pub extern "C" fn vrpn_analog_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
    channels: i32,
) -> *mut VrpnAnalogServer {
    device(
        server,
        name,
        Interface::Analog,
        channels,
        |conn, name, n, claim| {
            Ok(VrpnAnalogServer {
                header: Header::new::<VrpnAnalogServer>(),
                server: RefCell::new(AnalogServer::new(name, conn, n)?),
                _name: claim,
            })
        },
    )
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
    _name: Claim,
}

impl Object for VrpnDialServer {
    const TAG: u32 = 0x7672_0105;
    const NAME: &'static str = "VrpnDialServer";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Serves dial device `name` with `dials` dials (1..=128) on `server`; NULL on failure (see
/// `vrpn_tracker_server_new`).
#[no_mangle]
pub extern "C" fn vrpn_dial_server_new(
    server: *mut VrpnServer,
    name: *const c_char,
    dials: i32,
) -> *mut VrpnDialServer {
    device(
        server,
        name,
        Interface::Dial,
        dials,
        |conn, name, n, claim| {
            Ok(VrpnDialServer {
                header: Header::new::<VrpnDialServer>(),
                conn: conn.clone(),
                server: RefCell::new(DialServer::new(name, conn, n)?),
                _name: claim,
            })
        },
    )
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
