//! `vrpn.SharedInt32`, `vrpn.SharedFloat64`, `vrpn.SharedString`: a value kept equal between
//! a server and its remotes.

use std::rc::Rc;

use pyo3::exceptions::PyValueError;
use pyo3::gc::PyVisit;
use pyo3::prelude::*;
use pyo3::PyTraverseError;

use super::super::callbacks::{run, stash, Owner, Registry};
use super::super::errors::closed;
use super::super::owned::Owned;
use super::super::server::{Held, Server};
use super::super::waiting::{fileno, wait};
use super::super::{time_or_now, to_py};
use crate::devices::shared_object::{SerializerPolicy, SharedMode, SharedObject, SharedValue};
use crate::dispatch::HandlerId;
use crate::time::TimeVal;

/// A change's value, whichever the kind.
#[derive(Clone)]
enum Value {
    Int(i32),
    Float(f64),
    Text(String),
}

trait ToValue {
    fn to_value(&self) -> Value;
}

impl ToValue for i32 {
    fn to_value(&self) -> Value {
        Value::Int(*self)
    }
}

impl ToValue for f64 {
    fn to_value(&self) -> Value {
        Value::Float(*self)
    }
}

impl ToValue for String {
    fn to_value(&self) -> Value {
        Value::Text(self.clone())
    }
}

fn value_obj<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Int(i) => i.into_pyobject(py)?.into_any(),
        Value::Float(f) => f.into_pyobject(py)?.into_any(),
        Value::Text(s) => s.into_pyobject(py)?.into_any(),
    })
}

/// A change of a shared value, as `on_change` callbacks get it.
#[pyclass(frozen, module = "vrpn", name = "SharedChange")]
pub(crate) struct SharedChange {
    value: Value,
    when: f64,
    is_local: bool,
}

#[pymethods]
impl SharedChange {
    /// The new value.
    #[getter]
    fn value<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        value_obj(py, &self.value)
    }
    /// The time of the change (the value's version), seconds since the epoch.
    #[getter]
    fn when(&self) -> f64 {
        self.when
    }
    /// True when it was set on this side.
    #[getter]
    fn is_local(&self) -> bool {
        self.is_local
    }
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!(
            "SharedChange(value={}, when={:.6}, is_local={})",
            value_obj(py, &self.value)?.repr()?,
            self.when,
            if self.is_local { "True" } else { "False" }
        ))
    }
}

/// The object, owned (a remote) or held by a `Server`, and the callables it registered.
struct Shared<V: SharedValue> {
    own: std::cell::RefCell<Option<Rc<SharedObject<V>>>>,
    adopted: Option<Rc<Held<SharedObject<V>>>>,
    reg: Registry,
}

impl<V: SharedValue> Shared<V> {
    fn get(&self, class: &str) -> PyResult<Rc<SharedObject<V>>> {
        let own = self.own.borrow().clone();
        own.or_else(|| self.adopted.as_ref().and_then(|h| h.get()))
            .ok_or_else(|| closed(class))
    }
    fn close(&self) {
        let gone = self.own.borrow_mut().take();
        drop(gone);
        if let Some(h) = &self.adopted {
            use super::super::server::Release as _;
            h.release();
        }
        self.reg.clear();
    }
}

fn mode(serialized: bool, ignore_old: bool, ignore_idempotent: bool) -> SharedMode {
    SharedMode {
        defer_updates: serialized,
        ignore_old,
        ignore_idempotent,
    }
}

fn policy(name: &str) -> PyResult<SerializerPolicy> {
    match name {
        "accept" => Ok(SerializerPolicy::Accept),
        "deny_remote" => Ok(SerializerPolicy::DenyRemote),
        "deny_local" => Ok(SerializerPolicy::DenyLocal),
        _ => Err(PyValueError::new_err(format!(
            "policy must be \"accept\", \"deny_remote\" or \"deny_local\" (or use \
             set_policy_callback), got {name:?}"
        ))),
    }
}

macro_rules! shared_class {
    ($class:ident, $name:literal, $t:ty, $py:ty, $default:expr, $new_sig:literal, $server_sig:literal) => {
        #[doc = concat!("A shared value: `", $name, "(\"name@host\", value)` on a client, `",
                        $name, ".server(server, \"name\", value)` on a server.")]
        #[pyclass(module = "vrpn", name = $name)]
        pub(crate) struct $class {
            held: Owned<Shared<$t>>,
        }

        impl $class {
            fn h(&self) -> PyResult<&Shared<$t>> {
                self.held.get($name)
            }
            fn o(&self) -> PyResult<Rc<SharedObject<$t>>> {
                self.h()?.get($name)
            }
        }

        #[pymethods]
        impl $class {
            /// The remote side of `name@host` (`serialized`: the server decides every change;
            /// `ignore_old`, `ignore_idempotent`: see the Rust `SharedMode`).
            #[new]
            #[pyo3(signature = (name, value = $default, serialized = false, ignore_old = false, ignore_idempotent = false), text_signature = $new_sig)]
            fn new(
                name: &str,
                value: $py,
                serialized: bool,
                ignore_old: bool,
                ignore_idempotent: bool,
            ) -> PyResult<Self> {
                let m = mode(serialized, ignore_old, ignore_idempotent);
                let o = SharedObject::<$t>::open_remote(name, value, m).map_err(to_py)?;
                Ok($class {
                    held: Owned::new(Shared {
                        own: std::cell::RefCell::new(Some(Rc::new(o))),
                        adopted: None,
                        reg: Registry::default(),
                    }),
                })
            }

            /// The server side of `name` on `server` (the serializer at first).
            #[staticmethod]
            #[pyo3(signature = (server, name, value = $default, serialized = false, ignore_old = false, ignore_idempotent = false), text_signature = $server_sig)]
            fn server(
                server: PyRef<'_, Server>,
                name: &str,
                value: $py,
                serialized: bool,
                ignore_old: bool,
                ignore_idempotent: bool,
            ) -> PyResult<Self> {
                let m = mode(serialized, ignore_old, ignore_idempotent);
                let v = value;
                let held = server.adopt(|conn| SharedObject::<$t>::server(name, conn, v, m))?;
                let adopted = held.get($name)?.clone();
                Ok($class {
                    held: Owned::new(Shared {
                        own: std::cell::RefCell::new(None),
                        adopted: Some(adopted),
                        reg: Registry::default(),
                    }),
                })
            }

            /// The value.
            #[getter]
            fn value(&self) -> PyResult<$t> {
                Ok(self.o()?.value())
            }

            /// The time of the value's last change, seconds since the epoch.
            #[getter]
            fn last_update(&self) -> PyResult<f64> {
                Ok(self.o()?.last_update().as_secs_f64())
            }

            /// Sets the value, changed at `when` (seconds since the epoch; now when None).
            #[pyo3(signature = (value, when = None))]
            fn set(&self, value: $py, when: Option<f64>) -> PyResult<()> {
                let o = self.o()?;
                let t = time_or_now(when, o.connection())?;
                run(|| o.set_at(value, t))
            }

            /// True while this side is the serializer.
            #[getter]
            fn is_serializer(&self) -> PyResult<bool> {
                Ok(self.o()?.is_serializer())
            }

            /// Asks the other side for the serializer role.
            fn become_serializer(&self) -> PyResult<()> {
                self.o()?.become_serializer();
                Ok(())
            }

            /// "accept", "deny_remote" or "deny_local": what the serializer does with changes.
            fn set_policy(&self, name: &str) -> PyResult<()> {
                self.o()?.set_policy(policy(name)?);
                Ok(())
            }

            /// `f(value, when)` decides each change from the other side (truthy accepts).
            /// Returns a handle.
            fn set_policy_callback(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
                let o = self.o()?;
                self.h()?.reg.add(f, Owner::Device, |slot| {
                    o.set_policy_callback(move |v: &$t, t: TimeVal| {
                        Python::attach(|py| {
                            let Some(f) = slot.get(py) else { return false };
                            let f = f.bind(py);
                            match f.call1((v.clone(), t.as_secs_f64())).and_then(|r| r.is_truthy()) {
                                Ok(b) => b,
                                Err(e) => {
                                    stash(py, e, f);
                                    false
                                }
                            }
                        })
                    });
                    HandlerId::fresh()
                })
            }

            /// Calls `f(change)` for every change taken, local or not. Returns a handle.
            fn on_change(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
                let o = self.o()?;
                self.h()?.reg.add(f, Owner::Device, |slot| {
                    o.on_change(move |c| {
                        slot.call_with(|| SharedChange {
                            value: c.value.to_value(),
                            when: c.when.as_secs_f64(),
                            is_local: c.is_local,
                        })
                    })
                })
            }

            /// Calls `f()` when a local change went to the serializer instead of being taken.
            /// Returns a handle.
            fn on_deferred_update(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
                let o = self.o()?;
                self.h()?.reg.add(f, Owner::Device, |slot| {
                    o.on_deferred_update(move || slot.call0())
                })
            }

            /// Removes a callback by its handle.
            fn remove_callback(&self, handle: u64) -> PyResult<()> {
                let o = self.o()?;
                let (id, _) = self.h()?.reg.take(handle)?;
                o.remove_callback(id);
                Ok(())
            }

            /// Services the connection and runs the callbacks.
            fn mainloop(&self) -> PyResult<()> {
                let o = self.o()?;
                run(|| o.mainloop())
            }

            /// Sleeps until data arrives or `timeout` seconds pass; returns whether data
            /// arrived.
            fn wait(&self, py: Python<'_>, timeout: f64) -> PyResult<bool> {
                let o = self.o()?;
                wait(py, o.connection(), timeout)
            }

            /// The descriptor to wait on (asyncio, `select`).
            fn fileno(&self) -> PyResult<i32> {
                fileno(self.o()?.connection())
            }

            /// Releases the object now. Closing twice is fine.
            fn close(&self) -> PyResult<()> {
                self.h()?.close();
                Ok(())
            }

            fn __enter__(slf: Bound<'_, Self>) -> Bound<'_, Self> {
                slf
            }

            fn __exit__(
                &self,
                _ty: &Bound<'_, PyAny>,
                _value: &Bound<'_, PyAny>,
                _traceback: &Bound<'_, PyAny>,
            ) -> PyResult<bool> {
                self.close()?;
                Ok(false)
            }

            fn __traverse__(&self, visit: PyVisit<'_>) -> Result<(), PyTraverseError> {
                match self.held.mine() {
                    Some(h) => h.reg.traverse(&visit),
                    None => Ok(()),
                }
            }

            fn __clear__(&self) {
                if let Some(h) = self.held.mine() {
                    h.reg.clear();
                }
            }
        }
    };
}

shared_class!(
    SharedInt32,
    "SharedInt32",
    i32,
    i32,
    0,
    "(name, value=0, serialized=False, ignore_old=False, ignore_idempotent=False)",
    "(server, name, value=0, serialized=False, ignore_old=False, ignore_idempotent=False)"
);
shared_class!(
    SharedFloat64,
    "SharedFloat64",
    f64,
    f64,
    0.0,
    "(name, value=0.0, serialized=False, ignore_old=False, ignore_idempotent=False)",
    "(server, name, value=0.0, serialized=False, ignore_old=False, ignore_idempotent=False)"
);
shared_class!(
    SharedString,
    "SharedString",
    String,
    String,
    String::new(),
    "(name, value='', serialized=False, ignore_old=False, ignore_idempotent=False)",
    "(server, name, value='', serialized=False, ignore_old=False, ignore_idempotent=False)"
);

pub(super) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<SharedChange>()?;
    m.add_class::<SharedInt32>()?;
    m.add_class::<SharedFloat64>()?;
    m.add_class::<SharedString>()
}
