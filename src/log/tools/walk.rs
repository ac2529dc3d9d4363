//! A walk over a log's entries that resolves names as a replaying reader does.

use super::decode::{system_type_name, Decoded};
use crate::log::format::LogEntry;
use crate::log::names::NameTable;
use crate::log::reader::{Entries, LogError, LogReader};

/// One entry with its names resolved and its payload decoded.
#[derive(Clone, Debug)]
pub struct Record<'w, 'a> {
    /// The entry as stored.
    pub entry: LogEntry<'a>,
    /// The sender's name; `None` for system entries and undescribed senders.
    pub sender: Option<&'w str>,
    /// The type's name; for system entries [`system_type_name`]; `None` for an undescribed
    /// user type.
    pub type_name: Option<&'w str>,
    /// The decoded payload.
    pub decoded: Decoded<'a>,
}

impl Record<'_, '_> {
    /// The sender's name, or `<sender N>` when it was never described (`-` for system
    /// entries).
    pub fn sender_label(&self) -> String {
        match self.sender {
            Some(s) => s.to_owned(),
            None if self.entry.is_system() => "-".to_owned(),
            None => format!("<sender {}>", self.entry.sender()),
        }
    }

    /// True for a user message whose [`Record::sender_label`] is `device`.
    pub fn is_from(&self, device: &str) -> bool {
        match self.sender {
            Some(s) => s == device,
            None => !self.entry.is_system() && self.sender_label() == device,
        }
    }

    /// The type's name, or `<type N>` when it was never described.
    pub fn type_label(&self) -> String {
        match self.type_name {
            Some(t) => t.to_owned(),
            None => format!("<type {}>", self.entry.type_id()),
        }
    }
}

/// Walks a log's entries in file order, keeping the name tables up to date.
///
/// A lending iterator: each [`Record`] borrows the walk (its names and its window onto the
/// file) until the next call.
#[derive(Debug)]
pub struct Walk<'a> {
    entries: Entries<'a>,
    names: NameTable,
}

impl<'a> Walk<'a> {
    /// Starts at the first entry with empty name tables.
    pub fn new(reader: &'a LogReader) -> Walk<'a> {
        Walk {
            entries: reader.entries(),
            names: NameTable::new(),
        }
    }

    /// The next entry, or the error that ends the walk (then `None`).
    pub fn next_record(&mut self) -> Option<Result<Record<'_, '_>, LogError>> {
        let entry = match self.entries.next_entry()? {
            Ok(e) => e,
            Err(e) => return Some(Err(e)),
        };
        // A malformed description changes nothing; the entry shows as malformed.
        let _ = self.names.observe(&entry);
        let (sender, type_name) = if entry.is_system() {
            (None, Some(system_type_name(entry.type_id())))
        } else {
            (
                self.names.sender_name(entry.sender()),
                self.names.type_name(entry.type_id()),
            )
        };
        let decoded = Decoded::entry(&entry, type_name);
        Some(Ok(Record {
            entry,
            sender,
            type_name,
            decoded,
        }))
    }

    /// The names as of the last entry returned.
    pub fn names(&self) -> &NameTable {
        &self.names
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_log::{pose, sample};
    use super::*;
    use crate::time::TimeVal;
    use crate::wire::payload::tracker;

    #[test]
    fn walk_resolves_names_and_disconnect_clears_them() {
        let mut b = sample();
        b.entry(-5, 0, TimeVal::new(12, 0), &[]);
        b.entry(4, 1, TimeVal::new(13, 0), &pose(0, 0.0));
        let r = b.reader();
        let mut w = Walk::new(&r);
        let mut seen = Vec::new();
        while let Some(rec) = w.next_record() {
            let rec = rec.unwrap();
            seen.push((rec.sender_label(), rec.type_label(), rec.decoded.kind()));
        }
        assert_eq!(seen[0], ("-".into(), "SENDER_DESCRIPTION".into(), "system"));
        assert_eq!(
            seen[5],
            ("Tracker0".into(), tracker::POS_QUAT.into(), "pose")
        );
        assert_eq!(seen[11], ("Tracker0".into(), "<type 99>".into(), "raw"));
        assert_eq!(seen[12], ("-".into(), "DISCONNECT".into(), "system"));
        assert_eq!(seen[13], ("<sender 1>".into(), "<type 4>".into(), "raw"));
    }
}
