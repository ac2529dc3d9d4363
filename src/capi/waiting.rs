//! Waiting without spinning from C: `vrpn_*_wait` blocks in the reactor's poll until data
//! arrives, the connection has timed work due, or the time-out passes; `vrpn_*_fd` gives the
//! descriptor for a program's own `poll`/`select`/`epoll` loop. Both are
//! [`Connection::wait`](crate::Connection::wait) and [`Connection::fd`](crate::Connection::fd),
//! as in Rust and Python.

use std::time::Duration;

use super::client::{Remote, VrpnTracker};
use super::handle;
use super::remotes::{VrpnAnalog, VrpnButton, VrpnDial};
use super::{status, Failure, VrpnStatus};
use crate::Connection;

/// Waits on `conn`: `Ok` when data arrived, `NoData` when the time-out or a deadline ended it.
pub(crate) fn wait_on(conn: &Connection, timeout_ms: u32) -> Result<VrpnStatus, Failure> {
    let data = conn.wait(Duration::from_millis(u64::from(timeout_ms)))?;
    Ok(if data {
        VrpnStatus::Ok
    } else {
        VrpnStatus::NoData
    })
}

/// `conn`'s descriptor, or `Unsupported` for connections without sockets.
pub(crate) fn fd_of(conn: &Connection) -> Result<i32, Failure> {
    conn.fd().ok_or_else(|| {
        Failure::new(
            VrpnStatus::Unsupported,
            "this connection has no descriptor (a replay or loopback connection has no \
             sockets): call mainloop on a timer instead",
        )
    })
}

fn wait<T: Remote>(r: *mut T, timeout_ms: u32) -> VrpnStatus {
    status(handle::with(r, |r| {
        wait_on(r.core().connection(), timeout_ms)
    }))
}

fn fd<T: Remote>(r: *const T) -> i32 {
    match handle::with(r, |r| fd_of(r.core().connection())) {
        Ok(fd) => fd,
        Err(f) => super::record(f) as i32,
    }
}

/// Blocks (without spinning: in the reactor's poll) until data arrives for the tracker's
/// connection, the connection has timed work due (a reconnection attempt, a liveness ping),
/// or `timeout_ms` pass. Returns `VRPN_STATUS_OK` when data arrived, `VRPN_STATUS_NO_DATA`
/// otherwise; call `vrpn_tracker_mainloop` next.
#[no_mangle]
pub extern "C" fn vrpn_tracker_wait(tracker: *mut VrpnTracker, timeout_ms: u32) -> VrpnStatus {
    wait(tracker, timeout_ms)
}

/// The descriptor to wait on for reading in the program's own `poll`/`select`/`epoll` loop:
/// readable when data arrives or the connection's next timed work is due (each mainloop sets
/// a timer in it). Call `vrpn_tracker_mainloop` when it is readable. The descriptor belongs
/// to the library: never read it or close it. A negative status on failure
/// (`VRPN_STATUS_UNSUPPORTED` for a replay, which has no sockets).
#[no_mangle]
pub extern "C" fn vrpn_tracker_fd(tracker: *const VrpnTracker) -> i32 {
    fd(tracker)
}

/// `vrpn_tracker_wait` for a button remote.
#[no_mangle]
pub extern "C" fn vrpn_button_wait(button: *mut VrpnButton, timeout_ms: u32) -> VrpnStatus {
    wait(button, timeout_ms)
}

/// `vrpn_tracker_fd` for a button remote.
#[no_mangle]
pub extern "C" fn vrpn_button_fd(button: *const VrpnButton) -> i32 {
    fd(button)
}

/// `vrpn_tracker_wait` for an analog remote.
#[no_mangle]
pub extern "C" fn vrpn_analog_wait(analog: *mut VrpnAnalog, timeout_ms: u32) -> VrpnStatus {
    wait(analog, timeout_ms)
}

/// `vrpn_tracker_fd` for an analog remote.
#[no_mangle]
pub extern "C" fn vrpn_analog_fd(analog: *const VrpnAnalog) -> i32 {
    fd(analog)
}

/// `vrpn_tracker_wait` for a dial remote.
#[no_mangle]
pub extern "C" fn vrpn_dial_wait(dial: *mut VrpnDial, timeout_ms: u32) -> VrpnStatus {
    wait(dial, timeout_ms)
}

/// `vrpn_tracker_fd` for a dial remote.
#[no_mangle]
pub extern "C" fn vrpn_dial_fd(dial: *const VrpnDial) -> i32 {
    fd(dial)
}
