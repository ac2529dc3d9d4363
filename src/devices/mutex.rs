//! Mutex (`vrpn_Mutex`): one lock shared by every client of a server. [`MutexServer`] keeps
//! the lock, [`MutexRemote`] asks for it, holds it and gives it back; every remote hears who
//! has it. [`PeerMutex`](super::peer_mutex::PeerMutex) is the serverless variant.
//!
//! The exchange, as in C++: a remote first asks for an index (sending its IPv4 address and
//! process id); the server answers every remote with the index it assigned and the request
//! echoed, and the remote whose address and process id match takes it. A request carries the
//! index; the server grants it if the lock is free, otherwise denies it, and broadcasts the
//! grant so that the other remotes learn the lock is held. A release frees the lock and the
//! server tells everyone. When the last client leaves, the server frees the lock.
//!
//! A mutex is not a `vrpn_BaseClass`: no text, ping or pong.

use std::cell::Cell;
use std::net::{IpAddr, ToSocketAddrs};
use std::rc::Rc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

use crate::connection::{Connection, ConnectionEvent};
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::name::DeviceName;
use crate::wire::class;
use crate::wire::payload::mutex::{self as codec, Index, IndexRequest, Initialize};

/// Ids of the seven mutex types and the mutex's sender on one connection.
#[derive(Clone, Copy, Debug)]
pub struct MutexIds {
    /// The mutex's sender (its name).
    pub sender: SenderId,
    /// Index request.
    pub request_index: TypeId,
    /// Lock request.
    pub request_mutex: TypeId,
    /// Release.
    pub release: TypeId,
    /// Release notification.
    pub release_notification: TypeId,
    /// Grant.
    pub grant: TypeId,
    /// Deny.
    pub deny: TypeId,
    /// Index assignment.
    pub initialize: TypeId,
}

impl MutexIds {
    /// Registers the sender `name` and the seven types in C++ order.
    pub fn register(conn: &Connection, name: &str) -> Result<MutexIds, Error> {
        let sender = conn.register_sender(name)?;
        let mut ids = [TypeId(0); 7];
        for (slot, t) in ids.iter_mut().zip(codec::TYPE_NAMES) {
            *slot = conn.register_type(t)?;
        }
        Ok(MutexIds {
            sender,
            request_index: ids[0],
            request_mutex: ids[1],
            release: ids[2],
            release_notification: ids[3],
            grant: ids[4],
            deny: ids[5],
            initialize: ids[6],
        })
    }
}

/// Where the lock is, as one participant sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MutexState {
    /// Nobody holds it.
    Available,
    /// This participant asked and waits for the answer.
    Requesting,
    /// This participant holds it.
    Ours,
    /// Someone else holds it.
    HeldRemotely,
}

/// The four callback lists of a mutex participant (C++ `add*Callback`).
#[derive(Default)]
pub(crate) struct MutexCallbacks {
    pub(crate) granted: CallbackList<()>,
    pub(crate) denied: CallbackList<()>,
    pub(crate) taken: CallbackList<()>,
    pub(crate) released: CallbackList<()>,
}

impl MutexCallbacks {
    pub(crate) fn remove(&self, id: HandlerId) -> bool {
        self.granted.remove(id)
            || self.denied.remove(id)
            || self.taken.remove(id)
            || self.released.remove(id)
    }
}

/// The IPv4 address C++ identifies this host by: the first address its name resolves to, as
/// a host-order number (0 if it resolves to none). Resolved at set-up only.
pub(crate) fn host_ip() -> u32 {
    let Ok(name) = std::fs::read_to_string("/proc/sys/kernel/hostname") else {
        return 0;
    };
    (name.trim(), 0)
        .to_socket_addrs()
        .ok()
        .and_then(|mut a| {
            a.find_map(|s| match s.ip() {
                IpAddr::V4(v4) => Some(u32::from(v4)),
                IpAddr::V6(_) => None,
            })
        })
        .unwrap_or(0)
}

fn pack(conn: &Connection, ids: &MutexIds, type_id: TypeId, payload: &[u8]) -> Result<(), Error> {
    conn.pack_message(
        conn.now().wall,
        type_id,
        ids.sender,
        payload,
        class::RELIABLE,
    )
}

fn pack_index(conn: &Connection, ids: &MutexIds, type_id: TypeId, index: i32) -> Result<(), Error> {
    let mut buf = [0u8; Index::LEN];
    Index { index }.encode(&mut buf);
    pack(conn, ids, type_id, &buf)
}

struct ServerState {
    held: Cell<bool>,
    /// The index the holder asked with (the server does not otherwise know who holds it).
    holder: Cell<Option<i32>>,
    next_index: Cell<i32>,
}

/// The server half: keeps the lock (C++ `vrpn_Mutex_Server`).
pub struct MutexServer {
    ids: MutexIds,
    state: Rc<ServerState>,
}

impl MutexServer {
    /// Serves the mutex `name` on `conn`.
    pub fn new(name: &str, conn: &Connection) -> Result<MutexServer, Error> {
        let ids = MutexIds::register(conn, name)?;
        let state = Rc::new(ServerState {
            held: Cell::new(false),
            holder: Cell::new(None),
            next_index: Cell::new(0),
        });
        let only = SenderFilter::Only(ids.sender);
        let s = state.clone();
        conn.register_handler(ids.request_index, only, move |m| {
            // Echo whatever identifies the remote, then its index.
            let mut buf = [0u8; 256 + 4];
            let n = m.payload.len();
            if n > 256 {
                return;
            }
            buf[..n].copy_from_slice(m.payload);
            let index = s.next_index.get();
            buf[n..n + 4].copy_from_slice(&index.to_be_bytes());
            s.next_index.set(index.wrapping_add(1));
            let _ = pack(m.connection(), &ids, ids.initialize, &buf[..n + 4]);
        });
        let s = state.clone();
        conn.register_handler(ids.request_mutex, only, move |m| {
            let Ok(r) = Index::decode(m.payload) else {
                return;
            };
            if s.held.get() {
                let _ = pack_index(m.connection(), &ids, ids.deny, r.index);
            } else {
                s.held.set(true);
                s.holder.set(Some(r.index));
                let _ = pack_index(m.connection(), &ids, ids.grant, r.index);
            }
        });
        let s = state.clone();
        conn.register_handler(ids.release, only, move |m| {
            s.held.set(false);
            s.holder.set(None);
            let _ = pack(m.connection(), &ids, ids.release_notification, &[]);
        });
        let s = state.clone();
        conn.on_event(ConnectionEvent::DroppedLastConnection, move || {
            s.held.set(false);
            s.holder.set(None);
        });
        Ok(MutexServer { ids, state })
    }

    /// True while a remote holds the lock.
    pub fn is_held(&self) -> bool {
        self.state.held.get()
    }

    /// The index of the remote holding the lock.
    pub fn holder(&self) -> Option<i32> {
        self.state.holder.get()
    }

    /// The mutex's sender id.
    pub fn sender(&self) -> SenderId {
        self.ids.sender
    }
}

struct RemoteState {
    ids: MutexIds,
    state: Cell<MutexState>,
    index: Cell<i32>,
    identity: IndexRequest,
    request_before_init: Cell<bool>,
    /// A request that timed out: a grant arriving for it is given back at once.
    abandoned: Cell<bool>,
    timeout: Cell<Option<Duration>>,
    deadline: Cell<Option<Instant>>,
    callbacks: MutexCallbacks,
}

impl RemoteState {
    fn request_index(&self, conn: &Connection) {
        let mut buf = [0u8; IndexRequest::LEN];
        self.identity.encode(&mut buf);
        let _ = pack(conn, &self.ids, self.ids.request_index, &buf);
    }

    fn request(&self, conn: &Connection) -> Result<(), Error> {
        if self.state.get() != MutexState::Available {
            self.callbacks.denied.call(&());
            return Ok(());
        }
        if self.index.get() == -1 {
            self.request_before_init.set(true);
            return Ok(());
        }
        pack_index(conn, &self.ids, self.ids.request_mutex, self.index.get())?;
        self.state.set(MutexState::Requesting);
        self.abandoned.set(false);
        self.deadline
            .set(self.timeout.get().map(|t| conn.now().mono + t));
        Ok(())
    }

    fn release(&self, conn: &Connection) -> Result<(), Error> {
        if self.state.get() != MutexState::Ours {
            return Ok(());
        }
        self.state.set(MutexState::Available);
        let sent = pack(conn, &self.ids, self.ids.release, &[]);
        self.callbacks.released.call(&());
        sent
    }
}

/// Process-wide count of mutex remotes, to tell apart several in one process (C++ gives
/// them all the same identity, and the first index answer goes to all of them).
static REMOTES: AtomicU32 = AtomicU32::new(0);

/// The client half: asks for the lock, holds it, gives it back (C++ `vrpn_Mutex_Remote`).
///
/// Callbacks: [`on_granted`](Self::on_granted) (this remote got the lock),
/// [`on_denied`](Self::on_denied) (it did not, or asked while the lock was not available),
/// [`on_taken`](Self::on_taken) (anyone got the lock), [`on_released`](Self::on_released)
/// (the lock became available).
///
/// Beyond C++: [`set_request_timeout`](Self::set_request_timeout) turns a request left
/// unanswered into a denial (a grant arriving later is given back at once), and a dropped
/// connection makes the lock available and the index unknown (a new index is asked for on
/// reconnection, since the server may have restarted and reassigned it).
pub struct MutexRemote {
    conn: Connection,
    state: Rc<RemoteState>,
    handlers: Vec<HandlerId>,
}

impl Drop for MutexRemote {
    fn drop(&mut self) {
        // As C++: never leave the lock held by a remote that is gone.
        let _ = self.state.release(&self.conn);
        for h in self.handlers.drain(..) {
            self.conn.remove_handler(h);
        }
    }
}

impl MutexRemote {
    /// Opens `Mutex@location`.
    pub fn new(name: &str) -> Result<MutexRemote, Error> {
        let parsed = DeviceName::parse_remote(name)?;
        let conn = Connection::open_location(&parsed)?;
        Self::on_connection(&parsed.device, &conn)
    }

    /// A remote of the mutex `name` on an existing connection.
    pub fn on_connection(name: &str, conn: &Connection) -> Result<MutexRemote, Error> {
        let ids = MutexIds::register(conn, name)?;
        let serial = REMOTES.fetch_add(1, Ordering::Relaxed) as i32;
        let identity = IndexRequest {
            ip: host_ip(),
            pid: (std::process::id() as i32) ^ (serial << 22),
        };
        let state = Rc::new(RemoteState {
            ids,
            state: Cell::new(MutexState::Available),
            index: Cell::new(-1),
            identity,
            request_before_init: Cell::new(false),
            abandoned: Cell::new(false),
            timeout: Cell::new(None),
            deadline: Cell::new(None),
            callbacks: MutexCallbacks::default(),
        });
        let only = SenderFilter::Only(ids.sender);
        let mut handlers = Vec::new();
        let s = state.clone();
        handlers.push(conn.register_handler(ids.grant, only, move |m| {
            let Ok(g) = Index::decode(m.payload) else {
                return;
            };
            if g.index != s.index.get() {
                s.state.set(MutexState::HeldRemotely);
                s.callbacks.taken.call(&());
                return;
            }
            s.deadline.set(None);
            if s.abandoned.replace(false) {
                // Timed out meanwhile: the application was told no; give it back.
                s.state.set(MutexState::Available);
                let _ = pack(m.connection(), &s.ids, s.ids.release, &[]);
                return;
            }
            s.state.set(MutexState::Ours);
            s.callbacks.granted.call(&());
            s.callbacks.taken.call(&());
        }));
        let s = state.clone();
        handlers.push(conn.register_handler(ids.deny, only, move |m| {
            let Ok(d) = Index::decode(m.payload) else {
                return;
            };
            if d.index != s.index.get() {
                return;
            }
            s.deadline.set(None);
            s.state.set(MutexState::HeldRemotely);
            if !s.abandoned.replace(false) {
                s.callbacks.denied.call(&());
            }
        }));
        let s = state.clone();
        handlers.push(
            conn.register_handler(ids.release_notification, only, move |_| {
                s.state.set(MutexState::Available);
                s.callbacks.released.call(&());
            }),
        );
        let s = state.clone();
        handlers.push(conn.register_handler(ids.initialize, only, move |m| {
            if s.index.get() != -1 {
                return;
            }
            let Ok(init) = Initialize::decode(m.payload) else {
                return;
            };
            if init.ip != s.identity.ip || init.pid != s.identity.pid {
                return;
            }
            s.index.set(init.index);
            if s.request_before_init.replace(false) {
                let _ = s.request(m.connection());
            }
        }));
        let (s, weak) = (state.clone(), conn.downgrade());
        handlers.push(conn.on_event(ConnectionEvent::GotConnection, move || {
            if s.index.get() == -1 {
                if let Some(c) = weak.upgrade() {
                    s.request_index(&c);
                }
            }
        }));
        let s = state.clone();
        handlers.push(conn.on_event(ConnectionEvent::DroppedConnection, move || {
            s.index.set(-1);
            s.deadline.set(None);
            let was = s.state.replace(MutexState::Available);
            if was == MutexState::Requesting && !s.abandoned.replace(false) {
                s.callbacks.denied.call(&());
            }
            if matches!(was, MutexState::Ours | MutexState::HeldRemotely) {
                s.callbacks.released.call(&());
            }
        }));
        if conn.connected() {
            state.request_index(conn);
        }
        Ok(MutexRemote {
            conn: conn.clone(),
            state,
            handlers,
        })
    }

    /// Services the connection, and turns a request unanswered past its time-out into a
    /// denial.
    pub fn mainloop(&self) -> Result<(), Error> {
        let r = self.conn.mainloop();
        if let Some(d) = self.state.deadline.get() {
            if self.conn.now().mono >= d && self.state.state.get() == MutexState::Requesting {
                self.state.deadline.set(None);
                self.state.abandoned.set(true);
                self.state.state.set(MutexState::Available);
                self.state.callbacks.denied.call(&());
            }
        }
        r
    }

    /// The connection the remote uses.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// Where the lock is.
    pub fn state(&self) -> MutexState {
        self.state.state.get()
    }

    /// True when nobody holds the lock (C++ `isAvailable`).
    pub fn is_available(&self) -> bool {
        self.state() == MutexState::Available
    }

    /// True when this remote holds it (C++ `isHeldLocally`).
    pub fn is_held_locally(&self) -> bool {
        self.state() == MutexState::Ours
    }

    /// True when another participant holds it (C++ `isHeldRemotely`).
    pub fn is_held_remotely(&self) -> bool {
        self.state() == MutexState::HeldRemotely
    }

    /// The index the server assigned, once it did.
    pub fn index(&self) -> Option<i32> {
        let i = self.state.index.get();
        (i != -1).then_some(i)
    }

    /// Asks for the lock. If it is not available, the denied callbacks run at once; before
    /// the server assigned an index, the request waits for it (as in C++).
    pub fn request(&self) -> Result<(), Error> {
        self.state.request(&self.conn)
    }

    /// Gives the lock back (nothing if this remote does not hold it).
    pub fn release(&self) -> Result<(), Error> {
        self.state.release(&self.conn)
    }

    /// After this long without an answer a request counts as denied (checked by
    /// [`mainloop`](Self::mainloop)); `None` (the default, as C++) waits forever.
    pub fn set_request_timeout(&self, timeout: Option<Duration>) {
        self.state.timeout.set(timeout);
    }

    /// Calls `f` when this remote's request is granted.
    pub fn on_granted(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.state.callbacks.granted.add(move |_| f())
    }

    /// Calls `f` when this remote's request is denied.
    pub fn on_denied(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.state.callbacks.denied.add(move |_| f())
    }

    /// Calls `f` when anyone gets the lock.
    pub fn on_taken(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.state.callbacks.taken.add(move |_| f())
    }

    /// Calls `f` when the lock becomes available.
    pub fn on_released(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.state.callbacks.released.add(move |_| f())
    }

    /// Removes a callback an `on_*` of this remote returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.state.callbacks.remove(id)
    }
}
