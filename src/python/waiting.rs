//! Waiting without spinning: `wait(timeout)` blocks in `poll(2)` on the connection's
//! descriptor with the GIL released, and `fileno()` hands that descriptor to asyncio or a
//! `select` loop. Both rest on [`Connection::prepare_wait`] and [`Connection::fd`], as the
//! Rust and C waits do.

use std::time::{Duration, Instant};

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::callbacks::run;
use super::remote::seconds;
use crate::error::Error;
use crate::{Connection, Wake};

/// Waits until data arrives on `conn`, its next deadline passes or `timeout` ends. The wait
/// blocks in `poll(2)` on the reactor's descriptor with the GIL released (a [`Waiter`]
/// holds nothing of the connection, which stays on its thread); Ctrl-C interrupts it.
/// Returns whether data arrived; the events stay for the next `mainloop()`.
///
/// [`Waiter`]: crate::Waiter
pub(crate) fn wait(py: Python<'_>, conn: &Connection, timeout: f64) -> PyResult<bool> {
    let end = crate::time::instant_after(Instant::now(), seconds(timeout)?);
    loop {
        let waiter = conn.prepare_wait(None);
        let left = end.saturating_duration_since(Instant::now());
        let wake = py
            .detach(|| waiter.block(left))
            .map_err(|e| super::to_py(Error::io("waiting for the connection", e)))?;
        if wake == Wake::Interrupted {
            py.check_signals()?;
            if Instant::now() < end {
                continue;
            }
        }
        // Take what the descriptor announced (one poll without blocking).
        return run(|| conn.wait(Duration::ZERO));
    }
}

/// The descriptor asyncio's `loop.add_reader` or `select` waits on (see [`Connection::fd`]).
pub(crate) fn fileno(conn: &Connection) -> PyResult<i32> {
    conn.fd().ok_or_else(|| {
        PyValueError::new_err(
            "this connection has no descriptor (a replay or loopback connection has no \
             sockets): call mainloop() on a timer instead",
        )
    })
}
