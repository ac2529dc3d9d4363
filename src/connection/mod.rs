//! The connection: local names, handlers, peers, and the `mainloop()` that moves messages.
//!
//! A [`Connection`] is a cheap handle (`Rc`) shared by every device object that uses it. Three
//! kinds exist: a **server** listening on one UDP+TCP port for many peers, a **client** that
//! reaches one server (and reconnects forever), and the **loopback** connection of this process,
//! which has no sockets at all. All three deliver every packed message to local handlers
//! directly, which is how an in-process remote hears an in-process server.
//!
//! Callbacks run only inside [`Connection::mainloop`] or inside a call that sends a message.
//! A callback may itself send, register, or read state: messages a callback sends to local
//! handlers are queued and delivered right after it returns, so no handler is ever re-entered.

pub(crate) mod endpoint;
pub mod names;

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::net::Ipv4Addr;
use std::rc::{Rc, Weak};
use std::time::{Duration, Instant};

use crate::dispatch::{
    CallbackList, HandlerId, HandlerTable, Message, SenderFilter, SenderId, TypeId,
};
use crate::error::Error;
use crate::name::{DeviceName, Location};
use crate::net::{Core, Delivery};
use crate::time::TimeVal;
use crate::wire;

pub(crate) use endpoint::Backlogged;

/// Largest payload a VRPN peer can receive over TCP (64000-byte buffer less the header).
pub const MAX_PAYLOAD: usize = wire::MAX_TCP_MESSAGE - wire::HEADER_LEN;

/// What a connection is doing now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConnectionState {
    /// Client: trying to reach the server for the first time.
    Connecting,
    /// Client: connected to the server. Server: at least one peer connected. Loopback: always.
    Connected,
    /// Client: was connected, lost the server, and keeps trying.
    Reconnecting,
    /// Server: listening, no peer connected.
    Listening,
}

/// Local connection events (sent as messages of the four `VRPN_Connection_*` types).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConnectionEvent {
    /// The first peer completed its handshake.
    GotFirstConnection,
    /// A peer completed its handshake.
    GotConnection,
    /// A connected peer was lost.
    DroppedConnection,
    /// The last connected peer was lost.
    DroppedLastConnection,
}

impl ConnectionEvent {
    fn type_id(self) -> TypeId {
        TypeId(match self {
            ConnectionEvent::GotFirstConnection => 0,
            ConnectionEvent::GotConnection => 1,
            ConnectionEvent::DroppedConnection => 2,
            ConnectionEvent::DroppedLastConnection => 3,
        })
    }
}

/// How serious a [`Notice`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// For the curious (a peer with another minor version, a peer that left).
    Info,
    /// Something a user may need to act on (no answer from a server, a dropped peer).
    Warning,
    /// Something failed.
    Error,
}

/// A diagnostic from the connection, in words a user can act on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Notice {
    /// How serious it is.
    pub severity: Severity,
    /// What happened and what to do.
    pub text: String,
}

/// Limits and timings of a connection. The defaults suit a lab network.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Reliable output that may wait for one peer before the peer is dropped as not reading.
    pub max_pending_output: usize,
    /// Peers a server serves at once (C++: 255).
    pub max_connections: usize,
    /// Client: time between connection attempts (C++ 07.38 uses 2 s; the paper says 1 s).
    pub retry_interval: Duration,
    /// Client: when to explain that the server does not answer.
    pub no_answer_warning: Duration,
    /// Time allowed for a TCP connect (server call-back or TCP-only client).
    pub connect_timeout: Duration,
    /// Messages taken from one peer before others get their turn in a mainloop pass.
    pub max_messages_per_peer_per_loop: usize,
    /// Largest message payload accepted from a peer; a peer that sends a larger one is dropped
    /// with a notice. Default: the C++ receive limit (64008 padded bytes).
    pub max_message_payload: usize,
    /// Sender names, and separately type names, one peer may describe (C++: 2000 each); a peer
    /// describing more is dropped with a notice.
    pub max_names_per_peer: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_pending_output: 4 * 1024 * 1024,
            max_connections: 255,
            retry_interval: Duration::from_secs(1),
            no_answer_warning: Duration::from_secs(3),
            connect_timeout: Duration::from_secs(5),
            max_messages_per_peer_per_loop: 100_000,
            max_message_payload: wire::MAX_TCP_PADDED_PAYLOAD,
            max_names_per_peer: wire::MAX_IDS,
        }
    }
}

struct Inner {
    core: RefCell<Core>,
    handlers: HandlerTable,
    dispatching: Cell<bool>,
    /// Local deliveries requested while a handler runs: encoded messages, delivered in order.
    deferred: RefCell<Vec<u8>>,
    deferred_scratch: RefCell<Vec<u8>>,
    notices: CallbackList<Notice>,
    peer_senders: CallbackList<str>,
}

/// A VRPN connection handle. Clones share the connection.
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

impl Connection {
    fn from_core(core: Core) -> Connection {
        Connection {
            inner: Rc::new(Inner {
                core: RefCell::new(core),
                handlers: HandlerTable::default(),
                dispatching: Cell::new(false),
                deferred: RefCell::new(Vec::with_capacity(64 * 1024)),
                deferred_scratch: RefCell::new(Vec::with_capacity(64 * 1024)),
                notices: CallbackList::default(),
                peer_senders: CallbackList::default(),
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
        match &name.location {
            Location::Loopback => Ok(Connection::loopback()),
            Location::File { path } => {
                Self::shared(&name.location_text, || Connection::replay_file(path))
            }
            Location::Net {
                host,
                port,
                tcp_only,
            } => Self::shared(&name.location_text, || {
                Connection::client(host, *port, *tcp_only, Limits::default())
            }),
        }
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
        Ok(Connection::from_core(Core::file(path, Limits::default())?))
    }

    /// A new, unshared client connection to `host:port`.
    pub fn client(
        host: &str,
        port: u16,
        tcp_only: bool,
        limits: Limits,
    ) -> Result<Connection, Error> {
        Ok(Connection::from_core(Core::client(
            host, port, tcp_only, limits,
        )?))
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
        Ok(Connection::from_core(Core::server(nic, port, limits)?))
    }

    /// The in-process connection of this thread (`loopback:`): no sockets, always connected.
    pub fn loopback() -> Connection {
        LOOPBACK.with(|l| {
            if let Some(inner) = l.borrow().upgrade() {
                return Connection { inner };
            }
            let conn = Connection::from_core(Core::loopback(Limits::default()));
            *l.borrow_mut() = Rc::downgrade(&conn.inner);
            conn
        })
    }

    /// A new private in-process connection, not shared through `loopback:`.
    pub fn new_loopback() -> Connection {
        Connection::from_core(Core::loopback(Limits::default()))
    }

    /// A number identifying this connection while it exists.
    pub fn identity(&self) -> usize {
        Rc::as_ptr(&self.inner) as *const () as usize
    }

    /// True when both handles are the same connection.
    pub fn same_as(&self, other: &Connection) -> bool {
        Rc::ptr_eq(&self.inner, &other.inner)
    }

    // -------------------------------------------------------------- names

    /// Registers (or finds) a sender name and describes it to connected peers.
    pub fn register_sender(&self, name: &str) -> Result<SenderId, Error> {
        let mut core = self.inner.core.borrow_mut();
        let (id, new) = core.names.senders.register(name)?;
        if new {
            core.describe_to_all(true, id);
        }
        Ok(SenderId(id))
    }

    /// Registers (or finds) a message type name and describes it to connected peers.
    pub fn register_type(&self, name: &str) -> Result<TypeId, Error> {
        let mut core = self.inner.core.borrow_mut();
        let (id, new) = core.names.types.register(name)?;
        if new {
            core.describe_to_all(false, id);
        }
        Ok(TypeId(id))
    }

    /// The name of a local sender id.
    pub fn sender_name(&self, id: SenderId) -> Option<String> {
        self.inner
            .core
            .borrow()
            .names
            .senders
            .name(id.0)
            .map(str::to_string)
    }

    /// The name of a local type id.
    pub fn type_name(&self, id: TypeId) -> Option<String> {
        self.inner
            .core
            .borrow()
            .names
            .types
            .name(id.0)
            .map(str::to_string)
    }

    // -------------------------------------------------------------- handlers

    /// Calls `f` for each message of `type_id` from the senders `sender` selects.
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

    /// Removes a handler.
    pub fn remove_handler(&self, id: HandlerId) -> bool {
        self.inner.handlers.remove(id)
    }

    /// Calls `f` on a local connection event.
    pub fn on_event(&self, event: ConnectionEvent, mut f: impl FnMut() + 'static) -> HandlerId {
        self.register_handler(event.type_id(), SenderFilter::Any, move |_| f())
    }

    /// Receives this connection's diagnostics. Without any handler they go to stderr.
    pub fn on_notice(&self, f: impl FnMut(&Notice) + 'static) -> HandlerId {
        self.inner.notices.add(f)
    }

    /// Calls `f` with each sender name a peer describes for the first time.
    pub fn on_peer_sender(&self, f: impl FnMut(&str) + 'static) -> HandlerId {
        self.inner.peer_senders.add(f)
    }

    // -------------------------------------------------------------- sending

    /// Sends a message to every connected peer and to local handlers.
    ///
    /// `class_of_service` is a mask of [`wire::class`] bits: RELIABLE goes over TCP, anything
    /// else over UDP once the peer announced a UDP port. Allocation-free.
    pub fn pack_message(
        &self,
        time: TimeVal,
        type_id: TypeId,
        sender: SenderId,
        payload: &[u8],
        class_of_service: u32,
    ) -> Result<(), Error> {
        if payload.len() > MAX_PAYLOAD {
            return Err(Error::PayloadTooLarge(payload.len()));
        }
        self.inner.core.borrow_mut().pack_to_peers(
            time,
            sender.0,
            type_id.0,
            payload,
            class_of_service,
        );
        if self.inner.handlers.has_handlers(type_id) {
            let msg = Message {
                time,
                sender,
                type_id,
                payload,
            };
            if self.inner.dispatching.get() {
                self.defer(&msg);
            } else {
                self.deliver(&msg);
            }
        }
        Ok(())
    }

    fn defer(&self, msg: &Message<'_>) {
        let mut q = self.inner.deferred.borrow_mut();
        q.extend_from_slice(&msg.type_id.0.to_ne_bytes());
        q.extend_from_slice(&msg.sender.0.to_ne_bytes());
        q.extend_from_slice(&msg.time.sec.to_ne_bytes());
        q.extend_from_slice(&msg.time.usec.to_ne_bytes());
        q.extend_from_slice(&(msg.payload.len() as u32).to_ne_bytes());
        q.extend_from_slice(msg.payload);
    }

    /// Delivers one message to handlers, then everything handlers queued meanwhile.
    fn deliver(&self, msg: &Message<'_>) {
        self.inner.dispatching.set(true);
        self.inner.handlers.dispatch(msg);
        if self.inner.deferred.borrow().is_empty() {
            // The common case: no handler sent anything to local handlers.
            self.inner.dispatching.set(false);
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
                    self.inner.handlers.dispatch(&Message {
                        time,
                        sender: SenderId(sender),
                        type_id: TypeId(type_id),
                        payload: &scratch,
                    });
                    *self.inner.deferred_scratch.borrow_mut() = scratch;
                }
                None => {
                    *self.inner.deferred_scratch.borrow_mut() = scratch;
                    break;
                }
            }
        }
        self.inner.deferred.borrow_mut().clear();
        self.inner.dispatching.set(false);
    }

    // -------------------------------------------------------------- the loop

    /// Does all pending work without blocking: accepts and (re)connects peers, reads and
    /// dispatches every message that arrived, and writes queued output.
    ///
    /// Called from inside a callback it returns at once (the outer call does the work).
    pub fn mainloop(&self) -> Result<(), Error> {
        if self.inner.dispatching.get() {
            return Ok(());
        }
        {
            let mut core = self.inner.core.borrow_mut();
            core.poll_io(Some(Duration::ZERO))?;
            core.service_setup();
            core.begin_pass();
        }
        self.pump();
        let mut core = self.inner.core.borrow_mut();
        core.flush();
        core.flush_logs_some(LOG_FLUSH_PER_PASS);
        Ok(())
    }

    // -------------------------------------------------------------- logging

    /// Logs every message this side receives to a new file at `path` (C++ format; an
    /// existing file is never overwritten). A client logs into one file across reconnects; a
    /// server opens one file per client, `in.vrpn` → `in-1.vrpn`, `in-2.vrpn`, … (`-li`).
    pub fn log_incoming(&self, path: &str) -> Result<(), Error> {
        self.inner.core.borrow_mut().log_incoming(path)
    }

    /// Logs every message this side sends (descriptions included) to a new file at `path`
    /// (`-lo`). A server logs from now on, clients connected or not.
    pub fn log_outgoing(&self, path: &str) -> Result<(), Error> {
        self.inner.core.borrow_mut().log_outgoing(path)
    }

    /// Writes all buffered log data now (`vrpn_server -flush` calls it every pass). Otherwise
    /// each `mainloop()` writes a bounded amount and the rest goes out when the connection
    /// closes.
    pub fn flush_logs(&self) -> Result<(), Error> {
        self.inner.core.borrow_mut().flush_logs_all()
    }

    /// Ends logging: writes the closing DISCONNECT entry of an outgoing log and flushes.
    pub fn close_logs(&self) -> Result<(), Error> {
        self.inner.core.borrow_mut().close_logs()
    }

    /// Replay controls, when this connection replays a log file.
    pub fn replay(&self) -> Option<ReplayControl<'_>> {
        self.inner
            .core
            .borrow_mut()
            .replay_mut()
            .is_some()
            .then_some(ReplayControl { conn: self })
    }

    /// True when this connection replays a log file.
    pub fn is_replay(&self) -> bool {
        self.inner.core.borrow_mut().replay_mut().is_some()
    }

    fn with_replay<T>(&self, f: impl FnOnce(&mut crate::log::replay::Replay) -> T) -> T {
        let mut core = self.inner.core.borrow_mut();
        f(core.replay_mut().expect("a replay connection"))
    }

    /// Blocks until a socket of this connection is ready or `timeout` passes (or a client's
    /// next connection attempt is due). Dispatches nothing: call [`mainloop`](Self::mainloop)
    /// next. Returns whether a socket became ready.
    pub fn wait(&self, timeout: Duration) -> Result<bool, Error> {
        let timeout = {
            let core = self.inner.core.borrow();
            match core.next_deadline() {
                Some(d) => timeout.min(d.saturating_duration_since(Instant::now())),
                None => timeout,
            }
        };
        self.inner.core.borrow_mut().poll_io(Some(timeout))
    }

    /// Blocks until a socket is ready, `deadline` passes (woken precisely, not on a
    /// millisecond grid), or `max` elapses. Dispatches nothing: call
    /// [`mainloop`](Self::mainloop) next. This is how a server sleeps until its next device
    /// report without spinning a core.
    pub fn wait_until(&self, deadline: Option<Instant>, max: Duration) -> Result<bool, Error> {
        let mut core = self.inner.core.borrow_mut();
        let deadline = match (deadline, core.next_deadline()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        core.wait_until(deadline, max)
    }

    /// True once since the last call if data arrived on any socket (for busy-poll windows).
    pub fn take_activity(&self) -> bool {
        std::mem::take(&mut self.inner.core.borrow_mut().activity)
    }

    fn pump(&self) {
        loop {
            let next = self.inner.core.borrow_mut().next_delivery();
            let Some(d) = next else {
                break;
            };
            match d {
                Delivery::Message {
                    time,
                    sender,
                    type_id,
                    len,
                } => {
                    let scratch = std::mem::take(&mut self.inner.core.borrow_mut().scratch);
                    self.deliver(&Message {
                        time,
                        sender: SenderId(sender),
                        type_id: TypeId(type_id),
                        payload: &scratch[..len],
                    });
                    self.inner.core.borrow_mut().scratch = scratch;
                }
                Delivery::Event(ev) => {
                    self.deliver(&Message {
                        time: TimeVal::now(),
                        sender: SenderId(0),
                        type_id: ev.type_id(),
                        payload: &[],
                    });
                }
                Delivery::Notice(n) => {
                    if self.inner.notices.is_empty() {
                        eprintln!("vrpn: {}", n.text);
                    } else {
                        self.inner.notices.call(&n);
                    }
                }
                Delivery::PeerSender(local) => {
                    let name = self.sender_name(SenderId(local));
                    if let Some(name) = name {
                        self.inner.peer_senders.call(name.as_str());
                    }
                }
            }
        }
    }

    // -------------------------------------------------------------- state

    /// What the connection is doing now.
    pub fn state(&self) -> ConnectionState {
        self.inner.core.borrow().state()
    }

    /// True when at least one peer is connected (always for loopback).
    pub fn connected(&self) -> bool {
        self.state() == ConnectionState::Connected
    }

    /// Number of peers that completed the handshake.
    pub fn connected_peers(&self) -> usize {
        self.inner.core.borrow().connected
    }

    /// Address and VRPN version of each connected peer.
    pub fn peers(&self) -> Vec<(String, Option<String>)> {
        self.inner.core.borrow().peer_descriptions()
    }

    /// The port a server listens on.
    pub fn local_port(&self) -> Option<u16> {
        self.inner.core.borrow().server_port()
    }

    /// Sender names the connected peers have described (device names, for a server).
    pub fn peer_senders(&self) -> Vec<String> {
        self.inner.core.borrow().peer_sender_names()
    }

    /// Reliable bytes queued for peers and not yet written.
    pub fn pending_output(&self) -> usize {
        self.inner.core.borrow().pending_output()
    }

    /// Sends a text message (`vrpn_Base text_message`) from `sender`.
    pub fn send_text(
        &self,
        sender: SenderId,
        severity: crate::devices::text::TextSeverity,
        level: u32,
        text: &str,
    ) -> Result<(), Error> {
        crate::devices::base::send_text(self, sender, severity, level, text)
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

impl Connection {
    /// A handle that does not keep the connection alive.
    pub fn downgrade(&self) -> WeakConnection {
        WeakConnection {
            inner: Rc::downgrade(&self.inner),
        }
    }
}

/// Controls of a log replay (C++ `vrpn_File_Connection`), borrowed from its connection.
pub struct ReplayControl<'a> {
    conn: &'a Connection,
}

impl ReplayControl<'_> {
    /// Sets the speed: 1.0 real time, 0 paused, 10 ten times faster, `f64::INFINITY` as
    /// fast as possible.
    pub fn set_rate(&self, rate: f64) {
        self.conn.with_replay(|r| r.set_rate(rate));
    }

    /// The speed factor.
    pub fn rate(&self) -> f64 {
        self.conn.with_replay(|r| r.rate())
    }

    /// Back to the start (handlers see a dropped-connection event, as in C++).
    pub fn reset(&self) {
        self.conn.with_replay(|r| r.reset());
        self.conn.pump();
    }

    /// Plays, now, every message up to `secs` after the first one (rewinding first when that
    /// is behind the current position).
    pub fn play_to_time(&self, secs: f64) {
        self.conn.with_replay(|r| r.play_to_time(secs));
        self.conn.pump();
    }

    /// Plays the next message now, whatever its time. Returns false at the end of the file.
    pub fn play_one(&self) -> bool {
        if self.eof() {
            return false;
        }
        self.conn.with_replay(|r| r.play_one());
        self.conn.pump();
        true
    }

    /// Moves to `secs` after the first message without delivering the messages in between
    /// (descriptions on the way are still learned). Returns whether that time is in the log.
    pub fn jump_to_time(&self, secs: f64) -> bool {
        let inside = self.conn.with_replay(|r| r.jump_to_time(secs));
        self.conn.skip_due();
        inside
    }

    /// True when every message has been played.
    pub fn eof(&self) -> bool {
        self.conn.with_replay(|r| r.eof())
    }

    /// Where the replay stands, on the log's own clock.
    pub fn file_time(&self) -> TimeVal {
        self.conn.with_replay(|r| r.file_time())
    }

    /// Seconds since the first message.
    pub fn elapsed(&self) -> f64 {
        self.conn.with_replay(|r| r.elapsed())
    }

    /// Time of the first user message.
    pub fn first_time(&self) -> Option<TimeVal> {
        self.conn.with_replay(|r| r.first_time())
    }

    /// Time of the last user message.
    pub fn last_time(&self) -> Option<TimeVal> {
        self.conn.with_replay(|r| r.last_time())
    }

    /// Seconds between the first and last user messages.
    pub fn length_secs(&self) -> f64 {
        self.conn.with_replay(|r| r.length_secs())
    }
}

impl Connection {
    /// Consumes due replay entries without delivering user messages (jump).
    fn skip_due(&self) {
        loop {
            let d = self.inner.core.borrow_mut().next_delivery();
            match d {
                None => break,
                Some(Delivery::Message { .. }) => {}
                Some(Delivery::Notice(n)) => self.inner.notices.call(&n),
                Some(_) => {}
            }
        }
    }
}
