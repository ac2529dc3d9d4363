//! Every log written by C++ VRPN in `tests/fixtures/golden` must decode to exactly the values in
//! its `.expected.json`, re-encode byte for byte through `LogWriter`, and fail cleanly when cut
//! short or corrupted.

use std::path::{Path, PathBuf};

use byteorder::{BigEndian, ByteOrder};
use serde_json::Value;
use vrpn::log::{
    EntryProblem, LogEntry, LogError, LogReader, LogWriter, NameTable, SystemEntry,
    ENTRY_HEADER_LEN,
};
use vrpn::TimeVal;

const GOLDEN_LOGS: usize = 7;

fn fixture_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/golden")
}

/// Every `*.vrpn` fixture with its parsed `.expected.json`.
fn golden_logs() -> Vec<(PathBuf, Value)> {
    let mut logs: Vec<(PathBuf, Value)> = std::fs::read_dir(fixture_dir())
        .expect("fixture dir")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "vrpn"))
        .map(|p| {
            let mut json = p.clone().into_os_string();
            json.push(".expected.json");
            let text = std::fs::read_to_string(&json)
                .unwrap_or_else(|e| panic!("{}: {e}", Path::new(&json).display()));
            (p, serde_json::from_str(&text).expect("valid JSON"))
        })
        .collect();
    logs.sort_by(|a, b| a.0.cmp(&b.0));
    assert_eq!(logs.len(), GOLDEN_LOGS, "golden logs missing from fixtures");
    logs
}

fn int(v: &Value) -> i64 {
    v.as_i64().unwrap_or_else(|| panic!("not an integer: {v}"))
}

fn float(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Compares `n` big-endian doubles at `payload[at..]` with a JSON array, bit for bit.
fn assert_doubles(payload: &[u8], at: usize, expected: &Value, what: &str) {
    let expected = expected.as_array().expect("array");
    for (i, v) in expected.iter().enumerate() {
        let got = BigEndian::read_f64(&payload[at + 8 * i..]);
        assert_eq!(
            got.to_bits(),
            float(v).to_bits(),
            "{what}[{i}]: {got:?} vs {v}"
        );
    }
}

/// Checks a tracker report: sensor, pad word, then 7 doubles (Pos_Quat) or 8 (Velocity and
/// Acceleration, whose last is the quaternion dt).
fn check_tracker_payload(payload: &[u8], kind: &str, p: &Value) {
    assert_eq!(
        BigEndian::read_i32(&payload[0..4]) as i64,
        int(&p["sensor"]),
        "sensor"
    );
    assert_eq!(
        BigEndian::read_i32(&payload[4..8]) as i64,
        int(&p["pad_word"]),
        "pad_word"
    );
    let (v, q) = match kind {
        "vrpn_Tracker Pos_Quat" => ("pos", "quat"),
        "vrpn_Tracker Velocity" => ("vel", "vel_quat"),
        _ => ("acc", "acc_quat"),
    };
    assert_doubles(payload, 8, &p[v], v);
    assert_doubles(payload, 32, &p[q], q);
    if kind != "vrpn_Tracker Pos_Quat" {
        let dt = BigEndian::read_f64(&payload[64..72]);
        let key = format!("{q}_dt");
        assert_eq!(dt.to_bits(), float(&p[&key]).to_bits(), "{key}");
    }
}

fn check_entry(e: &LogEntry<'_>, j: &Value, names: &NameTable, described: &mut Described) {
    assert_eq!(e.offset as i64, int(&j["offset"]), "offset");
    assert_eq!(e.type_id() as i64, int(&j["type_id"]), "type_id");
    assert_eq!(e.sender() as i64, int(&j["sender_id"]), "sender_id");
    assert_eq!(e.header.sec as i64, int(&j["sec"]), "sec");
    assert_eq!(e.header.usec as i64, int(&j["usec"]), "usec");
    assert_eq!(e.header.payload_len as i64, int(&j["payload_len"]), "len");
    assert_eq!(e.payload.len() as i64, int(&j["payload_len"]), "payload");
    assert_eq!(e.header.zero_word as i64, int(&j["zero_word"]), "zero_word");

    match e.system() {
        Some(system) => {
            let system = system.expect("system payload decodes");
            let label = j["system"].as_str().expect("system label");
            match system {
                SystemEntry::SenderDescription { id, name } => {
                    assert_eq!(label, "SENDER_DESCRIPTION");
                    check_description(e, id, name, &j["described_sender"]);
                    described.senders.push((id as i64, name.to_owned()));
                }
                SystemEntry::TypeDescription { id, name } => {
                    assert_eq!(label, "TYPE_DESCRIPTION");
                    check_description(e, id, name, &j["described_type"]);
                    described.types.push((id as i64, name.to_owned()));
                }
                SystemEntry::UdpDescription { port, host } => {
                    assert_eq!(label, "UDP_DESCRIPTION");
                    let u = &j["udp_description"];
                    assert_eq!(port as i64, int(&u["port"]));
                    assert_eq!(host, u["host"].as_str().unwrap());
                    described.udp.push((port as i64, host.to_owned()));
                }
                SystemEntry::LogDescription { mode, names } => {
                    assert_eq!(label, "LOG_DESCRIPTION");
                    described
                        .log
                        .push(format!("{mode} {} {}", names.incoming, names.outgoing));
                }
                SystemEntry::Disconnect => {
                    assert_eq!(label, "DISCONNECT");
                    assert!(j["disconnect"].is_object());
                }
                SystemEntry::Unknown(t) => panic!("unknown system type {t} at {}", e.offset),
            }
        }
        None => {
            // Names resolved through the log's own descriptions, as the JSON did.
            assert_eq!(
                names.type_name(e.type_id()),
                j["type"].as_str(),
                "type name"
            );
            assert_eq!(
                names.sender_name(e.sender()),
                j["sender"].as_str(),
                "sender name"
            );
            let kind = j["type"].as_str().unwrap_or("");
            if kind.starts_with("vrpn_Tracker ") && j["payload"].is_object() {
                check_tracker_payload(e.payload, kind, &j["payload"]);
            }
            if let Some(h) = j["payload_hex"].as_str() {
                assert_eq!(hex(e.payload), h, "payload_hex");
            }
        }
    }
}

fn check_description(e: &LogEntry<'_>, id: i32, name: &str, j: &Value) {
    assert_eq!(id as i64, int(&j["id"]), "described id");
    assert_eq!(name, j["name"].as_str().unwrap(), "described name");
    let declared = BigEndian::read_u32(&e.payload[0..4]);
    assert_eq!(
        declared as i64,
        int(&j["declared_length"]),
        "declared_length"
    );
}

#[derive(Default)]
struct Described {
    senders: Vec<(i64, String)>,
    types: Vec<(i64, String)>,
    udp: Vec<(i64, String)>,
    log: Vec<String>,
}

fn id_names(v: &Value) -> Vec<(i64, String)> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|d| (int(&d["id"]), d["name"].as_str().unwrap().to_owned()))
        .collect()
}

#[test]
fn every_golden_log_decodes_to_its_expected_json() {
    let mut total = 0;
    for (path, json) in golden_logs() {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let log = LogReader::open(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(log.len() as i64, int(&json["length"]), "{name}");
        let cookie = &json["cookie"];
        assert_eq!(hex(log.cookie_bytes()), cookie["raw_hex"].as_str().unwrap());
        assert_eq!(
            &log.cookie().magic[..],
            cookie["magic"].as_str().unwrap().as_bytes()
        );
        assert_eq!(log.cookie().log_mode as i64, int(&cookie["log_mode"]));

        let expected = json["entries"].as_array().unwrap();
        assert!(!expected.is_empty(), "{name}: no entries in JSON");
        let mut names = NameTable::new();
        let mut described = Described::default();
        let mut count = 0;
        let mut end = vrpn::wire::COOKIE_LEN;
        let mut entries = log.entries();
        let mut i = 0;
        while let Some(entry) = entries.next_entry() {
            let entry = entry.unwrap_or_else(|e| panic!("{e}"));
            let j = expected.get(i).unwrap_or_else(|| {
                panic!("{name}: more entries than the JSON's {}", expected.len())
            });
            // Resolve user-message names before this entry changes the tables.
            if !entry.is_system() {
                check_entry(&entry, j, &names, &mut described);
            }
            names.observe(&entry).expect("descriptions decode");
            if entry.is_system() {
                check_entry(&entry, j, &names, &mut described);
            }
            end = entry.end_offset();
            count += 1;
            i += 1;
        }
        assert_eq!(count, expected.len(), "{name}: entry count");
        assert_eq!(
            (log.len() - end as u64) as i64,
            int(&json["trailing_bytes"]),
            "{name}: trailing bytes"
        );
        assert_eq!(described.senders, id_names(&json["senders_described"]));
        assert_eq!(described.types, id_names(&json["types_described"]));
        let udp: Vec<(i64, String)> = json["udp_descriptions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| (int(&d["port"]), d["host"].as_str().unwrap().to_owned()))
            .collect();
        assert_eq!(described.udp, udp, "{name}: UDP descriptions");
        assert_eq!(
            described.log.len(),
            json["log_descriptions"].as_array().unwrap().len(),
            "{name}: log descriptions"
        );
        total += count;
    }
    assert_eq!(total, 47 + 249 + 883 + 34 + 299 + 34 + 1259);
}

#[test]
fn tracker_reports_were_checked() {
    // Guard against the tracker comparison above silently matching nothing.
    let mut reports = 0;
    for (path, json) in golden_logs() {
        let log = LogReader::open(&path).unwrap();
        let mut entries = log.entries();
        for j in json["entries"].as_array().unwrap() {
            let entry = entries.next_entry().unwrap().unwrap();
            if j["type"].as_str() == Some("vrpn_Tracker Pos_Quat") {
                assert_eq!(entry.payload.len(), 64);
                assert!(j["payload"]["quat"].as_array().unwrap().len() == 4);
                reports += 1;
            }
        }
    }
    assert_eq!(reports, 286 + 90 + 410);
}

/// Re-encodes every entry of `log` through a writer into `sink`, draining it in uneven bounded
/// steps along the way.
fn relog<W: std::io::Write>(log: &LogReader, writer: &mut LogWriter<W>) {
    let mut entries = log.entries();
    let mut i = 0;
    while let Some(entry) = entries.next_entry() {
        let e = entry.unwrap();
        writer
            .log_message(e.type_id(), e.sender(), e.time(), e.payload)
            .unwrap();
        i += 1;
        let step = (i * 37) % 500;
        let n = writer.flush_some(step).unwrap();
        assert!(n <= step);
    }
}

#[test]
fn writer_reproduces_every_golden_log_byte_for_byte() {
    for (path, _) in golden_logs() {
        let log = LogReader::open(&path).unwrap();
        let mut w = LogWriter::new(Vec::new(), "mem", log.cookie_bytes(), 0);
        relog(&log, &mut w);
        let out = w.finish().unwrap();
        assert!(
            out == std::fs::read(&path).unwrap(),
            "{}: bytes differ",
            path.display()
        );
    }
}

#[test]
fn writer_file_output_matches_and_drop_flushes() {
    let dir = std::env::temp_dir().join(format!("vrpn-golden-relog-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (path, _) in golden_logs() {
        let log = LogReader::open(&path).unwrap();
        let out = dir.join(path.file_name().unwrap());
        let _ = std::fs::remove_file(&out);
        {
            let mut w = LogWriter::create(&out, log.cookie_bytes()).unwrap();
            relog(&log, &mut w);
            // Dropped with bytes still buffered.
        }
        let written = std::fs::read(&out).unwrap();
        assert!(
            written == std::fs::read(&path).unwrap(),
            "{}: file differs",
            out.display()
        );
        std::fs::remove_file(&out).unwrap();
    }
    let _ = std::fs::remove_dir(&dir);
}

#[test]
fn truncation_anywhere_in_the_tail_stops_cleanly() {
    for (path, _) in golden_logs() {
        let full = std::fs::read(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let whole = LogReader::open(&path).unwrap();
        let mut bounds: Vec<(usize, usize, u32)> = Vec::new();
        let mut entries = whole.entries();
        while let Some(e) = entries.next_entry() {
            let e = e.unwrap();
            bounds.push((e.offset, e.end_offset(), e.header.payload_len));
        }
        assert!(bounds.len() >= 4);
        let tail_start = bounds[bounds.len() - 4].0;
        for cut in tail_start..=full.len() {
            let log = LogReader::from_bytes(full[..cut].to_vec(), &name).unwrap();
            let mut it = log.entries();
            let whole_entries = bounds.iter().filter(|b| b.1 <= cut).count();
            for (i, b) in bounds.iter().take(whole_entries).enumerate() {
                let e = it
                    .next_entry()
                    .unwrap()
                    .unwrap_or_else(|e| panic!("cut {cut}: {e}"));
                assert_eq!(e.offset, b.0, "cut {cut}, entry {i}");
            }
            match bounds.iter().find(|b| b.0 < cut && cut < b.1) {
                None => {}
                Some(&(start, _, payload_len)) => {
                    let err = it
                        .next_entry()
                        .expect("an error after the whole entries")
                        .unwrap_err();
                    let have = cut - start;
                    let problem = if have < ENTRY_HEADER_LEN {
                        EntryProblem::TruncatedHeader { available: have }
                    } else {
                        EntryProblem::TruncatedPayload {
                            payload_len,
                            available: have - ENTRY_HEADER_LEN,
                        }
                    };
                    match &err {
                        LogError::BadEntry {
                            offset, problem: p, ..
                        } => {
                            assert_eq!((*offset, *p), (start, problem), "cut {cut}");
                        }
                        other => panic!("cut {cut}: unexpected {other:?}"),
                    }
                    let text = err.to_string();
                    assert!(
                        text.starts_with(&format!("{name}: byte {start}: ")),
                        "{text}"
                    );
                }
            }
            assert!(it.next_entry().is_none(), "cut {cut}: iterator must end");
        }
        for cut in 0..vrpn::wire::COOKIE_LEN {
            let err = LogReader::from_bytes(full[..cut].to_vec(), &name).unwrap_err();
            assert!(matches!(err, LogError::BadCookie { .. }), "cut {cut}");
        }
    }
}

#[test]
fn corrupted_length_fields_are_errors() {
    for (path, _) in golden_logs() {
        let full = std::fs::read(&path).unwrap();
        let whole = LogReader::open(&path).unwrap();
        let mut offsets: Vec<(usize, u32)> = Vec::new();
        let mut entries = whole.entries();
        while let Some(e) = entries.next_entry() {
            let e = e.unwrap();
            offsets.push((e.offset, e.header.payload_len));
        }
        let mid = offsets.len() / 2;
        let (at, _) = offsets[mid];
        let (last_at, last_len) = offsets[offsets.len() - 1];
        let cases = [
            (at, 0x7fff_ffffu32, EntryProblem::LengthTooLong(0x7fff_ffff)),
            (at, 1_000_000, EntryProblem::LengthTooLong(1_000_000)),
            (at, 0xffff_fff0, EntryProblem::NegativeLength(-16)),
            (
                last_at,
                last_len + 1,
                EntryProblem::TruncatedPayload {
                    payload_len: last_len + 1,
                    available: last_len as usize,
                },
            ),
        ];
        for (at, len, problem) in cases {
            let mut bytes = full.clone();
            BigEndian::write_u32(&mut bytes[at + 16..at + 20], len);
            let log = LogReader::from_bytes(bytes, "corrupt.vrpn").unwrap();
            let mut items = Vec::new();
            let mut entries = log.entries();
            while let Some(e) = entries.next_entry() {
                items.push(e.map(|e| e.offset));
            }
            let before = offsets.iter().filter(|o| o.0 < at).count();
            assert_eq!(items.len(), before + 1, "{}", path.display());
            assert!(items[..before].iter().all(|r| r.is_ok()));
            match &items[before] {
                Err(LogError::BadEntry {
                    offset, problem: p, ..
                }) => assert_eq!((*offset, *p), (at, problem)),
                other => panic!("unexpected {other:?}"),
            }
        }
    }
}

#[test]
fn timestamps_round_trip_through_timeval() {
    // The writer takes a TimeVal; header seconds above 2^31 must survive the trip.
    for (path, _) in golden_logs() {
        let log = LogReader::open(&path).unwrap();
        let mut entries = log.entries();
        while let Some(e) = entries.next_entry() {
            let e = e.unwrap();
            let (sec, usec) = e.time().to_wire();
            assert_eq!((sec, usec), (e.header.sec, e.header.usec));
        }
    }
    assert_eq!(
        TimeVal::from_header_words(0xffff_fff0, 1).to_wire(),
        (0xffff_fff0, 1)
    );
}
