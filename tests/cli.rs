//! The command lines of the programs: `--help` lists the options and exits 0, `--version`
//! prints the crate version, a wrong option is a one-line error with exit status 2.

use std::process::Command;

const SERVER: &str = env!("CARGO_BIN_EXE_vrpn_server");
const PRINT: &str = env!("CARGO_BIN_EXE_vrpn_print_devices");
const PING: &str = env!("CARGO_BIN_EXE_vrpn_ping");
const LOG: &str = env!("CARGO_BIN_EXE_vrpn_log");

/// Runs `bin args`; returns exit code, stdout, stderr.
fn run(bin: &str, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(bin).args(args).output().unwrap();
    (
        out.status.code().expect("an exit code, not a signal"),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// Every program, its help spellings, and the options its help must list.
const PROGRAMS: [(&str, &str, &[&str]); 4] = [
    (
        SERVER,
        "vrpn_server",
        &[
            "-f FILE",
            "-warn",
            "-v ",
            "-q ",
            "-millisleep N",
            "-NIC ADDR",
            "-li FILE",
            "-lo FILE",
            "-flush",
            "PORT",
            "--help",
            "--version",
        ],
    ),
    (
        PRINT,
        "vrpn_print_devices",
        &[
            "--json",
            "--seconds S",
            "--log FILE",
            "--list HOST[:PORT]",
            "--help",
            "--version",
        ],
    ),
    (
        PING,
        "vrpn_ping",
        &["-n, --count COUNT", "--help", "--version"],
    ),
    (
        LOG,
        "vrpn_log",
        &[
            "summary FILE",
            "dump FILE",
            "csv FILE DEVICE",
            "--json",
            "--device NAME",
            "--type NAME",
            "--kind KIND",
            "-o, --output OUT",
            "--help",
            "--version",
        ],
    ),
];

#[test]
fn help_lists_the_options_and_exits_0() {
    for (bin, name, options) in PROGRAMS {
        for flag in ["--help", "-h"] {
            let (code, out, err) = run(bin, &[flag]);
            assert_eq!(code, 0, "{name} {flag}: {err}");
            assert!(out.starts_with(&format!("usage: {name}")), "{name}: {out}");
            for option in options {
                assert!(
                    out.contains(option),
                    "{name} {flag} lacks {option:?}: {out}"
                );
            }
            assert!(err.is_empty(), "{name}: {err}");
        }
    }
    // The C++ spelling too.
    let (code, out, _) = run(SERVER, &["-help"]);
    assert_eq!(code, 0);
    assert!(out.starts_with("usage: vrpn_server"));
}

#[test]
fn version_prints_the_crate_version() {
    for (bin, name, _) in PROGRAMS {
        let (code, out, err) = run(bin, &["--version"]);
        assert_eq!(code, 0, "{name}: {err}");
        assert_eq!(out, format!("{name} {}\n", env!("CARGO_PKG_VERSION")));
    }
}

#[test]
fn unknown_option_is_one_line_and_status_2() {
    for (bin, name, _) in PROGRAMS {
        for bad in ["--frobnicate", "-Z"] {
            let (code, out, err) = run(bin, &[bad]);
            assert_eq!(code, 2, "{name} {bad}: {err}");
            assert!(out.is_empty(), "{name} {bad}: {out}");
            assert_eq!(err.lines().count(), 1, "{name} {bad}: {err}");
            assert!(
                err.starts_with(&format!("{name}: unknown option {bad}")),
                "{name} {bad}: {err}"
            );
        }
    }
}

#[test]
fn bad_values_are_one_line_and_status_2() {
    for (bin, args, message) in [
        (
            PRINT,
            &["--seconds", "soon", "T@h"][..],
            "--seconds needs a number of seconds",
        ),
        (PRINT, &["--log"], "--log needs a value"),
        (PRINT, &["--json"], "name at least one DEVICE@HOST"),
        (PING, &["-n", "0", "T@h"], "-n needs a positive count"),
        (PING, &["T@h", "U@h"], "unexpected argument"),
        (
            LOG,
            &["dump", "x.vrpn", "--device"],
            "--device needs a value",
        ),
        (
            LOG,
            &["summary", "x.vrpn", "--json"],
            "summary takes no --json option",
        ),
        (
            SERVER,
            &["-millisleep", "x"],
            "-millisleep \"x\": expected a whole number",
        ),
        (SERVER, &["-f"], "-f needs a value"),
    ] {
        let (code, _, err) = run(bin, args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
}

#[test]
fn options_keep_their_meaning() {
    // Options after operands, `-oFILE`, `--opt=value` and `--` all work as GNU tools do.
    let log = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/golden/button_analog_dial.out.vrpn"
    );
    let dir = std::env::temp_dir().join(format!("vrpn-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out_file = dir.join("a.csv");
    let o = format!("-o{}", out_file.display());
    let (code, out, err) = run(LOG, &["csv", log, "Analog0", &o, "--kind=analog"]);
    assert_eq!((code, out.as_str()), (0, ""), "{err}");
    let csv = std::fs::read_to_string(&out_file).unwrap();
    assert!(csv.starts_with("time,n,ch0"), "{csv}");
    let (code, out, _) = run(LOG, &["dump", "--type", "DISCONNECT", "--", log]);
    assert_eq!(code, 0);
    assert_eq!(out.lines().count(), 1, "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}
