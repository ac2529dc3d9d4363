//! Mindtel's TNG-3 ("Totally Neat Gadget": 8 analog and 8 digital inputs, powered by the
//! serial line's control lines): its `vrpn.cfg` line ([`config`]), how its records are found
//! ([`framer`]), its [`Protocol`] run by the shared [`Lifecycle`](crate::driver::Lifecycle),
//! and a device simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tng3 NAME PORT BUTTONS ANALOGS
//! ```
//!
//! The line is 8N1 at 19200 baud (fixed inside the box). At most 8 of each: a larger count is
//! an error naming the limit (C++ reduces it and prints a line on its standard error).
//!
//! # What is sent
//!
//! `NAME` is an Analog with `ANALOGS` channels and a Button with `BUTTONS` buttons. Each
//! record sends a `vrpn_Analog Channel` message if a channel changed (channel *i* is analog
//! byte *i*, 0-255, as C++ reports it) and one `vrpn_Button Change` per changed button
//! (button *i* is pressed while bit *i* of the digital byte is clear; toggle modes not
//! applied, as C++), stamped with the arrival of the record's start byte.
//!
//! # Reset and supervision
//!
//! The box takes no commands; it streams. The reset only finds the stream's step: two records
//! in a row with alternating start bytes ([`framer`]), within [`SYNC_LIMIT`] (else C++'s
//! warning `syncDatastream timeout expired` and another attempt); records found meanwhile
//! are reported. More than 2 s without a record sends C++'s `Too long since last report,
//! resetting` (error) and the step is looked for again. Losing step is reported in the
//! skipped-bytes note (C++ sends `Resyncing` for every byte). A port that fails is reopened
//! by the serial layer.
//!
//! # Differences from C++ VRPN
//!
//! * C++ busy-waits up to 2 s for the step, stalling the server; here records are read as
//!   they come and the first is reported as soon as the next one confirms it.
//! * Out of step, a start byte counts only when the next record's start byte follows it;
//!   C++ takes the first byte equal to the start byte it expects, so a data byte of that value
//!   after a lost byte is read as a record.
//! * Reports carry the start byte's arrival (C++: the time the record was decoded).

pub mod config;
pub mod framer;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::framer::{Framed, Framer};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::Tng3;

/// The registry entry: `vrpn_Tng3`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tng3"],
    parse: config::parse,
    hints: &[],
};

/// The line's speed (fixed inside the box).
pub const BAUD: u32 = 19200;
/// Longest search for the stream's step (C++'s 2 s).
pub const SYNC_LIMIT: Duration = Duration::from_secs(2);
/// Longest silence before the step is looked for again (C++'s 2 s).
pub const WATCHDOG: Duration = Duration::from_secs(2);

/// The TNG-3's protocol. See the module documentation.
pub struct Tng3Protocol {
    num_buttons: usize,
    num_analogs: usize,
    analog: AnalogServer,
    buttons: ButtonServer,
    framer: Framer,
    sync_by: Option<Instant>,
}

impl Tng3Protocol {
    /// The protocol of a `vrpn_Tng3` entry, with its servers on `conn`.
    pub fn new(cfg: &Tng3, conn: &Connection) -> Result<Tng3Protocol, Error> {
        Ok(Tng3Protocol {
            num_buttons: cfg.buttons as usize,
            num_analogs: cfg.analogs as usize,
            analog: AnalogServer::new(&cfg.name, conn, cfg.analogs as usize)?,
            buttons: ButtonServer::new(&cfg.name, conn, cfg.buttons as usize)?,
            framer: Framer::new(),
            sync_by: None,
        })
    }

    /// The analog server.
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }

    /// The button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// Bytes skipped while looking for records, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn report(&mut self, f: Framed, cx: &mut Cx<'_>) {
        cx.skipped(
            u64::from(f.skipped),
            "vrpn_Tng3",
            format_args!(" (out of step)"),
        );
        cx.record(f.first_byte);
        for i in 0..self.num_analogs {
            self.analog.set_channel(i, f64::from(f.bytes[1 + i]));
        }
        let digital = f.bytes[9];
        for i in 0..self.num_buttons {
            self.buttons.set_button(i, digital & (1 << i) == 0);
        }
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.analog.report_changes(Some(f.first_byte.wall));
        self.buttons.set_timestamp(f.first_byte.wall);
        let _ = self.buttons.report_changes_unfiltered();
    }
}

impl Protocol for Tng3Protocol {
    const KIND: &'static str = "vrpn_Tng3";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(BAUD))
    }

    fn supervision(&self) -> Supervision {
        Supervision {
            watchdog: Some(WATCHDOG),
            on_silence: Recovery::Reset,
            ..Supervision::TRACKER
        }
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        cx.flush_input();
        self.framer.clear();
        self.sync_by = Some(cx.now.mono + SYNC_LIMIT);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        for (i, &b) in bytes.iter().enumerate() {
            if let Some(f) = self.framer.push(b, cx.now) {
                self.report(f, cx);
                self.sync_by = None;
                self.received(&bytes[i + 1..], cx);
                return Reset::Done;
            }
        }
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        cx.say(
            TextSeverity::Warning,
            format_args!("vrpn_Tng3::syncDatastream timeout expired: 2 secs"),
        );
        self.sync_by = None;
        Reset::Failed(Retry::Now)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.sync_by
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            if let Some(f) = self.framer.push(b, cx.now) {
                self.report(f, cx);
            }
        }
    }

    fn stopped(&mut self) {
        self.framer.clear();
        self.sync_by = None;
    }

    fn silent(&mut self, _last_record: Now, cx: &mut Cx<'_>) {
        cx.say(
            TextSeverity::Error,
            format_args!("Too long since last report, resetting"),
        );
    }
}
