//! What every remote shares (`vrpn.Remote`, the base class of `TrackerRemote` & co.), the
//! connection-level callbacks it and `vrpn.Server` offer, and `vrpn.Replay`.

use std::any::Any;
use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use pyo3::exceptions::PyValueError;
use pyo3::gc::PyVisit;
use pyo3::prelude::*;
use pyo3::PyTraverseError;

use super::callbacks::{raise_pending, run, Owner, Registry};
use super::errors::closed;
use super::owned::Owned;
use super::values::Notice;
use super::waiting::{fileno, wait};
use crate::devices::base::RemoteCore;
use crate::dispatch::HandlerId;
use crate::{Connection, ConnectionEvent, ConnectionState};

/// The name Python sees for a connection state.
pub(crate) fn state_name(s: ConnectionState) -> &'static str {
    match s {
        ConnectionState::Connecting => "connecting",
        ConnectionState::Connected => "connected",
        ConnectionState::Reconnecting => "reconnecting",
        ConnectionState::Listening => "listening",
    }
}

const EVENTS: [(&str, ConnectionEvent); 4] = [
    ("got_first_connection", ConnectionEvent::GotFirstConnection),
    ("got_connection", ConnectionEvent::GotConnection),
    ("dropped_connection", ConnectionEvent::DroppedConnection),
    (
        "dropped_last_connection",
        ConnectionEvent::DroppedLastConnection,
    ),
];

/// A seconds argument as a `Duration`, refusing what cannot be one.
pub(crate) fn seconds(timeout: f64) -> PyResult<Duration> {
    Duration::try_from_secs_f64(timeout).map_err(|_| {
        PyValueError::new_err(format!(
            "timeout must be a finite number of seconds >= 0, got {timeout}"
        ))
    })
}

/// `on_event(name, f)` on `conn`, kept in `reg`.
pub(crate) fn on_event(
    conn: &Connection,
    reg: &Registry,
    event: &str,
    f: &Bound<'_, PyAny>,
) -> PyResult<u64> {
    let Some(&(_, ev)) = EVENTS.iter().find(|(n, _)| *n == event) else {
        let names: Vec<&str> = EVENTS.iter().map(|(n, _)| *n).collect();
        return Err(PyValueError::new_err(format!(
            "unknown connection event {event:?}; expected one of {}",
            names.join(", ")
        )));
    };
    reg.add(f, Owner::Connection, |slot| {
        conn.on_event(ev, move || slot.call0())
    })
}

/// `on_state_change(f)` on `conn`: `f(state_name)`.
pub(crate) fn on_state_change(
    conn: &Connection,
    reg: &Registry,
    f: &Bound<'_, PyAny>,
) -> PyResult<u64> {
    reg.add(f, Owner::Connection, |slot| {
        conn.on_state_change(move |s| slot.call_str(state_name(*s)))
    })
}

/// `on_notice(f)` on `conn`: `f(Notice)`.
pub(crate) fn on_notice(conn: &Connection, reg: &Registry, f: &Bound<'_, PyAny>) -> PyResult<u64> {
    reg.add(f, Owner::Connection, |slot| {
        conn.on_notice(move |n| slot.call_with(|| Notice(n.clone())))
    })
}

/// `on_peer_sender(f)` on `conn`: `f(name)` for each sender name a peer describes.
pub(crate) fn on_peer_sender(
    conn: &Connection,
    reg: &Registry,
    f: &Bound<'_, PyAny>,
) -> PyResult<u64> {
    reg.add(f, Owner::Connection, |slot| {
        conn.on_peer_sender(move |name| slot.call_text(name))
    })
}

/// Removes the connection handlers a Python object registered.
pub(crate) fn remove_connection_handlers(conn: &Connection, reg: &Registry) {
    for id in reg.connection_handlers() {
        conn.remove_handler(id);
    }
}

/// A Rust remote as the base class sees it.
pub(crate) trait RemoteLike {
    /// Its common part.
    fn core(&self) -> &RemoteCore;
    /// Removes one of its device callbacks.
    fn remove(&self, id: HandlerId) -> bool;
}

/// `RemoteLike` for Rust remotes that deref to their `RemoteCore` and have
/// `remove_callback`.
macro_rules! remote_like {
    ($($t:ty),*) => {$(
        impl $crate::python::remote::RemoteLike for $t {
            fn core(&self) -> &$crate::devices::base::RemoteCore {
                self
            }
            fn remove(&self, id: $crate::dispatch::HandlerId) -> bool {
                self.remove_callback(id)
            }
        }
    )*};
}
pub(crate) use remote_like;
remote_like!(
    crate::TrackerRemote,
    crate::ButtonRemote,
    crate::AnalogRemote,
    crate::DialRemote,
    crate::TextReceiver
);

/// The Rust remote behind a Python one, seen both ways.
struct Device {
    core: Rc<dyn RemoteLike>,
    any: Rc<dyn Any>,
}

/// What a `Remote` holds on its thread.
struct RemoteState {
    /// `None` once closed.
    dev: RefCell<Option<Device>>,
    reg: Registry,
}

impl RemoteState {
    /// Releases the remote: its connection callbacks go, its device callbacks go with it, and
    /// the connection closes once no other remote uses it.
    fn close(&self) {
        let dev = self.dev.borrow_mut().take();
        if let Some(d) = dev {
            remove_connection_handlers(d.core.core().connection(), &self.reg);
        }
        self.reg.clear();
    }
}

impl Drop for RemoteState {
    fn drop(&mut self) {
        self.close();
    }
}

/// Base class of the remotes: the connection, its state and events, `mainloop()`.
#[pyclass(subclass, module = "vrpn", name = "Remote")]
pub(crate) struct Remote {
    /// The Python class name, for messages.
    class: &'static str,
    /// The device (sender) name, the part before "@".
    device: String,
    state: Owned<RemoteState>,
}

impl Remote {
    pub(crate) fn new<T: RemoteLike + 'static>(class: &'static str, dev: T) -> Remote {
        let device = dev.core().device().to_string();
        let rc = Rc::new(dev);
        let any: Rc<dyn Any> = rc.clone();
        Remote {
            class,
            device,
            state: Owned::new(RemoteState {
                dev: RefCell::new(Some(Device { core: rc, any })),
                reg: Registry::default(),
            }),
        }
    }

    fn st(&self) -> PyResult<&RemoteState> {
        self.state.get(self.class)
    }

    /// The callables this object registered.
    pub(crate) fn reg(&self) -> PyResult<&Registry> {
        Ok(&self.st()?.reg)
    }

    /// The Rust remote (a new reference: it outlives a `close()` from inside a callback).
    fn core(&self) -> PyResult<Rc<dyn RemoteLike>> {
        let st = self.st()?;
        let dev = st.dev.borrow();
        dev.as_ref()
            .map(|d| d.core.clone())
            .ok_or_else(|| closed(self.class))
    }

    /// The Rust remote of the subclass, `T`.
    pub(crate) fn inner<T: 'static>(&self) -> PyResult<Rc<T>> {
        let st = self.st()?;
        let dev = st.dev.borrow();
        let any = dev
            .as_ref()
            .map(|d| d.any.clone())
            .ok_or_else(|| closed(self.class))?;
        Ok(any
            .downcast::<T>()
            .unwrap_or_else(|_| unreachable!("a vrpn.{} holds its own kind", self.class)))
    }

    fn conn(&self) -> PyResult<Connection> {
        Ok(self.core()?.core().connection().clone())
    }
}

#[pymethods]
impl Remote {
    /// Services the connection: reads what arrived and runs the callbacks. Call it often
    /// (every frame, or every millisecond or so). Raises the first exception a callback raised.
    fn mainloop(&self) -> PyResult<()> {
        let dev = self.core()?;
        run(|| dev.core().mainloop())
    }

    /// Sleeps until data arrives, the connection has work due, or `timeout` seconds pass,
    /// letting other Python threads run; returns whether data arrived. Call `mainloop()` next.
    fn wait(&self, py: Python<'_>, timeout: f64) -> PyResult<bool> {
        wait(py, &self.conn()?, timeout)
    }

    /// The descriptor to wait on in asyncio (`loop.add_reader(r.fileno(), r.mainloop)`) or
    /// `select`: readable when data arrives or the connection's next timed work is due.
    fn fileno(&self) -> PyResult<i32> {
        fileno(&self.conn()?)
    }

    /// The device (sender) name, the part before "@".
    #[getter]
    fn device(&self) -> &str {
        &self.device
    }

    /// True while the server is connected (always for a replay).
    #[getter]
    fn connected(&self) -> PyResult<bool> {
        Ok(self.conn()?.connected())
    }

    /// "connecting", "connected" or "reconnecting".
    #[getter]
    fn state(&self) -> PyResult<&'static str> {
        Ok(state_name(self.conn()?.state()))
    }

    /// True once `close()` was called.
    #[getter]
    fn closed(&self) -> PyResult<bool> {
        Ok(self.st()?.dev.borrow().is_none())
    }

    /// Replay controls when the name was `Device@file:PATH`, else None.
    #[getter]
    fn replay(&self) -> PyResult<Option<Replay>> {
        let conn = self.conn()?;
        Ok(conn.is_replay().then(|| Replay {
            conn: Owned::new(conn),
        }))
    }

    /// Calls `f()` on a connection event: "got_first_connection", "got_connection",
    /// "dropped_connection" or "dropped_last_connection". Returns a handle.
    fn on_event(&self, event: &str, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_event(&self.conn()?, self.reg()?, event, f)
    }

    /// Calls `f(state)` whenever `state` changes. Returns a handle.
    fn on_state_change(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_state_change(&self.conn()?, self.reg()?, f)
    }

    /// Calls `f(notice)` with the connection's diagnostics (instead of printing them to
    /// stderr). Returns a handle.
    fn on_notice(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_notice(&self.conn()?, self.reg()?, f)
    }

    /// Calls `f(name)` with each device (sender) name the server describes, as it is
    /// described (inside `mainloop()`). Returns a handle.
    fn on_peer_sender(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_peer_sender(&self.conn()?, self.reg()?, f)
    }

    /// The device (sender) names the server has described so far.
    #[getter]
    fn peer_senders(&self) -> PyResult<Vec<String>> {
        Ok(self.conn()?.peer_senders())
    }

    /// Removes a callback by the handle an `on_*` method returned.
    fn remove_callback(&self, handle: u64) -> PyResult<()> {
        let dev = self.core()?;
        let (id, owner) = self.reg()?.take(handle)?;
        match owner {
            Owner::Device => dev.remove(id),
            Owner::Connection => dev.core().connection().remove_handler(id),
        };
        Ok(())
    }

    /// Releases the remote now: its callbacks are removed and the connection closes once no
    /// other remote uses it. Any later use raises `vrpn.ClosedError`; closing twice is fine.
    fn close(&self) -> PyResult<()> {
        self.st()?.close();
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

    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let class = slf.get_type().name()?;
        let this = slf.borrow();
        let state = match this.state.mine() {
            None => "of another thread",
            Some(st) => match st.dev.borrow().as_ref() {
                None => "closed",
                Some(d) => state_name(d.core.core().connection().state()),
            },
        };
        Ok(format!("<vrpn.{class} {:?} {state}>", this.device))
    }

    fn __traverse__(&self, visit: PyVisit<'_>) -> Result<(), PyTraverseError> {
        match self.state.mine() {
            Some(st) => st.reg.traverse(&visit),
            None => Ok(()),
        }
    }

    fn __clear__(&self) {
        if let Some(st) = self.state.mine() {
            st.reg.clear();
        }
    }
}

/// Controls of a log replay (`remote.replay` of a `Device@file:PATH` remote).
#[pyclass(module = "vrpn", name = "Replay")]
pub(crate) struct Replay {
    conn: Owned<Connection>,
}

impl Replay {
    fn with<T>(&self, f: impl FnOnce(crate::connection::ReplayControl<'_>) -> T) -> PyResult<T> {
        let conn = self.conn.get("Replay")?;
        let r = f(conn.replay().expect("a replay connection"));
        raise_pending()?;
        Ok(r)
    }
}

/// A position in seconds for `seek` and `play_to`: NaN is refused; anything else saturates at
/// the ends of the log's time range (`float("inf")` is the end).
fn not_nan(secs: f64) -> PyResult<f64> {
    if secs.is_nan() {
        return Err(PyValueError::new_err("seconds must be a number, got nan"));
    }
    Ok(secs)
}

#[pymethods]
impl Replay {
    /// Speed: 1.0 real time, 0 paused, 10 ten times faster, float("inf") as fast as possible.
    #[getter]
    fn get_rate(&self) -> PyResult<f64> {
        self.with(|r| r.rate())
    }

    #[setter]
    fn set_rate(&self, rate: f64) -> PyResult<()> {
        if rate.is_nan() || rate < 0.0 {
            return Err(PyValueError::new_err(format!(
                "replay rate must be >= 0 (0 pauses), got {rate}"
            )));
        }
        self.with(|r| r.set_rate(rate))
    }

    /// Moves to `secs` after the first message without delivering the messages in between.
    /// Returns whether that time is inside the log.
    fn seek(&self, secs: f64) -> PyResult<bool> {
        let secs = not_nan(secs)?;
        self.with(|r| r.jump_to_time(secs))
    }

    /// Delivers, now, every message up to `secs` after the first one.
    fn play_to(&self, secs: f64) -> PyResult<()> {
        let secs = not_nan(secs)?;
        self.with(|r| r.play_to_time(secs))
    }

    /// Delivers the next message now; False at the end of the log.
    fn play_one(&self) -> PyResult<bool> {
        self.with(|r| r.play_one())
    }

    /// Back to the start.
    fn reset(&self) -> PyResult<()> {
        self.with(|r| r.reset())
    }

    /// True once every message has been played.
    #[getter]
    fn eof(&self) -> PyResult<bool> {
        self.with(|r| r.eof())
    }

    /// Seconds since the first message, where the replay stands.
    #[getter]
    fn position(&self) -> PyResult<f64> {
        self.with(|r| r.elapsed())
    }

    /// Seconds between the first and the last message.
    #[getter]
    fn length(&self) -> PyResult<f64> {
        self.with(|r| r.length_secs())
    }

    /// Time of the first message (seconds since the epoch), None for an empty log.
    #[getter]
    fn start_time(&self) -> PyResult<Option<f64>> {
        self.with(|r| r.first_time().map(|t| t.as_secs_f64()))
    }
}

pub(crate) fn add_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Remote>()?;
    m.add_class::<Replay>()?;
    Ok(())
}
