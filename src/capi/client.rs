//! Client side, tracker: open a remote by name, `mainloop`, callbacks, latest-state polling.
//! (Buttons, analogs and dials are in `remotes.rs`; the parts every remote shares are here.)

use std::cell::RefCell;
use std::ffi::{c_char, c_void};

use super::handle::{self, write_out, Header, Object};
use super::types::{
    CCallback, VrpnTrackerAcceleration, VrpnTrackerAccelerationCallback, VrpnTrackerPose,
    VrpnTrackerPoseCallback, VrpnTrackerVelocity, VrpnTrackerVelocityCallback,
};
use super::{count, status, text_arg, Failure, VrpnConnectionState, VrpnStatus};
use crate::devices::base::RemoteCore;
use crate::dispatch::HandlerId;
use crate::TrackerRemote;

/// The callbacks a handle registered, by the id C was given (index + 1; ids are not reused).
#[derive(Default)]
pub(crate) struct Callbacks(RefCell<Vec<Option<HandlerId>>>);

impl Callbacks {
    /// Records `id` and writes the C id to `id_out` (which may be NULL).
    pub(crate) fn add(&self, id: HandlerId, id_out: *mut u64) -> Result<VrpnStatus, Failure> {
        let mut v = self.0.borrow_mut();
        v.push(Some(id));
        if !id_out.is_null() {
            // SAFETY: non-null; the caller passes a writable uint64_t or NULL.
            unsafe { write_out(id_out, v.len() as u64, "id_out")? };
        }
        Ok(VrpnStatus::Ok)
    }

    /// Forgets every callback and returns the handlers still registered.
    pub(crate) fn take_all(&self) -> Vec<HandlerId> {
        self.0.borrow_mut().drain(..).flatten().collect()
    }

    /// Forgets C id `id` and returns the handler to remove.
    pub(crate) fn take(&self, id: u64) -> Result<HandlerId, Failure> {
        let mut v = self.0.borrow_mut();
        usize::try_from(id)
            .ok()
            .and_then(|i| i.checked_sub(1))
            .and_then(|i| v.get_mut(i))
            .and_then(Option::take)
            .ok_or_else(|| Failure::invalid(format!("no callback with id {id} on this handle")))
    }
}

/// What every remote handle offers: its core (connection, mainloop) and its callbacks.
pub(crate) trait Remote: Object {
    fn core(&self) -> &RemoteCore;
}

/// Checks a C callback pointer.
pub(crate) fn callback<C: Copy>(
    f: Option<unsafe extern "C" fn(*mut c_void, *const C)>,
    userdata: *mut c_void,
) -> Result<CCallback<C>, Failure> {
    match f {
        Some(f) => Ok(CCallback { f, userdata }),
        None => Err(Failure::new(
            VrpnStatus::NullArgument,
            "callback function is NULL",
        )),
    }
}

/// Opens a remote of kind `T` for `name` with `make`.
pub(crate) fn open<T: Object>(
    name: *const c_char,
    make: impl FnOnce(&str) -> Result<T, crate::Error>,
) -> *mut T {
    handle::into_handle(|| {
        // SAFETY: C passes a NUL-terminated device name (checked for NULL).
        let name = unsafe { text_arg(name, "device name")? };
        Ok(make(name)?)
    })
}

pub(crate) fn mainloop<T: Remote>(r: *mut T) -> VrpnStatus {
    status(handle::with(r, |r| {
        r.core().mainloop()?;
        Ok(VrpnStatus::Ok)
    }))
}

pub(crate) fn connection_state<T: Remote>(r: *const T) -> i32 {
    match handle::with(r, |r| {
        Ok(VrpnConnectionState::from(r.core().connection().state()))
    }) {
        Ok(s) => s as i32,
        Err(f) => super::record(f) as i32,
    }
}

/// Sensor index from C.
pub(crate) fn index(i: i32, what: &str) -> Result<usize, Failure> {
    usize::try_from(i).map_err(|_| Failure::invalid(format!("{what} {i} is negative")))
}

/// Refuses a NULL output pointer. Every polling call checks its arguments first, so a call
/// with a NULL output fails the same way before and after data arrived.
pub(crate) fn out_arg<T>(out: *mut T, what: &str) -> Result<(), Failure> {
    if out.is_null() {
        return Err(Failure::new(
            VrpnStatus::NullArgument,
            format!("{what} is NULL"),
        ));
    }
    Ok(())
}

/// A tracker remote (C++ `vrpn_Tracker_Remote`).
pub struct VrpnTracker {
    header: Header,
    remote: TrackerRemote,
    callbacks: Callbacks,
}

impl Object for VrpnTracker {
    const TAG: u32 = 0x7672_0001;
    const NAME: &'static str = "VrpnTracker";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl Remote for VrpnTracker {
    fn core(&self) -> &RemoteCore {
        &self.remote
    }
}

/// Opens the tracker `name` ("Tracker0@host", "Tracker0@host:3884", "Tracker0@tcp://host").
///
/// Returns at once: the connection is made (and remade after a loss) during later
/// `vrpn_tracker_mainloop` calls. Devices at the same location share one connection.
/// NULL on failure (bad name, unknown host); see `vrpn_last_error`.
#[no_mangle]
pub extern "C" fn vrpn_tracker_open(name: *const c_char) -> *mut VrpnTracker {
    open(name, |n| {
        Ok(VrpnTracker {
            header: Header::new::<VrpnTracker>(),
            remote: TrackerRemote::new(n)?,
            callbacks: Callbacks::default(),
        })
    })
}

/// Frees a tracker (NULL is ignored). May be called from inside its own callback: it is then
/// released when the running `mainloop` returns.
#[no_mangle]
pub extern "C" fn vrpn_tracker_free(tracker: *mut VrpnTracker) -> VrpnStatus {
    handle::free(tracker)
}

/// Services the tracker's connection without blocking: connects, reads, runs callbacks.
/// Call it once per frame.
#[no_mangle]
pub extern "C" fn vrpn_tracker_mainloop(tracker: *mut VrpnTracker) -> VrpnStatus {
    mainloop(tracker)
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_tracker_connection_state(tracker: *const VrpnTracker) -> i32 {
    connection_state(tracker)
}

/// Calls `callback(userdata, pose)` for every pose report; writes the callback's id to
/// `id_out` unless it is NULL.
#[no_mangle]
pub extern "C" fn vrpn_tracker_on_pose(
    tracker: *mut VrpnTracker,
    callback: VrpnTrackerPoseCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        let cb = self::callback(callback, userdata)?;
        let id = t.remote.on_pose(move |p| cb.call(VrpnTrackerPose::from(p)));
        t.callbacks.add(id, id_out)
    }))
}

/// Calls `callback(userdata, velocity)` for every velocity report.
#[no_mangle]
pub extern "C" fn vrpn_tracker_on_velocity(
    tracker: *mut VrpnTracker,
    callback: VrpnTrackerVelocityCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        let cb = self::callback(callback, userdata)?;
        let id = t
            .remote
            .on_velocity(move |v| cb.call(VrpnTrackerVelocity::from(v)));
        t.callbacks.add(id, id_out)
    }))
}

/// Calls `callback(userdata, acceleration)` for every acceleration report.
#[no_mangle]
pub extern "C" fn vrpn_tracker_on_acceleration(
    tracker: *mut VrpnTracker,
    callback: VrpnTrackerAccelerationCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        let cb = self::callback(callback, userdata)?;
        let id = t
            .remote
            .on_acceleration(move |a| cb.call(VrpnTrackerAcceleration::from(a)));
        t.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by the id a `vrpn_tracker_on_*` call gave.
#[no_mangle]
pub extern "C" fn vrpn_tracker_remove_callback(tracker: *mut VrpnTracker, id: u64) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        let h = t.callbacks.take(id)?;
        t.remote.remove_callback(h);
        Ok(VrpnStatus::Ok)
    }))
}

/// Copies the latest pose of `sensor` into `*pose`: `VRPN_STATUS_OK`, or
/// `VRPN_STATUS_NO_DATA` (nothing written) while none has arrived.
#[no_mangle]
pub extern "C" fn vrpn_tracker_pose(
    tracker: *const VrpnTracker,
    sensor: i32,
    pose: *mut VrpnTrackerPose,
) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        let sensor = index(sensor, "sensor")?;
        out_arg(pose, "pose")?;
        match t.remote.pose(sensor) {
            // SAFETY: `pose` is a writable VrpnTrackerPose (checked non-NULL above).
            Some(p) => unsafe { write_out(pose, VrpnTrackerPose::from(&p), "pose")? },
            None => return Ok(VrpnStatus::NoData),
        }
        Ok(VrpnStatus::Ok)
    }))
}

/// Copies the latest velocity of `sensor` into `*velocity` (or `VRPN_STATUS_NO_DATA`).
#[no_mangle]
pub extern "C" fn vrpn_tracker_velocity(
    tracker: *const VrpnTracker,
    sensor: i32,
    velocity: *mut VrpnTrackerVelocity,
) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        let sensor = index(sensor, "sensor")?;
        out_arg(velocity, "velocity")?;
        match t.remote.velocity(sensor) {
            // SAFETY: `velocity` is writable or NULL (checked).
            Some(v) => unsafe { write_out(velocity, VrpnTrackerVelocity::from(&v), "velocity")? },
            None => return Ok(VrpnStatus::NoData),
        }
        Ok(VrpnStatus::Ok)
    }))
}

/// Copies the latest acceleration of `sensor` into `*acceleration` (or `VRPN_STATUS_NO_DATA`).
#[no_mangle]
pub extern "C" fn vrpn_tracker_acceleration(
    tracker: *const VrpnTracker,
    sensor: i32,
    acceleration: *mut VrpnTrackerAcceleration,
) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        let sensor = index(sensor, "sensor")?;
        out_arg(acceleration, "acceleration")?;
        match t.remote.acceleration(sensor) {
            // SAFETY: `acceleration` is writable or NULL (checked).
            Some(a) => unsafe {
                write_out(
                    acceleration,
                    VrpnTrackerAcceleration::from(&a),
                    "acceleration",
                )?
            },
            None => return Ok(VrpnStatus::NoData),
        }
        Ok(VrpnStatus::Ok)
    }))
}

/// Number of sensor slots seen so far (highest sensor index + 1), or a negative status.
#[no_mangle]
pub extern "C" fn vrpn_tracker_sensor_count(tracker: *const VrpnTracker) -> i32 {
    count(handle::with(tracker, |t| Ok(t.remote.sensor_count())))
}

/// Asks the server for `hz` reports per second (servers that cannot honour it ignore it).
#[no_mangle]
pub extern "C" fn vrpn_tracker_set_update_rate(tracker: *mut VrpnTracker, hz: f64) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        if !hz.is_finite() || hz < 0.0 {
            return Err(Failure::invalid(format!("update rate {hz} is not >= 0")));
        }
        t.remote.set_update_rate(hz)?;
        Ok(VrpnStatus::Ok)
    }))
}

/// Asks the server to re-zero its origin (servers that cannot honour it ignore it).
#[no_mangle]
pub extern "C" fn vrpn_tracker_reset_origin(tracker: *mut VrpnTracker) -> VrpnStatus {
    status(handle::with(tracker, |t| {
        t.remote.reset_origin()?;
        Ok(VrpnStatus::Ok)
    }))
}
