//! A whole-file summary: per device and type the count and rate, the time span, system entries.

use std::path::PathBuf;

use super::decode::Decoded;
use super::walk::{Record, Walk};
use crate::log::format::SystemEntry;
use crate::log::reader::{LogError, LogReader};
use crate::time::TimeVal;

/// Count and time span of one message type from one sender.
#[derive(Clone, Debug, PartialEq)]
pub struct TypeStats {
    /// Type name (`<type N>` when undescribed).
    pub name: String,
    /// Messages.
    pub count: u64,
    /// Lowest timestamp.
    pub first: TimeVal,
    /// Highest timestamp.
    pub last: TimeVal,
}

impl TypeStats {
    /// Average rate in messages per second between this stream's lowest and highest
    /// timestamps: `(count − 1) / (last − first)`. `None` with fewer than two messages or a
    /// zero span.
    pub fn rate(&self) -> Option<f64> {
        let span = self.last.seconds_since(self.first);
        (self.count >= 2 && span > 0.0).then(|| (self.count - 1) as f64 / span)
    }
}

/// The message types one sender sent, in order of first appearance.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceStats {
    /// Sender name (`<sender N>` when undescribed).
    pub name: String,
    /// Per type.
    pub types: Vec<TypeStats>,
}

impl DeviceStats {
    /// Messages of all types.
    pub fn total(&self) -> u64 {
        self.types.iter().map(|t| t.count).sum()
    }
}

/// System entries by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SystemCounts {
    /// Type −1.
    pub sender_descriptions: u64,
    /// Type −2.
    pub type_descriptions: u64,
    /// Type −3.
    pub udp_descriptions: u64,
    /// Type −4.
    pub log_descriptions: u64,
    /// Type −5.
    pub disconnects: u64,
    /// Other negative types.
    pub unknown: u64,
    /// System entries whose payload does not decode.
    pub malformed: u64,
}

impl SystemCounts {
    /// All system entries.
    pub fn total(&self) -> u64 {
        self.sender_descriptions
            + self.type_descriptions
            + self.udp_descriptions
            + self.log_descriptions
            + self.disconnects
            + self.unknown
            + self.malformed
    }
}

/// What a whole log holds, with the time bases a replay uses (first and last user message).
#[derive(Debug)]
pub struct Summary {
    /// The file.
    pub path: PathBuf,
    /// File size in bytes.
    pub file_len: u64,
    /// Cookie version text, e.g. `07.38`.
    pub cookie_version: String,
    /// The cookie's log-mode digit.
    pub cookie_log_mode: u8,
    /// Whole entries read.
    pub entries: u64,
    /// User messages (type ≥ 0) among them.
    pub user_messages: u64,
    /// Lowest user timestamp (C++ `get_lowest_user_timestamp`).
    pub lowest_user_time: Option<TimeVal>,
    /// Highest user timestamp (C++ `get_highest_user_timestamp`).
    pub highest_user_time: Option<TimeVal>,
    /// User messages stamped 0.000000 (a device that never set its timestamp).
    pub zero_time_user_messages: u64,
    /// Lowest non-zero user timestamp.
    pub lowest_nonzero_user_time: Option<TimeVal>,
    /// User messages of a known type whose payload does not decode.
    pub malformed_user_messages: u64,
    /// Senders of user messages, in order of first appearance.
    pub devices: Vec<DeviceStats>,
    /// System entries.
    pub system: SystemCounts,
    /// Why reading stopped before the end of the file, if it did.
    pub damage: Option<LogError>,
}

impl Summary {
    /// Reads every whole entry of `reader`.
    pub fn compute(reader: &LogReader) -> Summary {
        let mut s = Summary {
            path: reader.path().to_owned(),
            file_len: reader.len(),
            cookie_version: reader.cookie().version(),
            cookie_log_mode: reader.cookie().log_mode,
            entries: 0,
            user_messages: 0,
            lowest_user_time: None,
            highest_user_time: None,
            zero_time_user_messages: 0,
            lowest_nonzero_user_time: None,
            malformed_user_messages: 0,
            devices: Vec::new(),
            system: SystemCounts::default(),
            damage: None,
        };
        let mut walk = Walk::new(reader);
        while let Some(rec) = walk.next_record() {
            let rec = match rec {
                Ok(r) => r,
                Err(e) => {
                    s.damage = Some(e);
                    break;
                }
            };
            s.entries += 1;
            if rec.entry.is_system() {
                let c = &mut s.system;
                match &rec.decoded {
                    Decoded::System(SystemEntry::SenderDescription { .. }) => {
                        c.sender_descriptions += 1
                    }
                    Decoded::System(SystemEntry::TypeDescription { .. }) => {
                        c.type_descriptions += 1
                    }
                    Decoded::System(SystemEntry::UdpDescription { .. }) => c.udp_descriptions += 1,
                    Decoded::System(SystemEntry::LogDescription { .. }) => c.log_descriptions += 1,
                    Decoded::System(SystemEntry::Disconnect) => c.disconnects += 1,
                    Decoded::System(SystemEntry::Unknown(_)) => c.unknown += 1,
                    _ => c.malformed += 1,
                }
                continue;
            }
            s.add_user(&rec);
        }
        s
    }

    fn add_user(&mut self, rec: &Record<'_, '_>) {
        let t = rec.entry.time();
        self.user_messages += 1;
        self.lowest_user_time = Some(self.lowest_user_time.map_or(t, |l| l.min(t)));
        self.highest_user_time = Some(self.highest_user_time.map_or(t, |h| h.max(t)));
        if t == TimeVal::ZERO {
            self.zero_time_user_messages += 1;
        } else {
            self.lowest_nonzero_user_time =
                Some(self.lowest_nonzero_user_time.map_or(t, |l| l.min(t)));
        }
        if matches!(rec.decoded, Decoded::Malformed { .. }) {
            self.malformed_user_messages += 1;
        }
        let sender = rec.sender_label();
        let type_name = rec.type_label();
        let dev = match self.devices.iter_mut().position(|d| d.name == sender) {
            Some(i) => &mut self.devices[i],
            None => {
                self.devices.push(DeviceStats {
                    name: sender,
                    types: Vec::new(),
                });
                self.devices.last_mut().expect("just pushed")
            }
        };
        match dev.types.iter_mut().find(|ts| ts.name == type_name) {
            Some(ts) => {
                ts.count += 1;
                ts.first = ts.first.min(t);
                ts.last = ts.last.max(t);
            }
            None => dev.types.push(TypeStats {
                name: type_name,
                count: 1,
                first: t,
                last: t,
            }),
        }
    }

    /// Highest − lowest user timestamp (C++ `get_length`); `None` without user messages.
    pub fn duration(&self) -> Option<TimeVal> {
        Some(TimeVal::from_micros(
            self.highest_user_time?.as_micros() - self.lowest_user_time?.as_micros(),
        ))
    }

    /// Messages of type `type_name` from `device`, if it sent any.
    pub fn count(&self, device: &str, type_name: &str) -> Option<u64> {
        self.devices
            .iter()
            .find(|d| d.name == device)?
            .types
            .iter()
            .find(|t| t.name == type_name)
            .map(|t| t.count)
    }
}

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "file: {} ({} bytes)", self.path.display(), self.file_len)?;
        writeln!(
            f,
            "cookie: vrpn: ver. {}, log mode {}",
            self.cookie_version, self.cookie_log_mode
        )?;
        writeln!(
            f,
            "entries: {} whole ({} user messages, {} system messages)",
            self.entries,
            self.user_messages,
            self.system.total()
        )?;
        match (
            self.lowest_user_time,
            self.highest_user_time,
            self.duration(),
        ) {
            (Some(lo), Some(hi), Some(d)) => {
                writeln!(f, "first user message: {lo}")?;
                writeln!(f, "last user message: {hi}")?;
                writeln!(f, "duration: {d} s")?;
            }
            _ => writeln!(f, "duration: - (no user messages)")?,
        }
        if self.zero_time_user_messages > 0 {
            write!(
                f,
                "note: {} user messages carry a zero timestamp",
                self.zero_time_user_messages
            )?;
            match (self.lowest_nonzero_user_time, self.highest_user_time) {
                (Some(lo), Some(hi)) => writeln!(
                    f,
                    "; without them the first is {lo} and the duration {} s",
                    TimeVal::from_micros(hi.as_micros() - lo.as_micros())
                )?,
                _ => writeln!(f)?,
            }
        }
        if self.malformed_user_messages > 0 {
            writeln!(
                f,
                "note: {} user messages of known types do not decode",
                self.malformed_user_messages
            )?;
        }
        writeln!(f, "devices: {}", self.devices.len())?;
        for d in &self.devices {
            writeln!(f, "  device {} ({} messages)", d.name, d.total())?;
            for t in &d.types {
                let rate = match t.rate() {
                    Some(r) => format!("{r:.3}/s"),
                    None => "-".to_owned(),
                };
                writeln!(f, "    {:>8}  {:>12}  {}", t.count, rate, t.name)?;
            }
        }
        let c = &self.system;
        writeln!(f, "system messages: {}", c.total())?;
        writeln!(f, "    {:>8}  sender descriptions", c.sender_descriptions)?;
        writeln!(f, "    {:>8}  type descriptions", c.type_descriptions)?;
        writeln!(f, "    {:>8}  UDP descriptions", c.udp_descriptions)?;
        writeln!(f, "    {:>8}  log descriptions", c.log_descriptions)?;
        writeln!(f, "    {:>8}  disconnects", c.disconnects)?;
        if c.unknown > 0 {
            writeln!(f, "    {:>8}  unknown system types", c.unknown)?;
        }
        if c.malformed > 0 {
            writeln!(f, "    {:>8}  malformed", c.malformed)?;
        }
        if let Some(e) = &self.damage {
            writeln!(f, "damaged tail: {e}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_log::sample;
    use super::*;
    use crate::wire::payload::{analog, tracker};

    #[test]
    fn summary_counts_rates_and_times() {
        let r = sample().reader();
        let s = Summary::compute(&r);
        assert!(s.damage.is_none());
        assert_eq!(s.entries, 12);
        assert_eq!(s.user_messages, 7);
        assert_eq!(s.system.type_descriptions, 3);
        assert_eq!(s.system.sender_descriptions, 2);
        assert_eq!(s.count("Tracker0", tracker::POS_QUAT), Some(3));
        assert_eq!(s.count("Button0", analog::CHANNEL), Some(2));
        assert_eq!(s.count("Tracker0", "<type 99>"), Some(1));
        assert_eq!(s.count("Nobody", tracker::POS_QUAT), None);
        assert_eq!(s.lowest_user_time, Some(TimeVal::new(10, 0)));
        assert_eq!(s.highest_user_time, Some(TimeVal::new(11, 0)));
        assert_eq!(s.duration(), Some(TimeVal::new(1, 0)));
        let poses = &s.devices[0].types[0];
        assert_eq!(poses.rate(), Some(2.0));
        assert_eq!(s.devices[1].types[0].rate(), None);
        let text = s.to_string();
        assert!(text.contains("duration: 1.000000 s"), "{text}");
        assert!(text.contains("  device Tracker0 (4 messages)"), "{text}");
        assert!(
            text.contains("       3       2.000/s  vrpn_Tracker Pos_Quat"),
            "{text}"
        );
    }

    #[test]
    fn summary_keeps_whole_entries_of_a_cut_file() {
        let b = sample();
        let cut = b.0[..b.0.len() - 5].to_vec();
        let last = b.0.len() - 26; // the 2-byte raw entry starts here
        let r = LogReader::from_bytes(cut, "cut.vrpn").unwrap();
        let s = Summary::compute(&r);
        assert_eq!(s.entries, 11);
        assert_eq!(s.count("Tracker0", tracker::POS_QUAT), Some(3));
        let e = s.damage.as_ref().unwrap();
        assert_eq!(e.offset(), Some(last));
        assert!(s.to_string().contains(&format!(
            "damaged tail: cut.vrpn: byte {last}: file ends inside"
        )));
    }

    #[test]
    fn zero_timestamps_are_noted() {
        let mut b = sample();
        b.entry(5, 2, TimeVal::ZERO, &[0, 0, 0, 0, 0, 0, 0, 0]);
        let s = Summary::compute(&b.reader());
        assert_eq!(s.zero_time_user_messages, 1);
        assert_eq!(s.lowest_user_time, Some(TimeVal::ZERO));
        assert_eq!(s.lowest_nonzero_user_time, Some(TimeVal::new(10, 0)));
        assert!(s
            .to_string()
            .contains("1 user messages carry a zero timestamp"));
    }
}
