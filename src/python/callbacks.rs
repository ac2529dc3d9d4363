//! Python callables as callbacks of the Rust API.
//!
//! Each callable sits in a [`Slot`] that the Rust closure shares; the Python object that
//! registered it keeps the slots in a [`Registry`], so the garbage collector can see (and
//! break) cycles through them, and so `remove_callback` can find the Rust handler again.
//!
//! A callback that raises does not unwind into Rust: [`stash`] keeps the first exception of
//! the thread and [`raise_pending`] hands it to the Python call that ran the callback.

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::gc::PyVisit;
use pyo3::prelude::*;
use pyo3::PyTraverseError;

use crate::dispatch::HandlerId;

thread_local! {
    /// The first exception a callback raised since the last `raise_pending`.
    static PENDING: RefCell<Option<PyErr>> = const { RefCell::new(None) };
}

/// Keeps `e` to be raised by the running `mainloop()`; when one is already waiting, `e` goes
/// to `sys.unraisablehook` (printed by default) so that it is not lost silently.
///
/// An exception that is not an `Exception` (`KeyboardInterrupt` from Ctrl-C, `SystemExit`)
/// also ends the running pass after this callback, so that it reaches the program at once
/// rather than after the pass.
pub(crate) fn stash(py: Python<'_>, e: PyErr, callable: &Bound<'_, PyAny>) {
    if !e.is_instance_of::<pyo3::exceptions::PyException>(py) {
        crate::connection::interrupt_pass();
    }
    let spare = PENDING.with(|p| {
        let mut p = p.borrow_mut();
        if p.is_none() {
            *p = Some(e);
            None
        } else {
            Some(e)
        }
    });
    if let Some(e) = spare {
        e.write_unraisable(py, Some(callable));
    }
}

/// After a callback: keeps its exception, or, when it returned, lets Python's signal handlers
/// run (a Ctrl-C that came while Rust code ran between callbacks raises here), so that a
/// signal ends the pass after the callback that saw it.
fn after_call(py: Python<'_>, r: PyResult<()>, callable: &Bound<'_, PyAny>) {
    if let Err(e) = r.and_then(|()| py.check_signals()) {
        stash(py, e, callable);
    }
}

/// Raises the exception a callback left, if any. Every method that can run callbacks ends
/// with this.
pub(crate) fn raise_pending() -> PyResult<()> {
    match PENDING.with(|p| p.borrow_mut().take()) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Runs `f` (a Rust call that may run callbacks), then raises a callback's exception, or
/// `f`'s own error converted.
pub(crate) fn run<T>(f: impl FnOnce() -> Result<T, crate::Error>) -> PyResult<T> {
    let r = f();
    raise_pending()?;
    r.map_err(super::to_py)
}

/// One registered Python callable, shared with the Rust closure that calls it.
#[derive(Default)]
pub(crate) struct Slot {
    callable: RefCell<Option<Py<PyAny>>>,
}

impl Slot {
    /// The callable, with its own reference (the slot may be emptied while it runs).
    pub(crate) fn get(&self, py: Python<'_>) -> Option<Py<PyAny>> {
        self.callable.borrow().as_ref().map(|f| f.clone_ref(py))
    }

    /// Calls the callable with the object `make` builds (built only when there is a callable).
    pub(crate) fn call_with<T>(&self, make: impl FnOnce() -> T)
    where
        T: pyo3::PyClass + Into<pyo3::PyClassInitializer<T>>,
    {
        Python::attach(|py| {
            let Some(f) = self.get(py) else { return };
            let f = f.bind(py);
            let r = Bound::new(py, make()).and_then(|v| f.call1((v,)));
            after_call(py, r.map(drop), f);
        });
    }

    /// Calls the callable with one string argument (interned by the caller's `intern!`).
    pub(crate) fn call_str(&self, text: &'static str) {
        Python::attach(|py| {
            let Some(f) = self.get(py) else { return };
            let f = f.bind(py);
            let r = f.call1((pyo3::types::PyString::intern(py, text),));
            after_call(py, r.map(drop), f);
        });
    }

    /// Calls the callable with one string argument made from `text`.
    pub(crate) fn call_text(&self, text: &str) {
        Python::attach(|py| {
            let Some(f) = self.get(py) else { return };
            let f = f.bind(py);
            if let Err(e) = f.call1((text,)) {
                stash(py, e, f);
            }
        });
    }

    /// Calls the callable with no argument.
    pub(crate) fn call0(&self) {
        Python::attach(|py| {
            let Some(f) = self.get(py) else { return };
            let f = f.bind(py);
            after_call(py, f.call0().map(drop), f);
        });
    }
}

/// Where a Rust handler was registered, to remove it again.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Owner {
    /// A callback list of the device object (`on_pose`, `on_change`, …).
    Device,
    /// The connection (`on_event`, `on_state_change`, `on_notice`).
    Connection,
}

struct Entry {
    key: u64,
    id: HandlerId,
    owner: Owner,
    slot: Rc<Slot>,
}

/// The callables a Python object registered, by the key handed to Python.
#[derive(Default)]
pub(crate) struct Registry {
    entries: RefCell<Vec<Entry>>,
    next: Cell<u64>,
}

impl Registry {
    /// Registers `callable` through `register` (which adds the Rust closure calling the slot
    /// and returns its id). Returns the key Python passes to `remove_callback`.
    pub(crate) fn add(
        &self,
        callable: &Bound<'_, PyAny>,
        owner: Owner,
        register: impl FnOnce(Rc<Slot>) -> HandlerId,
    ) -> PyResult<u64> {
        if !callable.is_callable() {
            return Err(PyTypeError::new_err(format!(
                "a callback must be callable, got {}",
                callable.get_type().name()?
            )));
        }
        let slot = Rc::new(Slot {
            callable: RefCell::new(Some(callable.clone().unbind())),
        });
        let id = register(slot.clone());
        let key = self.next.get() + 1;
        self.next.set(key);
        self.entries.borrow_mut().push(Entry {
            key,
            id,
            owner,
            slot,
        });
        Ok(key)
    }

    /// Forgets the callable registered under `key` and returns where its handler is.
    pub(crate) fn take(&self, key: u64) -> PyResult<(HandlerId, Owner)> {
        let mut entries = self.entries.borrow_mut();
        let Some(i) = entries.iter().position(|e| e.key == key) else {
            return Err(PyValueError::new_err(format!(
                "no callback with handle {key} on this object"
            )));
        };
        let e = entries.remove(i);
        e.slot.callable.borrow_mut().take();
        Ok((e.id, e.owner))
    }

    /// The connection handlers still registered (to remove when the object goes away).
    pub(crate) fn connection_handlers(&self) -> Vec<HandlerId> {
        let entries = self.entries.borrow();
        let conn = entries.iter().filter(|e| e.owner == Owner::Connection);
        conn.map(|e| e.id).collect()
    }

    /// Lets the garbage collector see the callables.
    pub(crate) fn traverse(&self, visit: &PyVisit<'_>) -> Result<(), PyTraverseError> {
        let Ok(entries) = self.entries.try_borrow() else {
            return Ok(());
        };
        for e in entries.iter() {
            if let Ok(c) = e.slot.callable.try_borrow() {
                visit.call(&*c)?;
            }
        }
        Ok(())
    }

    /// Drops the callables (breaks reference cycles; the handlers stay, calling nothing).
    pub(crate) fn clear(&self) {
        for e in self.entries.borrow().iter() {
            e.slot.callable.borrow_mut().take();
        }
    }
}
