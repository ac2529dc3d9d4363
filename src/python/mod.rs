//! The Python module `vrpn` (cargo feature `python`, built by maturin from `pyproject.toml`).
//!
//! Thin classes over the Rust API: the remotes (`TrackerRemote`, `ButtonRemote`, …) share a
//! base class `Remote` with the connection-level calls; `Server` and the device servers publish
//! data. Everything runs on the thread that created it: VRPN objects are single-threaded, like
//! the Rust ones they wrap, and another thread gets `vrpn.WrongThreadError` ([`owned`]).
//! `close()` (or a `with` block) releases an object's Rust side at once, so a server's port is
//! free again without waiting for the garbage collector.
//!
//! A Python callback runs inside `mainloop()` (or a replay control), called from Rust. It must
//! not unwind through Rust, and the loop must not stop for it, so its exception is kept
//! ([`callbacks::stash`]) and raised by the `mainloop()` that ran it once the pass is over.

mod args;
mod callbacks;
mod errors;
mod families;
mod owned;
mod remote;
mod remotes;
mod server;
mod values;
mod waiting;

use pyo3::prelude::*;

pub(crate) use errors::to_py;

use crate::time::TimeVal;

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
    errors::add_classes(m)?;
    values::add_classes(m)?;
    remote::add_classes(m)?;
    remotes::add_classes(m)?;
    server::add_classes(m)?;
    families::add_classes(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
