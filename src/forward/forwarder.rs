//! Forwarding messages from one connection to another (C++ `vrpn_ConnectionForwarder` and
//! `vrpn_StreamForwarder`).
//!
//! A forwarder registers a handler on its source connection for each (type, sender) it
//! forwards and packs every message that arrives there on its destination, under the
//! destination's ids for the names it was told (the same names, or others: renaming is
//! allowed, as in C++). Every connection hands the messages packed on it to its own handlers
//! too, so a forwarder on a server connection forwards the server's own devices (that is what
//! C++ `vrpn_Forwarder_Server` does); [`ConnectionForwarder::from_peers_only`] restricts it to
//! messages read from peers, which is what a two-way relay needs so that nothing it forwards
//! comes back.
//!
//! Forwarding allocates nothing per message: the ids are looked up when forwarding starts
//! ([`forward_sender`](ConnectionForwarder::forward_sender) registers a type name on the
//! destination the first time the type is seen, then remembers it).

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use crate::connection::{Connection, ServiceClass, WeakConnection};
use crate::dispatch::{HandlerId, Message, SenderFilter, SenderId, TypeId};
use crate::error::Error;

/// Counts of what a forwarder passed on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ForwardCounts {
    /// Messages packed on the destination.
    pub forwarded: u64,
    /// Messages the destination did not take (a client destination not connected).
    pub not_sent: u64,
}

#[derive(Default)]
struct Shared {
    counts: Cell<ForwardCounts>,
}

impl Shared {
    fn pack(
        &self,
        dest: &WeakConnection,
        m: &Message<'_>,
        type_id: TypeId,
        sender: SenderId,
        class: ServiceClass,
    ) {
        let Some(dest) = dest.upgrade() else {
            return;
        };
        let mut c = self.counts.get();
        match dest.pack_message(m.time, type_id, sender, m.payload, class) {
            Ok(()) => c.forwarded += 1,
            Err(_) => c.not_sent += 1,
        }
        self.counts.set(c);
    }
}

/// One forwarding rule, kept so that it can be removed again.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Rule {
    source_type: Option<String>,
    source_sender: String,
    dest_type: Option<String>,
    dest_sender: String,
    class: u32,
    handler: HandlerId,
}

/// Forwards chosen messages from a source connection to a destination connection (C++
/// `vrpn_ConnectionForwarder`). Dropping it stops forwarding.
pub struct ConnectionForwarder {
    source: Connection,
    destination: Connection,
    peers_only: bool,
    rules: Vec<Rule>,
    shared: Rc<Shared>,
}

impl ConnectionForwarder {
    /// A forwarder from `source` to `destination` (it keeps both connections alive).
    pub fn new(source: &Connection, destination: &Connection) -> ConnectionForwarder {
        ConnectionForwarder {
            source: source.clone(),
            destination: destination.clone(),
            peers_only: false,
            rules: Vec::new(),
            shared: Rc::new(Shared::default()),
        }
    }

    /// Forward only messages read from the source's peers (or replayed), never those packed
    /// on the source itself: for rules added from now on.
    pub fn from_peers_only(mut self, yes: bool) -> ConnectionForwarder {
        self.peers_only = yes;
        self
    }

    /// The source connection.
    pub fn source(&self) -> &Connection {
        &self.source
    }

    /// The destination connection.
    pub fn destination(&self) -> &Connection {
        &self.destination
    }

    /// What was forwarded so far.
    pub fn counts(&self) -> ForwardCounts {
        self.shared.counts.get()
    }

    /// Forwards messages of type `source_type` from `source_sender`, sending them as type
    /// `dest_type` from `dest_sender` with `class` (C++ `forward`; C++'s default class is
    /// RELIABLE).
    pub fn forward(
        &mut self,
        source_type: &str,
        source_sender: &str,
        dest_type: &str,
        dest_sender: &str,
        class: impl Into<ServiceClass>,
    ) -> Result<(), Error> {
        let class = class.into();
        let st = self.source.register_type(source_type)?;
        let ss = self.source.register_sender(source_sender)?;
        let dt = self.destination.register_type(dest_type)?;
        let ds = self.destination.register_sender(dest_sender)?;
        let (dest, shared, peers_only) = (
            self.destination.downgrade(),
            self.shared.clone(),
            self.peers_only,
        );
        let handler = self
            .source
            .register_handler(st, SenderFilter::Only(ss), move |m| {
                if !peers_only || m.from_peer() {
                    shared.pack(&dest, m, dt, ds, class);
                }
            });
        self.rules.push(Rule {
            source_type: Some(source_type.into()),
            source_sender: source_sender.into(),
            dest_type: Some(dest_type.into()),
            dest_sender: dest_sender.into(),
            class: class.bits(),
            handler,
        });
        Ok(())
    }

    /// Forwards every message of `source_sender`, whatever its type, as `dest_sender`, keeping
    /// the type names (a device relayed as a whole: its reports one way, requests and pings
    /// the other way with a second forwarder).
    pub fn forward_sender(
        &mut self,
        source_sender: &str,
        dest_sender: &str,
        class: impl Into<ServiceClass>,
    ) -> Result<(), Error> {
        let class = class.into();
        let ss = self.source.register_sender(source_sender)?;
        let ds = self.destination.register_sender(dest_sender)?;
        let (dest, shared, peers_only) = (
            self.destination.downgrade(),
            self.shared.clone(),
            self.peers_only,
        );
        // Source type id → destination type id, filled the first time a type is seen.
        let map: RefCell<Vec<Option<TypeId>>> = RefCell::new(Vec::new());
        let handler = self
            .source
            .register_any_type_handler(SenderFilter::Only(ss), move |m| {
                if peers_only && !m.from_peer() {
                    return;
                }
                let Ok(i) = usize::try_from(m.type_id.0) else {
                    return; // the connection's own events
                };
                let known = map.borrow().get(i).copied().flatten();
                let dt = match known {
                    Some(dt) => dt,
                    None => {
                        let (Some(d), Some(name)) =
                            (dest.upgrade(), m.connection().type_name(m.type_id))
                        else {
                            return;
                        };
                        let Ok(dt) = d.register_type(&name) else {
                            return;
                        };
                        let mut map = map.borrow_mut();
                        if map.len() <= i {
                            map.resize(i + 1, None);
                        }
                        map[i] = Some(dt);
                        dt
                    }
                };
                shared.pack(&dest, m, dt, ds, class);
            });
        self.rules.push(Rule {
            source_type: None,
            source_sender: source_sender.into(),
            dest_type: None,
            dest_sender: dest_sender.into(),
            class: class.bits(),
            handler,
        });
        Ok(())
    }

    /// Stops the forwarding rules that match exactly (C++ `unforward`). Returns how many were
    /// removed.
    pub fn unforward(
        &mut self,
        source_type: &str,
        source_sender: &str,
        dest_type: &str,
        dest_sender: &str,
        class: impl Into<ServiceClass>,
    ) -> usize {
        let class = class.into().bits();
        let before = self.rules.len();
        let source = &self.source;
        self.rules.retain(|r| {
            let hit = r.source_type.as_deref() == Some(source_type)
                && r.source_sender == source_sender
                && r.dest_type.as_deref() == Some(dest_type)
                && r.dest_sender == dest_sender
                && r.class == class;
            if hit {
                source.remove_handler(r.handler);
            }
            !hit
        });
        before - self.rules.len()
    }
}

impl Drop for ConnectionForwarder {
    fn drop(&mut self) {
        for r in self.rules.drain(..) {
            self.source.remove_handler(r.handler);
        }
    }
}

/// Forwards chosen message types of one sender to another connection, as one (possibly
/// other) sender (C++ `vrpn_StreamForwarder`).
pub struct StreamForwarder {
    inner: ConnectionForwarder,
    source_sender: String,
    dest_sender: String,
}

impl StreamForwarder {
    /// Messages of `source_sender` on `source` go out on `destination` from `dest_sender`.
    pub fn new(
        source: &Connection,
        source_sender: &str,
        destination: &Connection,
        dest_sender: &str,
    ) -> Result<StreamForwarder, Error> {
        source.register_sender(source_sender)?;
        destination.register_sender(dest_sender)?;
        Ok(StreamForwarder {
            inner: ConnectionForwarder::new(source, destination),
            source_sender: source_sender.into(),
            dest_sender: dest_sender.into(),
        })
    }

    /// Forwards messages of type `source_type` as `dest_type`, with `class`.
    pub fn forward(
        &mut self,
        source_type: &str,
        dest_type: &str,
        class: impl Into<ServiceClass>,
    ) -> Result<(), Error> {
        let (s, d) = (self.source_sender.clone(), self.dest_sender.clone());
        self.inner.forward(source_type, &s, dest_type, &d, class)
    }

    /// Stops forwarding `source_type` as `dest_type` with `class`. Returns whether a rule
    /// was removed.
    pub fn unforward(
        &mut self,
        source_type: &str,
        dest_type: &str,
        class: impl Into<ServiceClass>,
    ) -> bool {
        let (s, d) = (self.source_sender.clone(), self.dest_sender.clone());
        self.inner.unforward(source_type, &s, dest_type, &d, class) > 0
    }

    /// What was forwarded so far.
    pub fn counts(&self) -> ForwardCounts {
        self.inner.counts()
    }
}
