//! Client side, the connection itself: the device names a server offers (sender discovery)
//! and the controls of a log replay (`Device@file:PATH`).
//!
//! A `VrpnConnection` is the connection of a location, shared with every remote opened with
//! the same location text (as remotes share it among themselves); its `mainloop` serves all
//! of them.

use std::cell::RefCell;
use std::ffi::{c_char, c_void};
use std::rc::Rc;

use super::client::{index, out_arg, Callbacks};
use super::handle::{self, write_out, Header, Object};
use super::types::VrpnTimeVal;
use super::{count, status, text_arg, Failure, VrpnConnectionState, VrpnStatus};
use crate::connection::ReplayControl;
use crate::Connection;

/// Capacity a buffer needs for any VRPN name: 95 bytes and the NUL.
pub const VRPN_NAME_CAPACITY: usize = 96;

const _: () = assert!(VRPN_NAME_CAPACITY == crate::wire::MAX_NAME_LEN + 1);

/// Receives a sender name a peer described; `name` is NUL-terminated and valid during the
/// call only.
pub type VrpnPeerSenderCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, name: *const c_char)>;

/// The connection of a location (C++ `vrpn_Connection` from `vrpn_get_connection_by_name`).
pub struct VrpnConnection {
    header: Header,
    conn: Connection,
    callbacks: Callbacks,
}

impl Drop for VrpnConnection {
    fn drop(&mut self) {
        // The handlers live in the connection, which remotes may keep open: they must not
        // call the caller's function after its handle is gone.
        for id in self.callbacks.take_all() {
            self.conn.remove_handler(id);
        }
    }
}

impl Object for VrpnConnection {
    const TAG: u32 = 0x7672_0006;
    const NAME: &'static str = "VrpnConnection";
    fn header(&self) -> &Header {
        &self.header
    }
}

/// Opens (or shares) the connection of the location in device name `name`
/// ("Tracker0@host", "Tracker0@file:log.vrpn"): the one remotes opened with the same location
/// use. NULL on failure; see `vrpn_last_error`.
#[no_mangle]
pub extern "C" fn vrpn_connection_open(name: *const c_char) -> *mut VrpnConnection {
    handle::into_handle(|| {
        // SAFETY: C passes a NUL-terminated device name (checked for NULL).
        let name = unsafe { text_arg(name, "device name")? };
        Ok(VrpnConnection {
            header: Header::new::<VrpnConnection>(),
            conn: Connection::open(name)?,
            callbacks: Callbacks::default(),
        })
    })
}

/// Frees a connection handle (NULL is ignored); the connection closes once no remote uses it.
#[no_mangle]
pub extern "C" fn vrpn_connection_free(connection: *mut VrpnConnection) -> VrpnStatus {
    handle::free(connection)
}

/// Services the connection without blocking; runs the callbacks of every remote on it.
#[no_mangle]
pub extern "C" fn vrpn_connection_mainloop(connection: *mut VrpnConnection) -> VrpnStatus {
    status(handle::with(connection, |c| {
        c.conn.mainloop()?;
        Ok(VrpnStatus::Ok)
    }))
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_connection_state(connection: *const VrpnConnection) -> i32 {
    match handle::with(connection, |c| {
        Ok(VrpnConnectionState::from(c.conn.state()))
    }) {
        Ok(s) => s as i32,
        Err(f) => super::record(f) as i32,
    }
}

/// Calls `callback(userdata, name)` with each sender (device) name the server describes, as
/// it is described, inside `mainloop`.
#[no_mangle]
pub extern "C" fn vrpn_connection_on_peer_sender(
    connection: *mut VrpnConnection,
    callback: VrpnPeerSenderCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(connection, |c| {
        let Some(f) = callback else {
            return Err(Failure::new(
                VrpnStatus::NullArgument,
                "callback function is NULL",
            ));
        };
        // The name with its NUL, built in a buffer kept with the callback (no allocation
        // per call once it has grown to the longest name).
        let buf = Rc::new(RefCell::new(Vec::<u8>::with_capacity(VRPN_NAME_CAPACITY)));
        let id = c.conn.on_peer_sender(move |name| {
            let mut b = buf.borrow_mut();
            b.clear();
            b.extend(name.bytes().filter(|&x| x != 0));
            b.push(0);
            // SAFETY: `f` is the caller's function with this signature; `userdata` goes back
            // untouched; the buffer is NUL-terminated and alive for the call.
            unsafe { f(userdata, b.as_ptr().cast()) };
        });
        c.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by the id `vrpn_connection_on_peer_sender` gave.
#[no_mangle]
pub extern "C" fn vrpn_connection_remove_callback(
    connection: *mut VrpnConnection,
    id: u64,
) -> VrpnStatus {
    status(handle::with(connection, |c| {
        c.conn.remove_handler(c.callbacks.take(id)?);
        Ok(VrpnStatus::Ok)
    }))
}

/// Number of sender (device) names the server has described so far, or a negative status.
#[no_mangle]
pub extern "C" fn vrpn_connection_peer_sender_count(connection: *const VrpnConnection) -> i32 {
    count(handle::with(connection, |c| {
        Ok(c.conn.peer_senders().len())
    }))
}

/// Copies sender name `index` (0 .. `vrpn_connection_peer_sender_count` - 1) into `name`, NUL
/// terminated (`VRPN_NAME_CAPACITY` bytes always suffice); returns its length in bytes, or a
/// negative status (`VRPN_STATUS_INVALID_ARGUMENT` for an index beyond the count or a buffer
/// too small, which is left untouched).
#[no_mangle]
pub extern "C" fn vrpn_connection_peer_sender(
    connection: *const VrpnConnection,
    index: i32,
    name: *mut c_char,
    capacity: usize,
) -> i32 {
    count(handle::with(connection, |c| {
        let i = self::index(index, "sender index")?;
        out_arg(name, "name")?;
        let names = c.conn.peer_senders();
        let Some(n) = names.get(i) else {
            return Err(Failure::invalid(format!(
                "sender index {i} is beyond the {} names described",
                names.len()
            )));
        };
        if n.len() >= capacity {
            return Err(Failure::invalid(format!(
                "name buffer of {capacity} bytes is too small for {:?} ({} bytes and the NUL)",
                n,
                n.len()
            )));
        }
        // SAFETY: `name` has room for `capacity > n.len()` bytes (caller's contract).
        unsafe {
            std::ptr::copy_nonoverlapping(n.as_ptr(), name.cast::<u8>(), n.len());
            name.add(n.len()).write(0);
        }
        Ok(n.len())
    }))
}

// ------------------------------------------------------------------------------ replay

/// Runs `f` on the replay controls of `connection`; `VRPN_STATUS_UNSUPPORTED` for a live one.
fn replay<R>(
    connection: *const VrpnConnection,
    f: impl FnOnce(ReplayControl<'_>) -> Result<R, Failure>,
) -> Result<R, Failure> {
    handle::with(connection, |c| match c.conn.replay() {
        Some(r) => f(r),
        None => Err(Failure::new(
            VrpnStatus::Unsupported,
            "not a replay: replay controls need a DEVICE@file:PATH connection",
        )),
    })
}

/// A seconds argument: finite and not negative.
fn secs_arg(secs: f64, what: &str) -> Result<f64, Failure> {
    if secs.is_finite() && secs >= 0.0 {
        Ok(secs)
    } else {
        Err(Failure::invalid(format!(
            "{what} must be a finite number of seconds >= 0, got {secs}"
        )))
    }
}

/// 1 when `connection` replays a log file, 0 for a live one, or a negative status.
#[no_mangle]
pub extern "C" fn vrpn_connection_is_replay(connection: *const VrpnConnection) -> i32 {
    count(handle::with(connection, |c| {
        Ok(usize::from(c.conn.is_replay()))
    }))
}

/// Sets the replay speed: 1.0 real time, 0 paused, 10 ten times faster, `INFINITY` as fast as
/// possible.
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_set_rate(
    connection: *mut VrpnConnection,
    rate: f64,
) -> VrpnStatus {
    status(replay(connection, |r| {
        if rate.is_nan() || rate < 0.0 {
            return Err(Failure::invalid(format!(
                "replay rate must be >= 0 (0 pauses), got {rate}"
            )));
        }
        r.set_rate(rate);
        Ok(VrpnStatus::Ok)
    }))
}

/// Writes the replay speed to `*rate`.
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_rate(
    connection: *const VrpnConnection,
    rate: *mut f64,
) -> VrpnStatus {
    status(replay(connection, |r| {
        out_arg(rate, "rate")?;
        // SAFETY: `rate` is a writable double (checked non-NULL).
        unsafe { write_out(rate, r.rate(), "rate")? };
        Ok(VrpnStatus::Ok)
    }))
}

/// Moves to `secs` after the first message without delivering the messages in between:
/// `VRPN_STATUS_OK`, or `VRPN_STATUS_NO_DATA` when that time is beyond the log's end (the
/// replay then stands at the end).
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_seek(
    connection: *mut VrpnConnection,
    secs: f64,
) -> VrpnStatus {
    status(replay(connection, |r| {
        let s = secs_arg(secs, "seek time")?;
        Ok(if r.jump_to_time(s) {
            VrpnStatus::Ok
        } else {
            VrpnStatus::NoData
        })
    }))
}

/// Delivers, now, every message up to `secs` after the first one (callbacks run inside).
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_play_to(
    connection: *mut VrpnConnection,
    secs: f64,
) -> VrpnStatus {
    status(replay(connection, |r| {
        r.play_to_time(secs_arg(secs, "play-to time")?);
        Ok(VrpnStatus::Ok)
    }))
}

/// Delivers the next message now: `VRPN_STATUS_OK`, or `VRPN_STATUS_NO_DATA` at the end.
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_play_one(connection: *mut VrpnConnection) -> VrpnStatus {
    status(replay(connection, |r| {
        Ok(if r.play_one() {
            VrpnStatus::Ok
        } else {
            VrpnStatus::NoData
        })
    }))
}

/// Back to the start of the log.
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_reset(connection: *mut VrpnConnection) -> VrpnStatus {
    status(replay(connection, |r| {
        r.reset();
        Ok(VrpnStatus::Ok)
    }))
}

/// 1 once every message has been played, 0 before, or a negative status.
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_eof(connection: *const VrpnConnection) -> i32 {
    count(replay(connection, |r| Ok(usize::from(r.eof()))))
}

/// Writes where the replay stands, in seconds since the first message, to `*secs`.
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_position(
    connection: *const VrpnConnection,
    secs: *mut f64,
) -> VrpnStatus {
    status(replay(connection, |r| {
        out_arg(secs, "secs")?;
        // SAFETY: `secs` is a writable double (checked non-NULL).
        unsafe { write_out(secs, r.elapsed(), "secs")? };
        Ok(VrpnStatus::Ok)
    }))
}

/// Writes the seconds between the log's first and last message to `*secs`.
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_length(
    connection: *const VrpnConnection,
    secs: *mut f64,
) -> VrpnStatus {
    status(replay(connection, |r| {
        out_arg(secs, "secs")?;
        // SAFETY: `secs` is a writable double (checked non-NULL).
        unsafe { write_out(secs, r.length_secs(), "secs")? };
        Ok(VrpnStatus::Ok)
    }))
}

/// Writes the time of the log's first message to `*time`: `VRPN_STATUS_OK`, or
/// `VRPN_STATUS_NO_DATA` (nothing written) for a log without messages.
#[no_mangle]
pub extern "C" fn vrpn_connection_replay_start_time(
    connection: *const VrpnConnection,
    time: *mut VrpnTimeVal,
) -> VrpnStatus {
    status(replay(connection, |r| {
        out_arg(time, "time")?;
        match r.first_time() {
            // SAFETY: `time` is a writable VrpnTimeVal (checked non-NULL).
            Some(t) => unsafe { write_out(time, t.into(), "time")? },
            None => return Ok(VrpnStatus::NoData),
        }
        Ok(VrpnStatus::Ok)
    }))
}
