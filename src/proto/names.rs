//! The local sender and type names of one connection, and what each peer holds of them.
//!
//! Names are bytes on the wire (a peer may send any byte but NUL), so they are kept as bytes
//! and shown lossily where text is needed. Each side numbers its names 0, 1, 2, … and a peer
//! can use at most [`MAX_IDS`] of each kind, so the id space is shared by everything a
//! connection knows. Two kinds of names live in it:
//!
//! - **registered** names, which this side's application and devices registered: permanent;
//! - **learned** names, which a peer described and this side did not know: C++ registers them
//!   for good, which lets one peer fill the table and lock every later client out. Here each
//!   learned name is held by the peers that described it and freed (its id reused) when the
//!   last of them leaves, and a peer that cannot get an id for a name is not dropped: its
//!   messages of that name are ignored, as messages of undescribed names are.

use std::collections::HashMap;

use crate::wire::{MAX_IDS, MAX_NAME_LEN};

/// Sender 0 on every VRPN connection.
pub const CONTROL_SENDER: &str = "VRPN Control";
/// True for the senders of the protocol itself ([`CONTROL_SENDER`] and the clock
/// synchronisation's), which no peer offers as a device.
pub(crate) fn is_protocol_sender(name: &[u8]) -> bool {
    name == CONTROL_SENDER.as_bytes() || name == crate::wire::payload::clock::SENDER.as_bytes()
}

/// Local event: the first peer finished its handshake.
pub const GOT_FIRST_CONNECTION: &str = "VRPN_Connection_Got_First_Connection";
/// Local event: a peer finished its handshake.
pub const GOT_CONNECTION: &str = "VRPN_Connection_Got_Connection";
/// Local event: a connected peer was lost.
pub const DROPPED_CONNECTION: &str = "VRPN_Connection_Dropped_Connection";
/// Local event: the last connected peer was lost.
pub const DROPPED_LAST_CONNECTION: &str = "VRPN_Connection_Dropped_Last_Connection";

/// Why a name could not be registered.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum NameLimit {
    /// Longer than what a C++ peer accepts.
    TooLong(String),
    /// The table already holds 2000 names.
    TableFull,
    /// The name contains a NUL byte, which the wire cannot carry.
    ContainsNul(String),
}

impl std::fmt::Display for NameLimit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NameLimit::TooLong(n) => write!(
                f,
                "name {n:?} is {} bytes; VRPN peers accept at most {MAX_NAME_LEN}",
                n.len()
            ),
            NameLimit::TableFull => write!(f, "a connection holds at most {MAX_IDS} names"),
            NameLimit::ContainsNul(n) => write!(f, "name {n:?} contains a NUL byte"),
        }
    }
}

impl std::error::Error for NameLimit {}

#[derive(Debug)]
struct Slot {
    name: Box<[u8]>,
    /// Registered by this side: never freed.
    registered: bool,
    /// Peers that described this name while it was only learned.
    holders: u32,
}

/// One id space (senders or types).
#[derive(Default, Debug)]
pub(crate) struct NameTable {
    slots: Vec<Option<Slot>>,
    ids: HashMap<Box<[u8]>, i32>,
    /// Ids of freed learned names, reused before the table grows.
    free: Vec<i32>,
    learned: usize,
}

impl NameTable {
    pub(crate) fn get(&self, name: &[u8]) -> Option<i32> {
        self.ids.get(name).copied()
    }

    fn check(name: &[u8]) -> Result<(), NameLimit> {
        if name.len() > MAX_NAME_LEN {
            return Err(NameLimit::TooLong(
                String::from_utf8_lossy(name).into_owned(),
            ));
        }
        if name.contains(&0) {
            return Err(NameLimit::ContainsNul(
                String::from_utf8_lossy(name).into_owned(),
            ));
        }
        Ok(())
    }

    fn insert(&mut self, name: &[u8], registered: bool) -> Result<i32, NameLimit> {
        let id = match self.free.pop() {
            Some(id) => id,
            None if self.slots.len() < MAX_IDS => {
                self.slots.push(None);
                (self.slots.len() - 1) as i32
            }
            None => return Err(NameLimit::TableFull),
        };
        self.slots[id as usize] = Some(Slot {
            name: name.into(),
            registered,
            holders: u32::from(!registered),
        });
        self.ids.insert(name.into(), id);
        if !registered {
            self.learned += 1;
        }
        Ok(id)
    }

    /// Registers `name` for this side (permanently). Returns its id and whether it is new to
    /// the table (then it must be described to every connected peer).
    pub(crate) fn register(&mut self, name: &[u8]) -> Result<(i32, bool), NameLimit> {
        if let Some(id) = self.get(name) {
            let slot = self.slots[id as usize].as_mut().expect("indexed name");
            if !slot.registered {
                slot.registered = true;
                self.learned -= 1;
            }
            return Ok((id, false));
        }
        Self::check(name)?;
        Ok((self.insert(name, true)?, true))
    }

    /// A peer described `name`: its id, whether the name is new to the table (to be described
    /// to every peer, as C++ does), and whether the peer now holds it (it must call
    /// [`release`](Self::release) once when it leaves).
    ///
    /// `may_add` says whether the peer may introduce one more learned name.
    pub(crate) fn learn(
        &mut self,
        name: &[u8],
        may_add: bool,
    ) -> Result<(i32, bool, bool), NameLimit> {
        if let Some(id) = self.get(name) {
            let slot = self.slots[id as usize].as_mut().expect("indexed name");
            if slot.registered {
                return Ok((id, false, false));
            }
            slot.holders += 1;
            return Ok((id, false, true));
        }
        Self::check(name)?;
        if !may_add {
            return Err(NameLimit::TableFull);
        }
        Ok((self.insert(name, false)?, true, true))
    }

    /// A peer that held `id` left: the name is freed when no peer holds it any more and this
    /// side never registered it.
    pub(crate) fn release(&mut self, id: i32) {
        let Some(Some(slot)) = usize::try_from(id).ok().and_then(|i| self.slots.get_mut(i)) else {
            return;
        };
        if slot.registered {
            return;
        }
        slot.holders = slot.holders.saturating_sub(1);
        if slot.holders == 0 {
            let slot = self.slots[id as usize].take().expect("checked above");
            self.ids.remove(&slot.name);
            self.free.push(id);
            self.learned -= 1;
        }
    }

    /// The name of `id`, as bytes.
    pub(crate) fn name(&self, id: i32) -> Option<&[u8]> {
        usize::try_from(id)
            .ok()
            .and_then(|i| self.slots.get(i))
            .and_then(Option::as_ref)
            .map(|s| &*s.name)
    }

    /// Whether this side registered `id` (rather than only learned it from peers).
    pub(crate) fn is_registered(&self, id: i32) -> bool {
        usize::try_from(id)
            .ok()
            .and_then(|i| self.slots.get(i))
            .and_then(Option::as_ref)
            .is_some_and(|s| s.registered)
    }

    /// Every name in id order.
    pub(crate) fn iter(&self) -> impl Iterator<Item = (i32, &[u8])> {
        self.slots
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.as_ref().map(|s| (i as i32, &*s.name)))
    }

    /// Names held only because peers described them.
    pub(crate) fn learned_count(&self) -> usize {
        self.learned
    }
}

/// Senders and types of one connection.
#[derive(Debug)]
pub(crate) struct Names {
    pub(crate) senders: NameTable,
    pub(crate) types: NameTable,
}

impl Names {
    /// The tables every VRPN connection starts with: sender 0 and the four event types 0–3.
    pub(crate) fn new() -> Names {
        let mut n = Names {
            senders: NameTable::default(),
            types: NameTable::default(),
        };
        let _ = n.senders.register(CONTROL_SENDER.as_bytes());
        for t in [
            GOT_FIRST_CONNECTION,
            GOT_CONNECTION,
            DROPPED_CONNECTION,
            DROPPED_LAST_CONNECTION,
        ] {
            let _ = n.types.register(t.as_bytes());
        }
        n
    }

    /// The table of senders (`true`) or types.
    pub(crate) fn table(&mut self, senders: bool) -> &mut NameTable {
        if senders {
            &mut self.senders
        } else {
            &mut self.types
        }
    }
}

/// A set of ids below [`MAX_IDS`], without allocation.
#[derive(Clone, Debug)]
pub(crate) struct IdSet([u64; MAX_IDS.div_ceil(64)]);

impl Default for IdSet {
    fn default() -> Self {
        IdSet([0; MAX_IDS.div_ceil(64)])
    }
}

impl IdSet {
    /// Adds `id`; returns whether it was absent.
    pub(crate) fn insert(&mut self, id: i32) -> bool {
        let i = id as usize;
        let (w, b) = (i / 64, 1u64 << (i % 64));
        let absent = self.0[w] & b == 0;
        self.0[w] |= b;
        absent
    }

    pub(crate) fn contains(&self, id: i32) -> bool {
        let i = id as usize;
        i < MAX_IDS && self.0[i / 64] & (1 << (i % 64)) != 0
    }

    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.0.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Empties the set, calling `f` with each id it held.
    pub(crate) fn drain(&mut self, mut f: impl FnMut(i32)) {
        for (w, word) in self.0.iter_mut().enumerate() {
            let mut bits = std::mem::take(word);
            while bits != 0 {
                let b = bits.trailing_zeros() as usize;
                f((w * 64 + b) as i32);
                bits &= bits - 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn learned_names_are_freed_with_their_last_holder() {
        let mut t = NameTable::default();
        let (a, new, held) = t.learn(b"junk", true).unwrap();
        assert!(new && held);
        let (a2, new, held) = t.learn(b"junk", true).unwrap();
        assert_eq!((a2, new, held), (a, false, true));
        t.release(a);
        assert_eq!(t.get(b"junk"), Some(a));
        t.release(a);
        assert_eq!(t.get(b"junk"), None);
        // The id is reused.
        let (b, _, _) = t.learn(b"other", true).unwrap();
        assert_eq!(b, a);
        assert_eq!(t.learned_count(), 1);
    }

    #[test]
    fn registered_names_are_never_freed() {
        let mut t = NameTable::default();
        let (a, _, _) = t.learn(b"Tracker0", true).unwrap();
        let (r, new) = t.register(b"Tracker0").unwrap();
        assert_eq!((r, new), (a, false));
        t.release(a);
        assert_eq!(t.get(b"Tracker0"), Some(a));
        assert_eq!(t.learned_count(), 0);
        // A peer describing a registered name does not hold it.
        assert_eq!(t.learn(b"Tracker0", false).unwrap(), (a, false, false));
    }

    #[test]
    fn non_utf8_names_are_bytes() {
        let mut t = NameTable::default();
        let (id, _, _) = t.learn(b"Tr\xe4cker", true).unwrap();
        assert_eq!(t.name(id), Some(&b"Tr\xe4cker"[..]));
        assert!(t.learn(b"a\0b", true).is_err());
    }

    #[test]
    fn a_full_table_refuses_without_losing_names() {
        let mut t = NameTable::default();
        for i in 0..MAX_IDS {
            t.learn(format!("n{i}").as_bytes(), true).unwrap();
        }
        assert_eq!(t.learn(b"one more", true), Err(NameLimit::TableFull));
        assert_eq!(t.register(b"app name"), Err(NameLimit::TableFull));
        assert!(t.learn(b"not allowed", false).is_err());
    }

    #[test]
    fn id_set_drains_in_order() {
        let mut s = IdSet::default();
        assert!(s.insert(5));
        assert!(!s.insert(5));
        s.insert(1999);
        s.insert(64);
        assert_eq!(s.len(), 3);
        let mut got = Vec::new();
        s.drain(|id| got.push(id));
        assert_eq!(got, vec![5, 64, 1999]);
        assert_eq!(s.len(), 0);
    }
}
