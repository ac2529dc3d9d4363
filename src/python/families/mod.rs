//! The families beyond trackers and buttons that an application drives from Python: the
//! imager remote (`ImagerRemote`), mutexes (`MutexRemote`, `MutexServer`, `PeerMutex`) and
//! shared objects (`SharedInt32`, `SharedFloat64`, `SharedString`).

mod imager;
mod mutex;
mod shared;

use pyo3::prelude::*;

pub(crate) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    imager::add_classes(m)?;
    mutex::add_classes(m)?;
    shared::add_classes(m)
}
