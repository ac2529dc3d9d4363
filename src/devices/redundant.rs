//! Redundant transmission (`vrpn_RedundantTransmission`): a sender that sends each message
//! several times over UDP, spaced in time, so that a lossy link loses fewer; a receiver that
//! hands each message to its handlers once; and the control messages a client uses to tune
//! the sender remotely.
//!
//! - [`RedundantTransmission`] wraps a connection: while enabled, every message packed
//!   through it goes LOW_LATENCY, followed by `retransmissions` copies `interval` apart
//!   (copies are sent by its [`mainloop`](RedundantTransmission::mainloop), which reports
//!   the next time it is due).
//! - [`RedundantController`] lets clients set a `RedundantTransmission`'s defaults and turn
//!   it on or off; [`RedundantRemote`] is the client that does.
//! - [`RedundantReceiver`] registers handlers that see each message once: a copy is known by
//!   its type, sender and timestamp among the last 8 timestamps of its type.

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::ops::Deref;
use std::rc::Rc;
use std::time::{Duration, Instant};

use super::base::{self, RemoteCore};
use crate::connection::Connection;
use crate::dispatch::{HandlerId, Message, SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::time::{Now, TimeVal};
use crate::wire::class;
use crate::wire::payload::redundant::{self as codec, Enable, SetDefaults, RECEIVER_MEMORY};

struct Queued {
    time: TimeVal,
    type_id: TypeId,
    sender: SenderId,
    payload: Vec<u8>,
    remaining: u32,
    interval: Duration,
    next: Instant,
}

struct SenderState {
    enabled: bool,
    retransmissions: u32,
    interval: Duration,
    queue: Vec<Queued>,
    /// Payload buffers of finished copies, reused.
    spare: Vec<Vec<u8>>,
}

/// The sending side (C++ `vrpn_RedundantTransmission`). Disabled by default: messages pass
/// straight through with their own class of service.
pub struct RedundantTransmission {
    conn: Connection,
    state: RefCell<SenderState>,
}

impl RedundantTransmission {
    /// A sender on `conn`, disabled, with no retransmissions.
    pub fn new(conn: &Connection) -> RedundantTransmission {
        RedundantTransmission {
            conn: conn.clone(),
            state: RefCell::new(SenderState {
                enabled: false,
                retransmissions: 0,
                interval: Duration::ZERO,
                queue: Vec::new(),
                spare: Vec::new(),
            }),
        }
    }

    /// The connection it sends on.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// Turns redundancy on or off.
    pub fn enable(&self, on: bool) {
        self.state.borrow_mut().enabled = on;
    }

    /// True while redundancy is on.
    pub fn is_enabled(&self) -> bool {
        self.state.borrow().enabled
    }

    /// Copies sent after each message and the time between them. A zero interval sends one
    /// copy per [`mainloop`](Self::mainloop) call (each in its own datagram).
    pub fn set_defaults(&self, retransmissions: u32, interval: Duration) {
        let mut s = self.state.borrow_mut();
        s.retransmissions = retransmissions;
        s.interval = interval;
    }

    /// The default number of copies.
    pub fn default_retransmissions(&self) -> u32 {
        self.state.borrow().retransmissions
    }

    /// The default time between copies.
    pub fn default_interval(&self) -> Duration {
        self.state.borrow().interval
    }

    /// Copies still to be sent.
    pub fn queued(&self) -> usize {
        self.state.borrow().queue.len()
    }

    /// Sends a message: with `class` when redundancy is off, otherwise LOW_LATENCY and then
    /// the default number of copies.
    pub fn pack_message(
        &self,
        time: TimeVal,
        type_id: TypeId,
        sender: SenderId,
        payload: &[u8],
        class_of_service: u32,
    ) -> Result<(), Error> {
        let (n, interval) = {
            let s = self.state.borrow();
            (s.retransmissions, s.interval)
        };
        self.pack_message_with(
            time,
            type_id,
            sender,
            payload,
            class_of_service,
            n,
            interval,
        )
    }

    /// [`pack_message`](Self::pack_message) with this message's own number of copies and
    /// interval.
    #[allow(clippy::too_many_arguments)]
    pub fn pack_message_with(
        &self,
        time: TimeVal,
        type_id: TypeId,
        sender: SenderId,
        payload: &[u8],
        class_of_service: u32,
        retransmissions: u32,
        interval: Duration,
    ) -> Result<(), Error> {
        if !self.state.borrow().enabled {
            return self
                .conn
                .pack_message(time, type_id, sender, payload, class_of_service);
        }
        self.conn
            .pack_message(time, type_id, sender, payload, class::LOW_LATENCY)?;
        if retransmissions == 0 {
            return Ok(());
        }
        let now = self.conn.now().mono;
        let mut s = self.state.borrow_mut();
        let mut buf = s.spare.pop().unwrap_or_default();
        buf.clear();
        buf.extend_from_slice(payload);
        s.queue.push(Queued {
            time,
            type_id,
            sender,
            payload: buf,
            remaining: retransmissions,
            interval,
            next: now + interval,
        });
        Ok(())
    }

    /// Sends the copies that are due at `now` (LOW_LATENCY, with the original timestamp).
    pub fn mainloop_at(&self, now: Now) {
        let mut s = self.state.borrow_mut();
        let SenderState { queue, spare, .. } = &mut *s;
        let mut i = 0;
        while i < queue.len() {
            let q = &mut queue[i];
            if now.mono >= q.next {
                let _ = self.conn.pack_message(
                    q.time,
                    q.type_id,
                    q.sender,
                    &q.payload,
                    class::LOW_LATENCY,
                );
                q.remaining -= 1;
                q.next = now.mono + q.interval;
            }
            if q.remaining == 0 {
                spare.push(queue.swap_remove(i).payload);
            } else {
                i += 1;
            }
        }
    }

    /// Sends the copies that are due now.
    pub fn mainloop(&self) {
        self.mainloop_at(self.conn.now());
    }

    /// When the next copy is due.
    pub fn next_deadline(&self) -> Option<Instant> {
        self.state.borrow().queue.iter().map(|q| q.next).min()
    }
}

fn register_types(conn: &Connection) -> Result<(TypeId, TypeId), Error> {
    Ok((
        conn.register_type(codec::SET)?,
        conn.register_type(codec::ENABLE)?,
    ))
}

/// Lets clients tune a [`RedundantTransmission`] (C++ `vrpn_RedundantController`): answers
/// `set` and `enable` messages sent by a [`RedundantRemote`] on the connection.
pub struct RedundantController {
    sender: SenderId,
}

impl RedundantController {
    /// Serves control of `target` on `conn` (the controller's sender name is fixed, so one
    /// per connection).
    pub fn new(
        conn: &Connection,
        target: &Rc<RedundantTransmission>,
    ) -> Result<RedundantController, Error> {
        let (b, (set, enable)) = base::register_server(conn, codec::CONTROLLER, register_types)?;
        let only = SenderFilter::Only(b.sender);
        let t = Rc::downgrade(target);
        conn.register_handler(set, only, move |m| {
            if let (Ok(d), Some(t)) = (SetDefaults::decode(m.payload), t.upgrade()) {
                let iv = d.interval();
                let interval = Duration::from_secs(iv.sec.max(0) as u64)
                    + Duration::from_micros(iv.usec.clamp(0, 999_999) as u64);
                t.set_defaults(d.retransmissions, interval);
            }
        });
        let t = Rc::downgrade(target);
        conn.register_handler(enable, only, move |m| {
            if let (Ok(e), Some(t)) = (Enable::decode(m.payload), t.upgrade()) {
                t.enable(e.on != 0);
            }
        });
        Ok(RedundantController { sender: b.sender })
    }

    /// The controller's sender id.
    pub fn sender(&self) -> SenderId {
        self.sender
    }
}

/// The client that tunes a remote [`RedundantTransmission`] (C++ `vrpn_RedundantRemote`).
pub struct RedundantRemote {
    core: RemoteCore,
    set: TypeId,
    enable: TypeId,
}

impl Deref for RedundantRemote {
    type Target = RemoteCore;
    fn deref(&self) -> &RemoteCore {
        &self.core
    }
}

impl RedundantRemote {
    /// A remote on `conn` (a client connection to the sender's server).
    pub fn new(conn: &Connection) -> Result<RedundantRemote, Error> {
        let (core, (set, enable)) = RemoteCore::new(codec::CONTROLLER, conn, register_types)?;
        Ok(RedundantRemote { core, set, enable })
    }

    /// Sets the sender's default number of copies and the time between them.
    pub fn set(&self, retransmissions: u32, interval: Duration) -> Result<(), Error> {
        let iv = TimeVal {
            sec: interval.as_secs() as i64,
            usec: i64::from(interval.subsec_micros()),
        };
        let mut buf = [0u8; SetDefaults::LEN];
        SetDefaults::new(retransmissions, iv).encode(&mut buf);
        self.core.send(self.set, &buf)
    }

    /// Turns the sender's redundancy on or off.
    pub fn enable(&self, on: bool) -> Result<(), Error> {
        let mut buf = [0u8; Enable::LEN];
        Enable { on: i16::from(on) }.encode(&mut buf);
        self.core.send(self.enable, &buf)
    }
}

/// The last timestamps seen of one message type: (sender, timestamp, copies seen).
struct Seen {
    entries: [(SenderId, TimeVal, u32); RECEIVER_MEMORY],
    next: usize,
}

impl Seen {
    fn new() -> Seen {
        Seen {
            entries: [(SenderId::UNKNOWN, TimeVal::default(), 0); RECEIVER_MEMORY],
            next: 0,
        }
    }
}

type RedundantHandler = Rc<RefCell<dyn FnMut(&Message<'_>)>>;

struct ReceiverState {
    seen: RefCell<HashMap<TypeId, Seen>>,
    handlers: RefCell<Vec<(HandlerId, TypeId, SenderFilter, RedundantHandler)>>,
    record: Cell<bool>,
    memory: RefCell<Vec<(TimeVal, u32)>>,
    duplicates: Cell<u64>,
}

/// The receiving side (C++ `vrpn_RedundantReceiver`): handlers registered through it see
/// each message once.
pub struct RedundantReceiver {
    conn: Connection,
    state: Rc<ReceiverState>,
    /// The connection handler of each type with handlers here.
    types: RefCell<Vec<(TypeId, HandlerId)>>,
}

impl Drop for RedundantReceiver {
    fn drop(&mut self) {
        for (_, h) in self.types.borrow_mut().drain(..) {
            self.conn.remove_handler(h);
        }
    }
}

impl RedundantReceiver {
    /// A receiver on `conn`.
    pub fn new(conn: &Connection) -> RedundantReceiver {
        RedundantReceiver {
            conn: conn.clone(),
            state: Rc::new(ReceiverState {
                seen: RefCell::new(HashMap::new()),
                handlers: RefCell::new(Vec::new()),
                record: Cell::new(false),
                memory: RefCell::new(Vec::new()),
                duplicates: Cell::new(0),
            }),
            types: RefCell::new(Vec::new()),
        }
    }

    /// Calls `f` once for each message of `type_id` from the senders `sender` selects,
    /// however many copies arrive.
    pub fn register_handler(
        &self,
        type_id: TypeId,
        sender: SenderFilter,
        f: impl FnMut(&Message<'_>) + 'static,
    ) -> HandlerId {
        let id = HandlerId::fresh();
        self.state
            .handlers
            .borrow_mut()
            .push((id, type_id, sender, Rc::new(RefCell::new(f))));
        let mut types = self.types.borrow_mut();
        if !types.iter().any(|(t, _)| *t == type_id) {
            let s = self.state.clone();
            let h = self
                .conn
                .register_handler(type_id, SenderFilter::Any, move |m| s.deliver(m));
            types.push((type_id, h));
        }
        id
    }

    /// Removes a handler [`register_handler`](Self::register_handler) returned.
    pub fn remove_handler(&self, id: HandlerId) -> bool {
        let mut h = self.state.handlers.borrow_mut();
        let before = h.len();
        h.retain(|(i, ..)| *i != id);
        h.len() != before
    }

    /// While on, each timestamp leaving the memory of its type is recorded with the number
    /// of copies that arrived ([`memory`](Self::memory)).
    pub fn record(&self, on: bool) {
        self.state.record.set(on);
    }

    /// The recorded (timestamp, copies seen) pairs, oldest first.
    pub fn memory(&self) -> Vec<(TimeVal, u32)> {
        self.state.memory.borrow().clone()
    }

    /// Forgets the recorded pairs.
    pub fn clear_memory(&self) {
        self.state.memory.borrow_mut().clear();
    }

    /// Copies dropped so far.
    pub fn duplicates(&self) -> u64 {
        self.state.duplicates.get()
    }
}

impl ReceiverState {
    fn deliver(&self, m: &Message<'_>) {
        {
            let mut seen = self.seen.borrow_mut();
            let s = seen.entry(m.type_id).or_insert_with(Seen::new);
            if let Some(e) = s
                .entries
                .iter_mut()
                .find(|(snd, t, n)| *n > 0 && *snd == m.sender && *t == m.sender_time)
            {
                e.2 += 1;
                self.duplicates.set(self.duplicates.get() + 1);
                return;
            }
            let slot = &mut s.entries[s.next];
            if self.record.get() && slot.2 > 0 {
                self.memory.borrow_mut().push((slot.1, slot.2));
            }
            *slot = (m.sender, m.sender_time, 1);
            s.next = (s.next + 1) % RECEIVER_MEMORY;
        }
        let mut i = 0;
        loop {
            let cb = match self.handlers.borrow().get(i) {
                Some((_, t, filter, cb)) if *t == m.type_id && filter.accepts(m.sender) => {
                    Some(cb.clone())
                }
                Some(_) => None,
                None => break,
            };
            if let Some(cb) = cb {
                if let Ok(mut f) = cb.try_borrow_mut() {
                    f(m);
                }
            }
            i += 1;
        }
    }
}
