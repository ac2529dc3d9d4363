//! Shared objects (`vrpn_Shared_int32`, `vrpn_Shared_float64`, `vrpn_Shared_String`): one
//! value kept equal on a server and its remotes. [`SharedInt32`], [`SharedFloat64`] and
//! [`SharedString`] are the three kinds; each is made as the server side or a remote side.
//!
//! Every change carries the time it was made (the value's version). What a side does with a
//! change, local or from the network, depends on its [`SharedMode`]:
//!
//! - Unserialized (the default): a change is taken everywhere it arrives and a local change
//!   is sent to the other side. With `ignore_old`, changes older than the value's time are
//!   dropped, so all sides end with the same value once quiet (not necessarily through the
//!   same sequence of callbacks).
//! - Serialized (`defer_updates`): one side, the serializer (the server at first), decides.
//!   A non-serializer's local change is not applied but sent to the serializer (the
//!   [`on_deferred_update`](SharedObject::on_deferred_update) callbacks run); the serializer
//!   applies what its [`SerializerPolicy`] accepts and sends it to everyone, so every side
//!   sees the same sequence. [`become_serializer`](SharedObject::become_serializer) moves
//!   the role with a request / grant / assume exchange.
//! - `ignore_idempotent`: a change to the value it already has is ignored.

use std::cell::{Cell, RefCell};
use std::rc::Rc;

use crate::connection::{Connection, ConnectionEvent};
use crate::dispatch::{CallbackList, HandlerId, SenderFilter, SenderId, TypeId};
use crate::error::Error;
use crate::name::DeviceName;
use crate::time::TimeVal;
use crate::wire::class;
use crate::wire::payload::shared_object::{
    self as codec, FloatUpdate, IntUpdate, StringUpdate, MAX_STRING_LEN,
};

/// How a shared object treats changes (C++ `VRPN_SO_*` flags).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SharedMode {
    /// Ignore a change to the value already held (`VRPN_SO_IGNORE_IDEMPOTENT`).
    pub ignore_idempotent: bool,
    /// Serialize changes through the serializer (`VRPN_SO_DEFER_UPDATES`).
    pub defer_updates: bool,
    /// Ignore changes older than the value (`VRPN_SO_IGNORE_OLD`).
    pub ignore_old: bool,
}

impl SharedMode {
    /// Serialized changes.
    pub const SERIALIZED: SharedMode = SharedMode {
        ignore_idempotent: false,
        defer_updates: true,
        ignore_old: false,
    };

    /// From the C++ flag bits (0x01, 0x10, 0x100).
    pub fn from_bits(bits: u32) -> SharedMode {
        SharedMode {
            ignore_idempotent: bits & 0x01 != 0,
            defer_updates: bits & 0x10 != 0,
            ignore_old: bits & 0x100 != 0,
        }
    }

    /// The C++ flag bits.
    pub fn bits(self) -> u32 {
        u32::from(self.ignore_idempotent)
            | (u32::from(self.defer_updates) << 4)
            | (u32::from(self.ignore_old) << 8)
    }
}

/// What the serializer does with changes (C++ `vrpn_SerializerPolicy`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SerializerPolicy {
    /// Take every change.
    #[default]
    Accept,
    /// Ignore changes from the other side.
    DenyRemote,
    /// Ignore local changes, take the other side's.
    DenyLocal,
    /// Ask the callback given to [`SharedObject::set_policy_callback`] about each change
    /// from the other side.
    Callback,
}

/// A change as the callbacks see it.
#[derive(Clone, Debug, PartialEq)]
pub struct SharedChange<V> {
    /// The new value.
    pub value: V,
    /// The time of the change (the value's version).
    pub when: TimeVal,
    /// True when it was set on this side.
    pub is_local: bool,
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for i32 {}
    impl Sealed for f64 {}
    impl Sealed for String {}
}

/// A type a shared object can hold: `i32`, `f64` or `String`.
pub trait SharedValue: Clone + PartialEq + std::fmt::Debug + sealed::Sealed + 'static {
    /// The type word in the object's sender names.
    const TYPE_WORD: &'static str;
    /// Encodes an update into `out` (1024 bytes); returns its length.
    fn encode(&self, when: TimeVal, out: &mut [u8]) -> usize;
    /// Decodes an update.
    fn decode(payload: &[u8]) -> Option<(Self, TimeVal)>;
    /// Checks a value before it is set locally.
    fn check(&self) -> Result<(), Error> {
        Ok(())
    }
}

impl SharedValue for i32 {
    const TYPE_WORD: &'static str = codec::INT32;
    fn encode(&self, when: TimeVal, out: &mut [u8]) -> usize {
        IntUpdate { value: *self, when }.encode(out)
    }
    fn decode(payload: &[u8]) -> Option<(i32, TimeVal)> {
        IntUpdate::decode(payload).ok().map(|u| (u.value, u.when))
    }
}

impl SharedValue for f64 {
    const TYPE_WORD: &'static str = codec::FLOAT64;
    fn encode(&self, when: TimeVal, out: &mut [u8]) -> usize {
        FloatUpdate { value: *self, when }.encode(out)
    }
    fn decode(payload: &[u8]) -> Option<(f64, TimeVal)> {
        FloatUpdate::decode(payload).ok().map(|u| (u.value, u.when))
    }
}

impl SharedValue for String {
    const TYPE_WORD: &'static str = codec::STRING;
    fn encode(&self, when: TimeVal, out: &mut [u8]) -> usize {
        StringUpdate {
            value: self.as_bytes(),
            when,
        }
        .encode(out)
    }
    fn decode(payload: &[u8]) -> Option<(String, TimeVal)> {
        StringUpdate::decode(payload)
            .ok()
            .map(|u| (String::from_utf8_lossy(u.value).into_owned(), u.when))
    }
    fn check(&self) -> Result<(), Error> {
        if self.len() > MAX_STRING_LEN || self.contains('\0') {
            return Err(Error::InvalidArgument(format!(
                "a shared string holds at most {MAX_STRING_LEN} bytes and no NUL"
            )));
        }
        Ok(())
    }
}

/// A shared `i32` (C++ `vrpn_Shared_int32_Server` / `_Remote`).
pub type SharedInt32 = SharedObject<i32>;
/// A shared `f64` (C++ `vrpn_Shared_float64_Server` / `_Remote`).
pub type SharedFloat64 = SharedObject<f64>;
/// A shared string (C++ `vrpn_Shared_String_Server` / `_Remote`).
pub type SharedString = SharedObject<String>;

#[derive(Clone, Copy, Debug)]
struct Ids {
    me: SenderId,
    peer: SenderId,
    update: TypeId,
    request: TypeId,
    grant: TypeId,
    assume: TypeId,
}

type PolicyCallback<V> = Box<dyn FnMut(&V, TimeVal) -> bool>;

struct Inner<V: SharedValue> {
    name: String,
    is_server: bool,
    mode: SharedMode,
    ids: Ids,
    value: RefCell<V>,
    last_update: Cell<TimeVal>,
    is_serializer: Cell<bool>,
    negotiating: Cell<bool>,
    policy: Cell<SerializerPolicy>,
    policy_callback: RefCell<Option<PolicyCallback<V>>>,
    changes: CallbackList<SharedChange<V>>,
    deferred: CallbackList<()>,
}

impl<V: SharedValue> Inner<V> {
    fn pack(&self, conn: &Connection, type_id: TypeId, payload: &[u8]) {
        let _ = conn.pack_message(
            self.last_update.get(),
            type_id,
            self.ids.me,
            payload,
            class::RELIABLE,
        );
    }

    fn send_update(&self, conn: &Connection, value: &V, when: TimeVal) {
        let mut buf = [0u8; 1024];
        let n = value.encode(when, &mut buf);
        self.pack(conn, self.ids.update, &buf[..n]);
    }

    fn should_accept(&self, value: &V, when: TimeVal, is_local: bool) -> bool {
        if self.mode.ignore_idempotent && *value == *self.value.borrow() {
            return false;
        }
        let last = self.last_update.get();
        if self.mode.ignore_old && when <= last {
            // An equal time: a serializer may still take its own change.
            if when != last || (!self.is_serializer.get() && is_local) {
                return false;
            }
        }
        if !self.mode.defer_updates {
            return true;
        }
        if !self.is_serializer.get() {
            if is_local {
                self.deferred.call(&());
                return false;
            }
            return true;
        }
        if is_local {
            return self.policy.get() != SerializerPolicy::DenyLocal;
        }
        match self.policy.get() {
            SerializerPolicy::Accept | SerializerPolicy::DenyLocal => true,
            SerializerPolicy::DenyRemote => false,
            SerializerPolicy::Callback => match self.policy_callback.try_borrow_mut() {
                Ok(mut cb) => cb.as_mut().is_some_and(|f| f(value, when)),
                Err(_) => false,
            },
        }
    }

    fn should_send(&self, is_local: bool, accepted: bool) -> bool {
        if accepted && is_local {
            return true;
        }
        if !self.mode.defer_updates {
            return false;
        }
        let serializer = self.is_serializer.get();
        (!serializer && is_local) || (serializer && !is_local && accepted)
    }

    fn set(&self, conn: &Connection, value: V, when: TimeVal, is_local: bool) {
        let accepted = self.should_accept(&value, when, is_local);
        if accepted {
            *self.value.borrow_mut() = value.clone();
            self.last_update.set(when);
        }
        // The update goes on the network before the callbacks (which may set again).
        if self.should_send(is_local, accepted) {
            self.send_update(conn, &value, when);
        }
        if accepted {
            self.changes.call(&SharedChange {
                value,
                when,
                is_local,
            });
        }
    }

    fn handle_update(&self, conn: &Connection, payload: &[u8]) {
        let Some((value, when)) = V::decode(payload) else {
            return;
        };
        // The echo of the value this side holds: nothing changes, and answering it could
        // bounce an update between two serializers forever.
        if when == self.last_update.get() && value == *self.value.borrow() {
            return;
        }
        self.set(conn, value, when, false);
    }
}

/// One side of a shared value of type `V` ([`SharedInt32`], [`SharedFloat64`],
/// [`SharedString`]).
pub struct SharedObject<V: SharedValue> {
    conn: Connection,
    inner: Rc<Inner<V>>,
    handlers: Vec<HandlerId>,
}

impl<V: SharedValue> Drop for SharedObject<V> {
    fn drop(&mut self) {
        for h in self.handlers.drain(..) {
            self.conn.remove_handler(h);
        }
    }
}

impl<V: SharedValue> SharedObject<V> {
    /// The server side of the object `name` on `conn`, holding `value` at first. The server
    /// is the serializer.
    pub fn server(
        name: &str,
        conn: &Connection,
        value: V,
        mode: SharedMode,
    ) -> Result<Self, Error> {
        Self::make(name, conn, value, mode, true)
    }

    /// A remote side of the object `name` on `conn` (a client connection to the server).
    pub fn remote(
        name: &str,
        conn: &Connection,
        value: V,
        mode: SharedMode,
    ) -> Result<Self, Error> {
        Self::make(name, conn, value, mode, false)
    }

    /// A remote side of `Name@location`, opening (or sharing) the connection.
    pub fn open_remote(name: &str, value: V, mode: SharedMode) -> Result<Self, Error> {
        let parsed = DeviceName::parse_remote(name)?;
        let conn = Connection::open_location(&parsed)?;
        Self::remote(&parsed.device, &conn, value, mode)
    }

    fn make(
        name: &str,
        conn: &Connection,
        value: V,
        mode: SharedMode,
        is_server: bool,
    ) -> Result<Self, Error> {
        value.check()?;
        let server = conn.register_sender(&codec::server_sender(V::TYPE_WORD, name))?;
        let peer = conn.register_sender(&codec::peer_sender(V::TYPE_WORD, name))?;
        let (me, other) = if is_server {
            (server, peer)
        } else {
            (peer, server)
        };
        let ids = Ids {
            me,
            peer: other,
            update: conn.register_type(codec::UPDATE)?,
            request: conn.register_type(codec::REQUEST_SERIALIZER)?,
            grant: conn.register_type(codec::GRANT_SERIALIZER)?,
            assume: conn.register_type(codec::ASSUME_SERIALIZER)?,
        };
        let inner = Rc::new(Inner {
            name: name.to_string(),
            is_server,
            mode,
            ids,
            value: RefCell::new(value),
            last_update: Cell::new(conn.now().wall),
            is_serializer: Cell::new(is_server),
            negotiating: Cell::new(false),
            policy: Cell::new(SerializerPolicy::Accept),
            policy_callback: RefCell::new(None),
            changes: CallbackList::default(),
            deferred: CallbackList::default(),
        });
        let from_peer = SenderFilter::Only(ids.peer);
        let mut handlers = Vec::new();
        let i = inner.clone();
        handlers.push(conn.register_handler(ids.update, from_peer, move |m| {
            i.handle_update(m.connection(), m.payload);
        }));
        let i = inner.clone();
        handlers.push(conn.register_handler(ids.request, from_peer, move |m| {
            // C++ grants whenever it is not negotiating already (its serializer test is
            // always true).
            if i.negotiating.replace(true) {
                return;
            }
            i.pack(m.connection(), i.ids.grant, &[]);
        }));
        let i = inner.clone();
        handlers.push(conn.register_handler(ids.grant, from_peer, move |m| {
            i.is_serializer.set(true);
            i.negotiating.set(false);
            i.pack(m.connection(), i.ids.assume, &[]);
        }));
        let i = inner.clone();
        handlers.push(conn.register_handler(ids.assume, from_peer, move |_| {
            i.is_serializer.set(false);
            i.negotiating.set(false);
        }));
        let (i, weak) = (inner.clone(), conn.downgrade());
        handlers.push(conn.on_event(ConnectionEvent::GotConnection, move || {
            // Give the new peer the current value (C++ means to, but registers this for a
            // sender that never sends the event).
            let send = i.is_serializer.get() || (!i.mode.defer_updates && i.is_server);
            if let (true, Some(c)) = (send, weak.upgrade()) {
                let v = i.value.borrow().clone();
                i.send_update(&c, &v, i.last_update.get());
            }
        }));
        Ok(SharedObject {
            conn: conn.clone(),
            inner,
            handlers,
        })
    }

    /// The object's name.
    pub fn name(&self) -> &str {
        &self.inner.name
    }

    /// True for the server side.
    pub fn is_server(&self) -> bool {
        self.inner.is_server
    }

    /// The connection it lives on.
    pub fn connection(&self) -> &Connection {
        &self.conn
    }

    /// The value.
    pub fn value(&self) -> V {
        self.inner.value.borrow().clone()
    }

    /// The time of the value's last change.
    pub fn last_update(&self) -> TimeVal {
        self.inner.last_update.get()
    }

    /// The mode.
    pub fn mode(&self) -> SharedMode {
        self.inner.mode
    }

    /// True while this side is the serializer.
    pub fn is_serializer(&self) -> bool {
        self.inner.is_serializer.get()
    }

    /// Sets the value now (C++ `operator=`).
    pub fn set(&self, value: V) -> Result<(), Error> {
        self.set_at(value, self.conn.now().wall)
    }

    /// Sets the value with the time of the change `when`. Whether it is taken here, sent,
    /// or forwarded to the serializer follows the mode; the callbacks run when it is taken.
    pub fn set_at(&self, value: V, when: TimeVal) -> Result<(), Error> {
        value.check()?;
        self.inner.set(&self.conn, value, when, true);
        Ok(())
    }

    /// Asks the other side for the serializer role (serialized mode).
    pub fn become_serializer(&self) {
        if self.inner.negotiating.replace(true) {
            return;
        }
        self.inner.pack(&self.conn, self.inner.ids.request, &[]);
    }

    /// How the serializer treats changes.
    pub fn set_policy(&self, policy: SerializerPolicy) {
        self.inner.policy.set(policy);
    }

    /// Sets [`SerializerPolicy::Callback`] with `f`, which returns true to take a change
    /// from the other side.
    pub fn set_policy_callback(&self, f: impl FnMut(&V, TimeVal) -> bool + 'static) {
        *self.inner.policy_callback.borrow_mut() = Some(Box::new(f));
        self.inner.policy.set(SerializerPolicy::Callback);
    }

    /// Calls `f` with every change taken, local or not.
    pub fn on_change(&self, f: impl FnMut(&SharedChange<V>) + 'static) -> HandlerId {
        self.inner.changes.add(f)
    }

    /// Calls `f` when a local change was sent to the serializer instead of being taken
    /// (C++ `registerDeferredUpdateCallback`).
    pub fn on_deferred_update(&self, mut f: impl FnMut() + 'static) -> HandlerId {
        self.inner.deferred.add(move |_| f())
    }

    /// Removes a callback an `on_*` returned.
    pub fn remove_callback(&self, id: HandlerId) -> bool {
        self.inner.changes.remove(id) || self.inner.deferred.remove(id)
    }

    /// Services the connection.
    pub fn mainloop(&self) -> Result<(), Error> {
        self.conn.mainloop()
    }
}
