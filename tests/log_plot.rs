//! `vrpn_log plot` on the C++-written golden logs: PNG and SVG files with the panels each
//! kind of device calls for, and its errors.

use std::path::{Path, PathBuf};
use std::process::Command;

fn golden(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/golden")
        .join(name)
        .display()
        .to_string()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vrpn-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn plot(args: &[&str]) -> (i32, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_vrpn_log"))
        .arg("plot")
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Width and height from a PNG's header.
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    assert_eq!(&b[12..16], b"IHDR");
    let be = |i: usize| u32::from_be_bytes(b[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn a_tracker_gives_trajectories_top_view_and_intervals_in_png_and_svg() {
    let log = golden("tracker_spin.out.vrpn");
    let png = scratch("spin.png");
    assert_eq!(plot(&[&log, "Tracker0", "-o", png.to_str().unwrap()]).0, 0);
    // Title 44 + trajectories 420 + intervals 260.
    assert_eq!(png_size(&png), (1200, 724));
    let svg = scratch("spin.svg");
    assert_eq!(plot(&[&log, "Tracker0", "-o", svg.to_str().unwrap()]).0, 0);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg"), "{}", &text[..100.min(text.len())]);
    for label in [
        "top view",
        "x (m)",
        "interval before each report",
        "Tracker0: 90 reports",
    ] {
        assert!(text.contains(label), "no {label:?} in the SVG");
    }
}

#[test]
fn buttons_analogs_and_dials_each_get_their_panel() {
    let log = golden("button_analog_dial.out.vrpn");
    // Analog0 is a C++ Joylin: analog channels and two buttons.
    for (device, label, height) in [
        ("Analog0", "analog channels", 44 + 230 + (70 + 2 * 26) + 260),
        ("Dial0", "dials (total turn)", 44 + 200 + 260),
    ] {
        let png = scratch(&format!("{device}.png"));
        assert_eq!(plot(&[&log, device, "-o", png.to_str().unwrap()]).0, 0);
        assert_eq!(png_size(&png), (1200, height));
        let svg = scratch(&format!("{device}.svg"));
        assert_eq!(plot(&[&log, device, "-o", svg.to_str().unwrap()]).0, 0);
        assert!(std::fs::read_to_string(&svg).unwrap().contains(label));
    }
    let svg = scratch("buttons.svg");
    assert_eq!(plot(&[&log, "Button0", "-o", svg.to_str().unwrap()]).0, 0);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("buttons (filled while pressed)") && text.contains("button 0"));
}

#[test]
fn errors_name_the_problem() {
    let log = golden("button_analog_dial.out.vrpn");
    let (code, err) = plot(&[&log, "Nothing", "-o", scratch("x.png").to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(
        err.contains("no device \"Nothing\"") && err.contains("Analog0"),
        "{err}"
    );
    let (code, err) = plot(&[&log, "Analog0", "-o", "out.jpg"]);
    assert_eq!(code, 2);
    assert!(err.contains(".png or .svg"), "{err}");
    let (code, err) = plot(&[&log]);
    assert_eq!(code, 2, "{err}");
}
