//! The C ABI (cargo feature `capi`): what C, C++, C# (`DllImport`), Unity, Unreal, MATLAB and
//! LabVIEW programs link against. The header is `include/vrpn.h`, generated from this module
//! with cbindgen; `docs/C_API.md` shows how to build, link and bind it.
//!
//! The shape every binding relies on:
//!
//! - **Opaque handles.** `vrpn_*_open` / `vrpn_*_new` return a pointer the caller passes back
//!   and finally hands to the matching `vrpn_*_free`; NULL means the call failed. Handles may
//!   be freed in any order: a connection lives as long as anything using it.
//! - **Status codes.** Every other call returns a [`VrpnStatus`] (0 is success, negative is an
//!   error, positive is a non-error outcome such as "no data yet"), or a count that is
//!   negative when it is a status. [`vrpn_last_error`] gives the text of the most recent
//!   failure on the calling thread.
//! - **Callbacks** get the caller's `void *userdata` back and a pointer to a report that is
//!   valid during the call only. They run inside the `mainloop` call that received the report.
//! - **Polling.** The latest report of each kind is kept and copied into a caller's struct,
//!   for frame loops that prefer reading state to callbacks.
//! - **One thread per handle.** A handle belongs to the thread that created it (connections
//!   are not thread-safe); a call from another thread is refused with
//!   [`VrpnStatus::WrongThread`] instead of corrupting memory. Panics never cross the
//!   boundary: they become [`VrpnStatus::Internal`].
//!
//! Everything here is a thin translation onto the Rust API ([`crate::TrackerRemote`],
//! [`crate::Connection`], [`crate::TrackerServer`], …); no protocol logic lives in this module.
//! It is the only module besides `net/sys.rs` that uses `unsafe` (raw pointers from C).

#![allow(unsafe_code)]
// The entry points take raw pointers from C by design; they are not `unsafe fn` because C has
// no such notion. The contract (valid handle from this library, writable output, arrays of the
// stated length) is in each function's documentation and the header.
#![allow(clippy::not_unsafe_ptr_arg_deref)]

pub mod client;
pub mod connection;
mod handle;
pub mod imager;
pub mod output_devices;
pub mod output_servers;
pub mod remotes;
pub mod server;
pub mod text;
pub mod types;
pub mod waiting;

use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};

use crate::connection::{set_text_printer, TextPrinter};
use crate::Error;

/// Version of this ABI: raised whenever a function or struct changes incompatibly, so a
/// binding can check at load time that it matches the library it loaded.
pub const VRPN_ABI_VERSION: i32 = 1;

/// Outcome of a call. Zero is success, positive values are outcomes that are not errors,
/// negative values are errors whose text `vrpn_last_error` returns.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VrpnStatus {
    /// Success.
    Ok = 0,
    /// Nothing received yet for what was asked (a polling call); the output is untouched.
    NoData = 1,
    /// A required pointer argument was NULL.
    NullArgument = -1,
    /// An argument is out of range or not valid UTF-8.
    InvalidArgument = -2,
    /// The handle is not a live handle of the expected kind (already freed, or another kind).
    InvalidHandle = -3,
    /// The handle was created on another thread; handles are not thread-safe.
    WrongThread = -4,
    /// The device name cannot be parsed.
    Name = -5,
    /// The host name does not resolve to an IPv4 address.
    Resolve = -6,
    /// A socket or file operation failed (port in use, network down, …).
    Io = -7,
    /// A limit was reached (name table full, payload too large).
    Limit = -8,
    /// The operation is not supported here (e.g. a sensor beyond the server's count).
    Unsupported = -9,
    /// A log file could not be read or written.
    Log = -10,
    /// The handle is in use by a call further up the stack (a callback called back into it).
    Busy = -11,
    /// A bug in the library was caught at the boundary (a Rust panic); the text says where.
    Internal = -12,
    /// A client was asked to send before its connection is up (nothing was queued).
    NotConnected = -13,
}

/// What a connection is doing, as returned by the `*_connection_state` calls.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VrpnConnectionState {
    /// Client: trying to reach the server for the first time.
    Connecting = 0,
    /// Client: connected. Server: at least one client connected.
    Connected = 1,
    /// Client: was connected, lost the server, and keeps trying.
    Reconnecting = 2,
    /// Server: listening, no client connected.
    Listening = 3,
}

impl From<crate::ConnectionState> for VrpnConnectionState {
    fn from(s: crate::ConnectionState) -> Self {
        match s {
            crate::ConnectionState::Connecting => VrpnConnectionState::Connecting,
            crate::ConnectionState::Connected => VrpnConnectionState::Connected,
            crate::ConnectionState::Reconnecting => VrpnConnectionState::Reconnecting,
            crate::ConnectionState::Listening => VrpnConnectionState::Listening,
        }
    }
}

/// A failed call: the status to return and the text [`vrpn_last_error`] will give.
#[derive(Debug)]
pub(crate) struct Failure {
    pub(crate) status: VrpnStatus,
    pub(crate) text: String,
}

impl Failure {
    pub(crate) fn new(status: VrpnStatus, text: impl Into<String>) -> Failure {
        Failure {
            status,
            text: text.into(),
        }
    }

    pub(crate) fn invalid(text: impl Into<String>) -> Failure {
        Failure::new(VrpnStatus::InvalidArgument, text)
    }
}

impl From<Error> for Failure {
    fn from(e: Error) -> Failure {
        let status = match e {
            Error::Name(_) => VrpnStatus::Name,
            Error::Resolve { .. } => VrpnStatus::Resolve,
            Error::Io { .. } => VrpnStatus::Io,
            Error::NameLimit(_) | Error::PayloadTooLarge(_) => VrpnStatus::Limit,
            Error::Log(_) | Error::LogNotFound { .. } | Error::LogDamaged(_) => VrpnStatus::Log,
            Error::NotConnected(_) => VrpnStatus::NotConnected,
            Error::Unsupported(_) => VrpnStatus::Unsupported,
            Error::InvalidArgument(_) => VrpnStatus::InvalidArgument,
        };
        Failure::new(status, e.to_string())
    }
}

struct LastError {
    status: VrpnStatus,
    text: CString,
}

thread_local! {
    static LAST_ERROR: RefCell<LastError> = RefCell::new(LastError {
        status: VrpnStatus::Ok,
        text: CString::default(),
    });
}

/// Records `f` as this thread's last error and returns its status.
pub(crate) fn record(f: Failure) -> VrpnStatus {
    let text = CString::new(f.text.replace('\0', "\\0")).unwrap_or_default();
    // `try_with`: a call made while the thread is being torn down must not panic here.
    let _ = LAST_ERROR.try_with(|l| {
        *l.borrow_mut() = LastError {
            status: f.status,
            text,
        }
    });
    f.status
}

/// Turns a result into the status a call returns, recording a failure.
pub(crate) fn status(r: Result<VrpnStatus, Failure>) -> VrpnStatus {
    r.unwrap_or_else(record)
}

/// A count (non-negative) or a negative status, for calls that return a number.
pub(crate) fn count(r: Result<usize, Failure>) -> i32 {
    match r {
        Ok(n) => i32::try_from(n).unwrap_or(i32::MAX),
        Err(f) => record(f) as i32,
    }
}

/// Reads a C string argument as UTF-8.
///
/// # Safety
/// `p` is NULL or points to a NUL-terminated string that stays valid for `'a`.
pub(crate) unsafe fn text_arg<'a>(p: *const c_char, what: &str) -> Result<&'a str, Failure> {
    if p.is_null() {
        return Err(Failure::new(
            VrpnStatus::NullArgument,
            format!("{what} is NULL"),
        ));
    }
    // SAFETY: non-null, and the caller guarantees a NUL-terminated string alive for 'a.
    let s = unsafe { CStr::from_ptr(p) };
    s.to_str()
        .map_err(|_| Failure::invalid(format!("{what} is not valid UTF-8")))
}

/// Text of the most recent failed call on the calling thread ("" if none failed yet).
///
/// The pointer stays valid until the next failing call on this thread; copy the text to keep
/// it. Calls that succeed leave it unchanged.
#[no_mangle]
pub extern "C" fn vrpn_last_error() -> *const c_char {
    LAST_ERROR
        .try_with(|l| l.borrow().text.as_ptr())
        .unwrap_or(c"".as_ptr())
}

/// Status of the most recent failed call on the calling thread (`VRPN_STATUS_OK` if none).
#[no_mangle]
pub extern "C" fn vrpn_last_error_status() -> VrpnStatus {
    LAST_ERROR
        .try_with(|l| l.borrow().status)
        .unwrap_or(VrpnStatus::Ok)
}

/// The name of a status code without its prefix ("OK", "NO_DATA", "WRONG_THREAD", …), or
/// "UNKNOWN" for a value that is not one; a static string, for logs.
#[no_mangle]
pub extern "C" fn vrpn_status_name(status: i32) -> *const c_char {
    let name: &'static CStr = match status {
        0 => c"OK",
        1 => c"NO_DATA",
        -1 => c"NULL_ARGUMENT",
        -2 => c"INVALID_ARGUMENT",
        -3 => c"INVALID_HANDLE",
        -4 => c"WRONG_THREAD",
        -5 => c"NAME",
        -6 => c"RESOLVE",
        -7 => c"IO",
        -8 => c"LIMIT",
        -9 => c"UNSUPPORTED",
        -10 => c"LOG",
        -11 => c"BUSY",
        -12 => c"INTERNAL",
        -13 => c"NOT_CONNECTED",
        _ => c"UNKNOWN",
    };
    name.as_ptr()
}

/// The library's version, e.g. "0.1.0" (a static string).
#[no_mangle]
pub extern "C" fn vrpn_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// The ABI version this library implements (`VRPN_ABI_VERSION`).
#[no_mangle]
pub extern "C" fn vrpn_abi_version() -> i32 {
    VRPN_ABI_VERSION
}

/// Where text messages from devices and connection notices go when no callback takes them,
/// for the whole process: 0 = one line each on stderr (the default), 1 = device texts on
/// stdout in C++ VRPN's format, 2 = nowhere.
#[no_mangle]
pub extern "C" fn vrpn_set_default_printer(mode: i32) -> VrpnStatus {
    let printer = match mode {
        0 => TextPrinter::Stderr,
        1 => TextPrinter::CppStdout,
        2 => TextPrinter::Off,
        _ => {
            return record(Failure::invalid(format!(
                "printer mode {mode} is not 0 (stderr), 1 (C++ stdout) or 2 (off)"
            )))
        }
    };
    set_text_printer(printer);
    VrpnStatus::Ok
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_status_has_a_distinct_name_matching_its_variant() {
        use VrpnStatus::*;
        let all = [
            Ok,
            NoData,
            NullArgument,
            InvalidArgument,
            InvalidHandle,
            WrongThread,
            Name,
            Resolve,
            Io,
            Limit,
            Unsupported,
            Log,
            Busy,
            Internal,
            NotConnected,
        ];
        let mut names = std::collections::HashSet::new();
        for s in all {
            // SAFETY: vrpn_status_name returns a static NUL-terminated string.
            let name = unsafe { CStr::from_ptr(vrpn_status_name(s as i32)) };
            let name = name.to_str().unwrap();
            let variant = format!("{s:?}");
            assert_eq!(name.replace('_', ""), variant.to_uppercase(), "{variant}");
            assert!(names.insert(name));
        }
        // SAFETY: as above.
        let unknown = unsafe { CStr::from_ptr(vrpn_status_name(99)) };
        assert_eq!(unknown.to_str().unwrap(), "UNKNOWN");
    }

    #[test]
    fn a_failure_is_this_threads_last_error() {
        let s = record(Failure::invalid("first problem"));
        assert_eq!(s, VrpnStatus::InvalidArgument);
        // SAFETY: vrpn_last_error returns a NUL-terminated string valid until the next failure.
        let text = unsafe { CStr::from_ptr(vrpn_last_error()) }.to_owned();
        assert_eq!(text.to_str().unwrap(), "first problem");
        assert_eq!(vrpn_last_error_status(), VrpnStatus::InvalidArgument);
        let other = std::thread::spawn(|| {
            // SAFETY: as above.
            let t = unsafe { CStr::from_ptr(vrpn_last_error()) }.to_owned();
            (t, vrpn_last_error_status())
        })
        .join()
        .unwrap();
        assert_eq!(other.0.to_str().unwrap(), "");
        assert_eq!(other.1, VrpnStatus::Ok);
    }
}
