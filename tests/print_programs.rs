//! vrpn_print_messages, vrpn_print_performance, vrpn_print_devices' C++ options and
//! vrpn_server -quiet / -logdir, as child processes against a vrpn_server child on 127.0.0.1.

mod common;

use std::process::{Command, Stdio};
use std::time::Duration;

use common::{start_server, start_server_with};

const CFG: &str = "vrpn_Tracker_NULL Tracker0 2 100.0\n\
                   vrpn_Analog_Example Analog0 3 20.0\n\
                   vrpn_Text_Example Text0 0.2 hello from the server\n";

fn run(program: &str, args: &[&str]) -> (String, String, i32) {
    let out = Command::new(program)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        out.status.code().unwrap_or(-1),
    )
}

#[test]
fn print_messages_shows_every_message_in_the_cpp_format() {
    let server = start_server(CFG, 0);
    let at = format!("127.0.0.1:{}", server.port);
    let (out, err, code) = run(
        env!("CARGO_BIN_EXE_vrpn_print_messages"),
        &["--seconds", "1", &at],
    );
    assert_eq!(code, 0, "{err}");
    let poses = out
        .lines()
        .filter(|l| {
            l.starts_with("Time: ")
                && l.ends_with("Sender: Tracker0, Type vrpn_Tracker Pos_Quat, Length 64")
        })
        .count();
    // 2 sensors at 100 Hz for about a second (less the connection set-up).
    assert!(poses > 100, "{poses} pose lines in\n{out}");
    assert!(out.contains("Sender: Analog0, Type vrpn_Analog Channel, Length"));
    assert!(out.contains("Sender: Text0, Type vrpn_Base text_message, Length 1032"));
    // The connection's own events are not messages.
    assert!(!out.contains("Got_Connection"), "{out}");
    let (json, _, code) = run(
        env!("CARGO_BIN_EXE_vrpn_print_messages"),
        &["--json", "--seconds", "0.5", &at],
    );
    assert_eq!(code, 0);
    let first: serde_json::Value = serde_json::from_str(json.lines().next().unwrap()).unwrap();
    assert!(first["time"].as_f64().unwrap() > 1e9);
    assert!(first["length"].as_u64().is_some());
}

#[test]
fn print_messages_reads_a_log_to_its_end() {
    let dir = std::env::temp_dir().join(format!("vrpn-printmsg-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("run.vrpn");
    {
        let server = start_server(CFG, 0);
        let at = format!("Tracker0@127.0.0.1:{}", server.port);
        let (_, err, code) = run(
            env!("CARGO_BIN_EXE_vrpn_print_devices"),
            &["--seconds", "0.6", "--log", log.to_str().unwrap(), &at],
        );
        assert_eq!(code, 0, "{err}");
    }
    let (out, err, code) = run(
        env!("CARGO_BIN_EXE_vrpn_print_messages"),
        &["--seconds", "20", &format!("file:{}", log.display())],
    );
    assert_eq!(code, 0, "{err}");
    let poses = out.lines().filter(|l| l.contains("Pos_Quat")).count();
    assert!(poses > 20, "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn print_performance_reports_rates() {
    let server = start_server(CFG, 0);
    let tracker = format!("Tracker0@127.0.0.1:{}", server.port);
    let analog = format!("Analog0@127.0.0.1:{}", server.port);
    let (out, err, code) = run(
        env!("CARGO_BIN_EXE_vrpn_print_performance"),
        &["--seconds", "2.6", &tracker, "-notracker", &analog],
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains(&format!("Opened {tracker} as: Tracker Button Analog.")));
    assert!(out.contains(&format!("Opened {analog} as: Button Analog.")));
    let hz: Vec<f64> = out
        .lines()
        .filter(|l| l.starts_with(&format!("Tracker {tracker}, sensor 1:\t")) && l.contains("Hz"))
        .filter_map(|l| {
            l.split('\t')
                .nth(1)?
                .split_whitespace()
                .next()?
                .parse()
                .ok()
        })
        .collect();
    assert!(!hz.is_empty(), "{out}");
    assert!(hz.iter().all(|h| (70.0..130.0).contains(h)), "{hz:?}");
    assert!(out.contains(&format!("Analog {analog}:\t\t")), "{out}");
    assert!(!out.contains(&format!("Tracker {analog}")));
    // The GNU spelling of the C++ option does the same.
    let (out, _, _) = run(
        env!("CARGO_BIN_EXE_vrpn_print_performance"),
        &["--notracker", "--noanalog", "--seconds", "0.3", &tracker],
    );
    assert!(
        out.contains(&format!("Opened {tracker} as: Button.")),
        "{out}"
    );
}

#[test]
fn print_devices_cpp_options_select_what_is_printed() {
    let server = start_server(CFG, 0);
    let tracker = format!("Tracker0@127.0.0.1:{}", server.port);
    let analog = format!("Analog0@127.0.0.1:{}", server.port);
    let text = format!("Text0@127.0.0.1:{}", server.port);
    let pos_lines = |out: &str| out.lines().filter(|l| l.contains("pos (")).count();
    let (all, _, code) = run(
        env!("CARGO_BIN_EXE_vrpn_print_devices"),
        &["--seconds", "1", &tracker],
    );
    assert_eq!(code, 0);
    let (strided, _, _) = run(
        env!("CARGO_BIN_EXE_vrpn_print_devices"),
        &["-trackerstride", "10", "--seconds", "1", &tracker],
    );
    let (a, s) = (pos_lines(&all), pos_lines(&strided));
    assert!(a > 100, "{a}");
    assert!(s > 0 && s * 5 < a, "every 10th: {s} of {a}");
    // Options apply to the devices after them.
    let (out, _, _) = run(
        env!("CARGO_BIN_EXE_vrpn_print_devices"),
        &[
            "--seconds",
            "1",
            &analog,
            "-notracker",
            "-noanalog",
            &tracker,
        ],
    );
    assert!(out.contains(&format!(
        "Opened {analog} as: Tracker Button Analog Dial Text."
    )));
    assert!(out.contains(&format!("Opened {tracker} as: Button Dial Text.")));
    assert_eq!(pos_lines(&out), 0, "{out}");
    assert!(out.contains(&format!("Analog {analog}:")));
    // -notext: no text line; --notext (GNU spelling) the same.
    let (out, _, _) = run(
        env!("CARGO_BIN_EXE_vrpn_print_devices"),
        &["--seconds", "1", &text],
    );
    assert!(out.contains("hello from the server"), "{out}");
    for flag in ["-notext", "--notext"] {
        let (out, err, _) = run(
            env!("CARGO_BIN_EXE_vrpn_print_devices"),
            &[flag, "--seconds", "1", &text],
        );
        assert!(
            !out.contains("hello") && !err.contains("hello"),
            "{out}{err}"
        );
        assert!(out.contains(&format!("Opened {text} as: Tracker Button Analog Dial.")));
    }
    let (_, err, code) = run(
        env!("CARGO_BIN_EXE_vrpn_print_devices"),
        &["-trackerstride", "0", &tracker],
    );
    assert_eq!(code, 2);
    assert!(err.contains("1 or greater"), "{err}");
}

#[test]
fn server_quiet_prints_nothing_at_start() {
    let dir = std::env::temp_dir().join(format!("vrpn-quiet-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = dir.join("vrpn.cfg");
    std::fs::write(&cfg, CFG).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_vrpn_server"))
        .args(["-quiet", "-f", cfg.to_str().unwrap(), "0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(400));
    let _ = child.kill();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.stdout.is_empty(),
        "{:?}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(
        out.stderr.is_empty(),
        "{:?}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn server_logdir_takes_remote_logs_from_print_devices() {
    let dir = std::env::temp_dir().join(format!("vrpn-logdir-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let server = start_server_with(CFG, 0, &["-logdir", dir.to_str().unwrap()]);
    let tracker = format!("Tracker0@127.0.0.1:{}", server.port);
    let (_, err, code) = run(
        env!("CARGO_BIN_EXE_vrpn_print_devices"),
        &[
            "--seconds",
            "0.8",
            "-rlo",
            "sent.vrpn",
            "-rli",
            "got.vrpn",
            &tracker,
        ],
    );
    assert_eq!(code, 0, "{err}");
    drop(server);
    let sent = vrpn::log::LogReader::open(dir.join("sent.vrpn")).unwrap();
    let entries = sent.entries().count_whole();
    assert!(entries > 50, "{entries} entries");
    assert!(dir.join("got.vrpn").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
