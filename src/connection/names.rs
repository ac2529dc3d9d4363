//! The local sender and type names of one connection, numbered in registration order.

use std::collections::HashMap;

use crate::wire::{MAX_IDS, MAX_NAME_LEN};

/// Names registered on every connection before anything else (WIRE.md §9).
pub const CONTROL_SENDER: &str = "VRPN Control";
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
pub enum NameLimit {
    /// Longer than what a C++ peer accepts.
    TooLong(String),
    /// The table already holds 2000 names.
    TableFull,
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
        }
    }
}

/// One id space (senders or types).
#[derive(Default, Debug)]
pub(crate) struct NameTable {
    names: Vec<String>,
    ids: HashMap<String, i32>,
}

impl NameTable {
    pub(crate) fn get(&self, name: &str) -> Option<i32> {
        self.ids.get(name).copied()
    }

    /// Returns the id of `name`, registering it if needed; `true` when it is new.
    pub(crate) fn register(&mut self, name: &str) -> Result<(i32, bool), NameLimit> {
        if let Some(id) = self.get(name) {
            return Ok((id, false));
        }
        if name.len() > MAX_NAME_LEN {
            return Err(NameLimit::TooLong(name.to_string()));
        }
        if self.names.len() >= MAX_IDS {
            return Err(NameLimit::TableFull);
        }
        let id = self.names.len() as i32;
        self.names.push(name.to_string());
        self.ids.insert(name.to_string(), id);
        Ok((id, true))
    }

    pub(crate) fn name(&self, id: i32) -> Option<&str> {
        usize::try_from(id)
            .ok()
            .and_then(|i| self.names.get(i))
            .map(String::as_str)
    }

    pub(crate) fn iter(&self) -> impl Iterator<Item = (i32, &str)> {
        self.names
            .iter()
            .enumerate()
            .map(|(i, n)| (i as i32, n.as_str()))
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
        let _ = n.senders.register(CONTROL_SENDER);
        for t in [
            GOT_FIRST_CONNECTION,
            GOT_CONNECTION,
            DROPPED_CONNECTION,
            DROPPED_LAST_CONNECTION,
        ] {
            let _ = n.types.register(t);
        }
        n
    }
}
