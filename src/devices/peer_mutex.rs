//! Peer mutex (`vrpn_PeerMutex`): a lock shared by peers without a server. Each peer runs a
//! server connection and opens a client connection to every other peer; a peer that wants
//! the lock asks all of them and holds it once all granted.
//!
//! The exchange, as in C++: requests, releases, grants and denials carry the requesting
//! peer's IPv4 address and port and go out on the peer's client connections, so every peer
//! hears them on its server connection. A peer grants a request when the lock is available
//! or when the requester's address (then port) is lower than the one it last granted, which
//! breaks ties between simultaneous requests; it broadcasts its grant or denial to all its
//! peers, and the requester counts the grants meant for it. Every peer must add every other
//! one.

use std::cell::{Cell, RefCell};
use std::net::Ipv4Addr;
use std::rc::Rc;

use super::mutex::{host_ip, MutexCallbacks, MutexState};
use crate::connection::{Connection, ConnectionEvent};
use crate::dispatch::{HandlerId, SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::wire::class;
use crate::wire::payload::mutex::{self as codec, PeerId};

/// The ids a peer mutex uses on one connection.
#[derive(Clone, Copy, Debug)]
struct PeerIds {
    sender: SenderId,
    request: TypeId,
    release: TypeId,
    grant: TypeId,
    deny: TypeId,
}

impl PeerIds {
    /// The sender (the mutex's name) and the four types in C++ order.
    fn register(conn: &Connection, name: &str) -> Result<PeerIds, Error> {
        Ok(PeerIds {
            sender: conn.register_sender(name)?,
            request: conn.register_type(codec::REQUEST_MUTEX)?,
            release: conn.register_type(codec::RELEASE)?,
            grant: conn.register_type(codec::GRANT_REQUEST)?,
            deny: conn.register_type(codec::DENY_REQUEST)?,
        })
    }
}

struct Peer {
    station: String,
    conn: Connection,
    ids: PeerIds,
    dropped: HandlerId,
}

struct State {
    name: String,
    me: PeerId,
    state: Cell<MutexState>,
    /// The peer last granted (`port` -1: none).
    holder: Cell<(u32, i64)>,
    granting: Cell<usize>,
    peers: RefCell<Vec<Peer>>,
    /// A peer lost while its handler ran (removed on the next mainloop).
    lost: RefCell<Vec<String>>,
    callbacks: MutexCallbacks,
}

impl State {
    fn send_all(&self, kind: fn(&PeerIds) -> TypeId, who: PeerId) {
        let mut buf = [0u8; PeerId::LEN];
        who.encode(&mut buf);
        for p in self.peers.borrow().iter() {
            let _ = p.conn.pack_message(
                p.conn.now().wall,
                kind(&p.ids),
                p.ids.sender,
                &buf,
                class::RELIABLE,
            );
        }
    }

    fn check_grant(&self) {
        if self.state.get() == MutexState::Requesting
            && self.granting.get() >= self.peers.borrow().len()
        {
            self.state.set(MutexState::Ours);
            self.callbacks.taken.call(&());
            self.callbacks.granted.call(&());
        }
    }

    fn on_request(&self, who: PeerId) {
        let (hip, hport) = self.holder.get();
        let lower = who.ip < hip || (who.ip == hip && i64::from(who.port) < hport);
        let st = self.state.get();
        let yield_to = st == MutexState::Available
            || (matches!(st, MutexState::HeldRemotely | MutexState::Requesting) && lower);
        if yield_to {
            self.holder.set((who.ip, i64::from(who.port)));
            if st != MutexState::HeldRemotely {
                self.callbacks.taken.call(&());
            }
            self.state.set(MutexState::HeldRemotely);
            self.send_all(|i| i.grant, who);
        } else {
            self.send_all(|i| i.deny, who);
        }
    }
}

/// One peer of a peer mutex (C++ `vrpn_PeerMutex`).
///
/// Call [`mainloop`](Self::mainloop) often: it services the server connection and every
/// peer's. Callbacks as [`MutexRemote`](super::mutex::MutexRemote)'s. A peer whose
/// connection drops is forgotten, as in C++ (add it again when it is back).
pub struct PeerMutex {
    server: Connection,
    ids: PeerIds,
    state: Rc<State>,
}

impl PeerMutex {
    /// A peer of the mutex `name` serving on `port` (0: any free port), on every interface
    /// or on `nic` only. It identifies itself by `nic`, or else by the first address its host
    /// name resolves to (as C++).
    pub fn new(name: &str, port: u16, nic: Option<Ipv4Addr>) -> Result<PeerMutex, Error> {
        let server = Connection::server(nic, port)?;
        let ip = nic.map_or_else(host_ip, u32::from);
        Self::on_connection(name, &server, ip)
    }

    /// A peer on an existing server connection, identified by `ip` and the connection's
    /// port.
    pub fn on_connection(name: &str, server: &Connection, ip: u32) -> Result<PeerMutex, Error> {
        let port = server
            .local_port()
            .ok_or(Error::Unsupported("a peer mutex needs a server connection"))?;
        let ids = PeerIds::register(server, name)?;
        let state = Rc::new(State {
            name: name.to_string(),
            me: PeerId {
                ip,
                port: u32::from(port),
            },
            state: Cell::new(MutexState::Available),
            holder: Cell::new((0, -1)),
            granting: Cell::new(0),
            peers: RefCell::new(Vec::new()),
            lost: RefCell::new(Vec::new()),
            callbacks: MutexCallbacks::default(),
        });
        let only = SenderFilter::Only(ids.sender);
        let s = state.clone();
        server.register_handler(ids.request, only, move |m| {
            if let Ok(who) = PeerId::decode(m.payload) {
                s.on_request(who);
            }
        });
        let s = state.clone();
        server.register_handler(ids.release, only, move |m| {
            if PeerId::decode(m.payload).is_ok() {
                s.state.set(MutexState::Available);
                s.holder.set((0, -1));
                s.callbacks.released.call(&());
            }
        });
        let s = state.clone();
        server.register_handler(ids.grant, only, move |m| {
            if PeerId::decode(m.payload) == Ok(s.me) {
                s.granting.set(s.granting.get() + 1);
                s.check_grant();
            }
        });
        let s = state.clone();
        server.register_handler(ids.deny, only, move |m| {
            if PeerId::decode(m.payload) == Ok(s.me) {
                s.granting.set(0);
                s.callbacks.denied.call(&());
                s.state.set(MutexState::HeldRemotely);
            }
        });
        Ok(PeerMutex {
            server: server.clone(),
            ids,
            state,
        })
    }

    /// This peer's server connection.
    pub fn connection(&self) -> &Connection {
        &self.server
    }

    /// The port this peer serves on.
    pub fn port(&self) -> u16 {
        self.state.me.port as u16
    }

    /// The address and port this peer identifies itself by.
    pub fn identity(&self) -> (Ipv4Addr, u16) {
        (Ipv4Addr::from(self.state.me.ip), self.port())
    }

    /// Adds the peer serving at `station` (`host:port`, as C++ `addPeer`). Its connection
    /// waits in this peer's reactor.
    pub fn add_peer(&self, station: &str) -> Result<(), Error> {
        let station = station.trim();
        let conn = match self.server.reactor() {
            Some(r) => Connection::open_in(&r, station)?,
            None => Connection::open(station)?,
        };
        let ids = PeerIds::register(&conn, &self.state.name)?;
        let (lost, name) = (Rc::downgrade(&self.state), station.to_string());
        let dropped = conn.on_event(ConnectionEvent::DroppedConnection, move || {
            if let Some(s) = lost.upgrade() {
                s.lost.borrow_mut().push(name.clone());
            }
        });
        self.state.peers.borrow_mut().push(Peer {
            station: station.to_string(),
            conn,
            ids,
            dropped,
        });
        Ok(())
    }

    /// Peers known.
    pub fn num_peers(&self) -> usize {
        self.state.peers.borrow().len()
    }

    /// True when every peer's connection is up.
    pub fn peers_connected(&self) -> bool {
        self.state.peers.borrow().iter().all(|p| p.conn.connected())
    }

    /// Services the server connection and every peer's, forgets peers whose connection
    /// dropped, and takes the lock once every peer granted it.
    pub fn mainloop(&self) -> Result<(), Error> {
        self.server.mainloop()?;
        self.peers_mainloop()?;
        let lost: Vec<String> = std::mem::take(&mut *self.state.lost.borrow_mut());
        for station in lost {
            let mut peers = self.state.peers.borrow_mut();
            if let Some(i) = peers.iter().position(|p| p.station == station) {
                let p = peers.swap_remove(i);
                p.conn.remove_handler(p.dropped);
            }
        }
        self.state.check_grant();
        Ok(())
    }

    fn peers_mainloop(&self) -> Result<(), Error> {
        let mut i = 0;
        loop {
            let conn = match self.state.peers.borrow().get(i) {
                Some(p) => p.conn.clone(),
                None => return Ok(()),
            };
            conn.mainloop()?;
            i += 1;
        }
    }

    /// Where the lock is.
    pub fn state(&self) -> MutexState {
        self.state.state.get()
    }

    /// True when nobody holds the lock.
    pub fn is_available(&self) -> bool {
        self.state() == MutexState::Available
    }

    /// True when this peer holds it.
    pub fn is_held_locally(&self) -> bool {
        self.state() == MutexState::Ours
    }

    /// True when another peer holds it.
    pub fn is_held_remotely(&self) -> bool {
        self.state() == MutexState::HeldRemotely
    }

    /// Asks every peer for the lock; with no peers it is granted at once. If the lock is
    /// not available the denied callbacks run. Unlike C++, which would wait forever for a
    /// peer that cannot hear the request, a peer whose connection is not up makes this an
    /// error and nothing is asked.
    pub fn request(&self) -> Result<(), Error> {
        let s = &self.state;
        if s.state.get() != MutexState::Available {
            s.callbacks.denied.call(&());
            return Ok(());
        }
        if let Some(p) = s.peers.borrow().iter().find(|p| !p.conn.connected()) {
            return Err(Error::NotConnected(p.conn.state()));
        }
        s.state.set(MutexState::Requesting);
        s.granting.set(0);
        s.send_all(|i| i.request, s.me);
        s.holder.set((s.me.ip, i64::from(s.me.port)));
        s.check_grant();
        Ok(())
    }

    /// Gives the lock back (nothing if this peer does not hold it).
    pub fn release(&self) {
        let s = &self.state;
        if s.state.get() != MutexState::Ours {
            return;
        }
        s.state.set(MutexState::Available);
        s.holder.set((0, -1));
        s.send_all(|i| i.release, s.me);
        s.callbacks.released.call(&());
    }

    /// Calls `f` when this peer's request is granted by every peer.
    pub fn on_granted(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.state.callbacks.granted.add(move |_| f())
    }

    /// Calls `f` when this peer's request is denied.
    pub fn on_denied(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.state.callbacks.denied.add(move |_| f())
    }

    /// Calls `f` when any peer gets the lock.
    pub fn on_taken(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.state.callbacks.taken.add(move |_| f())
    }

    /// Calls `f` when the lock becomes available.
    pub fn on_released(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.state.callbacks.released.add(move |_| f())
    }

    /// Removes a callback an `on_*` returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.state.callbacks.remove(id)
    }

    /// The sender id of the mutex on the server connection.
    pub fn sender(&self) -> SenderId {
        self.ids.sender
    }
}

impl Drop for PeerMutex {
    fn drop(&mut self) {
        // As C++: tell the peers before going away (and push what is queued out).
        self.release();
        let _ = self.peers_mainloop();
    }
}
