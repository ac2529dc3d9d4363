//! The server loop: devices, then the connection, then one wait for everything.
//!
//! Every socket (the server's, and those of connections its layered devices open to other
//! servers) and every serial port waits in the one [`Reactor`] of the server connection, so
//! the loop sleeps in exactly one poll until a byte arrives or the earliest deadline of any
//! device, connection or liveness ping is due.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::options::SleepPolicy;
use crate::connection::{Connection, ConnectionEvent};
use crate::devices::ServerDevice;
use crate::error::Error;
use crate::net::Reactor;

/// A server connection and the devices it serves.
pub struct ServerLoop {
    conn: Connection,
    reactor: Option<Reactor>,
    devices: Vec<Box<dyn ServerDevice>>,
    sleep: SleepPolicy,
    quit_after_last: bool,
    last_left: std::rc::Rc<std::cell::Cell<bool>>,
    last_activity: Option<Instant>,
    flush_logs: bool,
}

impl ServerLoop {
    /// A loop over `devices` on `conn`.
    pub fn new(conn: Connection, devices: Vec<Box<dyn ServerDevice>>, sleep: SleepPolicy) -> Self {
        let last_left = std::rc::Rc::new(std::cell::Cell::new(false));
        let l = last_left.clone();
        conn.on_event(ConnectionEvent::DroppedLastConnection, move || l.set(true));
        ServerLoop {
            reactor: conn.reactor(),
            conn,
            devices,
            sleep,
            quit_after_last: false,
            last_left,
            last_activity: None,
            flush_logs: false,
        }
    }

    /// Write all log data after every pass (`-flush`).
    pub fn flush_logs_every_pass(&mut self, yes: bool) {
        self.flush_logs = yes;
    }

    /// Stop when the last client disconnects (`-q`).
    pub fn quit_after_last(&mut self, yes: bool) {
        self.quit_after_last = yes;
    }

    /// The server connection.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// One pass: every device in order, then the connection. Returns false when the loop
    /// should end (`-q` and the last client left).
    pub fn pass(&mut self) -> Result<bool, Error> {
        let now = crate::net::clock();
        for d in &mut self.devices {
            d.mainloop(now);
        }
        self.conn.mainloop()?;
        if self.flush_logs {
            self.conn.flush_logs()?;
        }
        Ok(!(self.quit_after_last && self.last_left.get()))
    }

    /// The earliest deadline of any device or of the connection.
    pub fn next_deadline(&self) -> Option<Instant> {
        self.devices
            .iter()
            .filter_map(|d| d.next_deadline())
            .chain(self.conn.poll_timeout())
            .min()
    }

    /// Waits as the policy says: not at all while spinning or shortly after traffic;
    /// otherwise until a socket or port is ready or the earliest deadline.
    pub fn wait(&mut self) -> Result<(), Error> {
        let SleepPolicy::EventDriven {
            busy_window,
            max_block,
        } = self.sleep
        else {
            return Ok(());
        };
        let Some(reactor) = self.reactor.clone() else {
            return Ok(());
        };
        let now = Instant::now();
        if reactor.take_activity() {
            self.last_activity = Some(now);
        }
        // A serial port that became readable during the pass's own poll (after its device
        // read) is read by the next pass at once.
        if reactor.timed_pending()
            || self
                .last_activity
                .is_some_and(|t| now.duration_since(t) < busy_window)
        {
            // Keep polling without blocking: answers go out at spinning-server latency.
            reactor
                .poll_now()
                .map_err(|e| Error::io("polling sockets", e))?;
            return Ok(());
        }
        let woke = reactor
            .wait(self.next_deadline(), max_block)
            .map_err(|e| Error::io("polling sockets", e))?;
        if woke {
            self.last_activity = Some(Instant::now());
        }
        Ok(())
    }

    /// Runs until `stop` is set or the loop ends by itself.
    pub fn run(&mut self, stop: &AtomicBool) -> Result<(), Error> {
        while !stop.load(Ordering::Relaxed) {
            if !self.pass()? {
                break;
            }
            self.wait()?;
        }
        Ok(())
    }
}

/// How long [`ServerLoop::wait`] keeps polling without sleeping after traffic, by default.
pub const DEFAULT_BUSY_WINDOW: Duration = Duration::from_millis(2);

/// Descriptors a full server needs: three per client on the UDP path (TCP, UDP in, UDP out)
/// for [`Limits::max_connections`](crate::Limits::max_connections) clients, call-backs in
/// progress, devices and logs.
const DESCRIPTORS_WANTED: u64 = 4096;

/// Raises this process's soft limit on open descriptors towards 4,096 (never
/// above the hard limit, never lowering it): the common default of 1,024 is short of what 255
/// clients and a burst of call-backs take. Returns the soft limit in force afterwards.
pub fn raise_descriptor_limit() -> Option<u64> {
    use nix::sys::resource::{getrlimit, setrlimit, Resource};
    let (soft, hard) = getrlimit(Resource::RLIMIT_NOFILE).ok()?;
    let want = DESCRIPTORS_WANTED.min(hard);
    if soft < want && setrlimit(Resource::RLIMIT_NOFILE, want, hard).is_ok() {
        return Some(want);
    }
    Some(soft)
}
