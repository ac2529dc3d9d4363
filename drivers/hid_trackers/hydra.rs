//! The Razer Hydra (C++ `vrpn_Tracker_RazerHydra`): two wands on a base, each a tracker
//! sensor, three analog channels and seven buttons.
//!
//! The Hydra has two HID interfaces: interface 0 streams 52-byte motion reports, interface 1
//! takes feature reports. A Hydra that starts in gamepad mode sends nothing on interface 0
//! until it is switched: the driver waits 1 s for a report, then sends C++'s 91-byte mode
//! feature report (and reads the feature report back, as C++ does), and tries again every
//! 5 s until reports come. When the server stops, a Hydra that was switched is put back in
//! gamepad mode. At open the driver reads feature report 0 for the serial number (17 bytes
//! at offset 216) and says `Connected to Razer Hydra with serial number …`.
//!
//! # What is sent
//!
//! A Tracker with 2 sensors (0 left, 1 right), an Analog with 6 channels and a Button with
//! 14 buttons, all named `NAME`. Per wand *s*: position (mm → m) and orientation from the
//! report (y and z negated, normalised), calibrated as C++ does when the wand rests in the
//! base (closer than 0.1 m): the orientation then is the reference, the hemisphere is
//! chosen from the position, and a jump to the mirrored position flips it; channels 3*s,
//! 3*s+1 the joystick (−1…1), 3*s+2 the trigger (0…1); buttons 8*s … 8*s+6 (bits 0x20,
//! 0x04, 0x08, 0x02, 0x10, 0x01, 0x40 of the buttons byte; the right wand's seventh is
//! button 14, beyond the 14 C++ declares, so it is not sent).
//!
//! # Differences from C++ VRPN
//!
//! * No waits: C++ sleeps 2 s in its destructor after switching back to gamepad mode.
//! * Interfaces are told apart by their numbers in sysfs, so the C++ fallback of swapping
//!   them when the control interface sends a report is not needed.
//! * A motion report of the wrong length is skipped with a warning (C++ reconnects).

use std::time::{Duration, Instant};

use crate::driver::text::with_text;
use crate::drivers::hid_pad::le_i16;
use crate::drivers::hid_quat::{invert, magnitude, mult, normalize, Quat, Vec3};
use crate::hid::{HidDriver, HidMatch, HidOps, InterfaceRule, NodeInfo};
use crate::time::Now;
use crate::{AnalogServer, ButtonServer, Connection, Error, TextSeverity, TrackerServer};

/// The Hydra's ids.
pub const IDS: (u16, u16) = (0x1532, 0x0300);
/// Length of a motion report.
pub const REPORT_LEN: usize = 52;
/// How long a freshly opened Hydra has to send a report before it is switched.
pub const INITIAL_WAIT: Duration = Duration::from_secs(1);
/// How long a switched Hydra has before it is switched again.
pub const RETRY_WAIT: Duration = Duration::from_secs(5);
/// Closer to the base than this (m), a wand is docked.
pub const DOCKING_DISTANCE: f32 = 0.1;

/// The feature report that puts the Hydra in motion-controller mode.
pub fn motion_mode_report() -> [u8; 91] {
    let mut r = [0u8; 91];
    r[6] = 1;
    r[8] = 4;
    r[9] = 3;
    r[89] = 6;
    r
}

/// The feature report that puts it back in gamepad mode.
pub fn gamepad_mode_report() -> [u8; 91] {
    let mut r = [0u8; 91];
    r[6] = 1;
    r[8] = 4;
    r[89] = 5;
    r
}

/// One wand's calibration, as C++ keeps it.
#[derive(Clone, Copy, Debug)]
struct Calibration {
    done: bool,
    mirror: f64,
    sign_x: f64,
    old_position: Vec3,
    reference_inverse: Quat,
}

impl Default for Calibration {
    fn default() -> Self {
        Calibration {
            done: false,
            mirror: 1.0,
            sign_x: 1.0,
            old_position: [0.0; 3],
            reference_inverse: [0.0, 0.0, 0.0, 1.0],
        }
    }
}

/// What one wand says in a report.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wand {
    /// Position, m (calibrated).
    pub pos: Vec3,
    /// Orientation `[x, y, z, w]` (calibrated).
    pub quat: Quat,
    /// Buttons 0-6.
    pub buttons: [bool; 7],
    /// Joystick x, y and trigger.
    pub analog: [f64; 3],
}

/// The decoding and calibration state of both wands.
#[derive(Clone, Debug, Default)]
pub struct Wands {
    cal: [Calibration; 2],
}

impl Wands {
    /// Forgets the calibration (C++ does at each reconnection).
    pub fn reset(&mut self) {
        for c in &mut self.cal {
            c.done = false;
            c.mirror = 1.0;
        }
    }

    /// Wand `s`'s 22 bytes (from byte 8 or 30 of the report).
    pub fn decode(&mut self, s: usize, d: &[u8]) -> Wand {
        const MM: f64 = 0.001;
        const I16: f64 = 1.0 / 32768.0;
        const U8: f64 = 1.0 / 255.0;
        let i = |at: usize| f64::from(le_i16(d, at));
        let ni = |at: usize| f64::from(-i32::from(le_i16(d, at)));
        let mut pos = [i(0) * MM, i(2) * MM, i(4) * MM];
        let mut quat = normalize(&[i(8) * I16, ni(10) * I16, ni(12) * I16, i(6) * I16]);
        let c = &mut self.cal[s];
        let docked = magnitude(&pos) < f64::from(DOCKING_DISTANCE);
        if docked {
            c.done = true;
            c.reference_inverse = invert(&quat);
            c.mirror = if pos[1] > 0.0 || pos[2] > 0.0 {
                -1.0
            } else {
                1.0
            };
            let mut tmp = pos.map(|v| v * c.mirror);
            c.sign_x = match s {
                0 if tmp[0] < 0.0 => 1.0,
                0 => -1.0,
                _ if tmp[0] > 0.0 => 1.0,
                _ => -1.0,
            };
            tmp[0] *= c.sign_x;
            c.old_position = tmp;
        }
        if c.done {
            quat = mult(&quat, &c.reference_inverse);
            pos[0] *= c.sign_x;
            pos = pos.map(|v| v * c.mirror);
            if !docked {
                let o = c.old_position;
                let direct = [pos[0] - o[0], pos[1] - o[1], pos[2] - o[2]];
                let inv = pos.map(|v| -v);
                let mirrored = [inv[0] - o[0], inv[1] - o[1], inv[2] - o[2]];
                if magnitude(&direct) > magnitude(&mirrored) {
                    pos = inv;
                    c.mirror = -c.mirror;
                }
            }
        }
        c.old_position = pos;
        let bits = d[14];
        let mut buttons = [false; 7];
        for (b, mask) in [0x20u8, 0x04, 0x08, 0x02, 0x10, 0x01, 0x40]
            .into_iter()
            .enumerate()
        {
            buttons[b] = bits & mask != 0;
        }
        Wand {
            pos,
            quat,
            buttons,
            analog: [i(15) * I16, i(17) * I16, f64::from(d[19]) * U8],
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Status {
    Closed,
    ListeningAfterConnect,
    ListeningAfterSetFeature,
    Reporting,
}

/// The Hydra driver.
pub struct HydraDriver {
    name: String,
    tracker: TrackerServer,
    analog: AnalogServer,
    buttons: ButtonServer,
    wands: Wands,
    status: Status,
    since: Option<Instant>,
    attempt: u32,
    was_in_gamepad_mode: bool,
    skipped: u64,
}

impl HydraDriver {
    /// The driver for `vrpn_Tracker_RazerHydra NAME`.
    pub fn new(name: &str, conn: &Connection) -> Result<HydraDriver, Error> {
        Ok(HydraDriver {
            name: name.to_string(),
            tracker: TrackerServer::new(name, conn, 2)?,
            analog: AnalogServer::new(name, conn, 6)?,
            buttons: ButtonServer::new(name, conn, 14)?,
            wands: Wands::default(),
            status: Status::Closed,
            since: None,
            attempt: 0,
            was_in_gamepad_mode: false,
            skipped: 0,
        })
    }

    /// Mode switches tried since the device opened.
    pub fn attempts(&self) -> u32 {
        self.attempt
    }

    fn say(&self, severity: TextSeverity, args: std::fmt::Arguments<'_>) {
        with_text(args, |t| {
            let _ = self.tracker.send_text(severity, 0, t);
        });
    }

    fn enter_motion_mode(&mut self, now: Now, ops: &mut HidOps) {
        self.attempt += 1;
        self.was_in_gamepad_mode = true;
        self.say(
            TextSeverity::Warning,
            format_args!(
                "Hydra not in motion-controller mode - attempting to change modes. Please be \
                 sure that the left and right sensors are to the left and right sides of the \
                 base for automatic calibration to take place."
            ),
        );
        ops.set_feature(1, &motion_mode_report());
        ops.get_feature(1, 0, 91);
        self.status = Status::ListeningAfterSetFeature;
        self.since = Some(now.mono);
    }
}

impl HidDriver for HydraDriver {
    fn name(&self) -> &str {
        &self.name
    }

    fn interfaces(&self) -> Vec<HidMatch> {
        vec![
            HidMatch::product(IDS.0, IDS.1).interface(InterfaceRule::Is(0)),
            HidMatch::product(IDS.0, IDS.1).interface(InterfaceRule::Is(1)),
        ]
    }

    fn opened(&mut self, now: Now, _nodes: &[Option<NodeInfo>], ops: &mut HidOps) {
        self.status = Status::ListeningAfterConnect;
        self.since = Some(now.mono);
        self.attempt = 0;
        self.was_in_gamepad_mode = false;
        self.wands.reset();
        // The serial number, then "listening" (in `feature`).
        ops.get_feature(1, 0, 255);
    }

    fn feature(
        &mut self,
        _interface: usize,
        report: std::io::Result<&[u8]>,
        _now: Now,
        _ops: &mut HidOps,
    ) {
        if self.status != Status::ListeningAfterConnect || self.attempt > 0 {
            return;
        }
        let serial = match &report {
            Ok(r) if !r.is_empty() => {
                let s = r.get(216..233.min(r.len())).unwrap_or(&[]);
                let end = s.iter().position(|b| *b == 0).unwrap_or(s.len());
                String::from_utf8_lossy(&s[..end]).into_owned()
            }
            _ => "[FAILED TO GET FEATURE REPORT]".to_string(),
        };
        self.say(
            TextSeverity::Warning,
            format_args!("Connected to Razer Hydra with serial number {serial}"),
        );
        self.say(
            TextSeverity::Normal,
            format_args!("Listening to see if device is in motion controller mode."),
        );
    }

    fn report(&mut self, interface: usize, r: &[u8], at: Now, _ops: &mut HidOps) {
        if interface != 0 {
            // The control interface sends nothing C++ uses.
            return;
        }
        if r.len() != REPORT_LEN {
            self.skipped += 1;
            let n = r.len();
            return self.say(
                TextSeverity::Warning,
                format_args!("Got input report of {n} bytes, expected 52! Discarding."),
            );
        }
        if self.status != Status::Reporting {
            let a = self.attempt;
            let s = if a == 1 { "" } else { "s" };
            self.say(
                TextSeverity::Warning,
                format_args!(
                    "Got first motion controller report! This means everything is working \
                     properly now. (Took {a} attempt{s} to change modes.)"
                ),
            );
            self.status = Status::Reporting;
            self.since = None;
        }
        for s in 0..2 {
            let w = self.wands.decode(s, &r[8 + 22 * s..]);
            // A failed send is the connection's business (it reports and drops the peer).
            let _ = self.tracker.report_pose(s, at.wall, w.pos, w.quat);
            for (b, pressed) in w.buttons.iter().enumerate() {
                self.buttons.set_button(8 * s + b, *pressed);
            }
            for (k, v) in w.analog.iter().enumerate() {
                self.analog.set_channel(3 * s + k, *v);
            }
        }
        let _ = self.analog.report_changes(Some(at.wall));
        self.buttons.set_timestamp(at.wall);
        let _ = self.buttons.report_changes();
    }

    fn poll(&mut self, now: Now, ops: &mut HidOps) {
        let Some(since) = self.since else { return };
        match self.status {
            Status::ListeningAfterConnect if now.mono >= since + INITIAL_WAIT => {
                self.enter_motion_mode(now, ops)
            }
            Status::ListeningAfterSetFeature if now.mono >= since + RETRY_WAIT => {
                let a = self.attempt;
                let s = if a == 1 { "" } else { "s" };
                self.say(
                    TextSeverity::Warning,
                    format_args!(
                        "Really sleepy device - won't start motion controller reports despite \
                         our earlier {a} attempt{s}. Will give it another try. If this doesn't \
                         work, unplug and replug device and restart the VRPN server."
                    ),
                );
                self.enter_motion_mode(now, ops);
            }
            _ => {}
        }
    }

    fn next_deadline(&self) -> Option<Instant> {
        let since = self.since?;
        match self.status {
            Status::ListeningAfterConnect => Some(since + INITIAL_WAIT),
            Status::ListeningAfterSetFeature => Some(since + RETRY_WAIT),
            _ => None,
        }
    }

    fn closed(&mut self, _now: Now) {
        self.status = Status::Closed;
        self.since = None;
        self.wands.reset();
    }

    fn shutdown(&mut self, ops: &mut HidOps) {
        if self.status == Status::Reporting && self.was_in_gamepad_mode {
            self.say(
                TextSeverity::Warning,
                format_args!(
                    "Hydra was in gamepad mode when we started: switching back to gamepad mode."
                ),
            );
            ops.set_feature(1, &gamepad_mode_report());
        }
    }
}

/// The running Hydra, waiting for it to be plugged in.
pub fn build(
    name: &str,
    conn: &Connection,
    hub: &crate::hid::DeviceHub,
) -> Result<Box<dyn crate::devices::ServerDevice>, Error> {
    Ok(Box::new(crate::hid::HidDevice::new(
        HydraDriver::new(name, conn)?,
        hub,
        conn,
    )))
}
