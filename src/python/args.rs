//! Integer arguments from Python: indices and counts of any size, checked here (Python ints
//! are unbounded, so a plain `usize` parameter would answer `-1` or `2**64` with a bare
//! `OverflowError`, and a huge count with an allocation that aborts the interpreter).

use pyo3::prelude::*;
use pyo3::types::PyInt;

use super::errors::{out_of_range, publish};
use crate::server::limits::{self, Interface};

/// The integer `obj` holds (`None` when it is beyond `i128`), or `TypeError` if it is none.
pub(crate) fn int_value(obj: &Bound<'_, PyAny>) -> PyResult<Option<i128>> {
    match obj.extract::<i64>() {
        Ok(v) => Ok(Some(v.into())),
        Err(e) if obj.is_instance_of::<PyInt>() => {
            let _ = e; // too large for i64: try wider, else it is simply huge
            Ok(obj.extract::<i128>().ok())
        }
        Err(e) => Err(e),
    }
}

/// An index of a `what` ("sensor", "button", …): non-negative and, when the device's count
/// is known (`count`), below it; else `vrpn.OutOfRangeError`.
pub(crate) fn index(obj: &Bound<'_, PyAny>, what: &str, count: Option<usize>) -> PyResult<usize> {
    let v = int_value(obj)?;
    let shown = || obj.str().map(|s| s.to_string()).unwrap_or_default();
    let i = match v {
        Some(v) if v < 0 => {
            return Err(out_of_range(format!(
                "{what} {} is negative; indices start at 0",
                shown()
            )))
        }
        Some(v) => usize::try_from(v).ok(),
        None => None,
    };
    match (i, count) {
        (Some(i), Some(n)) if i < n => Ok(i),
        (Some(i), None) => Ok(i),
        (_, Some(n)) => Err(out_of_range(format!(
            "{what} {} is out of range: the device has {n} {what}s{}",
            shown(),
            if n > 0 {
                format!(" (0 to {})", n - 1)
            } else {
                String::new()
            }
        ))),
        (None, None) => Err(out_of_range(format!("{what} {} is out of range", shown()))),
    }
}

/// The element count a device server is made with, within the bounds `vrpn.cfg` applies
/// (`vrpn.LimitError` otherwise).
pub(crate) fn count(obj: &Bound<'_, PyAny>, kind: Interface) -> PyResult<usize> {
    let v = int_value(obj)?;
    let shown = obj.str()?.to_string();
    limits::check_count(kind, v, &shown).map_err(publish)
}

/// A port number: 0 to 65535 (0 picks a free one), else `ValueError` saying so.
pub(crate) fn port(obj: &Bound<'_, PyAny>) -> PyResult<u16> {
    match int_value(obj)?.map(u16::try_from) {
        Some(Ok(p)) => Ok(p),
        _ => Err(pyo3::exceptions::PyValueError::new_err(format!(
            "port must be between 0 and 65535 (0 picks a free one), got {}",
            obj.str()?
        ))),
    }
}
