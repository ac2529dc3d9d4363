//! Client side, buttons, analogs and dials: the same shape as the tracker in `client.rs`.

use std::cell::RefCell;
use std::ffi::{c_char, c_void};
use std::rc::Rc;

use super::client::{
    callback, connection_state, index, mainloop, open, out_arg, Callbacks, Remote,
};
use super::handle::{self, write_out, Header, Object};
use super::types::{
    VrpnAnalogReport, VrpnAnalogReportCallback, VrpnButtonChange, VrpnButtonChangeCallback,
    VrpnDialUpdate, VrpnDialUpdateCallback, VRPN_BUTTON_MAX_BUTTONS, VRPN_DIAL_MAX_DIALS,
};
use super::{count, status, Failure, VrpnStatus};
use crate::devices::base::RemoteCore;
use crate::{AnalogRemote, ButtonRemote, DialRemote};

/// Copies `src` into the caller's array `dst` of `capacity` elements; returns how many.
///
/// # Safety
/// `dst` is NULL or points to `capacity` writable elements.
unsafe fn copy_out<T: Copy>(src: &[T], dst: *mut T, capacity: i32) -> Result<usize, Failure> {
    let cap = array_arg(dst, capacity)?;
    let n = src.len().min(cap);
    if n == 0 {
        return Ok(0);
    }
    // SAFETY: `dst` has room for `capacity >= n` elements (caller's contract) and cannot
    // overlap `src`, which is this library's own memory.
    unsafe { std::ptr::copy_nonoverlapping(src.as_ptr(), dst, n) };
    Ok(n)
}

/// Checks an output array and its capacity before anything is read: a NULL array with a
/// nonzero capacity is refused whatever there is to copy (NULL with capacity 0 asks for
/// nothing and is fine). Returns the capacity.
fn array_arg<T>(dst: *mut T, capacity: i32) -> Result<usize, Failure> {
    let cap = usize::try_from(capacity)
        .map_err(|_| Failure::invalid(format!("capacity {capacity} is negative")))?;
    if dst.is_null() && cap > 0 {
        return Err(Failure::new(
            VrpnStatus::NullArgument,
            format!("output array is NULL with a capacity of {cap}"),
        ));
    }
    Ok(cap)
}

// ------------------------------------------------------------------------------ button

/// A button remote (C++ `vrpn_Button_Remote`).
pub struct VrpnButton {
    header: Header,
    remote: ButtonRemote,
    callbacks: Callbacks,
}

impl Object for VrpnButton {
    const TAG: u32 = 0x7672_0002;
    const NAME: &'static str = "VrpnButton";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl Remote for VrpnButton {
    fn core(&self) -> &RemoteCore {
        &self.remote
    }
}

/// Opens the button device `name` (see `vrpn_tracker_open`); NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_button_open(name: *const c_char) -> *mut VrpnButton {
    open(name, |n| {
        Ok(VrpnButton {
            header: Header::new::<VrpnButton>(),
            remote: ButtonRemote::new(n)?,
            callbacks: Callbacks::default(),
        })
    })
}

/// Frees a button remote (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_button_free(button: *mut VrpnButton) -> VrpnStatus {
    handle::free(button)
}

/// Services the button's connection without blocking; runs callbacks.
#[no_mangle]
pub extern "C" fn vrpn_button_mainloop(button: *mut VrpnButton) -> VrpnStatus {
    mainloop(button)
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_button_connection_state(button: *const VrpnButton) -> i32 {
    connection_state(button)
}

/// Calls `callback(userdata, change)` for every button change.
#[no_mangle]
pub extern "C" fn vrpn_button_on_change(
    button: *mut VrpnButton,
    callback: VrpnButtonChangeCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(button, |b| {
        let cb = self::callback(callback, userdata)?;
        let id = b
            .remote
            .on_change(move |c| cb.call(VrpnButtonChange::from(c)));
        b.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by the id `vrpn_button_on_change` gave.
#[no_mangle]
pub extern "C" fn vrpn_button_remove_callback(button: *mut VrpnButton, id: u64) -> VrpnStatus {
    status(handle::with(button, |b| {
        b.remote.remove_callback(b.callbacks.take(id)?);
        Ok(VrpnStatus::Ok)
    }))
}

/// Latest state of button `index`: 1 pressed, 0 released (also before any report), or a
/// negative status.
#[no_mangle]
pub extern "C" fn vrpn_button_state(button: *const VrpnButton, index: i32) -> i32 {
    match handle::with(button, |b| {
        let i = self::index(index, "button")?;
        if i >= VRPN_BUTTON_MAX_BUTTONS {
            return Err(Failure::invalid(format!(
                "button {i} is beyond the {VRPN_BUTTON_MAX_BUTTONS} a device can have"
            )));
        }
        Ok(b.remote.state(i))
    }) {
        Ok(s) => s.raw(),
        Err(f) => super::record(f) as i32,
    }
}

/// Number of buttons the server announced (0 until its first States report), or a negative
/// status.
#[no_mangle]
pub extern "C" fn vrpn_button_count(button: *const VrpnButton) -> i32 {
    count(handle::with(button, |b| {
        Ok(if b.remote.got_states() {
            b.remote.num_buttons()
        } else {
            0
        })
    }))
}

/// Copies the latest state of buttons `0..n` into `states` (room for `capacity`), where `n`
/// is the announced count; returns how many were copied, or a negative status.
#[no_mangle]
pub extern "C" fn vrpn_button_states(
    button: *const VrpnButton,
    states: *mut i32,
    capacity: i32,
) -> i32 {
    count(handle::with(button, |b| {
        let n = if b.remote.got_states() {
            b.remote.num_buttons().min(VRPN_BUTTON_MAX_BUTTONS)
        } else {
            0
        };
        let mut all = [0i32; VRPN_BUTTON_MAX_BUTTONS];
        for (i, s) in all[..n].iter_mut().enumerate() {
            *s = b.remote.state(i).raw();
        }
        // SAFETY: `states` has room for `capacity` ints (caller's contract).
        unsafe { copy_out(&all[..n], states, capacity) }
    }))
}

// ------------------------------------------------------------------------------ analog

/// An analog remote (C++ `vrpn_Analog_Remote`).
pub struct VrpnAnalog {
    header: Header,
    remote: AnalogRemote,
    callbacks: Callbacks,
}

impl Object for VrpnAnalog {
    const TAG: u32 = 0x7672_0003;
    const NAME: &'static str = "VrpnAnalog";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl Remote for VrpnAnalog {
    fn core(&self) -> &RemoteCore {
        &self.remote
    }
}

/// Opens the analog device `name` (see `vrpn_tracker_open`); NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_analog_open(name: *const c_char) -> *mut VrpnAnalog {
    open(name, |n| {
        Ok(VrpnAnalog {
            header: Header::new::<VrpnAnalog>(),
            remote: AnalogRemote::new(n)?,
            callbacks: Callbacks::default(),
        })
    })
}

/// Frees an analog remote (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_analog_free(analog: *mut VrpnAnalog) -> VrpnStatus {
    handle::free(analog)
}

/// Services the analog's connection without blocking; runs callbacks.
#[no_mangle]
pub extern "C" fn vrpn_analog_mainloop(analog: *mut VrpnAnalog) -> VrpnStatus {
    mainloop(analog)
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_analog_connection_state(analog: *const VrpnAnalog) -> i32 {
    connection_state(analog)
}

/// Calls `callback(userdata, report)` for every analog report.
#[no_mangle]
pub extern "C" fn vrpn_analog_on_report(
    analog: *mut VrpnAnalog,
    callback: VrpnAnalogReportCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(analog, |a| {
        let cb = self::callback(callback, userdata)?;
        let id = a
            .remote
            .on_report(move |r| cb.call(VrpnAnalogReport::from(r)));
        a.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by the id `vrpn_analog_on_report` gave.
#[no_mangle]
pub extern "C" fn vrpn_analog_remove_callback(analog: *mut VrpnAnalog, id: u64) -> VrpnStatus {
    status(handle::with(analog, |a| {
        a.remote.remove_callback(a.callbacks.take(id)?);
        Ok(VrpnStatus::Ok)
    }))
}

/// Copies the latest report into `*report`: `VRPN_STATUS_OK`, or `VRPN_STATUS_NO_DATA`
/// (nothing written) before the first one.
#[no_mangle]
pub extern "C" fn vrpn_analog_latest(
    analog: *const VrpnAnalog,
    report: *mut VrpnAnalogReport,
) -> VrpnStatus {
    status(handle::with(analog, |a| {
        out_arg(report, "report")?;
        if !a.remote.got_report() {
            return Ok(VrpnStatus::NoData);
        }
        let r = VrpnAnalogReport::from(&a.remote.latest());
        // SAFETY: `report` is a writable VrpnAnalogReport or NULL (checked).
        unsafe { write_out(report, r, "report")? };
        Ok(VrpnStatus::Ok)
    }))
}

/// Copies the latest channel values into `values` (room for `capacity`); returns how many
/// were copied (0 before the first report), or a negative status.
#[no_mangle]
pub extern "C" fn vrpn_analog_channels(
    analog: *const VrpnAnalog,
    values: *mut f64,
    capacity: i32,
) -> i32 {
    count(handle::with(analog, |a| {
        array_arg(values, capacity)?;
        if !a.remote.got_report() {
            return Ok(0);
        }
        let r = a.remote.latest();
        // SAFETY: `values` has room for `capacity` doubles (caller's contract).
        unsafe { copy_out(r.channels(), values, capacity) }
    }))
}

// ------------------------------------------------------------------------------ dial

/// Rotation summed per dial since the remote was opened, for polling.
struct DialTotals {
    revolutions: [f64; VRPN_DIAL_MAX_DIALS],
    seen: [bool; VRPN_DIAL_MAX_DIALS],
}

/// A dial remote (C++ `vrpn_Dial_Remote`).
pub struct VrpnDial {
    header: Header,
    remote: DialRemote,
    callbacks: Callbacks,
    totals: Rc<RefCell<DialTotals>>,
}

impl Object for VrpnDial {
    const TAG: u32 = 0x7672_0004;
    const NAME: &'static str = "VrpnDial";
    fn header(&self) -> &Header {
        &self.header
    }
}

impl Remote for VrpnDial {
    fn core(&self) -> &RemoteCore {
        &self.remote
    }
}

/// Opens the dial device `name` (see `vrpn_tracker_open`); NULL on failure.
#[no_mangle]
pub extern "C" fn vrpn_dial_open(name: *const c_char) -> *mut VrpnDial {
    open(name, |n| {
        let remote = DialRemote::new(n)?;
        let totals = Rc::new(RefCell::new(DialTotals {
            revolutions: [0.0; VRPN_DIAL_MAX_DIALS],
            seen: [false; VRPN_DIAL_MAX_DIALS],
        }));
        let t = totals.clone();
        remote.on_update(move |u| {
            let i = u.dial;
            let mut t = t.borrow_mut();
            if i < VRPN_DIAL_MAX_DIALS {
                t.revolutions[i] += u.change;
                t.seen[i] = true;
            }
        });
        Ok(VrpnDial {
            header: Header::new::<VrpnDial>(),
            remote,
            callbacks: Callbacks::default(),
            totals,
        })
    })
}

/// Frees a dial remote (NULL is ignored).
#[no_mangle]
pub extern "C" fn vrpn_dial_free(dial: *mut VrpnDial) -> VrpnStatus {
    handle::free(dial)
}

/// Services the dial's connection without blocking; runs callbacks.
#[no_mangle]
pub extern "C" fn vrpn_dial_mainloop(dial: *mut VrpnDial) -> VrpnStatus {
    mainloop(dial)
}

/// The connection's state: a `VrpnConnectionState` (>= 0) or a negative `VrpnStatus`.
#[no_mangle]
pub extern "C" fn vrpn_dial_connection_state(dial: *const VrpnDial) -> i32 {
    connection_state(dial)
}

/// Calls `callback(userdata, update)` for every dial update.
#[no_mangle]
pub extern "C" fn vrpn_dial_on_update(
    dial: *mut VrpnDial,
    callback: VrpnDialUpdateCallback,
    userdata: *mut c_void,
    id_out: *mut u64,
) -> VrpnStatus {
    status(handle::with(dial, |d| {
        let cb = self::callback(callback, userdata)?;
        let id = d
            .remote
            .on_update(move |u| cb.call(VrpnDialUpdate::from(u)));
        d.callbacks.add(id, id_out)
    }))
}

/// Removes a callback by the id `vrpn_dial_on_update` gave.
#[no_mangle]
pub extern "C" fn vrpn_dial_remove_callback(dial: *mut VrpnDial, id: u64) -> VrpnStatus {
    status(handle::with(dial, |d| {
        d.remote.remove_callback(d.callbacks.take(id)?);
        Ok(VrpnStatus::Ok)
    }))
}

/// Writes the rotation of dial `index` summed over every update since the remote was opened
/// (revolutions) to `*revolutions`: `VRPN_STATUS_OK`, or `VRPN_STATUS_NO_DATA` before its
/// first update.
#[no_mangle]
pub extern "C" fn vrpn_dial_rotation(
    dial: *const VrpnDial,
    index: i32,
    revolutions: *mut f64,
) -> VrpnStatus {
    status(handle::with(dial, |d| {
        let i = self::index(index, "dial")?;
        if i >= VRPN_DIAL_MAX_DIALS {
            return Err(Failure::invalid(format!(
                "dial {i} is beyond the {VRPN_DIAL_MAX_DIALS} a device can have"
            )));
        }
        out_arg(revolutions, "revolutions")?;
        let t = d.totals.borrow();
        if !t.seen[i] {
            return Ok(VrpnStatus::NoData);
        }
        // SAFETY: `revolutions` is a writable double or NULL (checked).
        unsafe { write_out(revolutions, t.revolutions[i], "revolutions")? };
        Ok(VrpnStatus::Ok)
    }))
}
