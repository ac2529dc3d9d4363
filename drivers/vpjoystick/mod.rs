//! The buttons of a Virtual Presence joystick (`vrpn_VPJoystick`): an 8-button handle that
//! also holds an Ascension Flock of Birds sensor (read its pose with `vrpn_Tracker_Flock`).
//! Its `vrpn.cfg` line ([`config`]), its messages ([`message`]), its [`Protocol`], and a
//! simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_VPJoystick NAME PORT BAUD
//! ```
//!
//! 8N1 at `BAUD` (9600).
//!
//! # What is sent
//!
//! `NAME` is a Button with 8 buttons: 0 bottom, 1 middle, 2 top, 3 trigger, 4 hat up, 5 hat
//! right, 6 hat down, 7 hat left. Each message sends one `vrpn_Button Change` per button
//! that changed, stamped with the arrival of its `FF`.
//!
//! # Reset and supervision
//!
//! The joystick takes no commands: the driver reads messages as they come (no reset, no
//! watchdog). Bytes outside a message that are not its start are reported as skipped, at
//! most once a second. A port that fails is reopened by the serial layer.
//!
//! # Differences from C++ VRPN
//!
//! * Reports carry the `FF`'s arrival (C++ stamps them all with the time the server
//!   started).
//! * The server is never blocked (C++ waits up to 0.2 s for each part of a message).
//! * A port that fails is reopened (C++ prints a line for every pass of its loop).

pub mod config;
pub mod message;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use self::message::{Framer, Step, BUTTONS};
use crate::driver::{Cx, Driver, Protocol, Reset, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{ButtonServer, Connection, Error};

pub use self::config::VpJoystick;

/// The registry entry: `vrpn_VPJoystick`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_VPJoystick"],
    parse: config::parse,
    hints: &[],
};

/// The joystick's protocol. See the module documentation.
pub struct VpJoystickProtocol {
    baud: u32,
    buttons: ButtonServer,
    framer: Framer,
    /// The arrival of the message under way's `FF`.
    first_byte: Option<Now>,
}

impl VpJoystickProtocol {
    /// The protocol of an entry, with its Button on `conn`.
    pub fn new(cfg: &VpJoystick, conn: &Connection) -> Result<VpJoystickProtocol, Error> {
        Ok(VpJoystickProtocol {
            baud: cfg.baud,
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            framer: Framer::default(),
            first_byte: None,
        })
    }
}

impl Protocol for VpJoystickProtocol {
    const KIND: &'static str = "VP joystick";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        // What the line held before it was opened is stale.
        cx.flush_input();
        self.framer.clear();
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
            if self.framer.idle() {
                self.first_byte = Some(cx.now);
            }
            match self.framer.push(b) {
                Step::Message(state) => {
                    let at = self.first_byte.unwrap_or(cx.now);
                    cx.record(at);
                    for (i, &pressed) in state.iter().enumerate() {
                        self.buttons.set_button(i, pressed);
                    }
                    self.buttons.set_timestamp(at.wall);
                    // A failed send is the connection's business (it reports and drops the
                    // peer).
                    let _ = self.buttons.report_changes();
                }
                Step::Partial => {}
                Step::Garbage => garbage += 1,
            }
        }
        cx.skipped(garbage, "vrpn_VPJoystick", format_args!(""));
    }

    fn stopped(&mut self) {
        self.framer.clear();
    }
}
