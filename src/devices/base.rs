//! What every device shares (C++ `vrpn_BaseClass`): its sender, the text/ping/pong types, the
//! server's pong answer, the remote's ping cycle with its 3 s warning and 10 s error, and the
//! default printer of warnings and errors. [`RemoteCore`] bundles what every client half
//! repeats; [`register_server`] the registration every server half starts with.

use std::cell::RefCell;
use std::rc::Rc;

use super::text::TextSeverity;
use crate::connection::{Connection, Liveness};
use crate::dispatch::{HandlerId, Message, SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::name::DeviceName;
use crate::time::TimeVal;
use crate::wire::class;

/// Type name of text messages.
pub const TEXT_MESSAGE: &str = "vrpn_Base text_message";
/// Type name of pings (client to server).
pub const PING_MESSAGE: &str = "vrpn_Base ping_message";
/// Type name of pongs (server to client).
pub const PONG_MESSAGE: &str = "vrpn_Base pong_message";

/// Ids every device object holds.
#[derive(Clone, Copy, Debug)]
pub struct BaseIds {
    /// The device's sender id.
    pub sender: SenderId,
    /// `vrpn_Base text_message`.
    pub text: TypeId,
    /// `vrpn_Base ping_message`.
    pub ping: TypeId,
    /// `vrpn_Base pong_message`.
    pub pong: TypeId,
}

/// Registers the device's sender; the caller then registers its own types and calls
/// [`register_base_types`] (C++ order: sender, device types, then the three base types).
/// [`RemoteCore::new`] and [`register_server`] do all three in that order.
pub fn register_sender(conn: &Connection, device: &str) -> Result<SenderId, Error> {
    conn.register_sender(device)
}

/// Registers the three base types shared by all devices on a connection.
pub fn register_base_types(conn: &Connection, sender: SenderId) -> Result<BaseIds, Error> {
    Ok(BaseIds {
        sender,
        text: conn.register_type(TEXT_MESSAGE)?,
        ping: conn.register_type(PING_MESSAGE)?,
        pong: conn.register_type(PONG_MESSAGE)?,
    })
}

/// Sends a text message from `sender` (1032-byte payload, zero-filled, RELIABLE).
pub fn send_text(
    conn: &Connection,
    sender: SenderId,
    severity: TextSeverity,
    level: u32,
    text: &str,
) -> Result<(), Error> {
    conn.send_text(sender, severity, level, text)
}

/// Sets the lowest severity the default printer shows (`vrpn_server -v` shows everything).
pub use crate::connection::set_print_threshold;

/// Attaches the default printer for text from the device (once per connection and sender;
/// see [`crate::connection::set_text_printer`] for where it writes).
pub fn attach_default_printer(conn: &Connection, ids: &BaseIds) {
    conn.attach_text_printer(ids.sender, ids.text);
}

/// Server half: answers each ping from the device's own sender with a pong.
pub fn serve_pings(conn: &Connection, ids: &BaseIds) {
    let ids = *ids;
    conn.register_handler(ids.ping, SenderFilter::Only(ids.sender), move |m| {
        let c = m.connection();
        let _ = c.pack_message(c.now().wall, ids.pong, ids.sender, &[], class::RELIABLE);
    });
}

/// Remote half: the liveness cycle that tells whether the server's device answers (pings
/// every second while unanswered; "No response from server" texts after 3 s and 10 s).
///
/// The cycle runs inside the connection's `mainloop()`, so any remote's `mainloop()` (or the
/// connection's) keeps every remote's cycle going, and a server loop sleeps only until the
/// next ping is due.
pub struct PingCycle {
    state: Rc<Liveness>,
}

impl PingCycle {
    /// Starts the cycle of the device `ids.sender` on `conn` (registers its pong handler).
    pub fn new(conn: &Connection, ids: BaseIds) -> PingCycle {
        let state = Rc::new(Liveness {
            device: conn.sender_name(ids.sender).unwrap_or_default(),
            sender: ids.sender,
            ping: ids.ping,
            cycle: RefCell::new(crate::proto::ping::PingCycle::new()),
            started: std::cell::Cell::new(false),
        });
        conn.watch_liveness(&state);
        let s = Rc::downgrade(&state);
        conn.register_handler(ids.pong, SenderFilter::Only(ids.sender), move |m| {
            if let Some(s) = s.upgrade() {
                s.pong(m.connection(), m.time);
            }
        });
        PingCycle { state }
    }

    /// True while a ping waits for its pong.
    pub fn waiting_for_pong(&self) -> bool {
        self.state.cycle.borrow().waiting_for_pong()
    }

    /// Time of the last pong received (the server's clock).
    pub fn last_pong(&self) -> Option<TimeVal> {
        self.state.cycle.borrow().last_pong()
    }

    /// Suppresses (or re-enables) the "no response" texts; pings still go out.
    pub fn set_quiet(&self, quiet: bool) {
        self.state.cycle.borrow_mut().set_quiet(quiet);
    }
}

/// Server half: registers `device`'s sender, its own types (`types`), then the three base
/// types — the C++ order — and answers its pings. Returns the base ids and what `types`
/// returned.
pub fn register_server<T>(
    conn: &Connection,
    device: &str,
    types: impl FnOnce(&Connection) -> Result<T, Error>,
) -> Result<(BaseIds, T), Error> {
    let sender = register_sender(conn, device)?;
    let ids = types(conn)?;
    let base = register_base_types(conn, sender)?;
    serve_pings(conn, &base);
    Ok((base, ids))
}

/// What every remote (client half of a device) shares: its connection, base ids, ping cycle,
/// device name and the handlers it registered for its own sender, removed again on drop.
///
/// Each remote (`TrackerRemote`, `ButtonRemote`, ...) holds one and derefs to it, because every
/// remote offers the same [`mainloop`](Self::mainloop), [`connection`](Self::connection),
/// [`device`](Self::device), [`sender`](Self::sender) and [`ping_cycle`](Self::ping_cycle);
/// writing them once here keeps the remotes to their device-specific parts. It is public so
/// that a remote for a device type this crate does not know can be built the same way.
pub struct RemoteCore {
    conn: Connection,
    base: BaseIds,
    ping: PingCycle,
    device: String,
    handlers: Vec<HandlerId>,
}

impl RemoteCore {
    /// Opens the connection of `Device@location` (shared with other devices at that location)
    /// and returns the device part of the name with it.
    pub fn open(name: &str) -> Result<(String, Connection), Error> {
        Self::open_in(None, name)
    }

    /// Like [`open`](Self::open), with a new client connection's sockets waiting in
    /// `reactor` when one is given (a server loop reading other servers: one poll).
    pub fn open_in(
        reactor: Option<&crate::net::Reactor>,
        name: &str,
    ) -> Result<(String, Connection), Error> {
        let parsed = DeviceName::parse_remote(name)?;
        let conn = match reactor {
            Some(r) => Connection::open_in(r, name)?,
            None => Connection::open_location(&parsed)?,
        };
        Ok((parsed.device, conn))
    }

    /// Sets up a remote for `device` on `conn` in the C++ order: the sender, then the device's
    /// own types (`types`, whose result is returned alongside), then the three base types;
    /// then attaches the default printer and starts the ping cycle.
    pub fn new<T>(
        device: &str,
        conn: &Connection,
        types: impl FnOnce(&Connection) -> Result<T, Error>,
    ) -> Result<(RemoteCore, T), Error> {
        let sender = register_sender(conn, device)?;
        let ids = types(conn)?;
        let base = register_base_types(conn, sender)?;
        attach_default_printer(conn, &base);
        let ping = PingCycle::new(conn, base);
        let core = RemoteCore {
            conn: conn.clone(),
            base,
            ping,
            device: device.to_string(),
            handlers: Vec::new(),
        };
        Ok((core, ids))
    }

    /// Registers `f` for messages of `type_id` from this device's sender; the handler is
    /// removed when the remote is dropped. Takes `&mut self`, so only the remote's constructor
    /// can add handlers (remotes deref to `&RemoteCore` only).
    pub fn handle(&mut self, type_id: TypeId, f: impl FnMut(&Message<'_>) + 'static) {
        let h = self
            .conn
            .register_handler(type_id, SenderFilter::Only(self.base.sender), f);
        self.handlers.push(h);
    }

    /// Services the connection: every device on it. Remotes that share a connection (same
    /// location text) need this called on only one of them, once per frame. The first call
    /// also starts this device's ping cycle (as in C++), which the connection keeps running
    /// from then on.
    pub fn mainloop(&self) -> Result<(), Error> {
        if !self.ping.state.started.replace(true) {
            self.conn.liveness_start();
        }
        self.conn.mainloop()
    }

    /// The connection this remote uses.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// Blocks until data arrives, the connection has timed work due, or `timeout` passes,
    /// without spinning ([`Connection::wait`]); returns whether data arrived. Call
    /// [`mainloop`](Self::mainloop) next.
    pub fn wait(&self, timeout: std::time::Duration) -> Result<bool, Error> {
        self.conn.wait(timeout)
    }

    /// The descriptor to wait on in another event loop ([`Connection::fd`]).
    pub fn fd(&self) -> Option<std::os::fd::RawFd> {
        self.conn.fd()
    }

    /// The device (sender) name.
    pub fn device(&self) -> &str {
        &self.device
    }

    /// The device's sender id on this connection.
    pub fn sender(&self) -> SenderId {
        self.base.sender
    }

    /// The base type ids (text, ping, pong) and the sender.
    pub fn base_ids(&self) -> &BaseIds {
        &self.base
    }

    /// The ping cycle (server liveness).
    pub fn ping_cycle(&self) -> &PingCycle {
        &self.ping
    }

    /// Sends `payload` as `type_id` from this device, RELIABLE, stamped now.
    pub fn send(&self, type_id: TypeId, payload: &[u8]) -> Result<(), Error> {
        self.send_at(self.conn.now().wall, type_id, payload, class::RELIABLE)
    }

    /// Sends `payload` as `type_id` from this device with an explicit time and class.
    pub fn send_at(
        &self,
        time: TimeVal,
        type_id: TypeId,
        payload: &[u8],
        class_of_service: impl Into<crate::connection::ServiceClass>,
    ) -> Result<(), Error> {
        self.conn
            .pack_message(time, type_id, self.base.sender, payload, class_of_service)
    }

    /// Sends a text message from this device.
    pub fn send_text(&self, severity: TextSeverity, level: u32, text: &str) -> Result<(), Error> {
        send_text(&self.conn, self.base.sender, severity, level, text)
    }
}

impl Drop for RemoteCore {
    fn drop(&mut self) {
        for h in self.handlers.drain(..) {
            self.conn.remove_handler(h);
        }
    }
}
