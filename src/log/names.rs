//! The `log id → name` tables a reader rebuilds from the description entries of a log
//!.

use super::format::{LogEntry, SystemEntry};
use crate::wire::{WireError, MAX_IDS};

/// Sender and type names described so far in a log, indexed by the log's ids.
///
/// Feed it every entry in file order with [`NameTable::observe`]: sender (−1) and type (−2)
/// descriptions fill it, a DISCONNECT (−5) clears it (the descriptions that follow describe the
/// next session). A later description of the same id replaces the earlier name, as in C++.
#[derive(Clone, Debug, Default)]
pub struct NameTable {
    senders: Vec<Option<String>>,
    types: Vec<Option<String>>,
}

/// What [`NameTable::observe`] did with an entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NameEvent {
    /// The entry changed nothing (a user message, UDP or log description, unknown system type).
    None,
    /// A sender id got a name.
    SenderDescribed(i32),
    /// A type id got a name.
    TypeDescribed(i32),
    /// A DISCONNECT cleared both tables.
    Cleared,
}

impl NameTable {
    /// An empty table.
    pub fn new() -> NameTable {
        NameTable::default()
    }

    /// Applies one entry. A malformed description, or one whose id lies outside
    /// `0..MAX_IDS`, is reported and leaves the table unchanged.
    pub fn observe(&mut self, entry: &LogEntry<'_>) -> Result<NameEvent, WireError> {
        let Some(system) = entry.system() else {
            return Ok(NameEvent::None);
        };
        match system? {
            SystemEntry::SenderDescription { id, name } => {
                set(&mut self.senders, id, name)?;
                Ok(NameEvent::SenderDescribed(id))
            }
            SystemEntry::TypeDescription { id, name } => {
                set(&mut self.types, id, name)?;
                Ok(NameEvent::TypeDescribed(id))
            }
            SystemEntry::Disconnect => {
                self.clear();
                Ok(NameEvent::Cleared)
            }
            _ => Ok(NameEvent::None),
        }
    }

    /// Forgets every name (what a DISCONNECT entry or a replay reset does).
    pub fn clear(&mut self) {
        self.senders.clear();
        self.types.clear();
    }

    /// Name of the log's sender `id`, if described.
    pub fn sender_name(&self, id: i32) -> Option<&str> {
        get(&self.senders, id)
    }

    /// Name of the log's type `id`, if described.
    pub fn type_name(&self, id: i32) -> Option<&str> {
        get(&self.types, id)
    }

    /// Described senders, in id order.
    pub fn senders(&self) -> impl Iterator<Item = (i32, &str)> + '_ {
        iter(&self.senders)
    }

    /// Described types, in id order.
    pub fn types(&self) -> impl Iterator<Item = (i32, &str)> + '_ {
        iter(&self.types)
    }
}

fn set(table: &mut Vec<Option<String>>, id: i32, name: &str) -> Result<(), WireError> {
    if id < 0 || id as usize >= MAX_IDS {
        return Err(WireError::BadValue("described id"));
    }
    let i = id as usize;
    if table.len() <= i {
        table.resize(i + 1, None);
    }
    match &mut table[i] {
        Some(old) => {
            old.clear();
            old.push_str(name);
        }
        slot => *slot = Some(name.to_owned()),
    }
    Ok(())
}

fn get(table: &[Option<String>], id: i32) -> Option<&str> {
    usize::try_from(id)
        .ok()
        .and_then(|i| table.get(i))
        .and_then(|s| s.as_deref())
}

fn iter(table: &[Option<String>]) -> impl Iterator<Item = (i32, &str)> + '_ {
    table
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.as_deref().map(|s| (i as i32, s)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::format::{decode_entry, encode_entry};
    use crate::time::TimeVal;
    use crate::wire::system::encode_description;

    fn entry<'a>(buf: &'a mut [u8], type_id: i32, sender: i32, name: Option<&str>) -> LogEntry<'a> {
        let mut payload = [0u8; 128];
        let n = name.map_or(0, |s| encode_description(&mut payload, s));
        let len = encode_entry(buf, type_id, sender, TimeVal::ZERO, &payload[..n]).unwrap();
        decode_entry(&buf[..len], 24).unwrap()
    }

    #[test]
    fn descriptions_fill_and_disconnect_clears() {
        let mut t = NameTable::new();
        let mut b = [0u8; 256];
        let e = entry(&mut b, -1, 3, Some("Tracker0"));
        assert_eq!(t.observe(&e), Ok(NameEvent::SenderDescribed(3)));
        let e = entry(&mut b, -2, 4, Some("vrpn_Tracker Pos_Quat"));
        assert_eq!(t.observe(&e), Ok(NameEvent::TypeDescribed(4)));
        assert_eq!(t.sender_name(3), Some("Tracker0"));
        assert_eq!(t.sender_name(2), None);
        assert_eq!(t.sender_name(-1), None);
        assert_eq!(t.type_name(4), Some("vrpn_Tracker Pos_Quat"));
        assert_eq!(t.senders().collect::<Vec<_>>(), vec![(3, "Tracker0")]);
        let e = entry(&mut b, -1, 3, Some("Other"));
        t.observe(&e).unwrap();
        assert_eq!(t.sender_name(3), Some("Other"));
        let e = entry(&mut b, 4, 3, None);
        assert_eq!(t.observe(&e), Ok(NameEvent::None));
        let e = entry(&mut b, -5, 0, None);
        assert_eq!(t.observe(&e), Ok(NameEvent::Cleared));
        assert_eq!(t.sender_name(3), None);
        assert_eq!(t.type_name(4), None);
    }

    #[test]
    fn rejects_out_of_range_ids_and_bad_payloads() {
        let mut t = NameTable::new();
        let mut b = [0u8; 256];
        let e = entry(&mut b, -1, MAX_IDS as i32, Some("x"));
        assert!(t.observe(&e).is_err());
        let e = entry(&mut b, -2, -7, Some("x"));
        assert!(t.observe(&e).is_err());
        let e = entry(&mut b, -2, 1, None);
        assert!(t.observe(&e).is_err());
        assert_eq!(t.types().count(), 0);
    }
}
