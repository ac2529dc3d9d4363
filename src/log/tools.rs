//! Inspection tools over a log file, the library half of the `vrpn_log` program: a walk that
//! resolves names and decodes payloads ([`Walk`], [`Record`], [`Decoded`]), a whole-file
//! [`Summary`], one-line text and JSON renderings of an entry, and CSV export of one device's
//! reports ([`CsvKind`], [`plan_csv`], [`write_csv`]).
//!
//! Names are resolved the way a replaying reader resolves them (LOGFILE.md §1.3): through the
//! descriptions met so far in the file, in file order, with a DISCONNECT entry clearing them.
//! Every function stops at the first damaged entry and hands back the [`LogError`] (file, offset,
//! problem) alongside what it made of the whole entries before it.
//!
//! ```no_run
//! use vrpn::log::{LogReader, tools::Summary};
//!
//! let log = LogReader::open("server.vrpn")?;
//! let summary = Summary::compute(&log);
//! print!("{summary}");
//! println!("{:?} poses", summary.count("Tracker0", "vrpn_Tracker Pos_Quat"));
//! # Ok::<(), vrpn::log::LogError>(())
//! ```

use std::fmt::Write as _;
use std::io;
use std::path::PathBuf;

use super::format::{LogEntry, SystemEntry};
use super::names::NameTable;
use super::reader::{Entries, LogError, LogReader};
use crate::time::TimeVal;
use crate::wire::payload::{analog, analog_output, button, dial, force, poser, text, tracker};
use crate::wire::{system, WireError};

/// Bytes of an unknown payload shown in text output before it is cut short.
pub const TEXT_HEX_LIMIT: usize = 32;

/// A payload decoded according to its (resolved) type name.
#[derive(Clone, Debug, PartialEq)]
pub enum Decoded<'a> {
    /// `vrpn_Tracker Pos_Quat`.
    Pose {
        /// Sensor index.
        sensor: i32,
        /// Position `[x, y, z]`.
        pos: [f64; 3],
        /// Orientation `[x, y, z, w]`.
        quat: [f64; 4],
    },
    /// `vrpn_Tracker Velocity`.
    Velocity {
        /// Sensor index.
        sensor: i32,
        /// Linear velocity `[x, y, z]`.
        vel: [f64; 3],
        /// Rotation over `dt` seconds, `[x, y, z, w]`.
        quat: [f64; 4],
        /// Interval of `quat`, seconds.
        dt: f64,
    },
    /// `vrpn_Tracker Acceleration`.
    Acceleration {
        /// Sensor index.
        sensor: i32,
        /// Linear acceleration `[x, y, z]`.
        acc: [f64; 3],
        /// Change of the velocity quaternion over `dt`, `[x, y, z, w]`.
        quat: [f64; 4],
        /// Interval of `quat`, seconds.
        dt: f64,
    },
    /// A transform: `vrpn_Tracker To_Room` (no sensor), `vrpn_Tracker Unit_To_Sensor`, a
    /// poser pose request or a force device's `SCP`.
    Transform {
        /// Sensor index, where the message has one.
        sensor: Option<i32>,
        /// Translation `[x, y, z]`.
        pos: [f64; 3],
        /// Rotation `[x, y, z, w]`.
        quat: [f64; 4],
    },
    /// `vrpn_Tracker Workspace`.
    Workspace {
        /// Minimum corner.
        min: [f64; 3],
        /// Maximum corner.
        max: [f64; 3],
    },
    /// `vrpn_Tracker set_update_rate`.
    UpdateRate(f64),
    /// `vrpn_Button Change`.
    ButtonChange {
        /// Button index.
        button: i32,
        /// New state (0 released, 1 pressed).
        state: i32,
    },
    /// `vrpn_Button States`: every button's state.
    ButtonStates(Vec<i32>),
    /// `vrpn_Button Admin` (a mode request) or `vrpn_Button Alert` (a toggle event).
    ButtonMode {
        /// Button index (−99 = all).
        button: i32,
        /// Mode or event code (10 momentary, 20 toggle off, 21 toggle on).
        mode: i32,
    },
    /// `vrpn_Analog Channel`: the channel values.
    Analog(Vec<f64>),
    /// `vrpn_Analog_Output Change_request`.
    AnalogOutputSet {
        /// Channel index.
        channel: i32,
        /// Requested value.
        value: f64,
    },
    /// `vrpn_Analog_Output Change_Channels_request`: values for channels `0..n`.
    AnalogOutputChannels(Vec<f64>),
    /// `vrpn_Analog_Output Num_Channels_report`.
    AnalogOutputCount(i32),
    /// `vrpn_Dial update`.
    Dial {
        /// Dial index.
        dial: i32,
        /// Change in revolutions.
        change: f64,
    },
    /// `vrpn_Base text_message`.
    Text {
        /// 0 normal, 1 warning, 2 error.
        severity: u32,
        /// Sender-defined level.
        level: u32,
        /// The text, without its NUL (bytes as sent; usually ASCII).
        text: &'a [u8],
    },
    /// `vrpn_Base ping_message`.
    Ping,
    /// `vrpn_Base pong_message`.
    Pong,
    /// A poser velocity request.
    PoserVelocity {
        /// Linear velocity `[x, y, z]`.
        vel: [f64; 3],
        /// Rotation over `dt`, `[x, y, z, w]`.
        quat: [f64; 4],
        /// Interval of `quat`, seconds.
        dt: f64,
    },
    /// `vrpn_ForceDevice Force`.
    Force([f64; 3]),
    /// `vrpn_ForceDevice Force_Error`.
    ForceError(i32),
    /// A known request type that carries no payload (e.g. `Request_Tracker_To_Room`).
    Request,
    /// A system entry (negative type id).
    System(SystemEntry<'a>),
    /// A known type whose payload does not decode.
    Malformed {
        /// Why.
        error: WireError,
        /// The payload.
        payload: &'a [u8],
    },
    /// A type this tool does not decode (or an undescribed type id).
    Raw(&'a [u8]),
}

/// One rendered value of a [`Decoded`], for the text and JSON writers.
#[derive(Clone, Debug, PartialEq)]
pub enum Field<'v> {
    /// An integer.
    Int(i64),
    /// A float.
    Num(f64),
    /// Floats.
    Nums(&'v [f64]),
    /// Integers.
    Ints(&'v [i32]),
    /// Text.
    Str(&'v str),
    /// Owned text.
    String(String),
    /// Bytes shown as text (lossy UTF-8).
    Bytes(&'v [u8]),
    /// Bytes shown as hex (cut to [`TEXT_HEX_LIMIT`] bytes in text output).
    Hex(&'v [u8]),
}

impl<'a> Decoded<'a> {
    /// Decodes a user message's payload given its type name (`None`: undescribed type).
    ///
    /// Unknown types give [`Decoded::Raw`]; a known type with a bad payload gives
    /// [`Decoded::Malformed`]. Never panics.
    pub fn user(type_name: Option<&str>, payload: &'a [u8]) -> Decoded<'a> {
        let Some(name) = type_name else {
            return Decoded::Raw(payload);
        };
        match decode_known(name, payload) {
            Some(Ok(d)) => d,
            Some(Err(error)) => Decoded::Malformed { error, payload },
            None => Decoded::Raw(payload),
        }
    }

    /// Decodes any entry: system entries by their type id, user messages by `type_name`.
    pub fn entry(entry: &LogEntry<'a>, type_name: Option<&str>) -> Decoded<'a> {
        match entry.system() {
            Some(Ok(s)) => Decoded::System(s),
            Some(Err(error)) => Decoded::Malformed {
                error,
                payload: entry.payload,
            },
            None => Decoded::user(type_name, entry.payload),
        }
    }

    /// The `kind` value of the JSON output: `pose`, `velocity`, `acceleration`, `button`,
    /// `button_states`, `analog`, `dial`, `text`, `ping`, `pong`, `system`, `raw`, ….
    pub fn kind(&self) -> &'static str {
        match self {
            Decoded::Pose { .. } => "pose",
            Decoded::Velocity { .. } => "velocity",
            Decoded::Acceleration { .. } => "acceleration",
            Decoded::Transform { .. } => "transform",
            Decoded::Workspace { .. } => "workspace",
            Decoded::UpdateRate(_) => "update_rate",
            Decoded::ButtonChange { .. } => "button",
            Decoded::ButtonStates(_) => "button_states",
            Decoded::ButtonMode { .. } => "button_mode",
            Decoded::Analog(_) => "analog",
            Decoded::AnalogOutputSet { .. } => "analog_output",
            Decoded::AnalogOutputChannels(_) => "analog_output_channels",
            Decoded::AnalogOutputCount(_) => "analog_output_count",
            Decoded::Dial { .. } => "dial",
            Decoded::Text { .. } => "text",
            Decoded::Ping => "ping",
            Decoded::Pong => "pong",
            Decoded::PoserVelocity { .. } => "poser_velocity",
            Decoded::Force(_) => "force",
            Decoded::ForceError(_) => "force_error",
            Decoded::Request => "request",
            Decoded::System(_) => "system",
            Decoded::Malformed { .. } => "malformed",
            Decoded::Raw(_) => "raw",
        }
    }

    /// The decoded values as named fields, in output order.
    pub fn fields(&self) -> Vec<(&'static str, Field<'_>)> {
        use Field::*;
        match self {
            Decoded::Pose { sensor, pos, quat } => vec![
                ("sensor", Int(*sensor as i64)),
                ("pos", Nums(pos)),
                ("quat", Nums(quat)),
            ],
            Decoded::Velocity {
                sensor,
                vel,
                quat,
                dt,
            } => vec![
                ("sensor", Int(*sensor as i64)),
                ("vel", Nums(vel)),
                ("vel_quat", Nums(quat)),
                ("vel_quat_dt", Num(*dt)),
            ],
            Decoded::Acceleration {
                sensor,
                acc,
                quat,
                dt,
            } => vec![
                ("sensor", Int(*sensor as i64)),
                ("acc", Nums(acc)),
                ("acc_quat", Nums(quat)),
                ("acc_quat_dt", Num(*dt)),
            ],
            Decoded::Transform { sensor, pos, quat } => {
                let mut v = Vec::with_capacity(3);
                if let Some(s) = sensor {
                    v.push(("sensor", Int(*s as i64)));
                }
                v.push(("pos", Nums(pos)));
                v.push(("quat", Nums(quat)));
                v
            }
            Decoded::Workspace { min, max } => vec![("min", Nums(min)), ("max", Nums(max))],
            Decoded::UpdateRate(r) => vec![("rate", Num(*r))],
            Decoded::ButtonChange { button, state } => vec![
                ("button", Int(*button as i64)),
                ("state", Int(*state as i64)),
            ],
            Decoded::ButtonStates(s) => vec![("states", Ints(s))],
            Decoded::ButtonMode { button, mode } => {
                vec![("button", Int(*button as i64)), ("mode", Int(*mode as i64))]
            }
            Decoded::Analog(c) => vec![("channels", Nums(c))],
            Decoded::AnalogOutputSet { channel, value } => {
                vec![("channel", Int(*channel as i64)), ("value", Num(*value))]
            }
            Decoded::AnalogOutputChannels(c) => vec![("channels", Nums(c))],
            Decoded::AnalogOutputCount(n) => vec![("num_channels", Int(*n as i64))],
            Decoded::Dial { dial, change } => {
                vec![("dial", Int(*dial as i64)), ("change", Num(*change))]
            }
            Decoded::Text {
                severity,
                level,
                text,
            } => vec![
                (
                    "severity",
                    match text::severity_name(*severity) {
                        Some(n) => Str(n),
                        None => Int(*severity as i64),
                    },
                ),
                ("level", Int(*level as i64)),
                ("text", Bytes(text)),
            ],
            Decoded::Ping | Decoded::Pong | Decoded::Request => Vec::new(),
            Decoded::PoserVelocity { vel, quat, dt } => vec![
                ("vel", Nums(vel)),
                ("vel_quat", Nums(quat)),
                ("vel_quat_dt", Num(*dt)),
            ],
            Decoded::Force(f) => vec![("force", Nums(f))],
            Decoded::ForceError(c) => vec![("code", Int(*c as i64))],
            Decoded::System(s) => system_fields(s),
            Decoded::Malformed { error, payload } => vec![
                ("error", String(error.to_string())),
                ("len", Int(payload.len() as i64)),
                ("hex", Hex(payload)),
            ],
            Decoded::Raw(p) => vec![("len", Int(p.len() as i64)), ("hex", Hex(p))],
        }
    }
}

fn system_fields<'v>(s: &'v SystemEntry<'_>) -> Vec<(&'static str, Field<'v>)> {
    use Field::*;
    match s {
        SystemEntry::SenderDescription { id, name } => vec![
            ("system", Str("sender_description")),
            ("id", Int(*id as i64)),
            ("name", Str(name)),
        ],
        SystemEntry::TypeDescription { id, name } => vec![
            ("system", Str("type_description")),
            ("id", Int(*id as i64)),
            ("name", Str(name)),
        ],
        SystemEntry::UdpDescription { port, host } => vec![
            ("system", Str("udp_description")),
            ("port", Int(*port as i64)),
            ("host", Str(host)),
        ],
        SystemEntry::LogDescription { mode, names } => vec![
            ("system", Str("log_description")),
            ("mode", Int(*mode as i64)),
            ("incoming", Str(names.incoming)),
            ("outgoing", Str(names.outgoing)),
        ],
        SystemEntry::Disconnect => vec![("system", Str("disconnect"))],
        SystemEntry::Unknown(t) => vec![("system", Str("unknown")), ("id", Int(*t as i64))],
    }
}

/// Decodes the types this tool knows; `None` for any other name.
fn decode_known<'a>(name: &str, p: &'a [u8]) -> Option<Result<Decoded<'a>, WireError>> {
    use Decoded as D;
    let r = match name {
        tracker::POS_QUAT => tracker::PosQuat::decode(p).map(|m| D::Pose {
            sensor: m.sensor,
            pos: m.pos,
            quat: m.quat,
        }),
        tracker::VELOCITY => tracker::Velocity::decode(p).map(|m| D::Velocity {
            sensor: m.sensor,
            vel: m.vel,
            quat: m.vel_quat,
            dt: m.vel_quat_dt,
        }),
        tracker::ACCELERATION => tracker::Acceleration::decode(p).map(|m| D::Acceleration {
            sensor: m.sensor,
            acc: m.acc,
            quat: m.acc_quat,
            dt: m.acc_quat_dt,
        }),
        tracker::TO_ROOM => tracker::ToRoom::decode(p).map(|m| D::Transform {
            sensor: None,
            pos: m.pos,
            quat: m.quat,
        }),
        tracker::UNIT_TO_SENSOR => tracker::UnitToSensor::decode(p).map(|m| D::Transform {
            sensor: Some(m.sensor),
            pos: m.pos,
            quat: m.quat,
        }),
        tracker::WORKSPACE => tracker::Workspace::decode(p).map(|m| D::Workspace {
            min: m.min,
            max: m.max,
        }),
        tracker::SET_UPDATE_RATE => tracker::UpdateRate::decode(p).map(|m| D::UpdateRate(m.rate)),
        tracker::REQUEST_TRACKER_TO_ROOM
        | tracker::REQUEST_UNIT_TO_SENSOR
        | tracker::REQUEST_TRACKER_WORKSPACE
        | tracker::RESET_ORIGIN => Ok(D::Request),
        button::CHANGE => button::Change::decode(p).map(|m| D::ButtonChange {
            button: m.button,
            state: m.state,
        }),
        button::STATES => button::States::decode(p).map(|m| D::ButtonStates(m.as_slice().to_vec())),
        button::ADMIN => button::Admin::decode(p).map(|m| D::ButtonMode {
            button: m.button,
            mode: m.mode,
        }),
        button::ALERT => button::Alert::decode(p).map(|m| D::ButtonMode {
            button: m.button,
            mode: m.event,
        }),
        analog::CHANNEL => analog::Channels::decode(p).map(|m| D::Analog(m.as_slice().to_vec())),
        analog_output::CHANGE_REQUEST => {
            analog_output::ChangeRequest::decode(p).map(|m| D::AnalogOutputSet {
                channel: m.channel,
                value: m.value,
            })
        }
        analog_output::CHANGE_CHANNELS_REQUEST => analog_output::ChangeChannelsRequest::decode(p)
            .map(|m| D::AnalogOutputChannels(m.as_slice().to_vec())),
        analog_output::NUM_CHANNELS_REPORT => analog_output::NumChannelsReport::decode(p)
            .map(|m| D::AnalogOutputCount(m.num_channels)),
        dial::UPDATE => dial::Update::decode(p).map(|m| D::Dial {
            dial: m.dial,
            change: m.change,
        }),
        text::TEXT_MESSAGE => text::TextMessage::decode(p).map(|m| D::Text {
            severity: m.severity,
            level: m.level,
            text: m.text,
        }),
        text::PING_MESSAGE => Ok(D::Ping),
        text::PONG_MESSAGE => Ok(D::Pong),
        poser::REQUEST_POS_QUAT | poser::REQUEST_RELATIVE_POS_QUAT => poser::PoseRequest::decode(p)
            .map(|m| D::Transform {
                sensor: None,
                pos: m.pos,
                quat: m.quat,
            }),
        poser::REQUEST_VELOCITY | poser::REQUEST_RELATIVE_VELOCITY => {
            poser::VelocityRequest::decode(p).map(|m| D::PoserVelocity {
                vel: m.vel,
                quat: m.vel_quat,
                dt: m.vel_quat_dt,
            })
        }
        force::FORCE => force::Force::decode(p).map(|m| D::Force(m.force)),
        force::SCP => force::Scp::decode(p).map(|m| D::Transform {
            sensor: None,
            pos: m.pos,
            quat: m.quat,
        }),
        force::FORCE_ERROR => force::ForceError::decode(p).map(|m| D::ForceError(m.code)),
        _ => return None,
    };
    Some(r)
}

/// The name shown as the "type" of a system entry (as in the golden `.expected.json` files).
pub fn system_type_name(type_id: i32) -> &'static str {
    match type_id {
        system::SENDER_DESCRIPTION => "SENDER_DESCRIPTION",
        system::TYPE_DESCRIPTION => "TYPE_DESCRIPTION",
        system::UDP_DESCRIPTION => "UDP_DESCRIPTION",
        system::LOG_DESCRIPTION => "LOG_DESCRIPTION",
        system::DISCONNECT => "DISCONNECT",
        _ => "UNKNOWN_SYSTEM",
    }
}

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
/// A lending iterator: each [`Record`] borrows the walk's names until the next call.
#[derive(Clone, Debug)]
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
    pub fn next_record(&mut self) -> Option<Result<Record<'_, 'a>, LogError>> {
        let entry = match self.entries.next()? {
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

// ---------------------------------------------------------------------------------------------
// One-line renderings

fn json_num(out: &mut String, v: f64) {
    if v.is_finite() {
        let _ = write!(out, "{v:?}");
    } else {
        out.push_str("null");
    }
}

fn json_str(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if (c as u32) < 0x20 || c == '\u{7f}' => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

fn hex_into(out: &mut String, bytes: &[u8]) {
    for b in bytes {
        let _ = write!(out, "{b:02x}");
    }
}

fn json_field(out: &mut String, f: &Field<'_>) {
    match f {
        Field::Int(i) => {
            let _ = write!(out, "{i}");
        }
        Field::Num(v) => json_num(out, *v),
        Field::Nums(vs) => {
            out.push('[');
            for (i, v) in vs.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                json_num(out, *v);
            }
            out.push(']');
        }
        Field::Ints(vs) => {
            out.push('[');
            for (i, v) in vs.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                let _ = write!(out, "{v}");
            }
            out.push(']');
        }
        Field::Str(s) => json_str(out, s),
        Field::String(s) => json_str(out, s),
        Field::Bytes(b) => json_str(out, &String::from_utf8_lossy(b)),
        Field::Hex(b) => {
            out.push('"');
            hex_into(out, b);
            out.push('"');
        }
    }
}

fn text_field(out: &mut String, f: &Field<'_>) {
    match f {
        Field::Int(i) => {
            let _ = write!(out, "{i}");
        }
        Field::Num(v) => {
            let _ = write!(out, "{v}");
        }
        Field::Nums(vs) => {
            out.push('(');
            for (i, v) in vs.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                let _ = write!(out, "{v}");
            }
            out.push(')');
        }
        Field::Ints(vs) => {
            out.push('(');
            for (i, v) in vs.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                let _ = write!(out, "{v}");
            }
            out.push(')');
        }
        Field::Str(s) => {
            let _ = write!(out, "{s:?}");
        }
        Field::String(s) => out.push_str(s),
        Field::Bytes(b) => {
            let _ = write!(out, "{:?}", String::from_utf8_lossy(b));
        }
        Field::Hex(b) => {
            hex_into(out, &b[..b.len().min(TEXT_HEX_LIMIT)]);
            if b.len() > TEXT_HEX_LIMIT {
                out.push_str("...");
            }
        }
    }
}

/// Appends the one-line text form of a record (no newline):
/// `OFFSET  SEC.USEC  SENDER  TYPE  field value …`.
pub fn format_text(out: &mut String, rec: &Record<'_, '_>) {
    let _ = write!(
        out,
        "{:>8}  {}  {}  {}",
        rec.entry.offset,
        rec.entry.time(),
        rec.sender_label(),
        rec.type_label()
    );
    for (key, field) in rec.decoded.fields() {
        if key == "system" {
            continue; // the type column already says which
        }
        let _ = write!(out, "  {key} ");
        text_field(out, &field);
    }
}

/// Appends the one-line JSON form of a record (no newline): keys `offset`, `time` (exact
/// `sec.usec` decimal), `sec`, `usec`, `sender` (null when unnamed), `sender_id`, `type`,
/// `type_id`, `kind`, then the decoded fields of [`Decoded::fields`].
pub fn format_json(out: &mut String, rec: &Record<'_, '_>) {
    let e = &rec.entry;
    let t = e.time();
    let _ = write!(
        out,
        "{{\"offset\":{},\"time\":{},\"sec\":{},\"usec\":{},\"sender\":",
        e.offset, t, t.sec, t.usec
    );
    match rec.sender {
        Some(s) => json_str(out, s),
        None => out.push_str("null"),
    }
    let _ = write!(out, ",\"sender_id\":{},\"type\":", e.sender());
    match rec.type_name {
        Some(s) => json_str(out, s),
        None => out.push_str("null"),
    }
    let _ = write!(
        out,
        ",\"type_id\":{},\"kind\":\"{}\"",
        e.type_id(),
        rec.decoded.kind()
    );
    for (key, field) in rec.decoded.fields() {
        let _ = write!(out, ",\"{key}\":");
        json_field(out, &field);
    }
    out.push('}');
}

// ---------------------------------------------------------------------------------------------
// Summary

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

/// What a whole log holds (LOGFILE.md §6.3 time bases).
#[derive(Debug)]
pub struct Summary {
    /// The file.
    pub path: PathBuf,
    /// File size in bytes.
    pub file_len: usize,
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
            file_len: reader.bytes().len(),
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

// ---------------------------------------------------------------------------------------------
// CSV

/// Which reports [`write_csv`] exports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CsvKind {
    /// `time,sensor,x,y,z,qx,qy,qz,qw`.
    Pose,
    /// `time,sensor,vx,vy,vz,qx,qy,qz,qw,dt`.
    Velocity,
    /// `time,sensor,ax,ay,az,qx,qy,qz,qw,dt`.
    Acceleration,
    /// `time,button,state` (from `vrpn_Button Change`).
    Button,
    /// `time,n,ch0,…,chN-1`, N the most channels any report of the device has.
    Analog,
    /// `time,dial,change`.
    Dial,
}

impl CsvKind {
    /// Every kind, in the order usage text lists them.
    pub const ALL: [CsvKind; 6] = [
        CsvKind::Pose,
        CsvKind::Velocity,
        CsvKind::Acceleration,
        CsvKind::Button,
        CsvKind::Analog,
        CsvKind::Dial,
    ];

    /// The name used on the command line (and as [`Decoded::kind`]).
    pub fn name(self) -> &'static str {
        match self {
            CsvKind::Pose => "pose",
            CsvKind::Velocity => "velocity",
            CsvKind::Acceleration => "acceleration",
            CsvKind::Button => "button",
            CsvKind::Analog => "analog",
            CsvKind::Dial => "dial",
        }
    }

    /// Parses a command-line name.
    pub fn parse(s: &str) -> Option<CsvKind> {
        CsvKind::ALL.into_iter().find(|k| k.name() == s)
    }

    /// True when `d` is a report of this kind.
    pub fn matches(self, d: &Decoded<'_>) -> bool {
        d.kind() == self.name()
    }

    /// The header row (no newline); `width` is the analog column count.
    pub fn header(self, width: usize) -> String {
        match self {
            CsvKind::Pose => "time,sensor,x,y,z,qx,qy,qz,qw".to_owned(),
            CsvKind::Velocity => "time,sensor,vx,vy,vz,qx,qy,qz,qw,dt".to_owned(),
            CsvKind::Acceleration => "time,sensor,ax,ay,az,qx,qy,qz,qw,dt".to_owned(),
            CsvKind::Button => "time,button,state".to_owned(),
            CsvKind::Dial => "time,dial,change".to_owned(),
            CsvKind::Analog => {
                let mut h = "time,n".to_owned();
                for i in 0..width {
                    let _ = write!(h, ",ch{i}");
                }
                h
            }
        }
    }
}

/// Appends one CSV row (no newline) for a report of `kind`, floats in full precision (Rust
/// `{}`, which round-trips). An analog row is padded with empty cells to `width` channels.
/// Returns false, writing nothing, when `d` is not a report of `kind`.
pub fn csv_row(
    out: &mut String,
    kind: CsvKind,
    time: TimeVal,
    d: &Decoded<'_>,
    width: usize,
) -> bool {
    if !kind.matches(d) {
        return false;
    }
    let _ = write!(out, "{time}");
    fn nums(out: &mut String, vs: &[f64]) {
        for v in vs {
            let _ = write!(out, ",{v}");
        }
    }
    match d {
        Decoded::Pose { sensor, pos, quat } => {
            let _ = write!(out, ",{sensor}");
            nums(out, pos);
            nums(out, quat);
        }
        Decoded::Velocity {
            sensor,
            vel: v,
            quat,
            dt,
        }
        | Decoded::Acceleration {
            sensor,
            acc: v,
            quat,
            dt,
        } => {
            let _ = write!(out, ",{sensor}");
            nums(out, v);
            nums(out, quat);
            nums(out, &[*dt]);
        }
        Decoded::ButtonChange { button, state } => {
            let _ = write!(out, ",{button},{state}");
        }
        Decoded::Dial { dial, change } => {
            let _ = write!(out, ",{dial},{change}");
        }
        Decoded::Analog(ch) => {
            let _ = write!(out, ",{}", ch.len());
            nums(out, ch);
            for _ in ch.len()..width {
                out.push(',');
            }
        }
        _ => unreachable!("kind matched"),
    }
    true
}

/// Why a CSV export cannot start.
#[derive(Debug)]
pub enum CsvError {
    /// No user message in the log comes from the device.
    UnknownDevice {
        /// The device asked for.
        device: String,
        /// Senders of user messages in the log.
        devices: Vec<String>,
        /// Damage that ended the scan early, if any.
        damage: Option<LogError>,
    },
    /// The device sent no report of the kind asked for.
    NoReports {
        /// The device.
        device: String,
        /// The kind asked for.
        kind: CsvKind,
        /// Kinds ([`Decoded::kind`]) the device did send.
        kinds: Vec<&'static str>,
        /// Damage that ended the scan early, if any.
        damage: Option<LogError>,
    },
}

impl std::fmt::Display for CsvError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let damage = match self {
            CsvError::UnknownDevice {
                device,
                devices,
                damage,
            } => {
                write!(f, "no device {device:?} in the log; devices: ")?;
                if devices.is_empty() {
                    write!(f, "(none)")?;
                } else {
                    write!(f, "{}", devices.join(", "))?;
                }
                damage
            }
            CsvError::NoReports {
                device,
                kind,
                kinds,
                damage,
            } => {
                write!(
                    f,
                    "{device} sent no {} reports; it sent: {}",
                    kind.name(),
                    kinds.join(", ")
                )?;
                damage
            }
        };
        if let Some(e) = damage {
            write!(f, " (reading stopped early: {e})")?;
        }
        Ok(())
    }
}

impl std::error::Error for CsvError {}

/// What [`plan_csv`] found: how many rows and how wide.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CsvPlan {
    /// The device.
    pub device: String,
    /// The kind.
    pub kind: CsvKind,
    /// Rows to write.
    pub rows: u64,
    /// Analog channel columns (0 for other kinds).
    pub width: usize,
}

/// Scans the log for `device`'s reports of `kind`. Fails when the device sent no user
/// message at all, or none of that kind.
pub fn plan_csv(reader: &LogReader, device: &str, kind: CsvKind) -> Result<CsvPlan, CsvError> {
    let mut devices: Vec<String> = Vec::new();
    let mut kinds: Vec<&'static str> = Vec::new();
    let mut plan = CsvPlan {
        device: device.to_owned(),
        kind,
        rows: 0,
        width: 0,
    };
    let mut damage = None;
    let mut walk = Walk::new(reader);
    while let Some(rec) = walk.next_record() {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                damage = Some(e);
                break;
            }
        };
        if rec.entry.is_system() {
            continue;
        }
        let label = rec.sender_label();
        if label != device {
            if !devices.contains(&label) {
                devices.push(label);
            }
            continue;
        }
        if !kinds.contains(&rec.decoded.kind()) {
            kinds.push(rec.decoded.kind());
        }
        if kind.matches(&rec.decoded) {
            plan.rows += 1;
            if let Decoded::Analog(ch) = &rec.decoded {
                plan.width = plan.width.max(ch.len());
            }
        }
    }
    if kinds.is_empty() {
        return Err(CsvError::UnknownDevice {
            device: device.to_owned(),
            devices,
            damage,
        });
    }
    if plan.rows == 0 {
        return Err(CsvError::NoReports {
            device: device.to_owned(),
            kind,
            kinds,
            damage,
        });
    }
    Ok(plan)
}

/// Writes the header and one row per report of `plan`; returns the rows written and the damage
/// that ended the walk early, if any.
pub fn write_csv(
    reader: &LogReader,
    plan: &CsvPlan,
    out: &mut dyn io::Write,
) -> io::Result<(u64, Option<LogError>)> {
    let mut line = plan.kind.header(plan.width);
    line.push('\n');
    out.write_all(line.as_bytes())?;
    let mut rows = 0;
    let mut walk = Walk::new(reader);
    while let Some(rec) = walk.next_record() {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => return Ok((rows, Some(e))),
        };
        if !rec.is_from(&plan.device) {
            continue;
        }
        line.clear();
        if csv_row(
            &mut line,
            plan.kind,
            rec.entry.time(),
            &rec.decoded,
            plan.width,
        ) {
            line.push('\n');
            out.write_all(line.as_bytes())?;
            rows += 1;
        }
    }
    Ok((rows, None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::format::encode_entry;
    use crate::wire::system::encode_description;
    use crate::wire::Cookie;

    /// A log image built entry by entry.
    struct Builder(Vec<u8>);

    impl Builder {
        fn new() -> Builder {
            Builder(Cookie::ours(0).to_bytes().to_vec())
        }
        fn entry(&mut self, type_id: i32, sender: i32, t: TimeVal, payload: &[u8]) -> &mut Self {
            let mut buf = vec![0u8; 24 + payload.len()];
            let n = encode_entry(&mut buf, type_id, sender, t, payload).unwrap();
            self.0.extend_from_slice(&buf[..n]);
            self
        }
        fn describe(&mut self, type_id: i32, id: i32, name: &str) -> &mut Self {
            let mut p = [0u8; 128];
            let n = encode_description(&mut p, name);
            self.entry(type_id, id, TimeVal::new(1, 0), &p[..n])
        }
        fn reader(&self) -> LogReader {
            LogReader::from_bytes(self.0.clone(), "test.vrpn").unwrap()
        }
    }

    fn pose(sensor: i32, x: f64) -> Vec<u8> {
        let mut p = [0u8; 64];
        tracker::PosQuat::new(sensor, [x, 0.5, -1.0], [0.0, 0.0, 0.0, 1.0]).encode(&mut p);
        p.to_vec()
    }

    fn sample() -> Builder {
        let mut b = Builder::new();
        b.describe(-1, 1, "Tracker0")
            .describe(-2, 4, tracker::POS_QUAT)
            .describe(-1, 2, "Button0")
            .describe(-2, 5, button::CHANGE)
            .describe(-2, 6, analog::CHANNEL);
        b.entry(4, 1, TimeVal::new(10, 0), &pose(0, 0.1))
            .entry(4, 1, TimeVal::new(10, 500_000), &pose(1, 0.2))
            .entry(4, 1, TimeVal::new(11, 0), &pose(0, 0.3));
        b.entry(5, 2, TimeVal::new(10, 250_000), &[0, 0, 0, 1, 0, 0, 0, 1]);
        let mut a = [0u8; 32];
        let n = analog::encode_channels(&[0.25, -0.5, 1e-3], &mut a);
        b.entry(6, 2, TimeVal::new(10, 300_000), &a[..n]);
        let n = analog::encode_channels(&[0.75], &mut a);
        b.entry(6, 2, TimeVal::new(10, 400_000), &a[..n]);
        b.entry(99, 1, TimeVal::new(10, 1), &[0xde, 0xad]);
        b
    }

    #[test]
    fn decodes_known_and_unknown_types() {
        let p = pose(3, 1.5);
        assert_eq!(
            Decoded::user(Some(tracker::POS_QUAT), &p),
            Decoded::Pose {
                sensor: 3,
                pos: [1.5, 0.5, -1.0],
                quat: [0.0, 0.0, 0.0, 1.0]
            }
        );
        assert_eq!(Decoded::user(Some("something else"), &p), Decoded::Raw(&p));
        assert_eq!(Decoded::user(None, &p), Decoded::Raw(&p));
        match Decoded::user(Some(tracker::POS_QUAT), &p[..10]) {
            Decoded::Malformed { payload, .. } => assert_eq!(payload.len(), 10),
            other => panic!("{other:?}"),
        }
        assert_eq!(Decoded::user(Some(text::PING_MESSAGE), &[]).kind(), "ping");
        let mut t = [0u8; 1032];
        text::TextMessage::new(text::WARNING, 3, b"hi \"there\"")
            .unwrap()
            .encode(&mut t);
        let d = Decoded::user(Some(text::TEXT_MESSAGE), &t);
        assert_eq!(d.kind(), "text");
        assert_eq!(d.fields()[0], ("severity", Field::Str("warning")));
    }

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

    #[test]
    fn text_and_json_lines() {
        let r = sample().reader();
        let mut w = Walk::new(&r);
        let mut recs = Vec::new();
        while let Some(rec) = w.next_record() {
            let rec = rec.unwrap();
            let (mut t, mut j) = (String::new(), String::new());
            format_text(&mut t, &rec);
            format_json(&mut j, &rec);
            recs.push((t, j));
        }
        assert_eq!(
            recs[5].0,
            format!(
                "{:>8}  10.000000  Tracker0  vrpn_Tracker Pos_Quat  sensor 0  pos (0.1, 0.5, -1)  quat (0, 0, 0, 1)",
                recs_offset(&r, 5)
            )
        );
        assert!(recs[5].1.contains(
            "\"time\":10.000000,\"sec\":10,\"usec\":0,\"sender\":\"Tracker0\",\"sender_id\":1,\
             \"type\":\"vrpn_Tracker Pos_Quat\",\"type_id\":4,\"kind\":\"pose\",\"sensor\":0,\
             \"pos\":[0.1,0.5,-1.0],\"quat\":[0.0,0.0,0.0,1.0]}"
        ));
        assert!(recs[0].1.ends_with(
            "\"sender\":null,\"sender_id\":1,\"type\":\"SENDER_DESCRIPTION\",\"type_id\":-1,\
             \"kind\":\"system\",\"system\":\"sender_description\",\"id\":1,\"name\":\"Tracker0\"}"
        ));
        assert!(recs[9]
            .1
            .ends_with("\"kind\":\"analog\",\"channels\":[0.25,-0.5,0.001]}"));
        assert!(recs[11].0.ends_with("<type 99>  len 2  hex dead"));
        assert!(recs[11]
            .1
            .ends_with("\"kind\":\"raw\",\"len\":2,\"hex\":\"dead\"}"));
        let long = Decoded::Raw(&[0xab; 40]);
        let mut s = String::new();
        text_field(&mut s, &long.fields()[1].1);
        assert_eq!(s, format!("{}...", "ab".repeat(TEXT_HEX_LIMIT)));
        let mut s = String::new();
        json_str(&mut s, "a\"b\\c\nd\u{1}");
        assert_eq!(s, "\"a\\\"b\\\\c\\nd\\u0001\"");
    }

    fn recs_offset(r: &LogReader, i: usize) -> usize {
        r.entries().nth(i).unwrap().unwrap().offset
    }

    #[test]
    fn csv_export() {
        let r = sample().reader();
        let plan = plan_csv(&r, "Tracker0", CsvKind::Pose).unwrap();
        assert_eq!(plan.rows, 3);
        let mut out = Vec::new();
        let (rows, damage) = write_csv(&r, &plan, &mut out).unwrap();
        assert_eq!((rows, damage.is_none()), (3, true));
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<_> = text.lines().collect();
        assert_eq!(lines[0], "time,sensor,x,y,z,qx,qy,qz,qw");
        assert_eq!(lines[2], "10.500000,1,0.2,0.5,-1,0,0,0,1");

        let plan = plan_csv(&r, "Button0", CsvKind::Analog).unwrap();
        assert_eq!(plan.width, 3);
        let mut out = Vec::new();
        write_csv(&r, &plan, &mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "time,n,ch0,ch1,ch2\n10.300000,3,0.25,-0.5,0.001\n10.400000,1,0.75,,\n"
        );
        let plan = plan_csv(&r, "Button0", CsvKind::Button).unwrap();
        let mut out = Vec::new();
        write_csv(&r, &plan, &mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "time,button,state\n10.250000,1,1\n"
        );

        match plan_csv(&r, "Nobody", CsvKind::Pose) {
            Err(e @ CsvError::UnknownDevice { .. }) => assert_eq!(
                e.to_string(),
                "no device \"Nobody\" in the log; devices: Tracker0, Button0"
            ),
            other => panic!("{other:?}"),
        }
        match plan_csv(&r, "Button0", CsvKind::Dial) {
            Err(e @ CsvError::NoReports { .. }) => {
                assert_eq!(
                    e.to_string(),
                    "Button0 sent no dial reports; it sent: button, analog"
                )
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(CsvKind::parse("velocity"), Some(CsvKind::Velocity));
        assert_eq!(CsvKind::parse("poses"), None);
    }

    #[test]
    fn csv_floats_round_trip() {
        let vals = [0.1, 1.0 / 3.0, -2.5e-7, 123456.789, f64::MIN_POSITIVE];
        let mut s = String::new();
        assert!(csv_row(
            &mut s,
            CsvKind::Analog,
            TimeVal::new(5, 7),
            &Decoded::Analog(vals.to_vec()),
            5
        ));
        let cells: Vec<&str> = s.split(',').collect();
        assert_eq!(cells[0], "5.000007");
        for (cell, v) in cells[2..].iter().zip(vals) {
            assert_eq!(cell.parse::<f64>().unwrap().to_bits(), v.to_bits());
        }
        assert!(!csv_row(
            &mut s,
            CsvKind::Pose,
            TimeVal::ZERO,
            &Decoded::Ping,
            0
        ));
    }
}
