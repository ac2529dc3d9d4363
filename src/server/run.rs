//! The server loop: devices, then the connection, then a wait that sleeps only when nothing is
//! due (the C++ main loop, with an event-driven wait instead of a fixed sleep).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::options::SleepPolicy;
use crate::connection::{Connection, ConnectionEvent};
use crate::devices::ServerDevice;
use crate::error::Error;

/// A server connection and the devices it serves.
pub struct ServerLoop {
    conn: Connection,
    devices: Vec<Box<dyn ServerDevice>>,
    sleep: SleepPolicy,
    quit_after_last: bool,
    last_left: std::rc::Rc<std::cell::Cell<bool>>,
    last_activity: Instant,
    flush_logs: bool,
}

impl ServerLoop {
    /// A loop over `devices` on `conn`.
    pub fn new(conn: Connection, devices: Vec<Box<dyn ServerDevice>>, sleep: SleepPolicy) -> Self {
        let last_left = std::rc::Rc::new(std::cell::Cell::new(false));
        let l = last_left.clone();
        conn.on_event(ConnectionEvent::DroppedLastConnection, move || l.set(true));
        ServerLoop {
            conn,
            devices,
            sleep,
            quit_after_last: false,
            last_left,
            last_activity: Instant::now(),
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
        let now = Instant::now();
        for d in &mut self.devices {
            d.mainloop(now);
        }
        self.conn.mainloop()?;
        if self.flush_logs {
            self.conn.flush_logs()?;
        }
        Ok(!(self.quit_after_last && self.last_left.get()))
    }

    /// Waits as the policy says: not at all while spinning or shortly after traffic;
    /// otherwise until a socket is ready or the earliest device deadline.
    pub fn wait(&mut self) -> Result<(), Error> {
        let SleepPolicy::EventDriven {
            busy_window,
            max_block,
        } = self.sleep
        else {
            return Ok(());
        };
        let now = Instant::now();
        if self.conn.take_activity() {
            self.last_activity = now;
        }
        if now.duration_since(self.last_activity) < busy_window {
            // Keep polling without blocking: answers go out at spinning-server latency.
            self.conn.wait(Duration::ZERO)?;
            return Ok(());
        }
        let deadline = self.devices.iter().filter_map(|d| d.next_deadline()).min();
        if self.conn.wait_until(deadline, max_block)? {
            self.last_activity = Instant::now();
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
