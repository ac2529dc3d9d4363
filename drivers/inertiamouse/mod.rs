//! The UNC inertia mouse on a serial line (`vrpn_inertiamouse`): accelerometer records and
//! button records found byte by byte and turned into C++ VRPN's values ([`record`]); a
//! simulator in `sim` (with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_inertiamouse NAME PORT BAUD
//! ```
//!
//! 8N1 at `BAUD`, no flow control.
//!
//! # What is sent
//!
//! `NAME` is an Analog with 6 channels and a Button with 2 buttons. After each record, the
//! channels that changed (`vrpn_Analog Channel`, all six, LOW_LATENCY) and the buttons that
//! changed, stamped with the arrival of the record's first byte.
//!
//! # Supervision
//!
//! The device has nothing to ask: the reset flushes the input. There is no watchdog (C++ has
//! none either); a port that fails is reopened.

pub mod config;
pub mod record;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::Instant;

use self::record::{Applied, Framer, MouseState, BUTTONS, CHANNELS};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Reset, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::InertiaMouse;

/// The registry entry: `vrpn_inertiamouse`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_inertiamouse"],
    parse: config::parse,
    hints: &[],
};

/// The inertia mouse protocol: its records and reports.
pub struct InertiaMouseProtocol {
    baud: u32,
    analog: AnalogServer,
    buttons: ButtonServer,
    framer: Framer,
    state: MouseState,
}

impl InertiaMouseProtocol {
    /// The protocol of an entry, with its servers on `conn`.
    pub fn new(cfg: &InertiaMouse, conn: &Connection) -> Result<InertiaMouseProtocol, Error> {
        Ok(InertiaMouseProtocol {
            baud: cfg.baud,
            analog: AnalogServer::new(&cfg.name, conn, CHANNELS)?,
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            framer: Framer::new(),
            state: MouseState::default(),
        })
    }

    /// The Analog server.
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }
}

impl Protocol for InertiaMouseProtocol {
    const KIND: &'static str = "inertia mouse";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        cx.flush_input();
        self.framer.clear();
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
        for &b in bytes {
            let Some(f) = self.framer.push(b, cx.now) else {
                continue;
            };
            let (skipped, first_byte) = (u64::from(f.skipped), f.first_byte);
            let applied = self.state.apply(f.bytes);
            cx.skipped(skipped, "vrpn_inertiamouse", format_args!(""));
            if let Applied::BadChannel(c) = applied {
                cx.say(
                    TextSeverity::Error,
                    format_args!("vrpn_inertiamouse: Too-large channel value ({c})"),
                );
                continue;
            }
            cx.record(first_byte);
            for (i, v) in self.state.channels.iter().enumerate() {
                self.analog.set_channel(i, *v);
            }
            let _ = self.analog.report_changes(Some(first_byte.wall));
            for (i, p) in self.state.buttons.iter().enumerate() {
                self.buttons.set_button(i, *p);
            }
            self.buttons.set_timestamp(first_byte.wall);
            let _ = self.buttons.report_changes();
        }
    }

    fn stopped(&mut self) {
        self.framer.clear();
    }
}
