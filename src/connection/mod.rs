//! The connection: local names, handlers, peers, and the `mainloop()` that moves messages.
//!
//! A [`Connection`] is a cheap handle (`Rc`) shared by every device object that uses it. Three
//! kinds exist: a **server** listening on one UDP+TCP port for many peers, a **client** that
//! reaches one server (and reconnects forever), and the **loopback** connection of this process,
//! which has no sockets at all (plus the **replay** of a log file). All of them deliver every
//! packed message to local handlers directly, which is how an in-process remote hears an
//! in-process server.
//!
//! Under the handle sit the three layers: a [`Session`] (the protocol,
//! no sockets, no clock), the shell (the sockets, in a [`Reactor`]) and the handler tables.
//! One [`mainloop`](Connection::mainloop) pass reads the clock once and hands that time down.
//!
//! Callbacks run only inside [`Connection::mainloop`] or inside a call that sends a message.
//! A callback may itself send, register, or read state: messages a callback sends to local
//! handlers are queued and delivered right after it returns, so no handler is ever re-entered.
//! Connections are not `Send`: one thread owns a connection and every device on it.

pub mod dispatch;
mod liveness;
pub use liveness::is_service_sender;
mod logs;
pub mod names;
mod open;
mod pass;
mod printer;
mod replay_control;
mod service;
mod waiting;

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4, ToSocketAddrs};
use std::rc::{Rc, Weak};
use std::time::{Duration, Instant};

use crate::error::Error;
use crate::name::DeviceName;
use crate::net::shell::Shell;
use crate::net::{PassClock, Reactor};
use crate::proto::Session;
use crate::time::{Now, TimeSource, TimeVal};
use crate::wire;
use dispatch::{CallbackList, HandlerId, HandlerTable, Message, SenderFilter, SenderId, TypeId};

pub use crate::net::interrupt_pass;
pub(crate) use liveness::Liveness;
pub use open::ConnectionOptions;
pub use printer::{set_print_threshold, set_text_printer, TextPrinter};
pub use replay_control::ReplayControl;
pub use service::ServiceClass;

pub use crate::proto::clock::{ClockSyncConfig, Estimate};
pub use crate::proto::{
    ConnectionEvent, ConnectionState, DropReason, Limits, NameKind, Notice, NoticeKind, Severity,
};

/// Largest payload a VRPN peer can receive over TCP (64000-byte buffer less the header).
pub const MAX_PAYLOAD: usize = wire::MAX_PAYLOAD;

/// The protocol state and the sockets of one connection.
struct Core {
    session: Session,
    shell: Shell,
}

struct Inner {
    core: RefCell<Core>,
    /// The reactor the sockets wait in (kept here so a pass need not borrow the core for it).
    reactor: Option<Reactor>,
    handlers: HandlerTable,
    /// How many handler calls are running (a handler may cause nested deliveries).
    depth: Cell<u32>,
    /// The clock of the running pass: read at most once per pass, and only if something
    /// needs the time; handlers that stamp replies share the pass's reading.
    clock: PassClock,
    /// Local deliveries requested while a handler runs: encoded messages, delivered in order.
    deferred: RefCell<Vec<u8>>,
    /// `deferred` holds something (a flag: tested after every delivery).
    any_deferred: Cell<bool>,
    deferred_scratch: RefCell<Vec<u8>>,
    notices: CallbackList<Notice>,
    peer_senders: CallbackList<str>,
    states: CallbackList<ConnectionState>,
    /// The liveness cycles of the remotes on this connection.
    liveness: RefCell<Vec<Weak<Liveness>>>,
    /// The earliest liveness deadline, while known (`None` inside: no deadline). Cleared
    /// whenever a cycle may have changed (a pong, an event, a ping sent, a remote started).
    liveness_next: Cell<Option<Option<Instant>>>,
    /// A remote started its cycle and the connection has not polled it yet (a fresh cycle
    /// has no deadline until its first poll).
    liveness_started: Cell<bool>,
    /// Senders whose texts the default printer shows (with its handler), or that were muted
    /// (no handler).
    printed: RefCell<Vec<(i32, Option<HandlerId>)>>,
    /// Someone waits on the reactor's descriptor from outside ([`Connection::fd`]): every
    /// pass sets the reactor's timer for this connection's next deadline.
    watched: Cell<bool>,
    /// `Limits::max_pass_time`.
    pass_time: Duration,
    /// The last pass ended with deliveries left for the next (its time was up).
    left_over: Cell<bool>,
}

/// A VRPN connection handle. Clones share the connection.
///
/// Not `Send`: a connection and every device on it belong to the thread that made them
/// (sharing by location and `loopback:` are per thread too). To feed another thread, run the
/// connection on a worker that publishes latest states (docs/USING.md, "Threads").
#[derive(Clone)]
pub struct Connection {
    inner: Rc<Inner>,
}

impl std::fmt::Debug for Connection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Connection")
            .field("state", &self.state())
            .finish()
    }
}

thread_local! {
    static SHARED: RefCell<HashMap<String, Weak<Inner>>> = RefCell::new(HashMap::new());
    static LOOPBACK: RefCell<Weak<Inner>> = const { RefCell::new(Weak::new()) };
}

const DEFERRED_HEADER: usize = 4 + 4 + 8 + 8 + 4;
/// Log bytes written per mainloop pass: bounded so logging never stalls the loop.
const LOG_FLUSH_PER_PASS: usize = 256 * 1024;

/// Resolves `host` to its first IPv4 address (at set-up, never inside a loop pass).
pub(crate) fn resolve_v4(host: &str, port: u16) -> Result<SocketAddrV4, Error> {
    let addrs = (host, port).to_socket_addrs().map_err(|e| Error::Resolve {
        host: host.to_string(),
        reason: e.to_string(),
    })?;
    for a in addrs {
        if let SocketAddr::V4(v4) = a {
            return Ok(v4);
        }
    }
    Err(Error::Resolve {
        host: host.to_string(),
        reason: "no IPv4 address (VRPN 07 is IPv4 only)".into(),
    })
}

fn new_reactor() -> Result<Reactor, Error> {
    Reactor::new().map_err(|e| Error::io("creating the poll instance", e))
}

impl Connection {
    fn from_parts(session: Session, shell: Shell) -> Connection {
        let pass_time = session.limits().max_pass_time;
        Connection {
            inner: Rc::new(Inner {
                reactor: shell.reactor().cloned(),
                core: RefCell::new(Core { session, shell }),
                handlers: HandlerTable::default(),
                depth: Cell::new(0),
                clock: PassClock::default(),
                deferred: RefCell::new(Vec::with_capacity(64 * 1024)),
                any_deferred: Cell::new(false),
                deferred_scratch: RefCell::new(Vec::with_capacity(64 * 1024)),
                notices: CallbackList::default(),
                peer_senders: CallbackList::default(),
                states: CallbackList::default(),
                liveness: RefCell::new(Vec::new()),
                liveness_next: Cell::new(Some(None)),
                liveness_started: Cell::new(false),
                printed: RefCell::new(Vec::new()),
                watched: Cell::new(false),
                pass_time,
                left_over: Cell::new(false),
            }),
        }
    }

    /// Opens (or shares) the connection for a device name such as `Tracker0@host:3883`.
    ///
    /// Every device whose location text is identical shares one connection, as in C++. A
    /// network client returns at once; it connects during later [`mainloop`](Self::mainloop)
    /// calls and reconnects by itself whenever the server goes away.
    pub fn open(name: &str) -> Result<Connection, Error> {
        let parsed = DeviceName::parse(name)?;
        Self::open_location(&parsed)
    }

    /// Like [`open`](Self::open) for an already parsed name.
    pub fn open_location(name: &DeviceName) -> Result<Connection, Error> {
        Self::open_location_in(name, None)
    }

    /// Like [`open`](Self::open), with the sockets of a new client connection waiting in
    /// `reactor` (a server loop that also reads other servers: one poll for everything). A
    /// connection already open for the same location is shared as it is.
    pub fn open_in(reactor: &Reactor, name: &str) -> Result<Connection, Error> {
        let parsed = DeviceName::parse(name)?;
        Self::open_location_in(&parsed, Some(reactor))
    }

    fn open_location_in(name: &DeviceName, reactor: Option<&Reactor>) -> Result<Connection, Error> {
        let options = ConnectionOptions {
            reactor: reactor.cloned(),
            ..ConnectionOptions::default()
        };
        Self::open_location_with(name, &options)
    }

    /// The live connection opened for this location text, or a new one from `make` (C++
    /// shares one connection among all devices whose location text is byte-identical).
    fn shared(
        location_text: &str,
        make: impl FnOnce() -> Result<Connection, Error>,
    ) -> Result<Connection, Error> {
        if let Some(inner) = SHARED.with(|s| s.borrow().get(location_text).and_then(Weak::upgrade))
        {
            return Ok(Connection { inner });
        }
        let conn = make()?;
        SHARED.with(|s| {
            let mut s = s.borrow_mut();
            s.retain(|_, w| w.strong_count() > 0);
            s.insert(location_text.to_string(), Rc::downgrade(&conn.inner));
        });
        Ok(conn)
    }

    /// A new, unshared replay of the log at `path` (what `Device@file:path` opens).
    ///
    /// Callbacks fire at the original pace with the original timestamps; see
    /// [`Connection::replay`] for rate, reset, play-to and jump-to.
    pub fn replay_file(path: &str) -> Result<Connection, Error> {
        let replay = crate::log::replay::Replay::open(path).map_err(Error::from_log)?;
        let session = Session::file(replay, path, Limits::default());
        Ok(Connection::from_parts(session, Shell::none()))
    }

    /// A new, unshared client connection to `host:port`.
    pub fn client(
        host: &str,
        port: u16,
        tcp_only: bool,
        limits: Limits,
    ) -> Result<Connection, Error> {
        Self::client_in(&new_reactor()?, host, port, tcp_only, limits)
    }

    /// [`client`](Self::client) with its sockets waiting in `reactor`.
    pub fn client_in(
        reactor: &Reactor,
        host: &str,
        port: u16,
        tcp_only: bool,
        limits: Limits,
    ) -> Result<Connection, Error> {
        let server = resolve_v4(host, port)?;
        let (shell, listen) = Shell::client(reactor, server, tcp_only)?;
        let session = Session::client(server, host, listen, limits, crate::net::clock());
        Ok(Connection::from_parts(session, shell))
    }

    /// A server on `port` (0 picks a free one; see [`local_port`](Self::local_port)), on every
    /// interface or only on `nic`.
    pub fn server(nic: Option<Ipv4Addr>, port: u16) -> Result<Connection, Error> {
        Self::server_with_limits(nic, port, Limits::default())
    }

    /// A server with explicit limits.
    pub fn server_with_limits(
        nic: Option<Ipv4Addr>,
        port: u16,
        limits: Limits,
    ) -> Result<Connection, Error> {
        Self::server_in(&new_reactor()?, nic, port, limits)
    }

    /// A server whose sockets wait in `reactor` (shared with the serial ports and other
    /// connections of a server loop).
    pub fn server_in(
        reactor: &Reactor,
        nic: Option<Ipv4Addr>,
        port: u16,
        limits: Limits,
    ) -> Result<Connection, Error> {
        let shell = Shell::server(reactor, nic, port)?;
        Ok(Connection::from_parts(Session::server(limits, nic), shell))
    }

    /// The in-process connection of this thread (`loopback:`): no sockets, always connected.
    pub fn loopback() -> Connection {
        LOOPBACK.with(|l| {
            if let Some(inner) = l.borrow().upgrade() {
                return Connection { inner };
            }
            let conn = Connection::new_loopback();
            *l.borrow_mut() = Rc::downgrade(&conn.inner);
            conn
        })
    }

    /// A new private in-process connection, not shared through `loopback:`.
    pub fn new_loopback() -> Connection {
        Connection::from_parts(Session::loopback(Limits::default()), Shell::none())
    }

    /// A number identifying this connection while it exists.
    pub fn identity(&self) -> usize {
        Rc::as_ptr(&self.inner) as *const () as usize
    }

    /// True when both handles are the same connection.
    pub fn same_as(&self, other: &Connection) -> bool {
        Rc::ptr_eq(&self.inner, &other.inner)
    }

    /// The reactor this connection's sockets wait in (none for loopback and replay).
    pub fn reactor(&self) -> Option<Reactor> {
        self.inner.reactor.clone()
    }

    /// The current time: the time of the running pass while handlers run (so every reply a
    /// pass sends carries the same time), the clock otherwise.
    pub fn now(&self) -> Now {
        self.inner.clock.now()
    }

    /// The time of the running `mainloop()` pass (read now if nothing in the pass read it
    /// yet), or `None` outside a pass.
    #[inline]
    pub(crate) fn pass_time(&self) -> Option<TimeVal> {
        let clock = &self.inner.clock;
        clock.in_pass().then(|| clock.wall())
    }

    /// The clock-synchronisation estimate of the peer (a client's server; a server's first
    /// client), or `None` while sync is not in effect: not yet (the first exchanges take about
    /// 0.2 s after connecting), stale, off ([`Limits::clock_sync`]), or a peer that does not
    /// take part — C++ VRPN never does, and its timestamps then pass through unchanged.
    ///
    /// `offset` is the peer's clock minus ours in seconds; message times are translated with
    /// it (`local = sender − offset`), and the true offset lies within `± uncertainty`.
    pub fn clock_estimate(&self) -> Option<Estimate> {
        let now = self.now();
        self.inner.core.borrow().session.clock_estimate(now)
    }

    /// Each connected peer's address and clock estimate (see
    /// [`clock_estimate`](Self::clock_estimate)); a server learns each client's clock this way.
    pub fn peer_clocks(&self) -> Vec<(String, Option<Estimate>)> {
        let now = self.now();
        self.inner.core.borrow().session.peer_clocks(now)
    }

    // -------------------------------------------------------------- names

    /// Registers (or finds) a sender name and describes it to connected peers.
    pub fn register_sender(&self, name: &str) -> Result<SenderId, Error> {
        let now = self.now();
        let id = self
            .inner
            .core
            .borrow_mut()
            .session
            .register(now, true, name.as_bytes())?;
        Ok(SenderId(id))
    }

    /// Registers (or finds) a message type name and describes it to connected peers.
    pub fn register_type(&self, name: &str) -> Result<TypeId, Error> {
        let now = self.now();
        let id = self
            .inner
            .core
            .borrow_mut()
            .session
            .register(now, false, name.as_bytes())?;
        Ok(TypeId(id))
    }

    /// The name of a local sender id (bytes that are not UTF-8 are shown as U+FFFD).
    pub fn sender_name(&self, id: SenderId) -> Option<String> {
        let core = self.inner.core.borrow();
        core.session
            .name_of(true, id.0)
            .map(|n| String::from_utf8_lossy(n).into_owned())
    }

    /// The name of a local type id (bytes that are not UTF-8 are shown as U+FFFD).
    pub fn type_name(&self, id: TypeId) -> Option<String> {
        let core = self.inner.core.borrow();
        core.session
            .name_of(false, id.0)
            .map(|n| String::from_utf8_lossy(n).into_owned())
    }

    // -------------------------------------------------------------- handlers

    /// Calls `f` for each message of `type_id` from the senders `sender` selects.
    ///
    /// To answer from inside `f`, use [`Message::connection`]: a `Connection` clone captured
    /// by `f` would keep this connection alive as long as `f` is registered on it.
    pub fn register_handler(
        &self,
        type_id: TypeId,
        sender: SenderFilter,
        f: impl FnMut(&Message<'_>) + 'static,
    ) -> HandlerId {
        self.inner.handlers.add(Some(type_id), sender, f)
    }

    /// Calls `f` for every message of every type (loggers, monitors).
    pub fn register_any_type_handler(
        &self,
        sender: SenderFilter,
        f: impl FnMut(&Message<'_>) + 'static,
    ) -> HandlerId {
        self.inner.handlers.add(None, sender, f)
    }

    /// Removes a handler or callback registered on this connection (message handlers,
    /// [`on_event`](Self::on_event), [`on_notice`](Self::on_notice),
    /// [`on_peer_sender`](Self::on_peer_sender), [`on_state_change`](Self::on_state_change)).
    /// Returns whether it was found.
    pub fn remove_handler(&self, id: HandlerId) -> bool {
        self.inner.handlers.remove(id)
            || self.inner.notices.remove(id)
            || self.inner.peer_senders.remove(id)
            || self.inner.states.remove(id)
    }

    /// Calls `f` on a local connection event.
    pub fn on_event(&self, event: ConnectionEvent, mut f: impl FnMut() + 'static) -> HandlerId {
        self.register_handler(TypeId(event.type_id()), SenderFilter::Any, move |_| f())
    }

    /// Receives this connection's diagnostics. Without any handler they go to the default
    /// printer (see [`set_text_printer`]).
    pub fn on_notice(&self, f: impl FnMut(&Notice) + 'static) -> HandlerId {
        self.inner.notices.add(f)
    }

    /// Calls `f` with each sender name a peer offers, when it is first described.
    pub fn on_peer_sender(&self, f: impl FnMut(&str) + 'static) -> HandlerId {
        self.inner.peer_senders.add(f)
    }

    /// Calls `f` whenever [`state`](Self::state) changes, inside `mainloop()`.
    ///
    /// A client goes Connecting → Connected; when the server is lost (dropped, closed,
    /// silent), Connected → Reconnecting at once — that transition *is* the drop — and
    /// Reconnecting → Connected when it is back. A server goes Listening ↔ Connected as its
    /// first client arrives and its last leaves. The four raw events
    /// ([`on_event`](Self::on_event)) are still delivered beside these.
    pub fn on_state_change(&self, f: impl FnMut(&ConnectionState) + 'static) -> HandlerId {
        self.inner.states.add(f)
    }

    // -------------------------------------------------------------- sending

    /// Sends a message to every connected peer and to local handlers.
    ///
    /// `class_of_service` is a [`ServiceClass`] (or its raw `u32` mask): RELIABLE goes over
    /// TCP, anything else over UDP once the peer announced a UDP port. Allocation-free.
    ///
    /// Before the connection is up nothing is queued (as in C++, a message is sent only to
    /// peers that completed their handshake), and the result says so: a client that is
    /// [`Connecting`](ConnectionState::Connecting) or
    /// [`Reconnecting`](ConnectionState::Reconnecting) returns [`Error::NotConnected`] and
    /// sends nothing, not even to local handlers. Send requests again once
    /// [`on_state_change`](Self::on_state_change) reports `Connected`. A server with no
    /// client is not an error: its reports go to whoever is connected, which may be nobody.
    #[inline]
    pub fn pack_message(
        &self,
        time: TimeVal,
        type_id: TypeId,
        sender: SenderId,
        payload: &[u8],
        class_of_service: impl Into<ServiceClass>,
    ) -> Result<(), Error> {
        if payload.len() > MAX_PAYLOAD {
            return Err(Error::PayloadTooLarge(payload.len()));
        }
        {
            let mut core = self.inner.core.borrow_mut();
            let state = core.session.state();
            if matches!(
                state,
                ConnectionState::Connecting | ConnectionState::Reconnecting
            ) {
                return Err(Error::NotConnected(state));
            }
            let class = class_of_service.into().bits();
            let overflowed = core.session.pack(time, sender.0, type_id.0, payload, class);
            if overflowed {
                // Rare: a peer is not reading. Only now is the time needed (for the drop).
                core.session.drop_backlogged(self.inner.clock.now());
            }
        }
        if self.inner.handlers.wants_any(type_id, sender) {
            let msg = Message {
                time,
                sender_time: time,
                sender,
                type_id,
                payload,
                conn: self,
                from_peer: false,
                peer: None,
            };
            if self.inner.depth.get() > 0 {
                self.defer(&msg);
            } else {
                self.deliver(&msg);
            }
        }
        Ok(())
    }

    /// Sends a message to the one peer `to` only (see [`Message::reply`]); nothing reaches
    /// local handlers.
    pub(crate) fn pack_to_peer(
        &self,
        to: crate::proto::PeerId,
        time: TimeVal,
        type_id: TypeId,
        sender: SenderId,
        payload: &[u8],
        class_of_service: impl Into<ServiceClass>,
    ) -> Result<(), Error> {
        if payload.len() > MAX_PAYLOAD {
            return Err(Error::PayloadTooLarge(payload.len()));
        }
        let mut core = self.inner.core.borrow_mut();
        let class = class_of_service.into().bits();
        if core
            .session
            .pack_to(to, time, sender.0, type_id.0, payload, class)
        {
            core.session.drop_backlogged(self.inner.clock.now());
        }
        Ok(())
    }

    fn defer(&self, msg: &Message<'_>) {
        self.inner.any_deferred.set(true);
        let mut q = self.inner.deferred.borrow_mut();
        q.extend_from_slice(&msg.type_id.0.to_ne_bytes());
        q.extend_from_slice(&msg.sender.0.to_ne_bytes());
        q.extend_from_slice(&msg.time.sec.to_ne_bytes());
        q.extend_from_slice(&msg.time.usec.to_ne_bytes());
        q.extend_from_slice(&(msg.payload.len() as u32).to_ne_bytes());
        q.extend_from_slice(msg.payload);
    }

    /// Delivers one message to handlers, then (at the outermost level) everything handlers
    /// queued meanwhile.
    fn deliver(&self, msg: &Message<'_>) {
        let depth = self.inner.depth.get();
        self.inner.depth.set(depth + 1);
        self.inner.handlers.dispatch(msg);
        self.inner.depth.set(depth);
        if depth > 0 || !self.inner.any_deferred.get() {
            // Nested (the outer delivery drains the queue), or the common case: no handler
            // sent anything to local handlers.
            return;
        }
        let mut cursor = 0;
        loop {
            let mut scratch = std::mem::take(&mut *self.inner.deferred_scratch.borrow_mut());
            let next = {
                let q = self.inner.deferred.borrow();
                if cursor >= q.len() {
                    None
                } else {
                    let rd4 = |o: usize| [q[o], q[o + 1], q[o + 2], q[o + 3]];
                    let rd8 = |o: usize| {
                        let mut b = [0u8; 8];
                        b.copy_from_slice(&q[o..o + 8]);
                        b
                    };
                    let type_id = i32::from_ne_bytes(rd4(cursor));
                    let sender = i32::from_ne_bytes(rd4(cursor + 4));
                    let sec = i64::from_ne_bytes(rd8(cursor + 8));
                    let usec = i64::from_ne_bytes(rd8(cursor + 16));
                    let len = u32::from_ne_bytes(rd4(cursor + 24)) as usize;
                    let start = cursor + DEFERRED_HEADER;
                    scratch.clear();
                    scratch.extend_from_slice(&q[start..start + len]);
                    cursor = start + len;
                    Some((type_id, sender, TimeVal { sec, usec }))
                }
            };
            match next {
                Some((type_id, sender, time)) => {
                    self.inner.depth.set(1);
                    self.inner.handlers.dispatch(&Message {
                        time,
                        sender_time: time,
                        sender: SenderId(sender),
                        type_id: TypeId(type_id),
                        payload: &scratch,
                        conn: self,
                        from_peer: false,
                        peer: None,
                    });
                    self.inner.depth.set(0);
                    *self.inner.deferred_scratch.borrow_mut() = scratch;
                }
                None => {
                    *self.inner.deferred_scratch.borrow_mut() = scratch;
                    break;
                }
            }
        }
        self.inner.deferred.borrow_mut().clear();
        self.inner.any_deferred.set(false);
    }

    /// Hands a notice to the notice callbacks, or to the default printer when there are none.
    pub(crate) fn dispatch_notice(&self, n: crate::proto::Notice) {
        if self.inner.notices.is_empty() {
            printer::print_notice(&n);
        } else {
            self.inner.notices.call(&n);
        }
    }

    /// Prints text messages from `sender` with the default printer (once per connection and
    /// sender; see [`set_text_printer`]).
    pub(crate) fn attach_text_printer(&self, sender: SenderId, text_type: TypeId) {
        if self
            .inner
            .printed
            .borrow()
            .iter()
            .any(|(s, _)| *s == sender.0)
        {
            return;
        }
        let name = self.sender_name(sender).unwrap_or_default();
        let id = self.register_handler(text_type, SenderFilter::Only(sender), move |m| {
            if let Ok(t) = wire::payload::text::TextMessage::decode(m.payload) {
                let severity = wire::payload::text::TextSeverity::from_code(t.severity);
                let text = String::from_utf8_lossy(t.text);
                printer::print_text(&name, severity, t.level, &text);
            }
        });
        self.inner.printed.borrow_mut().push((sender.0, Some(id)));
    }

    /// Stops the default printer from showing text messages from `sender` on this connection
    /// (C++ `vrpn_System_TextPrinter.remove_object`), now and for remotes opened later.
    pub fn mute_text_printer(&self, sender: SenderId) {
        let mut printed = self.inner.printed.borrow_mut();
        match printed.iter_mut().find(|(s, _)| *s == sender.0) {
            Some((_, handler)) => {
                if let Some(id) = handler.take() {
                    self.inner.handlers.remove(id);
                }
            }
            None => printed.push((sender.0, None)),
        }
    }

    // -------------------------------------------------------------- waiting

    /// When this connection next has time-driven work (a connection attempt, a greeting
    /// time-out, a liveness ping), if ever. A loop that waits on several connections sleeps
    /// until the earliest of theirs.
    pub fn poll_timeout(&self) -> Option<Instant> {
        if self.inner.left_over.get() || self.inner.core.borrow().session.input_left_over() {
            // The last pass left messages buffered: the next is due now.
            return Some(Instant::now());
        }
        let session = self.inner.core.borrow().session.poll_timeout();
        let pings = self.liveness_deadline();
        match (session, pings) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Blocks until a socket of this connection is ready or `timeout` passes (or its next
    /// time-driven work is due). Dispatches nothing: call [`mainloop`](Self::mainloop) next.
    /// Returns whether a socket became ready.
    pub fn wait(&self, timeout: Duration) -> Result<bool, Error> {
        self.wait_until(None, timeout)
    }

    /// Blocks until a socket is ready, `deadline` or this connection's own next deadline
    /// passes (woken precisely, not on a millisecond grid), or `max` elapses. Dispatches
    /// nothing: call [`mainloop`](Self::mainloop) next. This is how a server sleeps until its
    /// next device report without spinning a core.
    pub fn wait_until(&self, deadline: Option<Instant>, max: Duration) -> Result<bool, Error> {
        let w = self.prepare_wait(deadline);
        match self.reactor() {
            // One `epoll_wait` that also takes the events (the reactor's timer wakes it at the
            // deadline); a `Waiter` would poll the descriptor and then take them.
            Some(r) if !w.ready() => r
                .wait(w.deadline(), max)
                .map_err(|e| Error::io("polling sockets", e)),
            Some(r) => r.poll_now().map_err(|e| Error::io("polling sockets", e)),
            None => {
                w.block(max).map_err(|e| Error::io("waiting", e))?;
                Ok(false)
            }
        }
    }

    /// True once since the last call if data arrived on any socket of this connection's
    /// reactor (for busy-poll windows).
    pub fn take_activity(&self) -> bool {
        self.reactor().is_some_and(|r| r.take_activity())
    }

    // -------------------------------------------------------------- state

    /// What the connection is doing now.
    pub fn state(&self) -> ConnectionState {
        self.inner.core.borrow().session.state()
    }

    /// True when at least one peer is connected (always for loopback and replay).
    pub fn connected(&self) -> bool {
        self.state() == ConnectionState::Connected
    }

    /// Number of peers that completed the handshake.
    pub fn connected_peers(&self) -> usize {
        self.inner.core.borrow().session.connected_peers()
    }

    /// Address and VRPN version of each connected peer.
    pub fn peers(&self) -> Vec<(String, Option<String>)> {
        self.inner.core.borrow().session.peer_descriptions()
    }

    /// The port a server listens on.
    pub fn local_port(&self) -> Option<u16> {
        self.inner.core.borrow().shell.server_port()
    }

    /// Sender names the connected peers offer: the devices of a server (for a client), the
    /// remotes of a client (for a server). Names this side described to a peer and the peer
    /// echoed back are not included.
    pub fn peer_senders(&self) -> Vec<String> {
        self.inner.core.borrow().session.peer_sender_names()
    }

    /// Reliable bytes queued for peers and not yet written.
    pub fn pending_output(&self) -> usize {
        self.inner.core.borrow().session.pending_output()
    }

    /// Sends a text message (`vrpn_Base text_message`) from `sender`.
    pub fn send_text(
        &self,
        sender: SenderId,
        severity: crate::wire::payload::text::TextSeverity,
        level: u32,
        text: &str,
    ) -> Result<(), Error> {
        use wire::payload::text::{TextMessage, TEXT_MESSAGE, TEXT_PAYLOAD_LEN};
        let text_type = self.register_type(TEXT_MESSAGE)?;
        let mut buf = [0u8; TEXT_PAYLOAD_LEN];
        let n = TextMessage::new(severity.code(), level, text.as_bytes())
            .map_err(|_| Error::PayloadTooLarge(text.len() + 9))?
            .encode(&mut buf);
        let now = self.now();
        self.pack_message(
            now.wall,
            text_type,
            sender,
            &buf[..n],
            wire::class::RELIABLE,
        )
    }

    /// A handle that does not keep the connection alive.
    pub fn downgrade(&self) -> WeakConnection {
        WeakConnection {
            inner: Rc::downgrade(&self.inner),
        }
    }
}

/// A non-owning handle, for handlers stored in the connection they refer to (no `Rc` cycle).
#[derive(Clone)]
pub struct WeakConnection {
    inner: Weak<Inner>,
}

impl WeakConnection {
    /// The connection, if it still exists.
    pub fn upgrade(&self) -> Option<Connection> {
        self.inner.upgrade().map(|inner| Connection { inner })
    }
}

impl Drop for Inner {
    fn drop(&mut self) {
        let core = self.core.get_mut();
        let _ = core.session.close_logs(crate::net::clock());
    }
}
