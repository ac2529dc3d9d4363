//! The Python module `vrpn` (cargo feature `python`, built by maturin from `pyproject.toml`).
//!
//! Thin classes over the Rust API: the remotes (`TrackerRemote`, `ButtonRemote`, …) share a
//! base class `Remote` with the connection-level calls; `Server` and the device servers publish
//! data. Everything runs on the thread that created it (`unsendable` classes): VRPN objects are
//! single-threaded, like the Rust ones they wrap.
//!
//! A Python callback runs inside `mainloop()` (or a replay control), called from Rust. It must
//! not unwind through Rust, and the loop must not stop for it, so its exception is kept
//! ([`callbacks::stash`]) and raised by the `mainloop()` that ran it once the pass is over.

mod callbacks;
mod remote;
mod remotes;
mod server;
mod values;

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

use crate::error::Error;
use crate::time::TimeVal;

create_exception!(
    vrpn,
    VrpnError,
    PyException,
    "Base class of the errors the vrpn module raises."
);
create_exception!(
    vrpn,
    DeviceNameError,
    VrpnError,
    "A device name that cannot be parsed (expected DEVICE@HOST[:PORT], DEVICE@file:PATH, ...)."
);
create_exception!(
    vrpn,
    ResolveError,
    VrpnError,
    "A host name that does not resolve to an IPv4 address."
);
create_exception!(
    vrpn,
    LogFileError,
    VrpnError,
    "A log file that cannot be read or written."
);

/// The crate's error as a Python exception, with the crate's message.
pub(crate) fn to_py(e: Error) -> PyErr {
    let text = e.to_string();
    match e {
        Error::Name(_) => DeviceNameError::new_err(text),
        Error::Resolve { .. } => ResolveError::new_err(text),
        Error::Log(_) | Error::LogNotFound { .. } | Error::LogDamaged(_) => {
            LogFileError::new_err(text)
        }
        _ => VrpnError::new_err(text),
    }
}

/// Seconds since the epoch as a `TimeVal`; `None` is "now" on `conn`'s clock.
pub(crate) fn time_or_now(time: Option<f64>, conn: &crate::Connection) -> PyResult<TimeVal> {
    match time {
        Some(t) => header_time(t),
        None => Ok(conn.now().wall),
    }
}

/// Seconds since the epoch as a message time, refusing what a message header cannot carry.
pub(crate) fn header_time(t: f64) -> PyResult<TimeVal> {
    TimeVal::checked_from_secs_f64(t)
        .filter(TimeVal::fits_header)
        .ok_or_else(|| {
            pyo3::exceptions::PyValueError::new_err(format!(
                "time must be between 0 and 4294967295.999999 seconds since 1970 (what a VRPN \
                 message carries), got {t}"
            ))
        })
}

/// The module: `import vrpn`.
#[pymodule]
#[pyo3(name = "_vrpn")]
fn vrpn_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("VrpnError", py.get_type::<VrpnError>())?;
    m.add("DeviceNameError", py.get_type::<DeviceNameError>())?;
    m.add("ResolveError", py.get_type::<ResolveError>())?;
    m.add("LogFileError", py.get_type::<LogFileError>())?;
    values::add_classes(m)?;
    remote::add_classes(m)?;
    remotes::add_classes(m)?;
    server::add_classes(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
