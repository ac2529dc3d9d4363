//! Payload decoding by resolved type name: [`Decoded`] and its named [`Field`]s.

use crate::log::format::{LogEntry, SystemEntry};
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

#[cfg(test)]
mod tests {
    use super::super::test_log::pose;
    use super::*;

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
}
