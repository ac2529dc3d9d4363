//! Biosciences Tools temperature controller on a serial line (C++ `vrpn_BiosciencesTools`):
//! its `vrpn.cfg` line ([`config`]), its [`Protocol`], and a device simulator (`sim`, with the
//! `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_BiosciencesTools NAME PORT TEMP1 TEMP2 CONTROL
//! ```
//!
//! `TEMP1` and `TEMP2` are the reference temperatures of the two channels (°C), `CONTROL` 1
//! turns temperature control on at start. The line is 115200 baud 8N1 with RTS/CTS flow
//! control, as C++ opens it.
//!
//! # Reset
//!
//! The input is flushed and C++'s commands written: the two reference temperatures
//! (`S1 0370\r`: whole degrees on three digits, then tenths), `ON\r` or `OFF\r`, and the
//! first temperature request (`T1\r`). The controller does not answer the settings, so the
//! reset is done at once ("reset complete (this is normal)"); C++ sleeps 0.2 s first.
//!
//! # What is served
//!
//! Under `NAME`:
//!
//! * an Analog with six channels, the readings of stage 1, bath 1, external 1 (or the set
//!   point), stage 2, bath 2, external 2, in °C. The controller is polled: each answer
//!   (`37.1C\r`) sets its channel and the next is asked for (`T1` … `T6` in turn); a
//!   `vrpn_Analog Channel` message (RELIABLE, as C++) follows each answer that changed a
//!   channel, stamped with the arrival of the answer's first byte;
//! * an Analog_Output with three channels: 0 and 1 set the reference temperatures, 2 turns
//!   temperature control on (non-zero) or off;
//! * a Button with one button: temperature control on.
//!
//! A client whose remote pings the device gets all channels at once, as in C++.
//!
//! # Supervision
//!
//! More than 2 s without an answer: two error texts, and the controller is set up again on
//! the open port. An answer that is not a reading is skipped and its request repeated.
//!
//! # Differences from C++ VRPN
//!
//! * No 0.2 s sleep, and the server is never blocked.
//! * The reset turns control on or off as the configuration (or the last request) says; C++
//!   looks at the first reference temperature instead.
//! * An answer that is not a reading is skipped and asked for again; C++ stores −1000 in the
//!   channel and resets the controller. Garbage before an answer costs nothing.
//! * A reset does not zero the channels (a reset never invents data).

pub mod config;
pub mod reading;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::io::Write as _;
use std::time::Instant;

use self::config::BAUD;
use self::reading::{Answer, Reader};
use crate::devices::analog_output::{AnalogOutputServer, OutputRequests};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::wire::class;
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::Biosciences;

/// The registry entry: `vrpn_BiosciencesTools`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_BiosciencesTools"],
    parse: config::parse,
    hints: &[],
};

/// Readings polled, in turn.
pub const READINGS: usize = 6;
/// Output channels: two reference temperatures and control on/off.
pub const OUTPUTS: usize = 3;

/// The controller's protocol. See the module documentation.
pub struct BioProtocol {
    analog: AnalogServer,
    output: AnalogOutputServer,
    button: ButtonServer,
    /// Settings asked for, not written yet (the last request per channel wins), and pings
    /// of the Analog.
    requests: OutputRequests,
    /// The settings in force: reference temperatures and control.
    settings: [f64; OUTPUTS],
    reader: Reader,
    next: usize,
    last_now: Option<Instant>,
}

/// The command setting reference temperature `channel` (0 or 1) to `value`, as C++ formats
/// it: `S1 0370\r` for 37.0 °C.
pub fn set_temperature(channel: usize, value: f32) -> ([u8; 24], usize) {
    let whole = value as i32;
    let tenths = (value * 10.0) as i32 - whole * 10;
    let mut buf = [0u8; 24];
    let mut w = &mut buf[..];
    let _ = write!(w, "S{} {:03}{}\r", channel + 1, whole, tenths);
    let len = 24 - w.len();
    (buf, len)
}

impl BioProtocol {
    /// The protocol of a `vrpn_BiosciencesTools` entry, with its devices on `conn`.
    pub fn new(cfg: &Biosciences, conn: &Connection) -> Result<BioProtocol, Error> {
        let mut analog = AnalogServer::new(&cfg.name, conn, READINGS)?;
        analog.set_class_of_service(class::RELIABLE);
        let output = AnalogOutputServer::new(&cfg.name, conn, OUTPUTS)?;
        let button = ButtonServer::new(&cfg.name, conn, 1)?;
        button.set_button(0, cfg.control);
        let requests = output.watch_requests(OUTPUTS, Some(analog.sender()))?;
        Ok(BioProtocol {
            analog,
            output,
            button,
            requests,
            settings: [
                f64::from(cfg.temp1),
                f64::from(cfg.temp2),
                f64::from(u8::from(cfg.control)),
            ],
            reader: Reader::new(),
            next: 0,
            last_now: None,
        })
    }

    /// The output server (three channels).
    pub fn output(&self) -> &AnalogOutputServer {
        &self.output
    }

    fn request(&self, channel: usize, cx: &mut Cx<'_>) {
        let cmd = [b'T', b'1' + channel as u8, b'\r'];
        cx.write(&cmd);
    }

    fn write_setting(&mut self, channel: usize, cx: &mut Cx<'_>) {
        let v = self.settings[channel];
        if channel < 2 {
            let (cmd, len) = set_temperature(channel, v as f32);
            cx.write(&cmd[..len]);
        } else {
            cx.write(if v != 0.0 { b"ON\r" } else { b"OFF\r" });
            self.button.set_button(0, v != 0.0);
            self.button.set_timestamp(cx.now.wall);
            // A failed send is the connection's business (it reports and drops the peer).
            let _ = self.button.report_changes_unfiltered();
        }
    }

    /// Writes what clients asked for, in channel order.
    fn send_requests(&mut self, cx: &mut Cx<'_>) {
        if self.requests.take_pinged() {
            let _ = self.analog.report(Some(cx.now.wall));
        }
        while let Some((i, v)) = self.requests.take_next() {
            self.settings[i] = v;
            self.write_setting(i, cx);
        }
    }
}

impl Protocol for BioProtocol {
    const KIND: &'static str = "BiosciencesTools";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings {
            rts_cts: true,
            ..PortSettings::n81(BAUD)
        })
    }

    fn supervision(&self) -> Supervision {
        Supervision {
            on_silence: Recovery::Reset,
            ..Supervision::TRACKER
        }
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        cx.flush_input();
        self.reader.clear();
        for i in 0..OUTPUTS {
            self.write_setting(i, cx);
        }
        self.next = 0;
        self.request(0, cx);
        cx.say(
            TextSeverity::Warning,
            format_args!("reset complete (this is normal)"),
        );
        Reset::Done
    }

    fn reset_received(&mut self, _bytes: &[u8], _cx: &mut Cx<'_>) -> Reset {
        Reset::Done
    }

    fn reset_poll(&mut self, _cx: &mut Cx<'_>) -> Reset {
        Reset::Done
    }

    fn reset_deadline(&self) -> Option<Instant> {
        None
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        for &b in bytes {
            let Some(answer) = self.reader.push(b, cx.now) else {
                continue;
            };
            let skipped = self.reader.take_skipped();
            cx.skipped(skipped, "BiosciencesTools", format_args!(""));
            match answer {
                Answer::Reading(v, first) => {
                    cx.record(first);
                    self.analog.set_channel(self.next, v);
                    // A failed send is the connection's business.
                    let _ = self.analog.report_changes(Some(first.wall));
                    self.next = (self.next + 1) % READINGS;
                }
                Answer::Bad(n) => cx.skipped(
                    n as u64,
                    "BiosciencesTools",
                    format_args!(" (an answer that is not a reading, channel {})", self.next),
                ),
            }
            self.request(self.next, cx);
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        self.send_requests(cx);
    }

    fn deadline(&self) -> Option<Instant> {
        if self.requests.is_pending() {
            return self.last_now;
        }
        None
    }

    fn stopped(&mut self) {
        self.reader.clear();
    }
}
