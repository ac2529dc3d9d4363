//! The plain C structs reports are copied into, and the callback types that receive them.
//!
//! Layouts are `#[repr(C)]` with fixed-size arrays, so a C# `[StructLayout(Sequential)]`
//! struct with `fixed double` or `[MarshalAs(ByValArray)]` fields maps them one to one.
//! Quaternions are (x, y, z, w), as on the wire and in C++ VRPN.

use std::ffi::c_void;

use crate::devices::analog::AnalogReport;
use crate::devices::button::ButtonChange;
use crate::devices::dial::DialUpdate;
use crate::devices::tracker::{TrackerAcceleration, TrackerPose, TrackerVelocity};
use crate::time::TimeVal;
use crate::wire::payload::{analog, button};

/// Most channels an analog report carries (C++ `vrpn_CHANNEL_MAX`).
pub const VRPN_ANALOG_MAX_CHANNELS: usize = 128;
/// Most buttons a button device has (C++ `vrpn_BUTTON_MAX_BUTTONS`).
pub const VRPN_BUTTON_MAX_BUTTONS: usize = 256;
/// Most dials a dial device has (C++ `vrpn_DIAL_MAX`).
pub const VRPN_DIAL_MAX_DIALS: usize = 128;

const _: () = assert!(VRPN_ANALOG_MAX_CHANNELS == analog::CHANNEL_MAX);
const _: () = assert!(VRPN_BUTTON_MAX_BUTTONS == button::MAX_BUTTONS);
const _: () = assert!(VRPN_DIAL_MAX_DIALS == crate::wire::payload::dial::MAX_DIALS);

/// A time stamp: seconds and microseconds since 1970-01-01 UTC (C `struct timeval`). The
/// report functions refuse a time a message cannot carry (before 1970, after 2106-02-07) with
/// `VRPN_STATUS_INVALID_ARGUMENT`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VrpnTimeVal {
    /// Whole seconds.
    pub sec: i64,
    /// Microseconds, 0..=999999.
    pub usec: i64,
}

impl From<TimeVal> for VrpnTimeVal {
    fn from(t: TimeVal) -> Self {
        VrpnTimeVal {
            sec: t.sec,
            usec: t.usec,
        }
    }
}

impl From<VrpnTimeVal> for TimeVal {
    fn from(t: VrpnTimeVal) -> Self {
        TimeVal::new(t.sec, t.usec)
    }
}

/// A tracker pose report.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VrpnTrackerPose {
    /// Time the server stamped on the report.
    pub time: VrpnTimeVal,
    /// Sensor index.
    pub sensor: i32,
    /// Position in metres, tracker frame.
    pub pos: [f64; 3],
    /// Orientation quaternion (x, y, z, w): rotates the tracker's axes onto the sensor's.
    pub quat: [f64; 4],
}

impl From<&TrackerPose> for VrpnTrackerPose {
    fn from(p: &TrackerPose) -> Self {
        VrpnTrackerPose {
            time: p.time.into(),
            sensor: p.sensor as i32,
            pos: [p.pos.x, p.pos.y, p.pos.z],
            quat: [p.quat.i, p.quat.j, p.quat.k, p.quat.w],
        }
    }
}

/// A tracker velocity report.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VrpnTrackerVelocity {
    /// Time the server stamped on the report.
    pub time: VrpnTimeVal,
    /// Sensor index.
    pub sensor: i32,
    /// Linear velocity, metres per second, tracker frame.
    pub vel: [f64; 3],
    /// Rotation over `vel_quat_dt` seconds (x, y, z, w), expressed in the tracker's frame:
    /// the orientation `vel_quat_dt` later is `vel_quat * quat`.
    pub vel_quat: [f64; 4],
    /// Interval of `vel_quat`, seconds.
    pub vel_quat_dt: f64,
}

impl From<&TrackerVelocity> for VrpnTrackerVelocity {
    fn from(v: &TrackerVelocity) -> Self {
        VrpnTrackerVelocity {
            time: v.time.into(),
            sensor: v.sensor as i32,
            vel: [v.vel.x, v.vel.y, v.vel.z],
            vel_quat: [v.vel_quat.i, v.vel_quat.j, v.vel_quat.k, v.vel_quat.w],
            vel_quat_dt: v.vel_quat_dt,
        }
    }
}

/// A tracker acceleration report.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VrpnTrackerAcceleration {
    /// Time the server stamped on the report.
    pub time: VrpnTimeVal,
    /// Sensor index.
    pub sensor: i32,
    /// Linear acceleration, metres per second squared, tracker frame.
    pub acc: [f64; 3],
    /// Change of rotation rate over `acc_quat_dt` seconds (x, y, z, w).
    pub acc_quat: [f64; 4],
    /// Interval of `acc_quat`, seconds.
    pub acc_quat_dt: f64,
}

impl From<&TrackerAcceleration> for VrpnTrackerAcceleration {
    fn from(a: &TrackerAcceleration) -> Self {
        VrpnTrackerAcceleration {
            time: a.time.into(),
            sensor: a.sensor as i32,
            acc: [a.acc.x, a.acc.y, a.acc.z],
            acc_quat: [a.acc_quat.i, a.acc_quat.j, a.acc_quat.k, a.acc_quat.w],
            acc_quat_dt: a.acc_quat_dt,
        }
    }
}

/// One button changed.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VrpnButtonChange {
    /// Time the server stamped on the report.
    pub time: VrpnTimeVal,
    /// Button index.
    pub button: i32,
    /// New state: 0 released, 1 pressed.
    pub state: i32,
}

impl From<&ButtonChange> for VrpnButtonChange {
    fn from(c: &ButtonChange) -> Self {
        VrpnButtonChange {
            time: c.time.into(),
            button: c.button as i32,
            state: c.state.raw(),
        }
    }
}

/// An analog report: every channel's value.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VrpnAnalogReport {
    /// Time the server stamped on the report.
    pub time: VrpnTimeVal,
    /// Number of channels in `channel`.
    pub num_channel: i32,
    /// Channel values; entries from `num_channel` on are zero.
    pub channel: [f64; VRPN_ANALOG_MAX_CHANNELS],
}

impl From<&AnalogReport> for VrpnAnalogReport {
    fn from(r: &AnalogReport) -> Self {
        VrpnAnalogReport {
            time: r.time.into(),
            num_channel: r.num_channel as i32,
            channel: r.channel,
        }
    }
}

/// A dial moved.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VrpnDialUpdate {
    /// Time the server stamped on the report.
    pub time: VrpnTimeVal,
    /// Dial index.
    pub dial: i32,
    /// Revolutions since the previous report of this dial.
    pub change: f64,
}

impl From<&DialUpdate> for VrpnDialUpdate {
    fn from(u: &DialUpdate) -> Self {
        VrpnDialUpdate {
            time: u.time.into(),
            dial: u.dial as i32,
            change: u.change,
        }
    }
}

/// Receives tracker poses; `pose` is valid during the call only.
pub type VrpnTrackerPoseCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, pose: *const VrpnTrackerPose)>;
/// Receives tracker velocities; `velocity` is valid during the call only.
pub type VrpnTrackerVelocityCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, velocity: *const VrpnTrackerVelocity)>;
/// Receives tracker accelerations; `acceleration` is valid during the call only.
pub type VrpnTrackerAccelerationCallback = Option<
    unsafe extern "C" fn(userdata: *mut c_void, acceleration: *const VrpnTrackerAcceleration),
>;
/// Receives button changes; `change` is valid during the call only.
pub type VrpnButtonChangeCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, change: *const VrpnButtonChange)>;
/// Receives analog reports; `report` is valid during the call only.
pub type VrpnAnalogReportCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, report: *const VrpnAnalogReport)>;
/// Receives dial updates; `update` is valid during the call only.
pub type VrpnDialUpdateCallback =
    Option<unsafe extern "C" fn(userdata: *mut c_void, update: *const VrpnDialUpdate)>;

/// A C callback and its userdata, called with a report converted to its C struct.
pub(crate) struct CCallback<C: Copy> {
    pub(crate) f: unsafe extern "C" fn(*mut c_void, *const C),
    pub(crate) userdata: *mut c_void,
}

impl<C: Copy> CCallback<C> {
    /// Hands `report` to the C function (no allocation: the struct lives on this stack).
    pub(crate) fn call(&self, report: C) {
        // SAFETY: `f` is a non-null function pointer the caller registered with this
        // signature; `userdata` is passed back untouched and `&report` is valid for the call.
        unsafe { (self.f)(self.userdata, &report) }
    }
}
