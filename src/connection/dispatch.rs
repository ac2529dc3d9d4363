//! Handler tables and callback lists that user code may re-enter.
//!
//! A callback may register another callback, send a message or read device state while it runs.
//! Lists therefore never hold a `RefCell` borrow across a call: each entry is an
//! `Rc<RefCell<dyn FnMut>>`, fetched by index with a short borrow (cloning an `Rc` allocates
//! nothing) and called with the list released. A callback that is already running is skipped
//! rather than re-entered, which is what makes a double borrow impossible at run time.

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::sync::atomic::{AtomicU64, Ordering};

use super::Connection;
use crate::time::TimeVal;

/// Local id of a sender name on a connection.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SenderId(pub i32);

/// Local id of a message type name on a connection.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TypeId(pub i32);

impl SenderId {
    /// A sender the peer never described: such messages reach only any-sender handlers.
    pub const UNKNOWN: SenderId = SenderId(-1);
}

/// One message as handlers see it: local ids, the timestamps, the payload, and the
/// connection it arrived on (so a handler can answer without keeping the connection alive).
#[derive(Clone, Copy, Debug)]
pub struct Message<'a> {
    /// The sender's timestamp, in local time when clock synchronisation with the sender is in
    /// effect (see [`Connection::clock_estimate`]); otherwise as the sender stamped it.
    pub time: TimeVal,
    /// The timestamp as the sender stamped it (its own clock; what logs keep).
    pub sender_time: TimeVal,
    /// Local sender id, or [`SenderId::UNKNOWN`].
    pub sender: SenderId,
    /// Local type id.
    pub type_id: TypeId,
    /// The payload, without padding.
    pub payload: &'a [u8],
    pub(crate) conn: &'a Connection,
    /// Read from a peer (or a replayed log), rather than packed on this side or raised by the
    /// connection itself.
    pub(crate) from_peer: bool,
    /// The peer it came from (`None`: packed here, raised here, replayed, or queued).
    pub(crate) peer: Option<crate::proto::PeerId>,
}

impl<'a> Message<'a> {
    /// The connection the message arrived on. Reply through it from inside a handler: a
    /// handler that captured a `Connection` clone would keep the connection (and its port)
    /// alive for as long as the handler is registered on it.
    pub fn connection(&self) -> &'a Connection {
        self.conn
    }

    /// True for a message read from a peer or a replayed log; false for one packed on this
    /// side (every connection hands its own messages to its local handlers too) and for the
    /// connection's own events. Forwarders use it to pass on only what came from elsewhere.
    #[inline]
    pub fn from_peer(&self) -> bool {
        self.from_peer
    }

    /// Answers this message: the reply goes to the peer that sent it only (to every peer and
    /// local handler, as [`Connection::pack_message`], when the message did not come from a
    /// peer). A request flood then costs the requester, never its neighbours.
    pub fn reply(
        &self,
        time: TimeVal,
        type_id: TypeId,
        sender: SenderId,
        payload: &[u8],
        class_of_service: impl Into<super::ServiceClass>,
    ) -> Result<(), crate::error::Error> {
        match self.peer {
            Some(peer) => {
                self.conn
                    .pack_to_peer(peer, time, type_id, sender, payload, class_of_service)
            }
            None => self
                .conn
                .pack_message(time, type_id, sender, payload, class_of_service),
        }
    }

    /// When the message arrived here, on the local clock: the time of the `mainloop()` pass
    /// that read it. A message delivered in-process outside a pass (an in-process server
    /// reporting to an in-process remote) arrives when it is sent: its own time.
    #[inline]
    pub fn arrived(&self) -> TimeVal {
        self.conn.pass_time().unwrap_or(self.time)
    }
}

/// Identifies a registered handler or callback so it can be removed.
///
/// Ids are unique in the whole process, whichever list they came from (connection handlers,
/// notice and state callbacks, a remote's `on_pose`, …), so an id can never remove another
/// list's callback by accident.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct HandlerId(u64);

impl HandlerId {
    /// A new id, never handed out before in this process.
    pub(crate) fn fresh() -> HandlerId {
        static NEXT: AtomicU64 = AtomicU64::new(1);
        HandlerId(NEXT.fetch_add(1, Ordering::Relaxed))
    }
}

type Callback<T> = Rc<RefCell<dyn FnMut(&T)>>;

/// A list of callbacks over values of type `T`, safe to modify and re-enter from a callback.
/// Internal (the remotes' `on_*` lists), public for remotes built outside the crate.
#[doc(hidden)]
pub struct CallbackList<T: ?Sized> {
    entries: RefCell<Vec<(HandlerId, Callback<T>)>>,
}

impl<T: ?Sized> Default for CallbackList<T> {
    fn default() -> Self {
        CallbackList {
            entries: RefCell::new(Vec::new()),
        }
    }
}

impl<T: ?Sized> CallbackList<T> {
    /// Adds a callback; callbacks run in registration order.
    pub fn add(&self, f: impl FnMut(&T) + 'static) -> HandlerId {
        let id = HandlerId::fresh();
        self.entries
            .borrow_mut()
            .push((id, Rc::new(RefCell::new(f))));
        id
    }

    /// Removes a callback; returns whether it was present.
    pub fn remove(&self, id: HandlerId) -> bool {
        let mut e = self.entries.borrow_mut();
        let before = e.len();
        e.retain(|(i, _)| *i != id);
        e.len() != before
    }

    /// Number of callbacks.
    pub fn len(&self) -> usize {
        self.entries.borrow().len()
    }

    /// True when no callback is registered.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Calls every callback with `value`. Allocation-free.
    pub fn call(&self, value: &T) {
        let mut i = 0;
        loop {
            let cb = match self.entries.borrow().get(i) {
                Some((_, cb)) => cb.clone(),
                None => break,
            };
            if let Ok(mut f) = cb.try_borrow_mut() {
                f(value);
            }
            i += 1;
        }
    }
}

/// Which senders a handler listens to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SenderFilter {
    /// Every sender, known or not (`vrpn_ANY_SENDER`).
    Any,
    /// One sender.
    Only(SenderId),
}

impl SenderFilter {
    /// Whether a message from `sender` passes this filter.
    #[inline]
    pub fn accepts(self, sender: SenderId) -> bool {
        match self {
            SenderFilter::Any => true,
            SenderFilter::Only(s) => s == sender,
        }
    }
}

type MessageHandler = Rc<RefCell<dyn FnMut(&Message<'_>)>>;

struct HandlerEntry {
    id: HandlerId,
    sender: SenderFilter,
    f: MessageHandler,
}

/// Message handlers by local type id, plus handlers for every type.
#[derive(Default)]
pub(crate) struct HandlerTable {
    by_type: RefCell<Vec<Vec<HandlerEntry>>>,
    any_type: RefCell<Vec<HandlerEntry>>,
    /// `any_type` has entries (a flag: tested for every message, and almost always false).
    any_type_used: Cell<bool>,
}

impl HandlerTable {
    pub(crate) fn add(
        &self,
        type_id: Option<TypeId>,
        sender: SenderFilter,
        f: impl FnMut(&Message<'_>) + 'static,
    ) -> HandlerId {
        let id = HandlerId::fresh();
        let entry = HandlerEntry {
            id,
            sender,
            f: Rc::new(RefCell::new(f)),
        };
        match type_id {
            Some(t) => {
                let mut by_type = self.by_type.borrow_mut();
                let idx = t.0.max(0) as usize;
                if by_type.len() <= idx {
                    by_type.resize_with(idx + 1, Vec::new);
                }
                by_type[idx].push(entry);
            }
            None => {
                self.any_type.borrow_mut().push(entry);
                self.any_type_used.set(true);
            }
        }
        id
    }

    pub(crate) fn remove(&self, id: HandlerId) -> bool {
        let mut found = false;
        for list in self.by_type.borrow_mut().iter_mut() {
            let before = list.len();
            list.retain(|e| e.id != id);
            found |= list.len() != before;
        }
        let mut any = self.any_type.borrow_mut();
        let before = any.len();
        any.retain(|e| e.id != id);
        self.any_type_used.set(!any.is_empty());
        found || any.len() != before
    }

    /// True when some handler wants messages of this type from this sender (lets senders skip
    /// building, queueing and dispatching a message nobody takes).
    #[inline]
    pub(crate) fn wants_any(&self, type_id: TypeId, sender: SenderId) -> bool {
        let wanted = |l: &Vec<HandlerEntry>| l.iter().any(|e| e.sender.accepts(sender));
        (self.any_type_used.get() && wanted(&self.any_type.borrow()))
            || self
                .by_type
                .borrow()
                .get(type_id.0.max(0) as usize)
                .is_some_and(wanted)
    }

    /// Calls the handlers for `msg`: type-specific ones first, then any-type ones.
    pub(crate) fn dispatch(&self, msg: &Message<'_>) {
        if msg.type_id.0 >= 0 {
            let t = msg.type_id.0 as usize;
            let mut i = 0;
            loop {
                let f = {
                    let by_type = self.by_type.borrow();
                    match by_type.get(t).and_then(|l| l.get(i)) {
                        Some(e) => Self::wants(e, msg).then(|| e.f.clone()),
                        None => break,
                    }
                };
                if let Some(f) = f {
                    if let Ok(mut f) = f.try_borrow_mut() {
                        f(msg);
                    }
                }
                i += 1;
            }
        }
        if !self.any_type_used.get() {
            return;
        }
        let mut i = 0;
        loop {
            let f = {
                let any = self.any_type.borrow();
                match any.get(i) {
                    Some(e) => Self::wants(e, msg).then(|| e.f.clone()),
                    None => break,
                }
            };
            if let Some(f) = f {
                if let Ok(mut f) = f.try_borrow_mut() {
                    f(msg);
                }
            }
            i += 1;
        }
    }

    fn wants(e: &HandlerEntry, msg: &Message<'_>) -> bool {
        e.sender.accepts(msg.sender)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn callbacks_may_register_callbacks_and_reenter() {
        let list: Rc<CallbackList<i32>> = Rc::new(CallbackList::default());
        let seen = Rc::new(RefCell::new(Vec::new()));
        let (l2, s2) = (list.clone(), seen.clone());
        list.add(move |v| {
            s2.borrow_mut().push(*v);
            if *v == 1 {
                let s3 = s2.clone();
                l2.add(move |v| s3.borrow_mut().push(v * 10));
                // Re-entering the list from inside a callback: the running one is skipped.
                l2.call(&2);
            }
        });
        list.call(&1);
        assert_eq!(*seen.borrow(), vec![1, 20, 10]);
    }

    #[test]
    fn sender_filter_and_any_type() {
        let t = HandlerTable::default();
        let hits = Rc::new(Cell::new(0));
        let h = hits.clone();
        t.add(
            Some(TypeId(3)),
            SenderFilter::Only(SenderId(1)),
            move |_| h.set(h.get() + 1),
        );
        let h = hits.clone();
        let any = t.add(None, SenderFilter::Any, move |_| h.set(h.get() + 100));
        let conn = Connection::new_loopback();
        let msg = |s| Message {
            time: TimeVal::ZERO,
            sender_time: TimeVal::ZERO,
            sender: SenderId(s),
            type_id: TypeId(3),
            payload: &[],
            conn: &conn,
            from_peer: true,
            peer: None,
        };
        t.dispatch(&msg(1));
        t.dispatch(&msg(2));
        assert_eq!(hits.get(), 201);
        assert!(t.remove(any));
        t.dispatch(&msg(1));
        assert_eq!(hits.get(), 202);
    }

    #[test]
    fn wants_any_answers_for_the_sender_not_just_the_type() {
        let t = HandlerTable::default();
        assert!(!t.wants_any(TypeId(3), SenderId(1)));
        t.add(Some(TypeId(3)), SenderFilter::Only(SenderId(1)), |_| {});
        assert!(t.wants_any(TypeId(3), SenderId(1)));
        assert!(!t.wants_any(TypeId(3), SenderId(2)));
        assert!(!t.wants_any(TypeId(4), SenderId(1)));
        let any = t.add(None, SenderFilter::Only(SenderId(2)), |_| {});
        assert!(t.wants_any(TypeId(4), SenderId(2)));
        assert!(t.remove(any));
        t.add(Some(TypeId(3)), SenderFilter::Any, |_| {});
        assert!(t.wants_any(TypeId(3), SenderId(9)));
    }
}
