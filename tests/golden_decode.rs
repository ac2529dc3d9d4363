//! Decodes every golden capture recorded from C++ VRPN (tests/fixtures/golden, copied from
//! the shared golden set) with the crate's codec and checks every message against the decoded
//! truth in `NAME.expected.json`: header fields, system descriptions, device payload values
//! (floats bit for bit), trailing bytes, cookies and UDP lob requests.

use std::collections::{BTreeMap, HashMap};
use std::fs;
use std::path::{Path, PathBuf};

use byteorder::{BigEndian, ByteOrder};
use serde_json::{json, Value};

use vrpn::wire::payload::{analog, button, dial, text, tracker};
use vrpn::wire::{lob, system, Cookie, DatagramMessages, Header, StreamDecoder};
use vrpn::wire::{COOKIE_LEN, HEADER_LEN};

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/golden")
}

fn read(name: &str) -> Vec<u8> {
    let p = golden_dir().join(name);
    fs::read(&p).unwrap_or_else(|e| panic!("reading {}: {e}", p.display()))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn int(v: &Value, what: &str) -> i64 {
    v.as_i64()
        .unwrap_or_else(|| panic!("{what}: expected an integer, got {v}"))
}

fn s<'a>(v: &'a Value, what: &str) -> &'a str {
    v.as_str()
        .unwrap_or_else(|| panic!("{what}: expected a string, got {v}"))
}

/// Compares JSON values exactly: same keys, same integers, floats bit for bit.
fn assert_same(ours: &Value, truth: &Value, path: &str) {
    match (ours, truth) {
        (Value::Number(a), Value::Number(b)) => {
            if a.is_f64() || b.is_f64() {
                assert!(
                    a.is_f64() && b.is_f64(),
                    "{path}: float/integer mismatch: ours {a}, expected {b}"
                );
                let (x, y) = (a.as_f64().unwrap(), b.as_f64().unwrap());
                assert_eq!(
                    x.to_bits(),
                    y.to_bits(),
                    "{path}: ours {x:?}, expected {y:?}"
                );
            } else {
                assert_eq!(a.as_i128(), b.as_i128(), "{path}");
            }
        }
        (Value::Array(a), Value::Array(b)) => {
            assert_eq!(a.len(), b.len(), "{path}: array length");
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                assert_same(x, y, &format!("{path}[{i}]"));
            }
        }
        (Value::Object(a), Value::Object(b)) => {
            let ka: Vec<_> = a.keys().collect();
            let kb: Vec<_> = b.keys().collect();
            assert_eq!(ka, kb, "{path}: keys");
            for (k, x) in a {
                assert_same(x, &b[k], &format!("{path}.{k}"));
            }
        }
        _ => assert_eq!(ours, truth, "{path}"),
    }
}

/// Names one side of a connection has described, built from its TCP stream.
#[derive(Default)]
struct Names {
    senders: HashMap<i32, String>,
    types: HashMap<i32, String>,
}

impl Names {
    fn learn(map: &mut HashMap<i32, String>, id: i32, name: &str, what: &str) {
        if let Some(old) = map.insert(id, name.to_owned()) {
            assert_eq!(
                old, name,
                "{what} id {id} described twice with different names"
            );
        }
    }
}

/// What one decoded message contributes to the per-direction counts.
fn count_key(header: &Header, names: &Names) -> String {
    match header.type_id {
        system::SENDER_DESCRIPTION => "SENDER_DESCRIPTION".into(),
        system::TYPE_DESCRIPTION => "TYPE_DESCRIPTION".into(),
        system::UDP_DESCRIPTION => "UDP_DESCRIPTION".into(),
        system::LOG_DESCRIPTION => "LOG_DESCRIPTION".into(),
        system::DISCONNECT => "DISCONNECT".into(),
        t => names
            .types
            .get(&t)
            .cloned()
            .unwrap_or_else(|| format!("unknown type {t}")),
    }
}

/// Decodes a user payload with the crate's codec into the JSON shape of the golden truth.
fn decode_user_payload(type_name: &str, p: &[u8]) -> Option<Value> {
    let v = match type_name {
        tracker::POS_QUAT => {
            let m = tracker::PosQuat::decode(p).expect("Pos_Quat");
            json!({"sensor": m.sensor, "pad_word": m.pad, "pos": m.pos, "quat": m.quat})
        }
        tracker::VELOCITY => {
            let m = tracker::Velocity::decode(p).expect("Velocity");
            json!({"sensor": m.sensor, "pad_word": m.pad, "vel": m.vel,
                   "vel_quat": m.vel_quat, "vel_quat_dt": m.vel_quat_dt})
        }
        tracker::ACCELERATION => {
            let m = tracker::Acceleration::decode(p).expect("Acceleration");
            json!({"sensor": m.sensor, "pad_word": m.pad, "acc": m.acc,
                   "acc_quat": m.acc_quat, "acc_quat_dt": m.acc_quat_dt})
        }
        button::CHANGE => {
            let m = button::Change::decode(p).expect("Button Change");
            json!({"button": m.button, "state": m.state})
        }
        button::STATES => {
            let m = button::States::decode(p).expect("Button States");
            json!({"num_buttons": m.count, "states": m.as_slice()})
        }
        analog::CHANNEL => {
            let m = analog::Channels::decode(p).expect("Analog Channel");
            json!({"num_channel": m.count, "channels": m.as_slice()})
        }
        dial::UPDATE => {
            let m = dial::Update::decode(p).expect("Dial update");
            json!({"dial": m.dial, "change": m.change})
        }
        text::TEXT_MESSAGE => {
            let m = text::TextMessage::decode(p).expect("text message");
            let string_bytes = m.text.len() + 1;
            json!({
                "severity": m.severity,
                "severity_name": text::severity_name(m.severity).expect("known severity"),
                "level": m.level,
                "string": m.as_str().expect("UTF-8 text"),
                "string_bytes": string_bytes,
                "bytes_after_nul": p.len().min(text::TextMessage::LEN) - 8 - string_bytes,
            })
        }
        text::PING_MESSAGE | text::PONG_MESSAGE => {
            assert!(p.is_empty(), "{type_name} with a payload");
            json!({})
        }
        _ => return None,
    };
    Some(v)
}

/// Checks one message against its JSON record; returns the count key.
#[allow(clippy::too_many_arguments)]
fn check_message(
    ctx: &str,
    channel: &str,
    offset: usize,
    raw: &[u8],
    header: &Header,
    payload: &[u8],
    names: &Names,
    m: &Value,
) -> String {
    let wire_size = header.wire_size();
    assert_eq!(m["channel"], channel, "{ctx}: channel");
    assert_eq!(int(&m["offset"], ctx) as usize, offset, "{ctx}: offset");
    assert_eq!(
        int(&m["length_field"], ctx) as usize,
        HEADER_LEN + header.payload_len,
        "{ctx}: length_field"
    );
    assert_eq!(
        int(&m["length_field"], ctx) as u32,
        BigEndian::read_u32(&raw[offset..offset + 4]),
        "{ctx}: raw length word"
    );
    assert_eq!(int(&m["payload_len"], ctx) as usize, header.payload_len);
    assert_eq!(
        int(&m["wire_size"], ctx) as usize,
        wire_size,
        "{ctx}: wire_size"
    );
    assert_eq!(int(&m["sec"], ctx), header.time.sec, "{ctx}: sec");
    assert_eq!(int(&m["usec"], ctx), header.time.usec, "{ctx}: usec");
    assert_eq!(
        int(&m["sender_id"], ctx),
        header.sender as i64,
        "{ctx}: sender"
    );
    assert_eq!(
        int(&m["type_id"], ctx),
        header.type_id as i64,
        "{ctx}: type"
    );
    assert_eq!(int(&m["seq"], ctx), header.seq as i64, "{ctx}: seq");
    let pad_start = offset + HEADER_LEN + header.payload_len;
    let pad_end = (offset + wire_size).min(raw.len());
    let pad_zero = raw[pad_start..pad_end].iter().all(|&b| b == 0);
    assert_eq!(m["pad_bytes_zero"], pad_zero, "{ctx}: pad_bytes_zero");

    let key = count_key(header, names);
    match header.type_id {
        system::SENDER_DESCRIPTION | system::TYPE_DESCRIPTION => {
            let (sys, field) = if header.type_id == system::SENDER_DESCRIPTION {
                ("SENDER_DESCRIPTION", "described_sender")
            } else {
                ("TYPE_DESCRIPTION", "described_type")
            };
            assert_eq!(m["system"], sys, "{ctx}: system kind");
            let name = system::decode_description(payload).expect("description");
            let ours = json!({
                "id": header.sender,
                "name": name,
                "declared_length": BigEndian::read_u32(&payload[0..4]),
            });
            assert_same(&ours, &m[field], &format!("{ctx}.{field}"));
        }
        system::UDP_DESCRIPTION => {
            assert_eq!(m["system"], "UDP_DESCRIPTION", "{ctx}: system kind");
            let host = system::decode_udp_description(payload).expect("UDP description");
            let ours = json!({"port": header.sender, "host": host});
            assert_same(&ours, &m["udp_description"], &format!("{ctx}.udp"));
        }
        t if t < 0 => panic!("{ctx}: system message {t} not expected in these captures"),
        t => {
            assert!(
                m.get("system").is_none(),
                "{ctx}: user message marked system"
            );
            let type_name = names.types.get(&t).expect("type described before use");
            let sender_name = names
                .senders
                .get(&header.sender)
                .expect("sender described before use");
            assert_eq!(m["type"], type_name.as_str(), "{ctx}: type name");
            assert_eq!(m["sender"], sender_name.as_str(), "{ctx}: sender name");
            match decode_user_payload(type_name, payload) {
                Some(ours) => assert_same(&ours, &m["payload"], &format!("{ctx}.payload")),
                None => assert_eq!(
                    s(&m["payload_hex"], ctx),
                    hex(payload),
                    "{ctx}: no decoder for {type_name}, raw bytes differ"
                ),
            }
        }
    }
    key
}

/// First pass over a TCP stream: the names its sender described, in order of appearance.
fn learn_names(raw: &[u8]) -> (Names, Vec<Value>, Vec<Value>, Vec<Value>) {
    let mut names = Names::default();
    let (mut senders, mut types, mut udps) = (Vec::new(), Vec::new(), Vec::new());
    let mut dec = StreamDecoder::default();
    assert_eq!(dec.feed(raw), raw.len());
    dec.take_exact(COOKIE_LEN).expect("cookie");
    while let Some(msg) = dec.next_message() {
        let (h, p) = msg.expect("stream frames");
        match h.type_id {
            system::SENDER_DESCRIPTION => {
                let name = system::decode_description(p).unwrap();
                Names::learn(&mut names.senders, h.sender, name, "sender");
                senders.push(json!({"id": h.sender, "name": name}));
            }
            system::TYPE_DESCRIPTION => {
                let name = system::decode_description(p).unwrap();
                Names::learn(&mut names.types, h.sender, name, "type");
                types.push(json!({"id": h.sender, "name": name}));
            }
            system::UDP_DESCRIPTION => {
                let host = system::decode_udp_description(p).unwrap();
                udps.push(json!({"port": h.sender, "host": host}));
            }
            _ => {}
        }
    }
    (names, senders, types, udps)
}

fn check_cookie(ctx: &str, raw: &[u8], truth: &Value) {
    let c = Cookie::parse(raw).expect("cookie");
    c.check().expect("C++ cookie accepted");
    let version = c.version();
    let (major, minor) = version.split_once('.').expect("version text");
    let ours = json!({
        "raw_hex": hex(&raw[..COOKIE_LEN]),
        "magic": std::str::from_utf8(&c.magic).unwrap(),
        "major": major,
        "minor": minor,
        "separator_hex": hex(&raw[16..18]),
        "log_mode_char": (raw[18] as char).to_string(),
        "log_mode": c.log_mode,
        "tail_hex": hex(&raw[19..COOKIE_LEN]),
    });
    assert_same(&ours, truth, &format!("{ctx}.cookie"));
}

/// Checks one TCP stream; returns (messages checked, per-type counts, names).
fn check_stream(ctx: &str, truth: &Value, counts: &mut BTreeMap<String, i64>) -> (usize, Names) {
    let raw = read(s(&truth["file"], ctx));
    assert_eq!(
        raw.len() as i64,
        int(&truth["length"], ctx),
        "{ctx}: stream length"
    );
    check_cookie(ctx, &raw, &truth["cookie"]);

    let (names, senders, types, udps) = learn_names(&raw);
    let strip = |list: &Value| -> Value {
        Value::Array(
            list.as_array()
                .unwrap()
                .iter()
                .map(|d| {
                    let mut d = d.clone();
                    if let Some(o) = d.as_object_mut() {
                        o.remove("declared_length");
                    }
                    d
                })
                .collect(),
        )
    };
    assert_same(
        &Value::Array(senders),
        &strip(&truth["senders_described"]),
        &format!("{ctx}.senders_described"),
    );
    assert_same(
        &Value::Array(types),
        &strip(&truth["types_described"]),
        &format!("{ctx}.types_described"),
    );
    assert_same(
        &Value::Array(udps),
        &truth["udp_descriptions"],
        &format!("{ctx}.udp_descriptions"),
    );
    assert_eq!(
        truth["log_descriptions"].as_array().map(Vec::len),
        Some(0),
        "{ctx}: no log descriptions expected"
    );

    let expected = truth["messages"].as_array().expect("messages");
    let mut dec = StreamDecoder::default();
    assert_eq!(dec.feed(&raw), raw.len());
    dec.take_exact(COOKIE_LEN).unwrap();
    let mut offset = COOKIE_LEN;
    let mut checked = 0;
    while let Some(msg) = dec.next_message() {
        let (h, p) = msg.expect("stream frames");
        let m = expected
            .get(checked)
            .unwrap_or_else(|| panic!("{ctx}: more messages than the JSON lists"));
        let mctx = format!("{ctx}.messages[{checked}]");
        let key = check_message(&mctx, "tcp", offset, &raw, &h, p, &names, m);
        *counts.entry(key).or_default() += 1;
        offset += h.wire_size();
        checked += 1;
    }
    assert_eq!(checked, expected.len(), "{ctx}: message count");
    assert_eq!(
        dec.buffered() as i64,
        int(&truth["trailing_bytes"], ctx),
        "{ctx}: trailing_bytes"
    );
    assert_eq!(offset + dec.buffered(), raw.len());
    (checked, names)
}

/// Splits a `u32_be_length_prefixed` frames file into datagrams.
fn frames(raw: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut rest = raw;
    while !rest.is_empty() {
        assert!(rest.len() >= 4, "frames file ends inside a length prefix");
        let n = BigEndian::read_u32(&rest[..4]) as usize;
        assert!(rest.len() >= 4 + n, "frames file ends inside a datagram");
        out.push(&rest[4..4 + n]);
        rest = &rest[4 + n..];
    }
    out
}

/// Checks one UDP direction; returns the number of messages checked.
fn check_udp(ctx: &str, truth: &Value, names: &Names, counts: &mut BTreeMap<String, i64>) -> usize {
    let expected = truth["datagrams"].as_array().expect("datagrams");
    let file = match truth["file"].as_str() {
        Some(f) => f,
        None => {
            assert!(expected.is_empty(), "{ctx}: datagrams without a file");
            return 0;
        }
    };
    assert_eq!(truth["framing"], "u32_be_length_prefixed", "{ctx}: framing");
    let raw = read(file);
    let datagrams = frames(&raw);
    assert_eq!(datagrams.len(), expected.len(), "{ctx}: datagram count");
    if let Some(n) = truth.get("datagram_count") {
        assert_eq!(
            int(n, ctx) as usize,
            datagrams.len(),
            "{ctx}: datagram_count"
        );
    }
    let mut checked = 0;
    for (i, (dg, dj)) in datagrams.iter().zip(expected).enumerate() {
        let dctx = format!("{ctx}.datagrams[{i}]");
        assert_eq!(int(&dj["index"], &dctx) as usize, i, "{dctx}: index");
        assert_eq!(
            int(&dj["length"], &dctx) as usize,
            dg.len(),
            "{dctx}: length"
        );
        let msgs = dj["messages"].as_array().expect("messages");
        let mut offset = 0;
        let mut n = 0;
        let mut trailing = 0;
        for msg in DatagramMessages::new(dg) {
            let (h, p) = match msg {
                Ok(hp) => hp,
                Err(_) => {
                    trailing = dg.len() - offset;
                    break;
                }
            };
            let m = msgs
                .get(n)
                .unwrap_or_else(|| panic!("{dctx}: more messages than the JSON lists"));
            let mctx = format!("{dctx}.messages[{n}]");
            let key = check_message(&mctx, "udp", offset, dg, &h, p, names, m);
            *counts.entry(key).or_default() += 1;
            offset = (offset + h.wire_size()).min(dg.len());
            n += 1;
        }
        assert_eq!(n, msgs.len(), "{dctx}: message count");
        assert_eq!(
            trailing as i64,
            int(&dj["trailing_bytes"], &dctx),
            "{dctx}: trailing_bytes"
        );
        checked += n;
    }
    checked
}

fn check_lob_requests(scenario: &str, truth: &Value) -> usize {
    let reqs = truth["udp_lob_requests"]
        .as_array()
        .expect("udp_lob_requests");
    // Every lob file of the scenario is listed (nothing on disk escapes the check).
    let prefix = format!("{scenario}.udp_lob.");
    let mut on_disk: Vec<String> = fs::read_dir(golden_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|f| f.starts_with(&prefix) && f.ends_with(".bin"))
        .collect();
    on_disk.sort();
    let listed: Vec<String> = reqs
        .iter()
        .map(|r| s(&r["file"], scenario).to_owned())
        .collect();
    assert_eq!(on_disk, listed, "{scenario}: lob files");
    for r in reqs {
        let ctx = format!("{scenario}.{}", s(&r["file"], scenario));
        let raw = read(s(&r["file"], &ctx));
        assert_eq!(raw.len() as i64, int(&r["length"], &ctx), "{ctx}: length");
        assert_eq!(hex(&raw), s(&r["hex"], &ctx), "{ctx}: bytes");
        let nul = raw.last() == Some(&0);
        assert_eq!(r["nul_terminated"], nul, "{ctx}: nul_terminated");
        let text_end = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
        assert_eq!(
            std::str::from_utf8(&raw[..text_end]).unwrap(),
            s(&r["text"], &ctx),
            "{ctx}: text"
        );
        let req = lob::parse_request(&raw).expect("lob request parses");
        assert_eq!(req.host, s(&r["callback_host"], &ctx), "{ctx}: host");
        assert_eq!(
            req.port as i64,
            int(&r["callback_port"], &ctx),
            "{ctx}: port"
        );
    }
    reqs.len()
}

/// Checks one scenario; returns (messages checked, lob requests checked).
fn check_scenario(scenario: &str) -> (usize, usize) {
    let truth: Value =
        serde_json::from_slice(&read(&format!("{scenario}.expected.json"))).expect("JSON");
    assert_eq!(truth["scenario"], scenario);
    let conns = truth["connections"].as_array().expect("connections");
    assert_eq!(
        int(&truth["summary"]["tcp_connections"], scenario) as usize,
        conns.len()
    );

    let mut s2c_counts = BTreeMap::new();
    let mut c2s_counts = BTreeMap::new();
    let mut checked = 0;
    let mut expected_total = 0;
    for (i, c) in conns.iter().enumerate() {
        let ctx = format!("{scenario}.connections[{i}]");
        for dir in ["server_to_client", "client_to_server"] {
            expected_total += c[dir]["messages"].as_array().unwrap().len();
            for dg in c[&format!("udp_{dir}")]["datagrams"].as_array().unwrap() {
                expected_total += dg["messages"].as_array().unwrap().len();
            }
        }
        // Each direction's names come from its own TCP stream: the JSON resolves a message's
        // type and sender with the sending side's descriptions.
        let (n, server_names) = check_stream(
            &format!("{ctx}.server_to_client"),
            &c["server_to_client"],
            &mut s2c_counts,
        );
        checked += n;
        let (n, client_names) = check_stream(
            &format!("{ctx}.client_to_server"),
            &c["client_to_server"],
            &mut c2s_counts,
        );
        checked += n;
        checked += check_udp(
            &format!("{ctx}.udp_server_to_client"),
            &c["udp_server_to_client"],
            &server_names,
            &mut s2c_counts,
        );
        checked += check_udp(
            &format!("{ctx}.udp_client_to_server"),
            &c["udp_client_to_server"],
            &client_names,
            &mut c2s_counts,
        );
    }
    assert!(expected_total > 0, "{scenario}: JSON lists no messages");
    assert_eq!(checked, expected_total, "{scenario}: messages checked");

    let to_json = |m: &BTreeMap<String, i64>| {
        Value::Object(m.iter().map(|(k, v)| (k.clone(), json!(v))).collect())
    };
    let summary = &truth["summary"];
    assert_same(
        &to_json(&s2c_counts),
        &summary["server_to_client_message_counts"],
        &format!("{scenario}.summary.server_to_client"),
    );
    assert_same(
        &to_json(&c2s_counts),
        &summary["client_to_server_message_counts"],
        &format!("{scenario}.summary.client_to_server"),
    );

    let lobs = check_lob_requests(scenario, &truth);
    assert_eq!(
        int(&summary["udp_lob_requests"], scenario) as usize,
        lobs,
        "{scenario}: lob count"
    );
    (checked, lobs)
}

fn scenarios() -> Vec<String> {
    let mut out: Vec<String> = fs::read_dir(golden_dir())
        .expect("tests/fixtures/golden")
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|f| f.ends_with(".expected.json") && !f.ends_with(".vrpn.expected.json"))
        .map(|f| f.trim_end_matches(".expected.json").to_owned())
        .collect();
    out.sort();
    out
}

#[test]
fn every_golden_capture_decodes_exactly() {
    let all = scenarios();
    // The seven scenarios of the golden set; new captures only add to this.
    for known in [
        "button_analog_dial",
        "reconnect",
        "text_and_ping",
        "tracker_client_log",
        "tracker_spin",
        "tracker_tcp_only",
        "tracker_udp_lob",
    ] {
        assert!(all.iter().any(|s| s == known), "missing scenario {known}");
    }
    let mut total = 0;
    for scenario in &all {
        let (messages, lobs) = check_scenario(scenario);
        eprintln!("{scenario}: {messages} messages, {lobs} lob requests checked");
        total += messages;
    }
    eprintln!("{} scenarios, {total} messages checked", all.len());
    assert!(total > 4000, "suspiciously few messages: {total}");
}
