//! The module's exceptions: `vrpn.VrpnError` and its subclasses, and how the crate's errors
//! become them. Every error the module raises on its own account is a `VrpnError`; the two
//! that also have a natural built-in meaning derive from it as well (`OutOfRangeError` is an
//! `IndexError`, `LimitError` a `ValueError`), so either `except` catches them.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::error::Error;
use crate::server::limits::PublishError;

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
    "A device name that cannot be parsed or published (expected DEVICE@HOST[:PORT], \
     DEVICE@file:PATH, ...; a server's device names have no '@')."
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
create_exception!(
    vrpn,
    WrongThreadError,
    VrpnError,
    "A VRPN object used from a thread other than the one that created it."
);
create_exception!(
    vrpn,
    ClosedError,
    VrpnError,
    "A VRPN object used after close()."
);

static OUT_OF_RANGE: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static LIMIT: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// `class NAME(VrpnError, builtin)` with `doc`, made through `type()`.
fn subclass(
    py: Python<'_>,
    name: &str,
    builtin: Bound<'_, PyType>,
    doc: &str,
) -> PyResult<Py<PyType>> {
    let dict = PyDict::new(py);
    dict.set_item("__doc__", doc)?;
    dict.set_item("__module__", "vrpn")?;
    let bases = PyTuple::new(py, [py.get_type::<VrpnError>(), builtin])?;
    let class = py.get_type::<PyType>().call1((name, bases, dict))?;
    Ok(class.cast_into::<PyType>()?.unbind())
}

fn out_of_range_type(py: Python<'_>) -> PyResult<&Py<PyType>> {
    OUT_OF_RANGE.get_or_try_init(py, || {
        subclass(
            py,
            "OutOfRangeError",
            py.get_type::<PyIndexError>(),
            "An index a device does not have (a sensor, button, channel or dial).",
        )
    })
}

fn limit_type(py: Python<'_>) -> PyResult<&Py<PyType>> {
    LIMIT.get_or_try_init(py, || {
        subclass(
            py,
            "LimitError",
            py.get_type::<PyValueError>(),
            "A count outside what a VRPN device may have (sensors, buttons, channels, dials).",
        )
    })
}

/// Raises a class made at import; if making it failed, the error says so instead.
fn raise(make: fn(Python<'_>) -> PyResult<&Py<PyType>>, text: String) -> PyErr {
    Python::attach(|py| match make(py) {
        Ok(class) => PyErr::from_type(class.bind(py).clone(), text),
        Err(e) => e,
    })
}

/// `vrpn.OutOfRangeError(text)`.
pub(crate) fn out_of_range(text: String) -> PyErr {
    raise(out_of_range_type, text)
}

/// `vrpn.LimitError(text)`.
pub(crate) fn limit(text: String) -> PyErr {
    raise(limit_type, text)
}

/// `vrpn.WrongThreadError` for an object of `class`.
pub(crate) fn wrong_thread(class: &str) -> PyErr {
    WrongThreadError::new_err(format!(
        "this vrpn.{class} belongs to the thread that created it and cannot be used from \
         another one (VRPN connections are single-threaded): create it on the thread that \
         calls its mainloop(), and hand values to other threads through a queue.Queue"
    ))
}

/// `vrpn.ClosedError` for an object of `class`.
pub(crate) fn closed(class: &str) -> PyErr {
    ClosedError::new_err(format!("this vrpn.{class} is closed"))
}

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

/// A refused device server: a bad count is a `LimitError`, a bad or taken name a
/// `DeviceNameError`.
pub(crate) fn publish(e: PublishError) -> PyErr {
    match e {
        PublishError::Count(t) => limit(t),
        PublishError::Name(t) | PublishError::Duplicate(t) => DeviceNameError::new_err(t),
    }
}

/// Adds the exception classes to the module.
pub(crate) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("VrpnError", py.get_type::<VrpnError>())?;
    m.add("DeviceNameError", py.get_type::<DeviceNameError>())?;
    m.add("ResolveError", py.get_type::<ResolveError>())?;
    m.add("LogFileError", py.get_type::<LogFileError>())?;
    m.add("WrongThreadError", py.get_type::<WrongThreadError>())?;
    m.add("ClosedError", py.get_type::<ClosedError>())?;
    m.add("OutOfRangeError", out_of_range_type(py)?.bind(py))?;
    m.add("LimitError", limit_type(py)?.bind(py))?;
    Ok(())
}
