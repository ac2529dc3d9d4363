//! What every device shares (C++ `vrpn_BaseClass`): its sender, the text/ping/pong types, the
//! server's pong answer, the remote's ping cycle with its 3 s warning and 10 s error, and the
//! default printer of warnings and errors. [`RemoteCore`] bundles what every client half
//! repeats; [`register_server`] the registration every server half starts with.

use std::cell::{Cell, RefCell};
use std::collections::HashSet;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::text::{decode_text, encode_text, TextSeverity, TEXT_PAYLOAD_LEN};
use crate::connection::{Connection, ConnectionEvent};
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
    let text_type = conn.register_type(TEXT_MESSAGE)?;
    let mut buf = [0u8; TEXT_PAYLOAD_LEN];
    if encode_text(&mut buf, severity, level, text).is_none() {
        return Err(Error::PayloadTooLarge(text.len() + 9));
    }
    conn.pack_message(TimeVal::now(), text_type, sender, &buf, class::RELIABLE)
}

thread_local! {
    /// (connection address, sender) pairs that already have the default printer.
    static PRINTERS: RefCell<HashSet<(usize, i32)>> = RefCell::new(HashSet::new());
    static PRINT_THRESHOLD: Cell<TextSeverity> = const { Cell::new(TextSeverity::Warning) };
}

/// Sets the lowest severity the default printer shows (`vrpn_server -v` shows everything).
pub fn set_print_threshold(severity: TextSeverity) {
    PRINT_THRESHOLD.with(|t| t.set(severity));
}

/// Attaches the default printer for text from `sender` (once per connection and sender), which
/// prints warnings and errors to stdout the way C++ does:
/// `VRPN Warning` then ` (LEVEL) from SENDER: TEXT`.
pub fn attach_default_printer(conn: &Connection, ids: &BaseIds) {
    let key = (conn_key(conn), ids.sender.0);
    let fresh = PRINTERS.with(|p| p.borrow_mut().insert(key));
    if !fresh {
        return;
    }
    let name = conn.sender_name(ids.sender).unwrap_or_default();
    conn.register_handler(ids.text, SenderFilter::Only(ids.sender), move |m| {
        if let Some((sev, level, text)) = decode_text(m.payload) {
            if sev >= PRINT_THRESHOLD.with(Cell::get) {
                println!("{}\n ({level}) from {name}: {text}", sev.heading());
            }
        }
    });
}

fn conn_key(conn: &Connection) -> usize {
    conn.identity()
}

/// Server half: answers each ping from the device's own sender with a pong.
pub fn serve_pings(conn: &Connection, ids: &BaseIds) {
    let weak = conn.downgrade();
    let ids = *ids;
    conn.register_handler(ids.ping, SenderFilter::Only(ids.sender), move |_| {
        if let Some(c) = weak.upgrade() {
            let _ = c.pack_message(TimeVal::now(), ids.pong, ids.sender, &[], class::RELIABLE);
        }
    });
}

/// Remote half: the ping cycle that tells whether the server is alive.
pub struct PingCycle {
    ids: BaseIds,
    state: Rc<PingState>,
}

#[derive(Default)]
struct PingState {
    started: Cell<bool>,
    unanswered: Cell<bool>,
    flatlined: Cell<bool>,
    cycle_start: Cell<Option<Instant>>,
    last_ping: Cell<Option<Instant>>,
    /// Set by a dropped-connection event: begin a new cycle on the next mainloop.
    restart: Cell<bool>,
    last_pong: Cell<Option<TimeVal>>,
    /// Suppresses the warning texts (pings still go out).
    pub(crate) shutup: Cell<bool>,
}

impl PingCycle {
    /// Registers the pong and dropped-connection handlers.
    pub fn new(conn: &Connection, ids: BaseIds) -> PingCycle {
        let state = Rc::new(PingState::default());
        let (s, weak) = (state.clone(), conn.downgrade());
        conn.register_handler(ids.pong, SenderFilter::Only(ids.sender), move |m| {
            s.last_pong.set(Some(m.time));
            if s.unanswered.replace(false) && s.flatlined.replace(false) {
                if let Some(c) = weak.upgrade() {
                    let _ = send_text(
                        &c,
                        ids.sender,
                        TextSeverity::Error,
                        0,
                        "Server connection re-established!",
                    );
                }
            }
        });
        let s = state.clone();
        conn.on_event(ConnectionEvent::DroppedConnection, move || {
            if !s.unanswered.get() {
                s.restart.set(true);
            }
        });
        PingCycle { ids, state }
    }

    /// Runs the cycle: call once per remote mainloop.
    pub fn poll(&self, conn: &Connection) {
        if conn.is_replay() {
            return; // nobody answers pings in a log
        }
        let now = Instant::now();
        let st = &self.state;
        if !st.started.get() || st.restart.replace(false) {
            st.started.set(true);
            st.unanswered.set(true);
            st.cycle_start.set(Some(now));
            st.last_ping.set(Some(now));
            self.ping(conn);
            return;
        }
        if !st.unanswered.get() {
            return;
        }
        let last = st.last_ping.get().unwrap_or(now);
        if now.duration_since(last) < Duration::from_secs(1) {
            return;
        }
        st.last_ping.set(Some(now));
        self.ping(conn);
        if st.shutup.get() {
            return;
        }
        let elapsed = now
            .duration_since(st.cycle_start.get().unwrap_or(now))
            .as_secs();
        if elapsed >= 10 {
            st.flatlined.set(true);
            let _ = send_text(
                conn,
                self.ids.sender,
                TextSeverity::Error,
                elapsed as u32,
                "No response from server for >= 10 seconds",
            );
        } else if elapsed >= 3 {
            let _ = send_text(
                conn,
                self.ids.sender,
                TextSeverity::Warning,
                elapsed as u32,
                "No response from server for >= 3 seconds",
            );
        }
    }

    fn ping(&self, conn: &Connection) {
        let _ = conn.pack_message(
            TimeVal::now(),
            self.ids.ping,
            self.ids.sender,
            &[],
            class::RELIABLE,
        );
    }

    /// True while a ping waits for its pong.
    pub fn waiting_for_pong(&self) -> bool {
        self.state.unanswered.get()
    }

    /// Time of the last pong received (the server's clock).
    pub fn last_pong(&self) -> Option<TimeVal> {
        self.state.last_pong.get()
    }

    /// Suppresses (or re-enables) the "no response" texts.
    pub fn set_quiet(&self, quiet: bool) {
        self.state.shutup.set(quiet);
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
        let parsed = DeviceName::parse(name)?;
        let conn = Connection::open_location(&parsed)?;
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

    /// Services the connection (all devices on it) and this device's ping cycle.
    pub fn mainloop(&self) -> Result<(), Error> {
        self.conn.mainloop()?;
        self.ping.poll(&self.conn);
        Ok(())
    }

    /// The connection this remote uses.
    pub fn connection(&self) -> &Connection {
        &self.conn
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
        self.send_at(TimeVal::now(), type_id, payload, class::RELIABLE)
    }

    /// Sends `payload` as `type_id` from this device with an explicit time and class.
    pub fn send_at(
        &self,
        time: TimeVal,
        type_id: TypeId,
        payload: &[u8],
        class_of_service: u32,
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
