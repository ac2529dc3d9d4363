//! The buttons of a serial mouse (`vrpn_Button_SerialMouse`): a mouse, or a box of switches
//! wired in parallel with a mouse's buttons, read straight from the serial line (not through
//! the system's mouse driver). Its `vrpn.cfg` line ([`config`]), its packets ([`packet`]),
//! its [`Protocol`], and a simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Button_SerialMouse NAME PORT mousesystems
//! vrpn_Button_SerialMouse NAME PORT 3button
//! ```
//!
//! The line runs at 1200 baud 8N1 (as C++ opens it; the rate is not on the line).
//!
//! # What is sent
//!
//! `NAME` is a Button with 3 buttons (left, middle, right). A packet that carries the
//! buttons sends one `vrpn_Button Change` per button that changed, stamped with the arrival
//! of the packet's first byte. The mouse's motion is not reported. With `3button` the middle
//! button is toggled by every packet that leaves left and right as they were (moving the
//! mouse toggles it, as C++ documents).
//!
//! # Reset and supervision
//!
//! The mouse takes no commands and sends only when it moves or a button changes: nothing to
//! reset, no watchdog. Bytes before the port opened are dropped; a port that fails is
//! reported (`vrpn_Button_SerialMouse failure!`, C++'s text) and reopened by the serial
//! layer.
//!
//! # Differences from C++ VRPN
//!
//! * Reports carry the first byte's arrival (C++ stamps every report with the time the
//!   server started).
//! * `3button`: every packet without a left/right change toggles the middle button; C++
//!   toggles it at most once per read of the port, so what it reports depends on how the
//!   bytes fall into reads.
//! * `mousesystems`: after a packet's first byte, its four motion bytes are skipped, so a
//!   motion byte of `80`-`87` is not read as buttons (C++ reads it so). Bytes outside a
//!   packet are reported as skipped.
//! * A port that fails is reopened (C++ gives up).

pub mod config;
pub mod packet;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use self::packet::{Decoder, Step, BUTTONS};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Reset, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{ButtonServer, Connection, Error};

pub use self::config::SerialMouse;

/// The registry entry: `vrpn_Button_SerialMouse`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Button_SerialMouse"],
    parse: config::parse,
    hints: &[],
};

/// The line's speed (C++ opens every serial mouse at 1200 baud).
pub const BAUD: u32 = 1200;

/// The serial mouse's protocol. See the module documentation.
pub struct SerialMouseProtocol {
    buttons: ButtonServer,
    decoder: Decoder,
}

impl SerialMouseProtocol {
    /// The protocol of an entry, with its Button on `conn`.
    pub fn new(cfg: &SerialMouse, conn: &Connection) -> Result<SerialMouseProtocol, Error> {
        Ok(SerialMouseProtocol {
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            decoder: Decoder::new(cfg.kind),
        })
    }

    /// The Button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }
}

impl Protocol for SerialMouseProtocol {
    const KIND: &'static str = "serial mouse";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(BAUD))
    }

    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        // What the line held before it was opened is stale.
        cx.flush_input();
        self.decoder.clear_packet();
        Reset::Done
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        self.received(bytes, cx);
        Reset::Done
    }

    fn reset_poll(&mut self, _cx: &mut Cx<'_>) -> Reset {
        Reset::Done
    }

    fn reset_deadline(&self) -> Option<std::time::Instant> {
        None
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        let mut garbage = 0;
        for &b in bytes {
            match self.decoder.push(b) {
                Step::Buttons(state) => {
                    // The buttons are in the packet's first byte: this one.
                    cx.record(cx.now);
                    for (i, &pressed) in state.iter().enumerate() {
                        self.buttons.set_button(i, pressed);
                    }
                    self.buttons.set_timestamp(cx.now.wall);
                    // A failed send is the connection's business (it reports and drops the
                    // peer).
                    let _ = self.buttons.report_changes();
                }
                Step::Motion => {}
                Step::Garbage => garbage += 1,
            }
        }
        cx.skipped(garbage, "vrpn_Button_SerialMouse", format_args!(""));
    }

    fn stopped(&mut self) {
        self.decoder.clear_packet();
    }

    fn lost(&mut self, cx: &mut Cx<'_>) {
        cx.say(
            TextSeverity::Error,
            format_args!("vrpn_Button_SerialMouse failure!"),
        );
    }
}
