//! The `vrpn_log` program run on the C++-written golden logs in `tests/fixtures/golden`: its
//! summary, dump and CSV output must agree with the decoded truth in each `.expected.json`, and
//! damaged files must be reported with file, offset and problem.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn fixture_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/golden")
}

/// Every golden `*.vrpn` with its parsed `.expected.json`.
fn golden_logs() -> Vec<(PathBuf, Value)> {
    let mut logs: Vec<(PathBuf, Value)> = std::fs::read_dir(fixture_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "vrpn"))
        .map(|p| {
            let mut json = p.clone().into_os_string();
            json.push(".expected.json");
            let text = std::fs::read_to_string(&json).unwrap();
            (p, serde_json::from_str(&text).unwrap())
        })
        .collect();
    logs.sort_by(|a, b| a.0.cmp(&b.0));
    assert_eq!(logs.len(), 7, "golden logs missing");
    logs
}

fn golden(name: &str) -> (PathBuf, Value) {
    golden_logs()
        .into_iter()
        .find(|(p, _)| p.file_name().unwrap() == name)
        .unwrap_or_else(|| panic!("no golden log {name}"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vrpn_log-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Runs vrpn_log; returns exit code, stdout, stderr.
fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vrpn_log"))
        .args(args)
        .output()
        .expect("run vrpn_log");
    (
        out.status.code().expect("exit code, not a signal"),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

fn entries(json: &Value) -> &Vec<Value> {
    json["entries"].as_array().unwrap()
}

fn user_entries(json: &Value) -> impl Iterator<Item = &Value> {
    entries(json)
        .iter()
        .filter(|e| e["type_id"].as_i64().unwrap() >= 0)
}

/// `(sender, type) → count` of user messages in the expected JSON.
fn expected_counts(json: &Value) -> BTreeMap<(String, String), u64> {
    let mut m = BTreeMap::new();
    for e in user_entries(json) {
        let key = (
            e["sender"].as_str().unwrap().to_owned(),
            e["type"].as_str().unwrap().to_owned(),
        );
        *m.entry(key).or_insert(0) += 1;
    }
    m
}

fn micros(e: &Value) -> i64 {
    e["sec"].as_i64().unwrap() * 1_000_000 + e["usec"].as_i64().unwrap()
}

fn time_text(us: i64) -> String {
    format!(
        "{}.{:06}",
        us.div_euclid(1_000_000),
        us.rem_euclid(1_000_000)
    )
}

/// What `vrpn_log summary` printed, parsed back.
#[derive(Debug, Default)]
struct ParsedSummary {
    fields: BTreeMap<String, String>,
    counts: BTreeMap<(String, String), u64>,
    system: BTreeMap<String, u64>,
}

fn parse_summary(text: &str) -> ParsedSummary {
    let mut s = ParsedSummary::default();
    let mut device: Option<String> = None;
    let mut in_system = false;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("  device ") {
            let name = rest.rsplit_once(" (").unwrap().0;
            device = Some(name.to_owned());
        } else if let Some(rest) = line.strip_prefix("    ") {
            let rest = rest.trim_start();
            let (count, rest) = rest.split_once(' ').unwrap();
            let count: u64 = count.parse().unwrap();
            if in_system {
                s.system.insert(rest.trim().to_owned(), count);
            } else {
                let (_rate, ty) = rest.trim_start().split_once("  ").unwrap();
                let dev = device.clone().expect("type line outside a device");
                s.counts.insert((dev, ty.to_owned()), count);
            }
        } else if let Some((k, v)) = line.split_once(": ") {
            in_system = k == "system messages";
            device = None;
            s.fields.insert(k.to_owned(), v.to_owned());
        }
    }
    s
}

#[test]
fn summary_counts_match_the_expected_json() {
    for (path, json) in golden_logs() {
        let (code, out, err) = run(&["summary", p(&path)]);
        assert_eq!(code, 0, "{}: {err}", path.display());
        let s = parse_summary(&out);
        let name = path.display();

        assert_eq!(s.counts, expected_counts(&json), "{name}\n{out}");
        let all = entries(&json);
        let users: Vec<&Value> = user_entries(&json).collect();
        assert_eq!(
            s.fields["entries"],
            format!(
                "{} whole ({} user messages, {} system messages)",
                all.len(),
                users.len(),
                all.len() - users.len()
            ),
            "{name}"
        );
        assert_eq!(
            s.fields["cookie"],
            format!("{}, log mode 0", json["cookie"]["magic"].as_str().unwrap())
        );

        let lo = users.iter().map(|e| micros(e)).min().unwrap();
        let hi = users.iter().map(|e| micros(e)).max().unwrap();
        assert_eq!(s.fields["first user message"], time_text(lo), "{name}");
        assert_eq!(s.fields["last user message"], time_text(hi), "{name}");
        assert_eq!(
            s.fields["duration"],
            format!("{} s", time_text(hi - lo)),
            "{name}"
        );

        let sys = |kind: &str| all.iter().filter(|e| e["system"] == kind).count() as u64;
        assert_eq!(s.system["sender descriptions"], sys("SENDER_DESCRIPTION"));
        assert_eq!(s.system["type descriptions"], sys("TYPE_DESCRIPTION"));
        assert_eq!(s.system["UDP descriptions"], sys("UDP_DESCRIPTION"));
        assert_eq!(s.system["log descriptions"], sys("LOG_DESCRIPTION"));
        assert_eq!(s.system["disconnects"], sys("DISCONNECT"));
        assert!(!out.contains("damaged tail"));
    }
}

#[test]
fn summary_of_specific_logs() {
    let (path, _) = golden("tracker_udp_lob.out.vrpn");
    let (_, out, _) = run(&["summary", p(&path)]);
    let s = parse_summary(&out);
    let pq = ("Tracker0".to_owned(), "vrpn_Tracker Pos_Quat".to_owned());
    assert_eq!(s.counts[&pq], 410);
    // Two sensors at 60 Hz: close to 120 poses a second.
    let rate_line = out
        .lines()
        .find(|l| l.ends_with("vrpn_Tracker Pos_Quat"))
        .unwrap();
    let rate: f64 = rate_line
        .split_whitespace()
        .nth(1)
        .unwrap()
        .trim_end_matches("/s")
        .parse()
        .unwrap();
    assert!((100.0..125.0).contains(&rate), "{rate_line}");

    // vrpn_Joylin's button half never stamps its States messages.
    let (path, _) = golden("button_analog_dial.out.vrpn");
    let (_, out, _) = run(&["summary", p(&path)]);
    assert!(out.contains("first user message: 0.000000"), "{out}");
    assert!(
        out.contains("note: 6 user messages carry a zero timestamp; without them the first is 1795309401.663779"),
        "{out}"
    );
}

/// Checks one `dump --json` object against its expected entry, doubles bit for bit.
fn check_entry(got: &Value, want: &Value, ctx: &str) {
    for key in ["offset", "sec", "usec", "type_id"] {
        assert_eq!(got[key], want[key], "{ctx}: {key}");
    }
    assert_eq!(got["sender_id"], want["sender_id"], "{ctx}");
    let t = format!(
        "{}.{:06}",
        want["sec"].as_i64().unwrap(),
        want["usec"].as_i64().unwrap()
    );
    assert_eq!(
        got["time"].as_f64().unwrap().to_bits(),
        t.parse::<f64>().unwrap().to_bits(),
        "{ctx}: time"
    );
    let bits = |v: &Value| -> Vec<u64> {
        match v {
            Value::Array(a) => a.iter().map(|x| x.as_f64().unwrap().to_bits()).collect(),
            x => vec![x.as_f64().unwrap().to_bits()],
        }
    };
    if let Some(system) = want["system"].as_str() {
        assert_eq!(got["kind"], "system", "{ctx}");
        assert_eq!(got["type"], system, "{ctx}");
        assert_eq!(got["sender"], Value::Null, "{ctx}");
        match system {
            "SENDER_DESCRIPTION" | "TYPE_DESCRIPTION" => {
                let d = if system == "SENDER_DESCRIPTION" {
                    &want["described_sender"]
                } else {
                    &want["described_type"]
                };
                assert_eq!(got["id"], d["id"], "{ctx}");
                assert_eq!(got["name"], d["name"], "{ctx}");
            }
            "UDP_DESCRIPTION" => {
                assert_eq!(got["port"], want["udp_description"]["port"], "{ctx}");
                assert_eq!(got["host"], want["udp_description"]["host"], "{ctx}");
            }
            "DISCONNECT" => assert_eq!(got["system"], "disconnect", "{ctx}"),
            other => panic!("{ctx}: unexpected system entry {other}"),
        }
        return;
    }
    assert_eq!(got["sender"], want["sender"], "{ctx}");
    assert_eq!(got["type"], want["type"], "{ctx}");
    let w = &want["payload"];
    match want["type"].as_str().unwrap() {
        "vrpn_Tracker Pos_Quat" => {
            assert_eq!(got["kind"], "pose", "{ctx}");
            assert_eq!(got["sensor"], w["sensor"], "{ctx}");
            assert_eq!(bits(&got["pos"]), bits(&w["pos"]), "{ctx}");
            assert_eq!(bits(&got["quat"]), bits(&w["quat"]), "{ctx}");
        }
        "vrpn_Tracker Velocity" => {
            assert_eq!(got["kind"], "velocity", "{ctx}");
            assert_eq!(got["sensor"], w["sensor"], "{ctx}");
            for k in ["vel", "vel_quat", "vel_quat_dt"] {
                assert_eq!(bits(&got[k]), bits(&w[k]), "{ctx}: {k}");
            }
        }
        "vrpn_Tracker Acceleration" => {
            assert_eq!(got["kind"], "acceleration", "{ctx}");
            assert_eq!(got["sensor"], w["sensor"], "{ctx}");
            for k in ["acc", "acc_quat", "acc_quat_dt"] {
                assert_eq!(bits(&got[k]), bits(&w[k]), "{ctx}: {k}");
            }
        }
        "vrpn_Button Change" => {
            assert_eq!(got["kind"], "button", "{ctx}");
            assert_eq!(got["button"], w["button"], "{ctx}");
            assert_eq!(got["state"], w["state"], "{ctx}");
        }
        "vrpn_Button States" => {
            assert_eq!(got["kind"], "button_states", "{ctx}");
            assert_eq!(got["states"], w["states"], "{ctx}");
            assert_eq!(
                got["states"].as_array().unwrap().len() as i64,
                w["num_buttons"].as_i64().unwrap()
            );
        }
        "vrpn_Analog Channel" => {
            assert_eq!(got["kind"], "analog", "{ctx}");
            assert_eq!(bits(&got["channels"]), bits(&w["channels"]), "{ctx}");
            assert_eq!(
                got["channels"].as_array().unwrap().len() as i64,
                w["num_channel"].as_i64().unwrap()
            );
        }
        "vrpn_Dial update" => {
            assert_eq!(got["kind"], "dial", "{ctx}");
            assert_eq!(got["dial"], w["dial"], "{ctx}");
            assert_eq!(bits(&got["change"]), bits(&w["change"]), "{ctx}");
        }
        "vrpn_Base ping_message" => assert_eq!(got["kind"], "ping", "{ctx}"),
        "vrpn_Base pong_message" => assert_eq!(got["kind"], "pong", "{ctx}"),
        other => panic!("{ctx}: no check for {other}"),
    }
}

#[test]
fn dump_json_matches_every_expected_entry() {
    for (path, json) in golden_logs() {
        let (code, out, err) = run(&["dump", "--json", p(&path)]);
        assert_eq!(code, 0, "{}: {err}", path.display());
        let lines: Vec<&str> = out.lines().collect();
        let want = entries(&json);
        assert_eq!(lines.len(), want.len(), "{}", path.display());
        for (i, (line, w)) in lines.iter().zip(want).enumerate() {
            let got: Value = serde_json::from_str(line).unwrap_or_else(|e| {
                panic!("{}: line {i} is not JSON ({e}): {line}", path.display())
            });
            check_entry(&got, w, &format!("{} entry {i}", path.display()));
        }
    }
}

#[test]
fn dump_text_and_filters() {
    let (path, json) = golden("tracker_spin.out.vrpn");
    let (code, out, _) = run(&["dump", p(&path)]);
    assert_eq!(code, 0);
    assert_eq!(out.lines().count(), entries(&json).len());
    let first_pose = out
        .lines()
        .find(|l| l.contains("Pos_Quat  sensor"))
        .unwrap();
    assert_eq!(
        first_pose,
        "    1003  1795309456.792781  Tracker0  vrpn_Tracker Pos_Quat  sensor 0  pos (0, 0, 0)  \
         quat (0, 0.00005654866773447817, 0, 0.9999999984011241)"
    );
    assert!(out
        .lines()
        .next()
        .unwrap()
        .ends_with("1795309456.792736  -  SENDER_DESCRIPTION  id 1  name \"Tracker0\""));
    assert!(out.lines().last().unwrap().ends_with("-  DISCONNECT"));

    let (code, out, _) = run(&[
        "dump",
        p(&path),
        "--device",
        "Tracker0",
        "--type",
        "vrpn_Tracker Velocity",
        "--json",
    ]);
    assert_eq!(code, 0);
    let want: Vec<&Value> = user_entries(&json)
        .filter(|e| e["type"] == "vrpn_Tracker Velocity")
        .collect();
    assert_eq!(out.lines().count(), want.len());
    for (line, w) in out.lines().zip(&want) {
        check_entry(&serde_json::from_str(line).unwrap(), w, "velocity filter");
    }

    let (code, out, _) = run(&["dump", p(&path), "--type", "DISCONNECT"]);
    assert_eq!((code, out.lines().count()), (0, 1));

    let (code, out, err) = run(&["dump", p(&path), "--device", "Nobody"]);
    assert_eq!((code, out.as_str()), (1, ""));
    assert!(
        err.contains("no device \"Nobody\"") && err.contains("devices: Tracker0"),
        "{err}"
    );
}

#[test]
fn dump_shows_text_messages_and_unknown_types_as_hex() {
    // A log made here with the entry encoder: a text message and an undescribed type (the
    // golden logs hold neither).
    use vrpn::log::encode_entry;
    use vrpn::wire::payload::text::{TextMessage, ERROR};
    use vrpn::wire::system::encode_description;
    use vrpn::TimeVal;

    let mut file = b"vrpn: ver. 07.38  0\0\0\0\0\0".to_vec();
    let mut add = |type_id: i32, sender: i32, payload: &[u8]| {
        let mut buf = vec![0u8; 24 + payload.len()];
        let n = encode_entry(&mut buf, type_id, sender, TimeVal::new(7, 8), payload).unwrap();
        file.extend_from_slice(&buf[..n]);
    };
    let mut d = [0u8; 64];
    let n = encode_description(&mut d, "Joy0");
    add(-1, 3, &d[..n]);
    let n = encode_description(&mut d, "vrpn_Base text_message");
    add(-2, 9, &d[..n]);
    let mut t = [0u8; 1032];
    TextMessage::new(ERROR, 2, b"Error reading from joystick")
        .unwrap()
        .encode(&mut t);
    add(9, 3, &t);
    add(42, 3, &[0x5a; 40]);
    let path = scratch("text.vrpn");
    std::fs::write(&path, &file).unwrap();

    let (code, out, err) = run(&["dump", p(&path)]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(
        lines[2],
        "     108  7.000008  Joy0  vrpn_Base text_message  severity \"error\"  level 2  \
         text \"Error reading from joystick\""
    );
    assert_eq!(
        lines[3],
        format!(
            "    1164  7.000008  Joy0  <type 42>  len 40  hex {}...",
            "5a".repeat(32)
        )
    );
    let (_, out, _) = run(&["dump", "--json", p(&path)]);
    let j: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(j[2]["kind"], "text");
    assert_eq!(j[2]["severity"], "error");
    assert_eq!(j[2]["text"], "Error reading from joystick");
    assert_eq!(j[3]["kind"], "raw");
    assert_eq!(j[3]["type"], Value::Null);
    assert_eq!(j[3]["hex"], "5a".repeat(40));
}

/// Parses CSV text into a header and rows of cells.
fn parse_csv(text: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect();
    (header, rows)
}

fn cell_bits(cell: &str) -> u64 {
    cell.parse::<f64>()
        .unwrap_or_else(|e| panic!("{cell:?}: {e}"))
        .to_bits()
}

#[test]
fn csv_poses_match_the_expected_json() {
    for name in [
        "tracker_spin.out.vrpn",
        "tracker_udp_lob.out.vrpn",
        "tracker_client_log.client_in.vrpn",
    ] {
        let (path, json) = golden(name);
        let (code, out, err) = run(&["csv", p(&path), "Tracker0"]);
        assert_eq!(code, 0, "{name}: {err}");
        let (header, rows) = parse_csv(&out);
        assert_eq!(header.join(","), "time,sensor,x,y,z,qx,qy,qz,qw");
        let poses: Vec<&Value> = user_entries(&json)
            .filter(|e| e["type"] == "vrpn_Tracker Pos_Quat")
            .collect();
        assert_eq!(rows.len(), poses.len(), "{name}");
        for (row, e) in rows.iter().zip(&poses) {
            assert_eq!(row.len(), 9);
            assert_eq!(row[0], time_text(micros(e)), "{name}");
            assert_eq!(row[1], e["payload"]["sensor"].to_string());
            let want: Vec<u64> = ["pos", "quat"]
                .iter()
                .flat_map(|k| e["payload"][*k].as_array().unwrap().clone())
                .map(|v| v.as_f64().unwrap().to_bits())
                .collect();
            let got: Vec<u64> = row[2..].iter().map(|c| cell_bits(c)).collect();
            assert_eq!(got, want, "{name} row at {}", row[0]);
        }
    }
}

#[test]
fn csv_other_kinds_and_output_file() {
    let (path, json) = golden("button_analog_dial.out.vrpn");
    let of_type = |t: &str, s: &str| -> Vec<Value> {
        user_entries(&json)
            .filter(|e| e["type"] == t && e["sender"] == s)
            .cloned()
            .collect()
    };

    let out_path = scratch("analog.csv");
    let (code, out, err) = run(&[
        "csv",
        p(&path),
        "Analog0",
        "--kind",
        "analog",
        "-o",
        p(&out_path),
    ]);
    assert_eq!((code, out.as_str()), (0, ""), "{err}");
    let (header, rows) = parse_csv(&std::fs::read_to_string(&out_path).unwrap());
    assert_eq!(header.join(","), "time,n,ch0,ch1");
    let want = of_type("vrpn_Analog Channel", "Analog0");
    assert_eq!(rows.len(), want.len());
    for (row, e) in rows.iter().zip(&want) {
        assert_eq!(row[0], time_text(micros(e)));
        assert_eq!(row[1], "2");
        let ch: Vec<u64> = e["payload"]["channels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap().to_bits())
            .collect();
        assert_eq!(
            row[2..].iter().map(|c| cell_bits(c)).collect::<Vec<_>>(),
            ch
        );
    }

    let (code, out, _) = run(&["csv", p(&path), "Button0", "--kind", "button"]);
    assert_eq!(code, 0);
    let (header, rows) = parse_csv(&out);
    assert_eq!(header.join(","), "time,button,state");
    let want = of_type("vrpn_Button Change", "Button0");
    assert_eq!(rows.len(), want.len());
    assert_eq!(
        rows[0],
        vec![
            time_text(micros(&want[0])),
            want[0]["payload"]["button"].to_string(),
            want[0]["payload"]["state"].to_string()
        ]
    );

    let (code, out, _) = run(&["csv", p(&path), "Dial0", "--kind", "dial"]);
    assert_eq!(code, 0);
    let (header, rows) = parse_csv(&out);
    assert_eq!(header.join(","), "time,dial,change");
    assert_eq!(rows.len(), of_type("vrpn_Dial update", "Dial0").len());
    assert_eq!(rows[1][1..], ["1".to_owned(), "0.1".to_owned()]);

    let (path, json) = golden("tracker_spin.out.vrpn");
    let (code, out, _) = run(&["csv", p(&path), "Tracker0", "--kind", "velocity"]);
    assert_eq!(code, 0);
    let (header, rows) = parse_csv(&out);
    assert_eq!(header.join(","), "time,sensor,vx,vy,vz,qx,qy,qz,qw,dt");
    let vels: Vec<&Value> = user_entries(&json)
        .filter(|e| e["type"] == "vrpn_Tracker Velocity")
        .collect();
    assert_eq!(rows.len(), vels.len());
    assert_eq!(cell_bits(&rows[0][6]), 0.9876883405951378f64.to_bits());
    assert_eq!(rows[0][9], "0.9");
}

#[test]
fn csv_unknown_device_or_kind_is_a_clear_error() {
    let (path, _) = golden("button_analog_dial.out.vrpn");
    let (code, out, err) = run(&["csv", p(&path), "Tracker0"]);
    assert_eq!((code, out.as_str()), (1, ""));
    assert!(
        err.contains("no device \"Tracker0\" in the log; devices: Button0, Dial0, Analog0"),
        "{err}"
    );
    let (code, _, err) = run(&["csv", p(&path), "Dial0"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("Dial0 sent no pose reports; it sent: dial, pong"),
        "{err}"
    );
    let (code, _, err) = run(&["csv", p(&path), "Dial0", "--kind", "spin"]);
    assert_eq!(code, 2);
    assert!(err.contains("unknown kind \"spin\""), "{err}");
}

#[test]
fn truncated_log_reports_offset_and_keeps_whole_entries() {
    let (path, json) = golden("tracker_udp_lob.out.vrpn");
    let bytes = std::fs::read(&path).unwrap();
    let all = entries(&json);
    // Cut inside the payload of entry 700, then inside the header of entry 900.
    for (k, into) in [(700usize, 30usize), (900, 10)] {
        let at = all[k]["offset"].as_u64().unwrap() as usize;
        let cut = scratch(&format!("cut-{k}.vrpn"));
        std::fs::write(&cut, &bytes[..at + into]).unwrap();

        let (code, out, err) = run(&["summary", p(&cut)]);
        assert_eq!(code, 1);
        let want_err = format!("{}: byte {at}: file ends inside an entry", cut.display());
        assert!(err.contains(&want_err), "{err}");
        assert!(out.contains(&format!("damaged tail: {want_err}")), "{out}");
        let s = parse_summary(&out);
        let whole = &all[..k];
        assert!(
            s.fields["entries"].starts_with(&format!("{} whole", k)),
            "{out}"
        );
        let pq = whole
            .iter()
            .filter(|e| e["type"] == "vrpn_Tracker Pos_Quat")
            .count() as u64;
        assert_eq!(
            s.counts[&("Tracker0".to_owned(), "vrpn_Tracker Pos_Quat".to_owned())],
            pq
        );

        let (code, out, err) = run(&["dump", "--json", p(&cut)]);
        assert_eq!(code, 1);
        assert!(err.contains(&want_err), "{err}");
        assert_eq!(out.lines().count(), k);

        let (code, out, _) = run(&["csv", p(&cut), "Tracker0"]);
        assert_eq!(code, 1);
        assert_eq!(out.lines().count() as u64, pq + 1);
    }
}

#[test]
fn corrupt_length_bad_cookie_and_missing_file() {
    let (path, json) = golden("tracker_spin.out.vrpn");
    let mut bytes = std::fs::read(&path).unwrap();
    let at = entries(&json)[50]["offset"].as_u64().unwrap() as usize;
    bytes[at + 16..at + 20].copy_from_slice(&0x7fff_0000u32.to_be_bytes());
    let bad = scratch("corrupt.vrpn");
    std::fs::write(&bad, &bytes).unwrap();
    let (code, out, err) = run(&["summary", p(&bad)]);
    assert_eq!(code, 1);
    assert!(
        err.contains(&format!(
            "{}: byte {at}: corrupt entry: payload length",
            bad.display()
        )),
        "{err}"
    );
    assert!(out.contains("entries: 50 whole"), "{out}");

    let not_log = scratch("notalog.vrpn");
    std::fs::write(&not_log, b"GIF89a this is no VRPN log at all").unwrap();
    let (code, out, err) = run(&["dump", p(&not_log)]);
    assert_eq!((code, out.as_str()), (1, ""));
    assert!(
        err.contains(&format!("{}: byte 0: not a VRPN", not_log.display())),
        "{err}"
    );

    let (code, _, err) = run(&["summary", "/nonexistent/x.vrpn"]);
    assert_eq!(code, 1);
    assert_eq!(
        err.trim_end(),
        "vrpn_log: cannot read log file /nonexistent/x.vrpn: no such file"
    );

    let empty = scratch("empty.vrpn");
    std::fs::write(&empty, b"").unwrap();
    let (code, _, err) = run(&["csv", p(&empty), "Tracker0"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("file too short for the 24-byte cookie"),
        "{err}"
    );

    // A cookie and nothing else is a valid, empty log.
    let bare = scratch("bare.vrpn");
    std::fs::write(&bare, b"vrpn: ver. 07.38  0\0\0\0\0\0").unwrap();
    let (code, out, _) = run(&["summary", p(&bare)]);
    assert_eq!(code, 0);
    assert!(out.contains("entries: 0 whole") && out.contains("duration: - (no user messages)"));
}

#[test]
fn usage() {
    for args in [&["-h"][..], &["--help"], &["dump", "-h"]] {
        let (code, out, _) = run(args);
        assert_eq!(code, 0);
        assert!(out.starts_with("usage: vrpn_log summary FILE"), "{out}");
        assert!(out.contains("--kind KIND"));
    }
    let (code, _, err) = run(&[]);
    assert_eq!(code, 2);
    assert!(err.contains("usage: vrpn_log"));
    let (code, _, err) = run(&["dump", "x.vrpn", "--frob"]);
    assert_eq!(code, 2);
    assert!(err.contains("unknown option --frob"), "{err}");
    let (code, _, err) = run(&["convert", "x.vrpn"]);
    assert_eq!(code, 2);
    assert!(err.contains("unknown command \"convert\""), "{err}");
    let (code, _, err) = run(&["summary"]);
    assert_eq!(code, 2);
    assert!(err.contains("expected 1 argument, got 0"), "{err}");
}
