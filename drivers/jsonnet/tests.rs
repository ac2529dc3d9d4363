//! JSON datagrams read as C++ VRPN 07.38 reads them (its capture in tests/fixtures/), the
//! number spelling of text messages, bad input, and the configuration line.

use super::message::{parse, write_real, Message, Rejected};
use super::{JsonNet, BUTTONS, CHANNELS, SENSORS, TEXT_MAX};
use crate::config::ConfigErrorKind;

/// See the header of the file.
pub(crate) const CXX_CAPTURE: &str = include_str!("../../tests/fixtures/cxx_jsonnet.txt");

/// The datagrams of the capture and, for each, the lines C++'s server made a client hear.
pub(crate) fn capture() -> Vec<(String, Vec<String>)> {
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for line in CXX_CAPTURE.lines().filter(|l| !l.starts_with('#')) {
        if let Some(rest) = line.strip_prefix("SEND ") {
            let (_, datagram) = rest.split_once(' ').expect("SEND N DATAGRAM");
            out.push((datagram.to_string(), Vec::new()));
        } else {
            out.last_mut()
                .expect("a SEND first")
                .1
                .push(line.to_string());
        }
    }
    out
}

/// What a client hears, as the capture writes it, from a model of the device's state.
struct Model {
    pos: [f64; 3],
    quat: [f64; 4],
    buttons: [bool; BUTTONS],
    reported_buttons: [bool; BUTTONS],
    channels: [f64; CHANNELS],
    reported_channels: [f64; CHANNELS],
    text: String,
}

impl Model {
    fn new() -> Model {
        Model {
            pos: [0.0; 3],
            quat: [0.0, 0.0, 0.0, 1.0],
            buttons: [false; BUTTONS],
            reported_buttons: [false; BUTTONS],
            channels: [0.0; CHANNELS],
            reported_channels: [0.0; CHANNELS],
            text: String::new(),
        }
    }

    fn datagram(&mut self, bytes: &[u8]) -> Vec<String> {
        let mut heard = Vec::new();
        let Ok(m) = parse(bytes, &mut self.text) else {
            return heard;
        };
        match m {
            Message::Tracker { sensor, quat, pos } => {
                self.quat = quat.unwrap_or(self.quat);
                self.pos = pos.unwrap_or(self.pos);
                if (0..SENSORS as i32).contains(&sensor) {
                    let (p, q) = (self.pos, self.quat);
                    heard.push(format!(
                        "OUT {sensor} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
                        p[0], p[1], p[2], q[0], q[1], q[2], q[3]
                    ));
                }
            }
            Message::Button { button, pressed } => {
                if (0..BUTTONS as i32).contains(&button) {
                    self.buttons[button as usize] = pressed;
                }
            }
            Message::Analog { channel, value } => {
                if (0..CHANNELS as i32).contains(&channel) {
                    self.channels[channel as usize] = value;
                }
            }
            Message::Text => heard.push(format!("TXT 0 {:?}", self.text)),
        }
        for b in 0..BUTTONS {
            if self.buttons[b] != self.reported_buttons[b] {
                heard.push(format!("BTN {b} {}", i32::from(self.buttons[b])));
            }
        }
        self.reported_buttons = self.buttons;
        if self.channels != self.reported_channels {
            let nz: Vec<String> = (0..CHANNELS)
                .filter(|&i| self.channels[i] != 0.0)
                .map(|i| format!("{i} {:?}", self.channels[i]))
                .collect();
            heard.push(format!("ANA {CHANNELS} {}", nz.join(" ")));
            self.reported_channels = self.channels;
        }
        heard
    }
}

#[test]
fn same_messages_as_cxx_for_the_same_datagrams() {
    let mut model = Model::new();
    let (mut datagrams, mut lines) = (0, 0);
    for (datagram, cxx) in capture() {
        let heard = model.datagram(datagram.as_bytes());
        assert_eq!(heard, cxx, "datagram {datagram}");
        datagrams += 1;
        lines += cxx.len();
    }
    assert_eq!((datagrams, lines), (63, 41));
}

#[test]
fn what_is_refused_and_why() {
    let mut text = String::with_capacity(4096);
    for (datagram, why) in [
        ("hello", Rejected::Syntax),
        ("{\"type\":1,\"id\":0,", Rejected::Syntax),
        ("", Rejected::Syntax),
        ("\u{7f}\u{0}\u{1}", Rejected::Syntax),
        (
            "{\"type\":2, /* a comment */ \"button\":1,\"state\":1}",
            Rejected::Syntax,
        ),
        ("[1,2]", Rejected::NotAnObject),
        ("5", Rejected::NotAnObject),
        ("\"type\"", Rejected::NotAnObject),
        ("null", Rejected::NoType),
        ("{}", Rejected::NoType),
        ("{\"type\":\"1\"}", Rejected::NoType),
        ("{\"type\":[1]}", Rejected::NoType),
        ("{\"type\":7}", Rejected::UnknownType),
        ("{\"type\":1}", Rejected::MissingField("id")),
        (
            "{\"type\":1,\"id\":2147483648}",
            Rejected::MissingField("id"),
        ),
        (
            "{\"type\":1,\"id\":1,\"quat\":[0,0,\"a\",1]}",
            Rejected::NotANumber,
        ),
        (
            "{\"type\":1,\"id\":1,\"pos\":[0,[0],0]}",
            Rejected::NotANumber,
        ),
        ("{\"type\":2,\"button\":1}", Rejected::MissingField("state")),
        ("{\"type\":2,\"state\":{}}", Rejected::MissingField("state")),
        (
            "{\"type\":2,\"state\":true}",
            Rejected::MissingField("button"),
        ),
        (
            "{\"type\":3,\"num\":1,\"data\":null}",
            Rejected::MissingField("data"),
        ),
        ("{\"type\":3,\"data\":1}", Rejected::MissingField("num")),
        (
            "{\"type\":4,\"data\":{\"a\":1}}",
            Rejected::MissingField("data"),
        ),
        ("{\"type\":4}", Rejected::MissingField("data")),
    ] {
        assert_eq!(
            parse(datagram.as_bytes(), &mut text),
            Err(why),
            "{datagram}"
        );
    }
    // Invalid UTF-8 in a string (jsoncpp passes the bytes on).
    assert_eq!(
        parse(b"{\"type\":4,\"data\":\"\xff\"}", &mut text),
        Err(Rejected::Syntax)
    );
    // Deeply nested values are skipped without recursing (never a stack overflow).
    let nest = |n: usize| format!("{}{}", "[".repeat(n), "]".repeat(n));
    for field in ["x", "pos"] {
        let deep = format!("{{\"type\":1,\"id\":1,\"{field}\":{}}}", nest(5000));
        assert_eq!(
            parse(deep.as_bytes(), &mut text),
            Ok(Message::Tracker {
                sensor: 1,
                quat: None,
                pos: None
            })
        );
    }
}

#[test]
fn the_last_of_a_repeated_field_counts_and_strings_are_copied_once() {
    let mut text = String::with_capacity(4096);
    let cap = text.capacity();
    let m = parse(
        br#"{"data":"first","type":4,"data":"second \u00e9"}"#,
        &mut text,
    );
    assert_eq!(m, Ok(Message::Text));
    assert_eq!(text, "second é");
    let m = parse(br#"{"type":4,"data":"str","data":0.5}"#, &mut text);
    assert_eq!(m, Ok(Message::Text));
    assert_eq!(text, "0.5");
    assert_eq!(text.capacity(), cap);
}

#[test]
fn numbers_in_texts_are_spelled_as_cxx_spells_them() {
    for (v, want) in [
        (0.1, "0.10000000000000001"),
        (2.0, "2.0"),
        (0.0, "0.0"),
        (-0.0, "-0.0"),
        (1e300, "1.0000000000000001e+300"),
        (123456789.125, "123456789.125"),
        (0.0001, "0.0001"),
        (0.00001, "1.0000000000000001e-05"),
        (1e16, "10000000000000000.0"),
        (1e17, "1e+17"),
        (-1.5e-300, "-1.5000000000000001e-300"),
        (5e-324, "4.9406564584124654e-324"),
        (f64::MAX, "1.7976931348623157e+308"),
    ] {
        let mut s = String::new();
        write_real(&mut s, v);
        assert_eq!(s, want, "{v:e}");
    }
}

#[test]
fn limits_are_those_of_cxx() {
    assert_eq!((BUTTONS, CHANNELS, TEXT_MAX), (256, 128, 1023));
}

fn parse_cfg(text: &str) -> Result<JsonNet, crate::config::ConfigError> {
    let entries = crate::server::config::parse_str(text, "jn.cfg")?;
    Ok(entries[0].spec::<JsonNet>().unwrap().clone())
}

#[test]
fn configuration_lines() {
    let j = parse_cfg("vrpn_Tracker_JsonNet Jsonnet 7777\n").unwrap();
    assert_eq!((j.name.as_str(), j.port), ("Jsonnet", 7777));
    for (text, kind) in [
        (
            "vrpn_Tracker_JsonNet J\n",
            ConfigErrorKind::MissingArguments,
        ),
        ("vrpn_Tracker_JsonNet J port\n", ConfigErrorKind::BadNumber),
        (
            "vrpn_Tracker_JsonNet J 70000\n",
            ConfigErrorKind::OutOfRange,
        ),
    ] {
        let e = parse_cfg(text).unwrap_err();
        assert_eq!(e.kind(), kind, "{text}: {e}");
        assert_eq!(e.line(), Some(1), "{text}: {e}");
    }
}
