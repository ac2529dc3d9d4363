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
    /// [`wait`](Self::wait) polled the reactor: the next pass's connection need not poll again.
    polled: bool,
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
            polled: false,
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
        let polled = std::mem::take(&mut self.polled);
        for d in &mut self.devices {
            d.mainloop(now);
        }
        if polled {
            self.conn.mainloop_after_poll()?;
        } else {
            self.conn.mainloop()?;
        }
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
            self.polled = true;
            return Ok(());
        }
        let woke = reactor
            .wait(self.next_deadline(), max_block)
            .map_err(|e| Error::io("polling sockets", e))?;
        self.polled = true;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::class;
    use crate::{Limits, SenderFilter, TimeVal};
    use std::cell::Cell;
    use std::net::Ipv4Addr;
    use std::rc::Rc;

    /// The pass after a wait does not poll the reactor again (the wait just did): one poll per
    /// loop iteration, whether the wait blocked or spun in the busy window, and every message a
    /// client sends is still delivered, each before the next is sent.
    #[test]
    fn one_poll_per_loop_iteration() {
        let server = Connection::server(Some(Ipv4Addr::LOCALHOST), 0).unwrap();
        let port = server.local_port().unwrap();
        let t = server.register_type("loop test").unwrap();
        let got = Rc::new(Cell::new(0usize));
        let g = got.clone();
        server.register_handler(t, SenderFilter::Any, move |_| g.set(g.get() + 1));
        let reactor = server.reactor().unwrap();
        let sleep = SleepPolicy::EventDriven {
            busy_window: Duration::from_millis(2),
            max_block: Duration::from_millis(5),
        };
        let mut lp = ServerLoop::new(server, Vec::new(), sleep);

        let client = Connection::client("127.0.0.1", port, true, Limits::default()).unwrap();
        let ct = client.register_type("loop test").unwrap();
        let cs = client.register_sender("loop test client").unwrap();
        let deadline = Instant::now() + Duration::from_secs(20);
        while !(client.connected() && lp.connection().connected()) {
            assert!(Instant::now() < deadline, "never connected");
            client.mainloop().unwrap();
            lp.pass().unwrap();
            lp.wait().unwrap();
        }

        const MESSAGES: usize = 50;
        let polls_before = reactor.polls();
        let mut iterations = 0;
        for k in 1..=MESSAGES {
            client
                .pack_message(TimeVal::now(), ct, cs, &[], class::RELIABLE)
                .unwrap();
            while got.get() < k {
                assert!(Instant::now() < deadline, "message {k} never arrived");
                client.mainloop().unwrap();
                lp.wait().unwrap();
                lp.pass().unwrap();
                iterations += 1;
            }
        }
        assert_eq!(got.get(), MESSAGES);
        assert_eq!(
            reactor.polls() - polls_before,
            iterations,
            "{iterations} loop iterations polled the reactor {} times",
            reactor.polls() - polls_before
        );
    }
}
