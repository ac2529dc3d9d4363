//! The wired unit's protocol: the reset over deadlines, then records found by [`Framer`].
//!
//! The reset: the start-up commands (LED mode and colour, gyro calibration, tare) once after
//! the port opens, then stop streaming; [`SETTLE`] later the input is flushed and the LED
//! mode and colour are read back. Their 13-byte answer proves the unit is there; then axes,
//! timing, slots, the `vrpn.cfg` commands and start streaming go out in one write, which
//! ends the reset (the unit answers none of them). Anything after the answer in its read is
//! handed to the framer.

use std::time::Instant;

use super::command::{reset_steps, setup_steps, Step, STOP_STREAMING};
use super::config::{Unit, Yei};
use super::framing::Framer;
use super::{say_timeout, supervision, UnitServers, ANSWER_WAIT, SETTLE};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{Connection, Error};

/// Bytes answering the two reads: the LED mode, then three floats.
const ANSWER_LEN: usize = 13;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Idle,
    Settling(Instant),
    Answer(Instant),
}

/// The wired unit's protocol. See the module documentation.
pub struct WiredProtocol {
    baud: u32,
    setup: Vec<u8>,
    stop: Vec<u8>,
    reads: Vec<u8>,
    rest: Vec<u8>,
    setup_due: bool,
    phase: Phase,
    answer: [u8; ANSWER_LEN],
    answer_len: usize,
    led: Option<(u8, [f32; 3])>,
    framer: Framer,
    servers: UnitServers,
}

fn wired_bytes(steps: &[Step]) -> Vec<u8> {
    let mut out = Vec::new();
    for s in steps {
        s.wired(&mut out);
    }
    out
}

impl WiredProtocol {
    /// The protocol of an entry, with its servers on `conn`.
    pub fn new(cfg: &Yei, conn: &Connection) -> Result<WiredProtocol, Error> {
        WiredProtocol::for_unit(&cfg.unit, cfg.baud, conn)
    }

    fn for_unit(u: &Unit, baud: u32, conn: &Connection) -> Result<WiredProtocol, Error> {
        Ok(WiredProtocol {
            baud,
            setup: wired_bytes(&setup_steps(u)),
            stop: wired_bytes(&[Step::Binary(vec![STOP_STREAMING])]),
            reads: wired_bytes(&reset_steps(u)[..2]),
            rest: wired_bytes(&reset_steps(u)[2..]),
            setup_due: true,
            phase: Phase::Idle,
            answer: [0; ANSWER_LEN],
            answer_len: 0,
            led: None,
            framer: Framer::default(),
            servers: UnitServers::new(&u.name, conn)?,
        })
    }

    /// The LED mode and colour the unit reported at its last reset.
    pub fn led(&self) -> Option<(u8, [f32; 3])> {
        self.led
    }

    fn check_answer(&self) -> Option<(u8, [f32; 3])> {
        let a = &self.answer;
        let f = |i: usize| f32::from_be_bytes([a[i], a[i + 1], a[i + 2], a[i + 3]]);
        let rgb = [f(1), f(5), f(9)];
        (a[0] <= 1 && rgb.iter().all(|v| (0.0..=1.0).contains(v))).then_some((a[0], rgb))
    }

    fn failed(cx: &mut Cx<'_>, why: &str) -> Reset {
        cx.say(
            TextSeverity::Error,
            format_args!("vrpn_YEI_3Space::reset: {why}"),
        );
        cx.say(
            TextSeverity::Error,
            format_args!("vrpn_YEI_3Space: Cannot reset!"),
        );
        Reset::Failed(Retry::Now)
    }
}

impl Protocol for WiredProtocol {
    const KIND: &'static str = "YEI 3-Space Sensor";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        supervision()
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        if self.setup_due {
            cx.write(&self.setup);
            self.setup_due = false;
        }
        cx.write(&self.stop);
        self.phase = Phase::Settling(cx.now.mono + SETTLE);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        if !matches!(self.phase, Phase::Answer(_)) {
            return Reset::Working; // the tail of the stream being stopped
        }
        let n = (ANSWER_LEN - self.answer_len).min(bytes.len());
        self.answer[self.answer_len..self.answer_len + n].copy_from_slice(&bytes[..n]);
        self.answer_len += n;
        if self.answer_len < ANSWER_LEN {
            return Reset::Working;
        }
        self.phase = Phase::Idle;
        let Some(led) = self.check_answer() else {
            return Self::failed(cx, "Unable to read get-led-mode response");
        };
        self.led = Some(led);
        cx.write(&self.rest);
        self.received(&bytes[n..], cx);
        Reset::Done
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        match self.phase {
            Phase::Settling(t) if cx.now.mono >= t => {
                cx.flush_input();
                cx.write(&self.reads);
                self.answer_len = 0;
                self.phase = Phase::Answer(cx.now.mono + ANSWER_WAIT);
                Reset::Working
            }
            Phase::Answer(t) if cx.now.mono >= t => {
                self.phase = Phase::Idle;
                Self::failed(cx, "Unable to read get-led-mode response")
            }
            _ => Reset::Working,
        }
    }

    fn reset_deadline(&self) -> Option<Instant> {
        match self.phase {
            Phase::Idle => None,
            Phase::Settling(t) | Phase::Answer(t) => Some(t),
        }
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            let Some(f) = self.framer.push(b, cx.now) else {
                continue;
            };
            if let Some(why) = f.rejected {
                cx.skipped(
                    u64::from(f.skipped),
                    "vrpn_YEI_3Space_Sensor",
                    format_args!(" (the bytes held {why})"),
                );
            }
            cx.record(f.first_byte);
            self.servers.report(&f.record, f.first_byte);
        }
    }

    fn stopped(&mut self) {
        self.phase = Phase::Idle;
        self.answer_len = 0;
        self.framer.clear();
    }

    fn lost(&mut self, _cx: &mut Cx<'_>) {
        // A unit plugged back in has forgotten its LED settings, calibration and tare.
        self.setup_due = true;
    }

    fn silent(&mut self, last_record: Now, cx: &mut Cx<'_>) {
        say_timeout(last_record, cx);
    }
}
