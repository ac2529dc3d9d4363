//! Tests of the `vrpn.cfg` / `vrpn_Tracker.cfg` parser against realistic files.

use std::path::{Path, PathBuf};

use vrpn::devices::examples::*;
use vrpn::drivers::cerealbox::CerealBox;
use vrpn::drivers::dyna::Dyna;
use vrpn::drivers::fastrak::config::*;
use vrpn::drivers::flock::config::*;
use vrpn::drivers::joylin::Joylin;
use vrpn::drivers::magellan::Magellan;
use vrpn::layered::config::*;
use vrpn::server::config::*;

/// Every configuration type, to compare parsed entries with expected values in one `==`.
#[derive(Clone, Debug, PartialEq)]
enum DeviceConfig {
    TrackerNull(TrackerNull),
    TrackerSpin(TrackerSpin),
    ButtonExample(ButtonExample),
    DialExample(DialExample),
    AnalogExample(AnalogExample),
    TextExample(TextExample),
    AnalogFly(Box<AnalogFly>),
    ButtonFly(ButtonFly),
    Joylin(Joylin),
    Fastrak(Fastrak),
    InterSense(InterSense),
    Flock(Flock),
    FlockParallel(FlockParallel),
    Magellan(Magellan),
    CerealBox(CerealBox),
    Dyna(Dyna),
    Unknown { keyword: String, args: Vec<String> },
}

/// The entry's configuration as its concrete type.
fn typed(e: &DeviceEntry) -> DeviceConfig {
    let c = &*e.config;
    macro_rules! try_as {
        ($($v:ident),*) => {
            $(if let Some(x) = c.downcast_ref::<$v>() {
                return DeviceConfig::$v(x.clone().into());
            })*
        };
    }
    try_as!(
        TrackerNull,
        TrackerSpin,
        ButtonExample,
        DialExample,
        AnalogExample,
        TextExample,
        AnalogFly,
        ButtonFly,
        Joylin,
        Fastrak,
        InterSense,
        Flock,
        FlockParallel,
        Magellan,
        CerealBox,
        Dyna
    );
    let u = c
        .downcast_ref::<UnknownDevice>()
        .expect("a known configuration type");
    DeviceConfig::Unknown {
        keyword: u.keyword.clone(),
        args: u.args.clone(),
    }
}

/// The entry's device name (none for an unknown keyword).
fn name_of(e: &DeviceEntry) -> Option<&str> {
    (!e.is_unknown()).then(|| e.config.name())
}

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// Parses `text` as `vrpn.cfg`, panicking with the error on failure.
fn parse(text: &str) -> Vec<DeviceEntry> {
    parse_str(text, "vrpn.cfg").unwrap_or_else(|e| panic!("{e}"))
}

/// The single entry of `text`.
fn one(text: &str) -> DeviceConfig {
    let mut entries = parse(text);
    assert_eq!(entries.len(), 1, "{entries:?}");
    typed(&entries.remove(0))
}

/// The error message `text` produces.
fn err(text: &str) -> String {
    match parse_str(text, "vrpn.cfg") {
        Ok(entries) => panic!("expected an error, got {entries:?}"),
        Err(e) => e.to_string(),
    }
}

// ---- golden files and the sample ------------------------------------------------------------

#[test]
fn every_golden_cfg_parses() {
    let dir = fixtures().join("golden");
    let mut count = 0;
    for file in std::fs::read_dir(&dir).expect("fixture dir") {
        let path = file.expect("dir entry").path();
        if path.extension().is_some_and(|e| e == "cfg") {
            let entries = parse_file(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(!entries.is_empty(), "{}", path.display());
            for entry in &entries {
                assert!(entry.unknown_error().is_none(), "{:?}", entry);
            }
            count += 1;
        }
    }
    assert_eq!(count, 7);
}

#[test]
fn golden_button_analog_dial() {
    let entries = parse_file(&fixtures().join("golden/button_analog_dial.cfg")).unwrap();
    let configs: Vec<_> = entries.iter().map(typed).collect();
    assert_eq!(
        configs,
        [
            DeviceConfig::ButtonExample(ButtonExample {
                name: "Button0".into(),
                buttons: 2,
                rate: 4.0
            }),
            DeviceConfig::DialExample(DialExample {
                name: "Dial0".into(),
                dials: 2,
                spin_rate: 1.0,
                update_rate: 10.0
            }),
            DeviceConfig::Joylin(Joylin {
                name: "Analog0".into(),
                device: "joy0.fifo".into()
            }),
        ]
    );
    assert_eq!(entries[2].location.line, 3);
    assert!(entries[2].location.file.ends_with("button_analog_dial.cfg"));
}

#[test]
fn golden_tracker_spin() {
    let entries = parse_file(&fixtures().join("golden/tracker_spin.cfg")).unwrap();
    assert_eq!(
        typed(&entries[0]),
        DeviceConfig::TrackerSpin(TrackerSpin {
            name: "Tracker0".into(),
            sensors: 1,
            rate: 30.0,
            axis: [0.0, 1.0, 0.0],
            spin_hz: 0.5
        })
    );
}

#[test]
fn sample_config_parses() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("vrpn.cfg.sample");
    let entries = parse_file(&path).unwrap_or_else(|e| panic!("{e}"));
    let kws: Vec<_> = entries.iter().map(|e| e.keyword.as_str()).collect();
    assert_eq!(
        kws,
        [
            "vrpn_Tracker_NULL",
            "vrpn_Tracker_Spin",
            "vrpn_Button_Example",
            "vrpn_Dial_Example",
            "vrpn_Analog_Example",
            "vrpn_Text_Example"
        ]
    );
    assert_eq!(
        typed(&entries[0]),
        DeviceConfig::TrackerNull(TrackerNull {
            name: "Tracker0".into(),
            sensors: 2,
            rate: 60.0
        })
    );
}

/// The commented-out examples of the sample, uncommented, parse too.
#[test]
fn sample_config_commented_examples_parse() {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("vrpn.cfg.sample"))
            .unwrap();
    let mut uncommented = String::new();
    // After an entry line ending in '\\' or '/', the next line continues the entry.
    let mut continued = false;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix('#') {
            let continues = continued;
            continued = rest.starts_with("vrpn_") || continues;
            continued &= rest.ends_with(['\\', '/']);
            if continues
                || rest.starts_with("vrpn_")
                || [
                    "X",
                    "Y",
                    "Z",
                    "RX",
                    "RY",
                    "RZ",
                    "RESET",
                    "CLUTCH",
                    "differential",
                ]
                .iter()
                .any(|k| rest.starts_with(&format!("{k}\t")))
                || [
                    "absolute",
                    "vel_scale",
                    "Wand",
                    "Stylus",
                    "end",
                    "axis_mapping",
                ]
                .iter()
                .any(|k| rest.starts_with(k))
                || rest.ends_with(".rom")
                // A layered device's lines naming its source device (IMU devices).
                || rest.starts_with('*')
            {
                uncommented.push_str(rest);
                uncommented.push('\n');
                continue;
            }
            if rest.is_empty() {
                // The empty comment line after the AnalogFly block closes it.
                uncommented.push('\n');
            }
        }
    }
    let entries = parse(&uncommented);
    assert!(entries.iter().all(|e| e.unknown_error().is_none()));
    let kws: Vec<_> = entries.iter().map(|e| e.keyword.as_str()).collect();
    assert_eq!(
        kws,
        [
            "vrpn_Tracker_AnalogFly",
            "vrpn_Tracker_ButtonFly",
            "vrpn_Joylin",
            "vrpn_Tracker_Fastrak",
            "vrpn_Tracker_Fastrak",
            "vrpn_Tracker_Fastrak",
            "vrpn_Tracker_Fastrak",
            "vrpn_Tracker_3Space",
            "vrpn_Tracker_Isotrak",
            "vrpn_Tracker_3DMouse",
            "vrpn_Tracker_Liberty",
            "vrpn_Tracker_Liberty",
            "vrpn_Tracker_Liberty",
            "vrpn_Tracker_NDI_Polaris",
            "vrpn_Tracker_Crossbow",
            "vrpn_Tracker_GPS",
            "vrpn_inertiamouse",
            "vrpn_GlobalHapticsOrb",
            "vrpn_YEI_3Space_Sensor",
            "vrpn_YEI_3Space_Sensor",
            "vrpn_YEI_3Space_Sensor_Wireless",
            "vrpn_YEI_3Space_Sensor_Wireless",
            "vrpn_Tracker_Flock",
            "vrpn_Tracker_Flock_Parallel",
            "vrpn_Magellan",
            "vrpn_Spaceball",
            "vrpn_5dt",
            "vrpn_5dt",
            "vrpn_5dt16",
            "vrpn_Streaming_Arduino",
            "vrpn_Zaber",
            "vrpn_BiosciencesTools",
            "vrpn_CerealBox",
            "vrpn_Tracker_Dyna",
            "vrpn_Wanda",
            "vrpn_Button_PinchGlove",
            "vrpn_Joystick",
            "vrpn_ImmersionBox",
            "vrpn_Radamec_SPI",
            "vrpn_Tng3",
            "vrpn_raw_SGIBox",
            "vrpn_Button_Python",
            "vrpn_Button_SerialMouse",
            "vrpn_Button_SerialMouse",
            "vrpn_VPJoystick",
            "vrpn_nikon_controls",
            "vrpn_Tek4662",
            "vrpn_IDEA",
            "vrpn_ADBox",
            "vrpn_Atmel",
            "vrpn_Tracker_DTrack",
            "vrpn_Tracker_DTrack",
            "vrpn_Tracker_DTrack",
            "vrpn_Tracker_DTrack",
            "vrpn_Tracker_JsonNet",
            "vrpn_Tracker_FilterOneEuro",
            "vrpn_Tracker_DeadReckoning_Rotation",
            "vrpn_IMU_Magnetometer",
            "vrpn_IMU_SimpleCombiner",
            "vrpn_Tracker_GameTrak",
            "vrpn_Button_5DT_Server",
            "vrpn_Poser_Analog",
            "vrpn_JoyFly",
            "vrpn_Tracker_WiimoteHead"
        ]
    );
    // The Fastrak examples' continuation lines are read as such.
    let fastraks: Vec<Fastrak> = entries
        .iter()
        .filter(|e| e.keyword == "vrpn_Tracker_Fastrak")
        .filter_map(|e| match typed(e) {
            DeviceConfig::Fastrak(f) => Some(f),
            _ => None,
        })
        .collect();
    let shape: Vec<(usize, usize, bool, bool)> = fastraks
        .iter()
        .map(|f| {
            (
                f.reset_commands.len(),
                f.stations.len(),
                f.is900_timestamps,
                f.really_fastrak(),
            )
        })
        .collect();
    assert_eq!(
        shape,
        [
            (0, 0, false, false),
            (0, 1, false, true),
            (0, 2, true, false),
            (4, 1, false, false)
        ]
    );
}

// ---- every variant from a realistic line ----------------------------------------------------

#[test]
fn tracker_null() {
    assert_eq!(
        one("vrpn_Tracker_NULL Tracker0 2 2.0\n"),
        DeviceConfig::TrackerNull(TrackerNull {
            name: "Tracker0".into(),
            sensors: 2,
            rate: 2.0
        })
    );
}

#[test]
fn rate_is_nearest_f32() {
    let DeviceConfig::TrackerNull(t) = one("vrpn_Tracker_NULL T 1 0.1\n") else {
        panic!()
    };
    assert_eq!(t.rate, 0.1f32);
}

#[test]
fn button_and_dial_examples() {
    assert_eq!(
        one("vrpn_Button_Example Button0 256 2.0\n"),
        DeviceConfig::ButtonExample(ButtonExample {
            name: "Button0".into(),
            buttons: 256,
            rate: 2.0
        })
    );
    assert_eq!(
        one("vrpn_Dial_Example Dial0 2 -2.0 10.0\n"),
        DeviceConfig::DialExample(DialExample {
            name: "Dial0".into(),
            dials: 2,
            spin_rate: -2.0,
            update_rate: 10.0
        })
    );
}

#[test]
fn analog_and_text_examples() {
    assert_eq!(
        one("vrpn_Analog_Example Analog0 4 10\n"),
        DeviceConfig::AnalogExample(AnalogExample {
            name: "Analog0".into(),
            channels: 4,
            rate: 10.0
        })
    );
    assert_eq!(
        one("vrpn_Text_Example\tText0 2.5   Hello,  lab  #1 \r\n"),
        DeviceConfig::TextExample(TextExample {
            name: "Text0".into(),
            period: 2.5,
            message: "Hello,  lab  #1".into()
        })
    );
}

#[test]
fn analog_fly_full_block() {
    let text = "\
vrpn_Tracker_AnalogFly Tracker0 60.0 differential
X  *Magellan0 0 0.0 0.0 2.0 1.0
Y  Joy0@otherhost:3884 1 0.1 0.05 2.0 1.5
# a comment inside the block is ignored
RZ *Magellan0 5 0.0 0.0 -2.0 1.0 extra tokens
x  *Ignored 9 9 9 9 9
WORLDFRAME
RESET *Button0 3
CLUTCH NULL 0

vrpn_Tracker_NULL Other 1 1
";
    let entries = parse(text);
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[0].last_line, 10);
    assert_eq!(entries[1].location.line, 11);
    let DeviceConfig::AnalogFly(fly) = typed(&entries[0]) else {
        panic!()
    };
    assert_eq!(fly.name, "Tracker0");
    assert_eq!(fly.update_rate, 60.0);
    assert_eq!(fly.mode, FlyMode::Differential);
    assert!(fly.world_frame);
    assert_eq!(
        *fly.axis(Axis::X),
        AnalogFlyAxis {
            source: Some(DeviceRef::Local("Magellan0".into())),
            channel: 0,
            offset: 0.0,
            threshold: 0.0,
            scale: 2.0,
            power: 1.0
        }
    );
    assert_eq!(
        fly.axis(Axis::Y).source,
        Some(DeviceRef::Remote("Joy0@otherhost:3884".into()))
    );
    assert_eq!(fly.axis(Axis::Y).power, 1.5);
    assert_eq!(fly.axis(Axis::RZ).scale, -2.0);
    assert_eq!(*fly.axis(Axis::Z), AnalogFlyAxis::default());
    assert_eq!(
        fly.reset,
        Some(ButtonRef {
            device: DeviceRef::Local("Button0".into()),
            button: 3
        })
    );
    assert_eq!(fly.clutch, None);
}

#[test]
fn analog_fly_repeated_axis_overrides_and_null_axis() {
    let text = "vrpn_Tracker_AnalogFly T 30 absolute\nX *A 0 0 0 1 1\nX NULL 0 0 0 1 1\n\n";
    let DeviceConfig::AnalogFly(fly) = one(text) else {
        panic!()
    };
    assert_eq!(fly.mode, FlyMode::Absolute);
    assert_eq!(fly.axis(Axis::X).source, None);
}

#[test]
fn analog_fly_blank_and_crlf_lines_do_not_end_block() {
    // "  \n" and "\r\n" are ordinary (ignored) block lines; only "\n" ends the block.
    let text = "vrpn_Tracker_AnalogFly T 30 absolute\n  \n\r\nX *A 0 0 0 1 1\n\n";
    let DeviceConfig::AnalogFly(fly) = one(text) else {
        panic!()
    };
    assert!(fly.axis(Axis::X).source.is_some());
}

#[test]
fn button_fly_block() {
    let text = "\
vrpn_Tracker_ButtonFly Walker0 60.0
absolute *Button0 0 1.0 2.0 3.0 0.25 0.0 0.0
differential Buttons@host 1 0.0 0.0 -0.5 0.0 0.0 0.1
# comments are ignored
vel_scale *Analog0 0 0.0 1.0 1.0
rot_scale NULL 0 0 1 1
end
";
    let entries = parse(text);
    assert_eq!(entries[0].last_line, 7);
    let DeviceConfig::ButtonFly(fly) = typed(&entries[0]) else {
        panic!()
    };
    assert_eq!(fly.name, "Walker0");
    assert_eq!(fly.axes.len(), 2);
    assert_eq!(
        fly.axes[0],
        ButtonFlyAxis {
            button: ButtonRef {
                device: DeviceRef::Local("Button0".into()),
                button: 0
            },
            mode: FlyMode::Absolute,
            vec: [1.0, 2.0, 3.0],
            rot: [0.25, 0.0, 0.0]
        }
    );
    assert_eq!(fly.axes[1].mode, FlyMode::Differential);
    assert_eq!(
        fly.vel_scale,
        Some(ScaleAnalog {
            source: DeviceRef::Local("Analog0".into()),
            channel: 0,
            offset: 0.0,
            scale: 1.0,
            power: 1.0
        })
    );
    assert_eq!(fly.rot_scale, None);
}

#[test]
fn joylin() {
    assert_eq!(
        one("vrpn_Joylin Joylin0 /dev/input/js0\n"),
        DeviceConfig::Joylin(Joylin {
            name: "Joylin0".into(),
            device: "/dev/input/js0".into()
        })
    );
}

#[test]
fn fastrak_plain_and_is900time() {
    assert_eq!(
        one("vrpn_Tracker_Fastrak Fastrak0 /dev/ttyS0 19200\n"),
        DeviceConfig::Fastrak(Fastrak {
            name: "Fastrak0".into(),
            port: "/dev/ttyS0".into(),
            baud: 19200,
            is900_timestamps: false,
            reset_commands: vec![],
            stations: vec![]
        })
    );
    let DeviceConfig::Fastrak(f) = one("vrpn_Tracker_Fastrak F COM1 115200 IS900time\n") else {
        panic!()
    };
    assert!(f.is900_timestamps);
}

#[test]
fn fastrak_reset_commands() {
    let text = "\
vrpn_Tracker_Fastrak Isense600 /dev/ttyS0 19200 \\
MCc\\
*5\\
MCM1,1,0.0900,0.0000,-0.2210,0.00,0.00,-1.00,89\\
MCe\\
*10
vrpn_Tracker_NULL T 1 1
";
    let entries = parse(text);
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[0].last_line, 6);
    let DeviceConfig::Fastrak(f) = typed(&entries[0]) else {
        panic!()
    };
    assert_eq!(
        f.reset_commands,
        [
            ResetStep::Command("MCc".into()),
            ResetStep::Pause(5),
            ResetStep::Command("MCM1,1,0.0900,0.0000,-0.2210,0.00,0.00,-1.00,89".into()),
            ResetStep::Command("MCe".into()),
            ResetStep::Pause(10),
        ]
    );
}

#[test]
fn fastrak_stations() {
    let text = "\
vrpn_Tracker_Fastrak Isense900 COM1 115200 /
Wand Wand0 0 -1.0 0.0 0.0 1.0 -1.0 0.0 0.0 1.0 /
Stylus Stylus0 2
";
    let DeviceConfig::Fastrak(f) = one(text) else {
        panic!()
    };
    let clip = WandClip {
        min: -1.0,
        low_zero: 0.0,
        high_zero: 0.0,
        max: 1.0,
    };
    assert_eq!(
        f.stations,
        [
            StationDevice::Wand {
                name: "Wand0".into(),
                sensor: 0,
                clip: [clip, clip]
            },
            StationDevice::Stylus {
                name: "Stylus0".into(),
                sensor: 2
            }
        ]
    );
    assert!(!f.really_fastrak());
    let DeviceConfig::Fastrak(f) =
        one("vrpn_Tracker_Fastrak Tracker0 COM1 115200 /\nFTStylus Stylus0 0\n")
    else {
        panic!()
    };
    assert!(f.really_fastrak());
}

#[test]
fn fastrak_reset_then_stations() {
    let text = "vrpn_Tracker_Fastrak F COM1 115200 \\\nMCe/\nStylus S0 1\n";
    let DeviceConfig::Fastrak(f) = one(text) else {
        panic!()
    };
    assert_eq!(f.reset_commands, [ResetStep::Command("MCe".into())]);
    assert_eq!(f.stations.len(), 1);
}

#[test]
fn fastrak_continuation_needs_last_character() {
    // A trailing blank after '/' means no continuation, as in C++: the next line is top level.
    let entries = parse("vrpn_Tracker_Fastrak F COM1 115200 / \nStylus S0 1\n");
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[1].keyword, "Stylus");
    assert!(entries[1].unknown_error().is_some());
}

#[test]
fn intersense() {
    let text = "vrpn_Tracker_InterSense Isense0 AUTO ResetAtStartup IS900time /\nStylus S0 5\n";
    let DeviceConfig::InterSense(i) = one(text) else {
        panic!()
    };
    assert_eq!(i.port, InterSensePort::Auto);
    assert!(i.is900_timestamps && i.reset_at_startup);
    assert_eq!(i.stations[0].sensor(), 5);
}

#[test]
fn flock() {
    assert_eq!(
        one("vrpn_Tracker_Flock Tracker0 4 /dev/ttyS0 115200 1\n"),
        DeviceConfig::Flock(Flock {
            name: "Tracker0".into(),
            sensors: 4,
            port: "/dev/ttyS0".into(),
            baud: 115200,
            invert_quaternion: true,
            use_ert: true,
            hemisphere: Hemisphere::PosZ
        })
    );
    let DeviceConfig::Flock(f) = one("vrpn_Tracker_Flock Tracker0 2 COM1 38400 0 N -X\n") else {
        panic!()
    };
    assert!(!f.use_ert && !f.invert_quaternion);
    assert_eq!(f.hemisphere, Hemisphere::NegX);
}

#[test]
fn flock_parallel() {
    assert_eq!(
        one("vrpn_Tracker_Flock_Parallel Tracker0 2 COM1 115200 1 COM2 COM3 extra\n"),
        DeviceConfig::FlockParallel(FlockParallel {
            name: "Tracker0".into(),
            sensors: 2,
            master_port: "COM1".into(),
            baud: 115200,
            invert_quaternion: true,
            slave_ports: vec!["COM2".into(), "COM3".into()]
        })
    );
}

#[test]
fn magellan_cerealbox_dyna() {
    assert_eq!(
        one("vrpn_Magellan Magellan0 /dev/ttyS0 9600 altreset\n"),
        DeviceConfig::Magellan(Magellan {
            name: "Magellan0".into(),
            port: "/dev/ttyS0".into(),
            baud: 9600,
            alt_reset: true
        })
    );
    assert_eq!(
        one("vrpn_CerealBox Cereal0 /dev/cua0 19200 8 8 8\n"),
        DeviceConfig::CerealBox(CerealBox {
            name: "Cereal0".into(),
            port: "/dev/cua0".into(),
            baud: 19200,
            buttons: 8,
            analogs: 8,
            encoders: 8
        })
    );
    assert_eq!(
        one("vrpn_Tracker_Dyna Tracker0 1 COM1 19200\n"),
        DeviceConfig::Dyna(Dyna {
            name: "Tracker0".into(),
            sensors: 1,
            port: "COM1".into(),
            baud: 19200
        })
    );
}

#[test]
fn unknown_keyword_is_an_entry() {
    let entries = parse("vrpn_Tracker_Foo T0 1 2\n");
    assert_eq!(
        typed(&entries[0]),
        DeviceConfig::Unknown {
            keyword: "vrpn_Tracker_Foo".into(),
            args: vec!["T0".into(), "1".into(), "2".into()]
        }
    );
    assert_eq!(name_of(&entries[0]), None);
    let e = entries[0].unknown_error().unwrap();
    assert_eq!(e.kind(), ConfigErrorKind::UnknownDevice);
    assert_eq!(
        e.to_string(),
        "vrpn.cfg:1: unknown device type vrpn_Tracker_Foo"
    );
}

// ---- comments and whitespace as C++ treats them ---------------------------------------------

#[test]
fn comments_blank_lines_and_odd_whitespace() {
    let text = "\
# full-line comment
\t  # indented comment

x
\tvrpn_Tracker_NULL \t Tracker0\t\t2   60.0   # trailing words are ignored
vrpn_Button_Example Button0 2 4.0\r
";
    let entries = parse(text);
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[0].location.line, 5);
    assert_eq!(name_of(&entries[0]), Some("Tracker0"));
    assert_eq!(entries[1].location.line, 6);
    assert_eq!(entries[1].keyword, "vrpn_Button_Example");
}

#[test]
fn last_line_without_newline() {
    assert_eq!(parse("vrpn_Tracker_NULL T 1 1").len(), 1);
}

#[test]
fn blank_only_line_is_unknown_like_cpp() {
    let entries = parse("vrpn_Tracker_NULL T 1 1\n   \n");
    assert_eq!(entries.len(), 2);
    let e = entries[1].unknown_error().unwrap();
    assert_eq!(
        e.to_string(),
        "vrpn.cfg:2: line contains only blanks; C++ vrpn_server treats it as an unknown \
         device, so make it truly empty"
    );
}

#[test]
fn keyword_case_matters() {
    let entries = parse("vrpn_tracker_null T 1 1\n");
    assert!(entries[0]
        .unknown_error()
        .unwrap()
        .message()
        .ends_with("did you mean vrpn_Tracker_NULL?"));
}

// ---- errors ---------------------------------------------------------------------------------

#[test]
fn error_argument_count() {
    assert_eq!(
        err("# c\nvrpn_Tracker_NULL Tracker0 2\n"),
        "vrpn.cfg:2: vrpn_Tracker_NULL: expected 3 arguments (name, sensors, rate), found 2"
    );
}

#[test]
fn error_keyword_alone() {
    assert_eq!(
        err("vrpn_Tracker_NULL\n"),
        "vrpn.cfg:1: vrpn_Tracker_NULL: expected 3 arguments (name, sensors, rate), found 0"
    );
}

#[test]
fn error_bad_numbers() {
    assert_eq!(
        err("vrpn_Tracker_NULL Tracker0 two 60\n"),
        "vrpn.cfg:1: vrpn_Tracker_NULL: sensors must be a whole number, found 'two'"
    );
    assert_eq!(
        err("vrpn_Tracker_NULL Tracker0 2.5 60\n"),
        "vrpn.cfg:1: vrpn_Tracker_NULL: sensors must be a whole number, found '2.5'"
    );
    assert_eq!(
        err("vrpn_Tracker_NULL Tracker0 2 60Hz\n"),
        "vrpn.cfg:1: vrpn_Tracker_NULL: rate must be a number, found '60Hz'"
    );
    assert_eq!(
        err("vrpn_Tracker_Spin S 1 30 0 one 0 0.5\n"),
        "vrpn.cfg:1: vrpn_Tracker_Spin: axis_y must be a number, found 'one'"
    );
}

#[test]
fn error_out_of_range() {
    assert_eq!(
        err("vrpn_Tracker_NULL Tracker0 0 60\n"),
        "vrpn.cfg:1: vrpn_Tracker_NULL: sensors must be between 1 and 1024, found 0"
    );
    assert_eq!(
        err("vrpn_Tracker_NULL Tracker0 2 -1\n"),
        "vrpn.cfg:1: vrpn_Tracker_NULL: rate must be greater than 0, found -1"
    );
    assert_eq!(
        err("vrpn_Button_Example B 300 2\n"),
        "vrpn.cfg:1: vrpn_Button_Example: buttons must be between 1 and 256, found 300"
    );
    assert_eq!(
        err("vrpn_Dial_Example D 129 1 1\n"),
        "vrpn.cfg:1: vrpn_Dial_Example: dials must be between 1 and 128, found 129"
    );
    assert_eq!(
        err("vrpn_Analog_Example A 0 1\n"),
        "vrpn.cfg:1: vrpn_Analog_Example: channels must be between 1 and 128, found 0"
    );
    assert_eq!(
        err("vrpn_Text_Example T 0 hi\n"),
        "vrpn.cfg:1: vrpn_Text_Example: period_seconds must be greater than 0, found 0"
    );
    assert_eq!(
        err("vrpn_CerealBox C /dev/cua0 19200 25 8 8\n"),
        "vrpn.cfg:1: vrpn_CerealBox: buttons must be between 0 and 24, found 25"
    );
    assert_eq!(
        err("vrpn_Tracker_Flock F 14 COM1 115200 0\n"),
        "vrpn.cfg:1: vrpn_Tracker_Flock: sensors must be between 1 and 13, found 14"
    );
    assert_eq!(
        err("vrpn_Magellan M COM1 9601\n"),
        "vrpn.cfg:1: vrpn_Magellan: baud must be one of 300, 1200, 2400, 4800, 9600, 19200, \
         38400, 57600, 115200, found 9601"
    );
}

#[test]
fn error_bad_values() {
    assert_eq!(
        err("vrpn_Magellan M COM1 9600 alt\n"),
        "vrpn.cfg:1: vrpn_Magellan: the optional 4th argument must be 'altreset', found 'alt'"
    );
    assert_eq!(
        err("vrpn_Tracker_Flock F 2 COM1 38400 1 N +w\n"),
        "vrpn.cfg:1: vrpn_Tracker_Flock: hemisphere must be one of +x -x +y -y +z -z, found '+w'"
    );
    assert_eq!(
        err("vrpn_Tracker_Fastrak F COM1 19200 fast\n"),
        "vrpn.cfg:1: vrpn_Tracker_Fastrak: the optional 4th argument must be IS900time, '/' or \
         '\\', found 'fast'"
    );
    assert_eq!(
        err("vrpn_Tracker_AnalogFly T 60 relative\n\n"),
        "vrpn.cfg:1: vrpn_Tracker_AnalogFly: the third argument must be 'absolute' or \
         'differential', found 'relative'"
    );
    assert_eq!(
        err("vrpn_Tracker_InterSense I COM5\n"),
        "vrpn.cfg:1: vrpn_Tracker_InterSense: port must be COM1, COM2, COM3, COM4 or AUTO, \
         found 'COM5'"
    );
    assert_eq!(
        err("vrpn_Tracker_Flock_Parallel F 3 COM1 115200 1 COM2 COM3\n"),
        "vrpn.cfg:1: vrpn_Tracker_Flock_Parallel: expected 3 slave port name(s) after \
         invert_quaternion (one per sensor), found 2"
    );
}

#[test]
fn error_bad_names() {
    assert_eq!(
        err("vrpn_Tracker_NULL Tracker0@host 1 1\n"),
        "vrpn.cfg:1: vrpn_Tracker_NULL: name 'Tracker0@host' must not contain '@' (clients \
         connect to NAME@host, so the name itself cannot have one)"
    );
    let long = "n".repeat(96);
    assert_eq!(
        err(&format!("vrpn_Joylin {long} /dev/input/js0\n")),
        format!(
            "vrpn.cfg:1: vrpn_Joylin: name '{long}' is 96 characters long; VRPN names are at \
             most 95"
        )
    );
}

// ---- names and interfaces ---------------------------------------------------------------------

/// The (name, interface) pairs of every entry of `text`, in order.
fn served(text: &str) -> Vec<(String, Interface)> {
    parse(text)
        .iter()
        .flat_map(|e| {
            e.config
                .served()
                .into_iter()
                .map(|s| (s.name.to_owned(), s.interface))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The warnings `text` gives.
fn clashes(text: &str) -> Vec<String> {
    name_clashes(&parse(text))
        .iter()
        .map(ToString::to_string)
        .collect()
}

#[test]
fn every_keyword_declares_its_interfaces() {
    use Interface::*;
    let cases: [(&str, &[Interface]); 16] = [
        ("vrpn_Tracker_NULL D 1 1\n", &[Tracker]),
        ("vrpn_Tracker_Spin D 1 30 0 1 0 1\n", &[Tracker]),
        ("vrpn_Button_Example D 2 2\n", &[Button]),
        ("vrpn_Dial_Example D 1 1 1\n", &[Dial]),
        ("vrpn_Analog_Example D 2 2\n", &[Analog]),
        ("vrpn_Text_Example D 1 hello\n", &[Text]),
        ("vrpn_Tracker_AnalogFly D 60 absolute\n\n", &[Tracker]),
        ("vrpn_Tracker_ButtonFly D 60\nend\n", &[Tracker]),
        ("vrpn_Joylin D /dev/input/js0\n", &[Analog, Button]),
        ("vrpn_Tracker_Fastrak D /dev/ttyS0 9600\n", &[Tracker]),
        ("vrpn_Tracker_InterSense D AUTO\n", &[Tracker]),
        ("vrpn_Tracker_Flock D 1 /dev/ttyS0 9600 0\n", &[Tracker]),
        (
            "vrpn_Tracker_Flock_Parallel D 1 /dev/ttyS0 9600 0 /dev/ttyS1\n",
            &[Tracker],
        ),
        ("vrpn_Magellan D /dev/ttyS0 9600\n", &[Analog, Button]),
        (
            "vrpn_CerealBox D /dev/ttyS0 19200 1 1 1\n",
            &[Button, Analog, Dial],
        ),
        ("vrpn_Tracker_Dyna D 1 /dev/ttyS0 19200\n", &[Tracker]),
    ];
    for (text, want) in cases {
        let want: Vec<_> = want.iter().map(|&i| ("D".to_owned(), i)).collect();
        assert_eq!(served(text), want, "{text}");
    }
    assert!(served("vrpn_Nothing D 1\n").is_empty());
}

#[test]
fn station_devices_serve_under_their_own_names() {
    use Interface::*;
    let text = "\
vrpn_Tracker_Fastrak F /dev/ttyS0 115200 /
Wand W 0 -1 0 0 1 -1 0 0 1 /
Stylus S 1
";
    let want = [
        ("F".to_owned(), Tracker),
        ("W".to_owned(), Button),
        ("W".to_owned(), Analog),
        ("S".to_owned(), Button),
    ];
    assert_eq!(served(text), want);
    assert!(clashes(text).is_empty());
}

#[test]
fn one_name_for_several_interfaces_is_allowed() {
    // Factoring, as C++ allows: Dev0 is a tracker and a button.
    let text = "vrpn_Tracker_NULL Dev0 1 20.0\nvrpn_Button_Example Dev0 2 4.0\n";
    assert_eq!(parse(text).len(), 2);
    assert!(clashes(text).is_empty());
    // A tracker whose stylus and wand share its name: tracker, button, analog.
    let text = "vrpn_Tracker_Fastrak F COM1 115200 /\nStylus F 0\n";
    assert_eq!(parse(text).len(), 1);
    assert!(clashes(text).is_empty());
    let text = "vrpn_Tracker_Fastrak F COM1 115200 /\nWand F 0 -1 0 0 1 -1 0 0 1\n";
    assert!(clashes(text).is_empty());
    // Every interface of the example devices under one name.
    let text = "\
vrpn_Tracker_NULL D 1 1
vrpn_Button_Example D 2 2
vrpn_Analog_Example D 2 2
vrpn_Dial_Example D 1 1 1
vrpn_Text_Example D 1 hi
";
    assert_eq!(parse(text).len(), 5);
    assert!(clashes(text).is_empty());
}

#[test]
fn same_interface_under_one_name_is_a_warning_naming_both_lines() {
    let text = "vrpn_Tracker_NULL Tracker0 1 1\n\nvrpn_Tracker_Spin Tracker0 1 30 0 1 0 1\n";
    assert_eq!(parse(text).len(), 2, "both entries are kept, as in C++");
    assert_eq!(
        clashes(text),
        [
            "vrpn.cfg:3: vrpn_Tracker_Spin: device name 'Tracker0' is already a tracker \
          (vrpn_Tracker_NULL at line 1); both run and their reports interleave under one \
          name, as in C++ VRPN: give each its own name"
        ]
    );
    let clash = &name_clashes(&parse(text))[0];
    assert_eq!(
        (
            clash.name.as_str(),
            clash.interface,
            clash.first.line,
            clash.second.line
        ),
        ("Tracker0", Interface::Tracker, 1, 3)
    );
    // A Joylin is a button too, so a button example under its name clashes; a tracker does not.
    let text = "vrpn_Joylin J /dev/input/js0\nvrpn_Tracker_NULL J 1 1\nvrpn_Button_Example J 2 2\n";
    assert_eq!(
        clashes(text),
        [
            "vrpn.cfg:3: vrpn_Button_Example: device name 'J' is already a button (vrpn_Joylin \
          at line 1); both run and their reports interleave under one name, as in C++ VRPN: \
          give each its own name"
        ]
    );
    // Two styluses of one tracker under one name.
    let text = "vrpn_Tracker_Fastrak F COM1 115200 /\nStylus S 0 /\nStylus S 1\n";
    assert_eq!(
        clashes(text),
        [
            "vrpn.cfg:1: vrpn_Tracker_Fastrak: device name 'S' is already a button (earlier in \
          this same entry); both run and their reports interleave under one name, as in C++ \
          VRPN: give each its own name"
        ]
    );
    // Three alike: each later one is reported against the first.
    let text = "vrpn_Tracker_NULL T 1 1\nvrpn_Tracker_NULL T 1 1\nvrpn_Tracker_NULL T 1 1\n";
    let lines: Vec<_> = name_clashes(&parse(text))
        .iter()
        .map(|c| (c.first.line, c.second.line))
        .collect();
    assert_eq!(lines, [(1, 2), (1, 3)]);
}

#[test]
fn error_line_too_long() {
    let line = format!("vrpn_Tracker_NULL T 1 1 {}\n", "#".repeat(490));
    assert_eq!(line.len(), 515);
    assert_eq!(
        err(&line),
        "vrpn.cfg:1: line is 515 characters long; lines must be at most 510 characters \
         including the newline (the C++ limit); shorten it"
    );
    let ok = format!("vrpn_Tracker_NULL T 1 1 {}\n", "#".repeat(510 - 25));
    assert_eq!(ok.len(), 510);
    assert_eq!(parse(&ok).len(), 1);
}

#[test]
fn error_analog_fly_truncated() {
    let text = "vrpn_Tracker_NULL T 1 1\nvrpn_Tracker_AnalogFly Fly0 60 absolute\nX *T 0 0 0 1 1\n";
    assert_eq!(
        err(text),
        "vrpn.cfg:2: vrpn_Tracker_AnalogFly Fly0: the file ends (after line 3) before the \
         empty line that must end the block (add an empty line after its last line)"
    );
    // A blank-only last line does not close it either.
    assert!(
        err("vrpn_Tracker_AnalogFly Fly0 60 absolute\nX *T 0 0 0 1 1\n  \n")
            .contains("the file ends (after line 3)")
    );
}

#[test]
fn error_analog_fly_lines() {
    assert_eq!(
        err("vrpn_Tracker_AnalogFly Fly0 60 absolute\nX *T 0 0 0 1\n\n"),
        "vrpn.cfg:2: vrpn_Tracker_AnalogFly Fly0: X line needs 6 values after 'X' (device or \
         NULL, channel, offset, threshold, scale, power), found 5"
    );
    // The block ended at line 2, so line 3 is read as a top-level line: an unknown device.
    let entries = parse("vrpn_Tracker_AnalogFly Fly0 60 absolute\n\nRY Magellan0 0 0 0 1 1\n");
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[1].keyword, "RY");
    assert!(entries[1].unknown_error().is_some());
}

#[test]
fn error_analog_fly_device_and_channel() {
    assert_eq!(
        err("vrpn_Tracker_AnalogFly Fly0 60 absolute\nRY Magellan0 0 0 0 1 1\n\n"),
        "vrpn.cfg:2: vrpn_Tracker_AnalogFly Fly0: axis RY device 'Magellan0' must be \
         *Magellan0 (a device of this server) or Magellan0@host (a device on another server)"
    );
    assert_eq!(
        err("vrpn_Tracker_AnalogFly Fly0 60 absolute\nZ *M 128 0 0 1 1\n\n"),
        "vrpn.cfg:2: vrpn_Tracker_AnalogFly Fly0: axis Z channel must be between 0 and 127, \
         found 128"
    );
    assert_eq!(
        err("vrpn_Tracker_AnalogFly Fly0 60 absolute\nRESET *B\n\n"),
        "vrpn.cfg:2: vrpn_Tracker_AnalogFly Fly0: RESET line needs 2 values after 'RESET' \
         (button device or NULL, button index), found 1"
    );
}

#[test]
fn error_button_fly() {
    assert_eq!(
        err("vrpn_Tracker_ButtonFly W 60\nabsolute *B 0 1 2 3\nend\n"),
        "vrpn.cfg:2: vrpn_Tracker_ButtonFly W: absolute line needs 8 values after 'absolute' \
         (button device, button index, x, y, z, rx, ry, rz), found 5"
    );
    assert_eq!(
        err("vrpn_Tracker_ButtonFly W 60\ndifferential *B 0 0 0 1 0 0 0\n\nend\n"),
        "vrpn.cfg:3: vrpn_Tracker_ButtonFly W: empty line inside the block; remove it (the \
         block ends at a line 'end')"
    );
    assert_eq!(
        err("vrpn_Tracker_ButtonFly W 60\ndifferential *B 0 0 0 1 0 0 0\n"),
        "vrpn.cfg:1: vrpn_Tracker_ButtonFly W: the file ends (after line 2) before the 'end' \
         line that must close the block"
    );
    assert_eq!(
        err("vrpn_Tracker_ButtonFly W 60\ndifferential NULL 0 0 0 1 0 0 0\nend\n"),
        "vrpn.cfg:2: vrpn_Tracker_ButtonFly W: button device cannot be NULL here; name a \
         device as *NAME or NAME@host"
    );
    let mut many = String::from("vrpn_Tracker_ButtonFly W 60\n");
    for _ in 0..201 {
        many.push_str("differential *B 0 0 0 1 0 0 0\n");
    }
    many.push_str("end\n");
    assert_eq!(
        err(&many),
        "vrpn.cfg:202: vrpn_Tracker_ButtonFly W: too many axis lines; at most 200 are allowed"
    );
}

#[test]
fn error_fastrak_blocks() {
    assert_eq!(
        err("vrpn_Tracker_Fastrak F COM1 115200 /\nWand W0 4 -1 0 0 1 -1 0 0 1\n"),
        "vrpn.cfg:2: vrpn_Tracker_Fastrak: Wand sensor must be between 0 and 3, found 4"
    );
    assert_eq!(
        err("vrpn_Tracker_Fastrak F COM1 115200 /\nMouse M0 1\n"),
        "vrpn.cfg:2: vrpn_Tracker_Fastrak: unknown station device 'Mouse'; expected Wand, \
         Stylus or FTStylus"
    );
    assert_eq!(
        err("vrpn_Tracker_Fastrak F COM1 115200 /\nStylus S0 0 /\n"),
        "vrpn.cfg:1: vrpn_Tracker_Fastrak: the file ends (after line 2) before the station \
         device line promised by the trailing '/'"
    );
    assert_eq!(
        err("vrpn_Tracker_Fastrak F COM1 115200 \\\n*five\n"),
        "vrpn.cfg:2: vrpn_Tracker_Fastrak: reset pause (*N, in seconds) must be a whole \
         number, found 'five'"
    );
    assert_eq!(
        err("vrpn_Tracker_Fastrak F COM1 115200 /\nWand W0 0 1 0 0 -1 -1 0 0 1\n"),
        "vrpn.cfg:2: vrpn_Tracker_Fastrak: Wand channel 0 clip values must satisfy min <= \
         lowzero <= highzero <= max, found 1 0 0 -1"
    );
}

#[test]
fn error_has_location_accessors() {
    let e = parse_str("\n\nvrpn_Dyna\n", "lab.cfg").map(|v| v.len());
    assert_eq!(e, Ok(1)); // vrpn_Dyna is unknown (the keyword is vrpn_Tracker_Dyna)
    let e = parse_str("\n\nvrpn_Tracker_Dyna D 1\n", "lab.cfg").unwrap_err();
    assert_eq!(e.file(), "lab.cfg");
    assert_eq!(e.line(), Some(3));
    assert_eq!(e.kind(), ConfigErrorKind::MissingArguments);
    assert_eq!(
        e.message(),
        "vrpn_Tracker_Dyna: expected 4 arguments (name, sensors, port, baud), found 2"
    );
    let boxed: Box<dyn std::error::Error> = Box::new(e);
    assert!(boxed.to_string().starts_with("lab.cfg:3: "));
}

// ---- lenient (-warn) mode -------------------------------------------------------------------

#[test]
fn lenient_skips_bad_entries_and_resumes() {
    let text = "\
vrpn_Tracker_NULL T0 1 1
vrpn_Tracker_NULL T1 x 1
vrpn_Tracker_AnalogFly Fly0 60 absolute
X *T0 0 0 0 1
Y *T0 1 0 0 1 1

vrpn_Tracker_NULL T0 1 1
vrpn_Button_Example B0 2 2
";
    let report = parse_str_lenient(text, "vrpn.cfg");
    let errors: Vec<_> = report.errors.iter().map(|e| e.line()).collect();
    // Line 2: bad number; line 4: bad axis line. Line 7 reuses T0 for a second tracker: kept,
    // and only a warning.
    assert_eq!(errors, [Some(2), Some(4)]);
    let clashes = name_clashes(&report.entries);
    assert_eq!(clashes.len(), 1);
    assert_eq!((clashes[0].first.line, clashes[0].second.line), (1, 7));
    let kws: Vec<_> = report
        .entries
        .iter()
        .map(|e| (e.location.line, e.keyword.as_str()))
        .collect();
    // As in C++, the rest of the failed block is read as top-level lines ("Y" is unknown).
    assert_eq!(
        kws,
        [
            (1, "vrpn_Tracker_NULL"),
            (5, "Y"),
            (7, "vrpn_Tracker_NULL"),
            (8, "vrpn_Button_Example")
        ]
    );
}

#[test]
fn strict_stops_at_first_error() {
    let e = parse_str(
        "vrpn_Tracker_NULL T1 x 1\nvrpn_Tracker_NULL T2 y 1\n",
        "vrpn.cfg",
    )
    .unwrap_err();
    assert_eq!(e.line(), Some(1));
}

// ---- files ----------------------------------------------------------------------------------

#[test]
fn file_errors() {
    let dir = std::env::temp_dir().join(format!("vrpn-config-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("missing.cfg");
    let e = parse_file(&missing).unwrap_err();
    assert_eq!(e.kind(), ConfigErrorKind::Io);
    assert_eq!(e.line(), None);
    assert!(
        e.to_string().starts_with(&format!(
            "{}: cannot read configuration file: ",
            missing.display()
        )),
        "{e}"
    );

    let latin1 = dir.join("latin1.cfg");
    std::fs::write(&latin1, b"vrpn_Tracker_NULL T 1 1\n# caf\xe9\n").unwrap();
    let e = parse_file(&latin1).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "{}:2: the file is not UTF-8 text (byte 0xE9 at column 6); save it as UTF-8 or \
             plain ASCII",
            latin1.display()
        )
    );

    let good = dir.join("good.cfg");
    std::fs::write(&good, "vrpn_Tracker_NULL T 1 1\nvrpn_Foo x\n").unwrap();
    let report = parse_file_lenient(&good).unwrap();
    assert_eq!(report.entries.len(), 2);
    assert!(report.errors.is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---- vrpn_Tracker.cfg -----------------------------------------------------------------------

const TRACKER_CFG: &str = "\
# comment lines before entries are skipped
Tracker01 (must not match Tracker0)
Tracker0 entry
0.1 0.2 0.3
0 0 0.6 0.8
-1 -1 0 1 1 2.5
2
0
0.01 0 0
0 0 0 1
3
0 0.02 0
0 0 1 0
Other@host
";

#[test]
fn tracker_cfg_full_entry() {
    let t = parse_tracker_cfg(TRACKER_CFG, "vrpn_Tracker.cfg", "Tracker0").unwrap();
    assert_eq!(t.tracker2room.translation, [0.1, 0.2, 0.3]);
    assert_eq!(t.tracker2room.rotation, [0.0, 0.0, 0.6, 0.8]);
    assert_eq!(t.workspace_min, [-1.0, -1.0, 0.0]);
    assert_eq!(t.workspace_max, [1.0, 1.0, 2.5]);
    assert_eq!(t.num_sensors, 2);
    assert_eq!(t.unit2sensor.len(), 2);
    assert_eq!(t.unit2sensor_for(3).translation, [0.0, 0.02, 0.0]);
    assert_eq!(t.unit2sensor_for(0).translation, [0.01, 0.0, 0.0]);
    assert_eq!(t.unit2sensor_for(1), RigidTransform::IDENTITY);
}

#[test]
fn tracker_cfg_defaults() {
    let d = TrackerTransforms::default();
    assert_eq!(d.workspace_min, [-0.5; 3]);
    assert_eq!(d.workspace_max, [0.5; 3]);
    assert_eq!(d.num_sensors, 1);
    assert_eq!(d.tracker2room, RigidTransform::IDENTITY);
}

#[test]
fn tracker_cfg_errors() {
    let e = parse_tracker_cfg(TRACKER_CFG, "vrpn_Tracker.cfg", "Tracker9").unwrap_err();
    assert_eq!(e.kind(), ConfigErrorKind::TrackerNotFound);
    assert_eq!(
        e.to_string(),
        "vrpn_Tracker.cfg:14: no entry for tracker 'Tracker9' (a line starting with the name \
         followed by a blank); it keeps the default transforms"
    );
    let e = parse_tracker_cfg(TRACKER_CFG, "vrpn_Tracker.cfg", "Other@host").unwrap_err();
    assert_eq!(
        e.to_string(),
        "vrpn_Tracker.cfg:14: tracker 'Other@host': the file ends (after line 14) before its \
         tracker-to-room translation line"
    );
    let bad = TRACKER_CFG.replace("0 0 0.6 0.8", "0 0 0.6");
    let e = parse_tracker_cfg(&bad, "vrpn_Tracker.cfg", "Tracker0").unwrap_err();
    assert_eq!(
        e.to_string(),
        "vrpn_Tracker.cfg:5: tracker 'Tracker0': tracker-to-room quaternion line needs 4 \
         numbers (x y z w), found 3"
    );
    let bad = TRACKER_CFG.replace("\n2\n", "\ntwo\n");
    let e = parse_tracker_cfg(&bad, "vrpn_Tracker.cfg", "Tracker0").unwrap_err();
    assert_eq!(
        e.to_string(),
        "vrpn_Tracker.cfg:7: tracker 'Tracker0': sensor count must be a whole number, found 'two'"
    );
    let bad = TRACKER_CFG.replace("0 0.02 0\n", "0 0.02 zero\n");
    let e = parse_tracker_cfg(&bad, "vrpn_Tracker.cfg", "Tracker0").unwrap_err();
    assert_eq!(
        e.to_string(),
        "vrpn_Tracker.cfg:12: tracker 'Tracker0': sensor 3 unit-to-sensor translation z must \
         be a number, found 'zero'"
    );
}

#[test]
fn tracker_cfg_file() {
    let missing = Path::new("/nonexistent-dir-for-vrpn-tests/vrpn_Tracker.cfg");
    assert_eq!(load_tracker_cfg(missing, "Tracker0"), Ok(None));
    let dir = std::env::temp_dir().join(format!("vrpn-trackercfg-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(TRACKER_CFG_FILE);
    std::fs::write(&path, TRACKER_CFG).unwrap();
    let t = load_tracker_cfg(&path, "Tracker0").unwrap().unwrap();
    assert_eq!(t.num_sensors, 2);
    std::fs::remove_dir_all(&dir).unwrap();
}
