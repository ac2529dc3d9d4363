//! What every remote shares (`vrpn.Remote`, the base class of `TrackerRemote` & co.), the
//! connection-level callbacks it and `vrpn.Server` offer, and `vrpn.Replay`.

use std::rc::Rc;
use std::time::{Duration, Instant};

use pyo3::exceptions::PyValueError;
use pyo3::gc::PyVisit;
use pyo3::prelude::*;
use pyo3::PyTraverseError;

use super::callbacks::{raise_pending, run, Owner, Registry};
use super::values::Notice;
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

/// Waits until data arrives on `conn`, its next deadline passes or `timeout` ends, with the
/// GIL released so that other Python threads run meanwhile. A connection is not `Send`, so
/// it cannot go to the thread-free section: the wait polls it (without blocking) and sleeps
/// in steps of at most a millisecond between polls; Ctrl-C is honoured at each step.
pub(crate) fn wait(py: Python<'_>, conn: &Connection, timeout: f64) -> PyResult<bool> {
    const STEP: Duration = Duration::from_millis(1);
    let end = crate::time::instant_after(Instant::now(), seconds(timeout)?);
    loop {
        if run(|| conn.wait(Duration::ZERO))? {
            return Ok(true);
        }
        let now = Instant::now();
        let due = conn.poll_timeout().map_or(end, |d| d.min(end));
        if now >= due {
            return Ok(false);
        }
        let nap = (due - now).min(STEP);
        py.detach(|| std::thread::sleep(nap));
        py.check_signals()?;
    }
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

macro_rules! remote_like {
    ($($t:ty),*) => {$(
        impl RemoteLike for $t {
            fn core(&self) -> &RemoteCore {
                self
            }
            fn remove(&self, id: HandlerId) -> bool {
                self.remove_callback(id)
            }
        }
    )*};
}
remote_like!(
    crate::TrackerRemote,
    crate::ButtonRemote,
    crate::AnalogRemote,
    crate::DialRemote,
    crate::TextReceiver
);

/// Base class of the remotes: the connection, its state and events, `mainloop()`.
#[pyclass(subclass, unsendable, module = "vrpn", name = "Remote")]
pub(crate) struct Remote {
    dev: Rc<dyn RemoteLike>,
    pub(crate) reg: Registry,
}

impl Remote {
    pub(crate) fn new(dev: Rc<dyn RemoteLike>) -> Remote {
        Remote {
            dev,
            reg: Registry::default(),
        }
    }

    fn conn(&self) -> &Connection {
        self.dev.core().connection()
    }
}

impl Drop for Remote {
    fn drop(&mut self) {
        remove_connection_handlers(self.dev.core().connection(), &self.reg);
    }
}

#[pymethods]
impl Remote {
    /// Services the connection: reads what arrived and runs the callbacks. Call it often
    /// (every frame, or every millisecond or so). Raises the first exception a callback raised.
    fn mainloop(&self) -> PyResult<()> {
        run(|| self.dev.core().mainloop())
    }

    /// Sleeps until data arrives, the connection has work due, or `timeout` seconds pass,
    /// letting other Python threads run; returns whether data arrived. Call `mainloop()` next.
    fn wait(&self, py: Python<'_>, timeout: f64) -> PyResult<bool> {
        wait(py, self.conn(), timeout)
    }

    /// The device (sender) name, the part before "@".
    #[getter]
    fn device(&self) -> String {
        self.dev.core().device().to_string()
    }

    /// True while the server is connected (always for a replay).
    #[getter]
    fn connected(&self) -> bool {
        self.conn().connected()
    }

    /// "connecting", "connected" or "reconnecting".
    #[getter]
    fn state(&self) -> &'static str {
        state_name(self.conn().state())
    }

    /// Replay controls when the name was `Device@file:PATH`, else None.
    #[getter]
    fn replay(&self) -> Option<Replay> {
        let conn = self.conn();
        conn.is_replay().then(|| Replay { conn: conn.clone() })
    }

    /// Calls `f()` on a connection event: "got_first_connection", "got_connection",
    /// "dropped_connection" or "dropped_last_connection". Returns a handle.
    fn on_event(&self, event: &str, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_event(self.conn(), &self.reg, event, f)
    }

    /// Calls `f(state)` whenever `state` changes. Returns a handle.
    fn on_state_change(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_state_change(self.conn(), &self.reg, f)
    }

    /// Calls `f(notice)` with the connection's diagnostics (instead of printing them to
    /// stderr). Returns a handle.
    fn on_notice(&self, f: &Bound<'_, PyAny>) -> PyResult<u64> {
        on_notice(self.conn(), &self.reg, f)
    }

    /// Removes a callback by the handle an `on_*` method returned.
    fn remove_callback(&self, handle: u64) -> PyResult<()> {
        let (id, owner) = self.reg.take(handle)?;
        match owner {
            Owner::Device => self.dev.remove(id),
            Owner::Connection => self.conn().remove_handler(id),
        };
        Ok(())
    }

    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let class = slf.get_type().name()?;
        let this = slf.borrow();
        Ok(format!(
            "<vrpn.{class} {:?} {}>",
            this.dev.core().device(),
            state_name(this.conn().state())
        ))
    }

    fn __traverse__(&self, visit: PyVisit<'_>) -> Result<(), PyTraverseError> {
        self.reg.traverse(&visit)
    }

    fn __clear__(&self) {
        self.reg.clear();
    }
}

/// Controls of a log replay (`remote.replay` of a `Device@file:PATH` remote).
#[pyclass(unsendable, module = "vrpn", name = "Replay")]
pub(crate) struct Replay {
    conn: Connection,
}

impl Replay {
    fn with<T>(&self, f: impl FnOnce(crate::connection::ReplayControl<'_>) -> T) -> PyResult<T> {
        let r = f(self.conn.replay().expect("a replay connection"));
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
