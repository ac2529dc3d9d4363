//! `vrpn.MutexRemote`, `vrpn.MutexServer` and `vrpn.PeerMutex`: a lock shared by a server's
//! clients, or by peers.

use std::cell::RefCell;
use std::net::Ipv4Addr;
use std::rc::Rc;

use pyo3::exceptions::PyValueError;
use pyo3::gc::PyVisit;
use pyo3::prelude::*;
use pyo3::PyTraverseError;

use super::super::callbacks::{run, Owner, Registry, Slot};
use super::super::errors::closed;
use super::super::owned::Owned;
use super::super::remote::seconds;
use super::super::server::{close_held, held, Held, Server};
use super::super::to_py;
use super::super::waiting::{fileno, wait};
use crate::devices::mutex::MutexState;
use crate::dispatch::HandlerId;
use crate::Connection;

fn state_name(s: MutexState) -> &'static str {
    match s {
        MutexState::Available => "available",
        MutexState::Requesting => "requesting",
        MutexState::Ours => "ours",
        MutexState::HeldRemotely => "held_remotely",
    }
}

/// What a mutex participant offers the shared Python methods.
trait Participant {
    fn conn(&self) -> &Connection;
    fn pump(&self) -> Result<(), crate::Error>;
    fn on(&self, which: &str, f: Box<dyn FnMut()>) -> Option<HandlerId>;
    fn remove(&self, id: HandlerId) -> bool;
}

impl Participant for crate::devices::mutex::MutexRemote {
    fn conn(&self) -> &Connection {
        self.connection()
    }
    fn pump(&self) -> Result<(), crate::Error> {
        self.mainloop()
    }
    fn on(&self, which: &str, f: Box<dyn FnMut()>) -> Option<HandlerId> {
        Some(match which {
            "granted" => self.on_granted(f),
            "denied" => self.on_denied(f),
            "taken" => self.on_taken(f),
            "released" => self.on_released(f),
            _ => return None,
        })
    }
    fn remove(&self, id: HandlerId) -> bool {
        self.remove_callback(id)
    }
}

impl Participant for crate::devices::peer_mutex::PeerMutex {
    fn conn(&self) -> &Connection {
        self.connection()
    }
    fn pump(&self) -> Result<(), crate::Error> {
        self.mainloop()
    }
    fn on(&self, which: &str, f: Box<dyn FnMut()>) -> Option<HandlerId> {
        Some(match which {
            "granted" => self.on_granted(f),
            "denied" => self.on_denied(f),
            "taken" => self.on_taken(f),
            "released" => self.on_released(f),
            _ => return None,
        })
    }
    fn remove(&self, id: HandlerId) -> bool {
        self.remove_callback(id)
    }
}

/// A participant and the callables it registered, until `close()`.
struct Held2<T> {
    inner: RefCell<Option<Rc<T>>>,
    reg: Registry,
}

impl<T> Held2<T> {
    fn new(v: T) -> Held2<T> {
        Held2 {
            inner: RefCell::new(Some(Rc::new(v))),
            reg: Registry::default(),
        }
    }
    fn get(&self, class: &str) -> PyResult<Rc<T>> {
        self.inner.borrow().clone().ok_or_else(|| closed(class))
    }
    fn close(&self) {
        let gone = self.inner.borrow_mut().take();
        drop(gone);
        self.reg.clear();
    }
}

fn on<T: Participant>(
    h: &Held2<T>,
    class: &str,
    which: &str,
    f: &Bound<'_, PyAny>,
) -> PyResult<u64> {
    let p = h.get(class)?;
    h.reg.add(f, Owner::Device, |slot: Rc<Slot>| {
        p.on(which, Box::new(move || slot.call0()))
            .expect("a known callback kind")
    })
}

fn remove<T: Participant>(h: &Held2<T>, class: &str, handle: u64) -> PyResult<()> {
    let p = h.get(class)?;
    let (id, _) = h.reg.take(handle)?;
    p.remove(id);
    Ok(())
}

macro_rules! participant_methods {
    ($class:ident, $name:literal, { $($extra:tt)* }) => {
        #[pymethods]
        impl $class {
            $($extra)*

            /// "available", "requesting", "ours" or "held_remotely".
            #[getter]
            fn state(&self) -> PyResult<&'static str> {
                Ok(state_name(self.p()?.state()))
            }
            /// True when nobody holds the lock.
            #[getter]
            fn is_available(&self) -> PyResult<bool> {
                Ok(self.p()?.state() == MutexState::Available)
            }
            /// True when this participant holds it.
            #[getter]
            fn is_held_locally(&self) -> PyResult<bool> {
                Ok(self.p()?.state() == MutexState::Ours)
            }
            /// True when another participant holds it.
            #[getter]
            fn is_held_remotely(&self) -> PyResult<bool> {
                Ok(self.p()?.state() == MutexState::HeldRemotely)
            }
            /// Services the connection(s) and runs the callbacks.
            fn mainloop(&self) -> PyResult<()> {
                let p = self.p()?;
                run(|| p.pump())
            }
            /// Sleeps until data arrives or `timeout` seconds pass; returns whether data
            /// arrived. Call `mainloop()` next.
            fn wait(&self, py: Python<'_>, timeout: f64) -> PyResult<bool> {
                let p = self.p()?;
                wait(py, p.conn(), timeout)
            }
            /// The descriptor to wait on (asyncio, `select`).
            fn fileno(&self) -> PyResult<i32> {
                fileno(self.p()?.conn())
            }
            /// Calls `f()` when this participant's request is granted. Returns a handle.
            fn on_granted(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
                on(self.h()?, $name, "granted", f)
            }
            /// Calls `f()` when this participant's request is denied. Returns a handle.
            fn on_denied(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
                on(self.h()?, $name, "denied", f)
            }
            /// Calls `f()` when anyone gets the lock. Returns a handle.
            fn on_taken(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
                on(self.h()?, $name, "taken", f)
            }
            /// Calls `f()` when the lock becomes available. Returns a handle.
            fn on_released(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
                on(self.h()?, $name, "released", f)
            }
            /// Removes a callback by its handle.
            fn remove_callback(&self, handle: u64) -> PyResult<()> {
                remove(self.h()?, $name, handle)
            }
            /// Releases the object now (a lock it holds is given back). Closing twice is
            /// fine.
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

type RustRemote = crate::devices::mutex::MutexRemote;
type RustPeer = crate::devices::peer_mutex::PeerMutex;

/// A client of a server's mutex: `MutexRemote("lock@host")`.
#[pyclass(module = "vrpn", name = "MutexRemote")]
pub(crate) struct MutexRemote {
    held: Owned<Held2<RustRemote>>,
}

impl MutexRemote {
    fn h(&self) -> PyResult<&Held2<RustRemote>> {
        self.held.get("MutexRemote")
    }
    fn p(&self) -> PyResult<Rc<RustRemote>> {
        self.h()?.get("MutexRemote")
    }
}

participant_methods!(MutexRemote, "MutexRemote", {
    #[new]
    fn new(name: &str) -> PyResult<Self> {
        let m = RustRemote::new(name).map_err(to_py)?;
        Ok(MutexRemote {
            held: Owned::new(Held2::new(m)),
        })
    }

    /// Asks for the lock (denied at once when it is not available).
    fn request(&self) -> PyResult<()> {
        let p = self.p()?;
        run(|| p.request())
    }

    /// Gives the lock back (nothing if this remote does not hold it).
    fn release(&self) -> PyResult<()> {
        let p = self.p()?;
        run(|| p.release())
    }

    /// The index the server assigned, None before.
    #[getter]
    fn index(&self) -> PyResult<Option<i32>> {
        Ok(self.p()?.index())
    }

    /// After `timeout` seconds without an answer a request counts as denied; None waits
    /// forever (the default).
    fn set_request_timeout(&self, timeout: Option<f64>) -> PyResult<()> {
        let t = timeout.map(seconds).transpose()?;
        self.p()?.set_request_timeout(t);
        Ok(())
    }
});

/// A peer of a serverless mutex: `PeerMutex("lock", port=0, nic=None)`.
#[pyclass(module = "vrpn", name = "PeerMutex")]
pub(crate) struct PeerMutex {
    held: Owned<Held2<RustPeer>>,
}

impl PeerMutex {
    fn h(&self) -> PyResult<&Held2<RustPeer>> {
        self.held.get("PeerMutex")
    }
    fn p(&self) -> PyResult<Rc<RustPeer>> {
        self.h()?.get("PeerMutex")
    }
}

participant_methods!(PeerMutex, "PeerMutex", {
    #[new]
    #[pyo3(signature = (name, port = 0, nic = None))]
    fn new(name: &str, port: u16, nic: Option<&str>) -> PyResult<Self> {
        let nic = nic
            .map(|t| {
                t.parse::<Ipv4Addr>().map_err(|e| {
                    PyValueError::new_err(format!("nic must be an IPv4 address, got {t:?}: {e}"))
                })
            })
            .transpose()?;
        let m = RustPeer::new(name, port, nic).map_err(to_py)?;
        Ok(PeerMutex {
            held: Owned::new(Held2::new(m)),
        })
    }

    /// Adds the peer serving at "host:port".
    fn add_peer(&self, station: &str) -> PyResult<()> {
        self.p()?.add_peer(station).map_err(to_py)
    }

    /// Asks every peer for the lock; raises if a peer's connection is not up.
    fn request(&self) -> PyResult<()> {
        let p = self.p()?;
        run(|| p.request())
    }

    /// Gives the lock back.
    fn release(&self) -> PyResult<()> {
        self.p()?.release();
        Ok(())
    }

    /// The port this peer serves on.
    #[getter]
    fn port(&self) -> PyResult<u16> {
        Ok(self.p()?.port())
    }

    /// Peers known.
    #[getter]
    fn num_peers(&self) -> PyResult<usize> {
        Ok(self.p()?.num_peers())
    }

    /// True when every peer's connection is up.
    #[getter]
    fn peers_connected(&self) -> PyResult<bool> {
        Ok(self.p()?.peers_connected())
    }
});

/// A mutex served on a `Server`: `MutexServer(server, "lock")`.
#[pyclass(module = "vrpn", name = "MutexServer")]
pub(crate) struct MutexServer {
    held: Owned<Rc<Held<crate::devices::mutex::MutexServer>>>,
}

#[pymethods]
impl MutexServer {
    #[new]
    fn new(server: PyRef<'_, Server>, name: &str) -> PyResult<Self> {
        let held = server.adopt(|conn| crate::devices::mutex::MutexServer::new(name, conn))?;
        Ok(MutexServer { held })
    }

    /// True while a remote holds the lock.
    #[getter]
    fn is_held(&self) -> PyResult<bool> {
        Ok(held(&self.held, "MutexServer")?.is_held())
    }

    /// The index of the remote holding it, None when free.
    #[getter]
    fn holder(&self) -> PyResult<Option<i32>> {
        Ok(held(&self.held, "MutexServer")?.holder())
    }

    /// Stops serving the mutex.
    fn close(&self) -> PyResult<()> {
        close_held(&self.held, "MutexServer")
    }
}

pub(super) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<MutexRemote>()?;
    m.add_class::<PeerMutex>()?;
    m.add_class::<MutexServer>()
}
