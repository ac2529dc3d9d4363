//! The Linux joystick interface (`/dev/input/jsN`, C++ `vrpn_Joylin`): its `vrpn.cfg` line
//! ([`config`]), a [`Protocol`] that reads `js_event` records (run by the shared
//! [`Lifecycle`](crate::driver::Lifecycle): no reset, no watchdog), and a joystick simulator
//! (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Joylin NAME DEVICE
//! ```
//!
//! `DEVICE` is opened read-only as it is (no terminal settings): a joystick device, or any
//! file that delivers `js_event` records (a pipe, a pseudo-terminal).
//!
//! # What is sent
//!
//! An Analog and a Button, both named `NAME`. Axis `n` is channel `n`, its value divided by
//! 32767 (so −1…1); button `n` is button `n`. After each event the Analog sends all its
//! channels if one changed (`vrpn_Analog Channel`, LOW_LATENCY) and the Button one
//! `vrpn_Button Change` (RELIABLE) per changed button, as C++ does; both carry the time the
//! event's read arrived.
//!
//! # How many axes and buttons
//!
//! C++ asks the device with the `JSIOCGAXES` and `JSIOCGBUTTONS` ioctls and keeps 2 and 2
//! when they fail (on a pipe or a pseudo-terminal). This driver does no I/O of its own, so it
//! learns the counts from the events instead: it starts at C++'s 2 and 2 and grows to cover
//! the highest axis and button number seen. A joystick device reports every axis and button
//! in its initial-state events right after it opens, so the counts are complete before the
//! first live event and match the ioctls' (for a stick with at least two of each). Once the
//! initial state has been seen, a live event beyond the counts is taken for damage in the
//! stream; without one (a stand-in that sends only live events) the counts grow with the
//! events. Numbers beyond the protocol's limits (128 channels, 256 buttons) are ignored with
//! one warning.
//!
//! # Differences from C++ VRPN
//!
//! * The initial-state events that one read returns are applied together and reported once
//!   (one Analog message with every axis instead of one per axis); live events are reported
//!   one by one, as in C++.
//! * A device that fails (an unplugged or sleeping wireless pad) is reported with C++'s
//!   text "Error reading from joystick" and reopened every second until it comes back; C++
//!   blocks the whole server for 5 s, tries once, and gives up for good if that fails.
//! * There is no watchdog: an untouched joystick is silent, and that is not a fault.

pub mod config;
pub mod event;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::Instant;

use self::event::{Framer, JsEvent, Kind};
use crate::devices::text::TextSeverity;
use crate::driver::registry::Driver;
use crate::driver::{Cx, Protocol, Reset, Supervision};
use crate::serial::PortKind;
use crate::time::Now;
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::Joylin;

/// The registry entry: `vrpn_Joylin`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Joylin"],
    parse: config::parse,
    hints: &[],
};

/// Axes assumed before the device says otherwise (C++'s default).
pub const DEFAULT_AXES: usize = 2;
/// Buttons assumed before the device says otherwise (C++'s default).
pub const DEFAULT_BUTTONS: usize = 2;
/// Most axes an Analog can carry.
pub const MAX_AXES: usize = 128;
/// Most buttons a Button can carry.
pub const MAX_BUTTONS: usize = 256;
/// The text C++ sends when the device fails.
pub const READ_ERROR: &str = "Error reading from joystick";

/// A Linux joystick's protocol. See the module documentation.
pub struct JoylinProtocol {
    device: String,
    analog: AnalogServer,
    buttons: ButtonServer,
    framer: Framer,
    /// Initial-state events applied but not reported yet.
    init_pending: bool,
    /// The device reported its initial state: the counts are known, and a live event beyond
    /// them is damage.
    counts_known: bool,
    events: u64,
    ignored: u64,
}

impl JoylinProtocol {
    /// The protocol of a `vrpn_Joylin` entry, with its Analog and Button served on `conn`.
    pub fn new(cfg: &Joylin, conn: &Connection) -> Result<JoylinProtocol, Error> {
        Ok(JoylinProtocol {
            device: cfg.device.clone(),
            analog: AnalogServer::new(&cfg.name, conn, DEFAULT_AXES)?,
            buttons: ButtonServer::new(&cfg.name, conn, DEFAULT_BUTTONS)?,
            framer: Framer::new(),
            init_pending: false,
            counts_known: false,
            events: 0,
            ignored: 0,
        })
    }

    /// The device file, as the configuration gives it.
    pub fn device(&self) -> &str {
        &self.device
    }

    /// The Analog the axes go out through.
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }

    /// The Button the buttons go out through.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// Events applied since construction (ignored ones not counted).
    pub fn events(&self) -> u64 {
        self.events
    }

    /// Events ignored for a number beyond the limits.
    pub fn ignored(&self) -> u64 {
        self.ignored
    }

    /// Bytes given up while looking for whole events.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    /// Applies an event to the state; false when it was ignored.
    fn apply(&mut self, ev: &JsEvent, cx: &mut Cx<'_>) -> bool {
        let n = usize::from(ev.number);
        let (limit, what) = match ev.kind {
            Kind::Axis => (MAX_AXES, "axis"),
            Kind::Button => (MAX_BUTTONS, "button"),
        };
        if n >= limit {
            self.ignored += 1;
            if self.ignored == 1 {
                cx.say(
                    TextSeverity::Warning,
                    format_args!(
                        "joystick {what} {n} is beyond the {limit} a VRPN device carries: \
                         ignored (said once)"
                    ),
                );
            }
            return false;
        }
        match ev.kind {
            Kind::Axis => {
                if n >= self.analog.num_channels() {
                    self.analog.set_num_channels(n + 1);
                }
                self.analog.set_channel(n, f64::from(ev.value) / 32767.0);
            }
            Kind::Button => {
                if n >= self.buttons.num_buttons() {
                    self.buttons.set_num_buttons(n + 1);
                }
                self.buttons.set_button(n, ev.value != 0);
            }
        }
        self.events += 1;
        true
    }

    /// Sends what changed, stamped `at`.
    fn report(&mut self, at: Now) {
        // A failed send is the connection's business (it reports and drops the peer).
        let _ = self.analog.report_changes(Some(at.wall));
        self.buttons.set_timestamp(at.wall);
        let _ = self.buttons.report_changes();
    }
}

impl Protocol for JoylinProtocol {
    const KIND: &'static str = "vrpn_Joylin";

    fn port_kind(&self) -> PortKind {
        PortKind::InputDevice
    }

    /// An untouched joystick is silent, and that is not a fault: no watchdog.
    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    /// No reset: the device sends its initial state as soon as it opens.
    fn start_reset(&mut self, _cx: &mut Cx<'_>) -> Reset {
        Reset::Done
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        self.received(bytes, cx);
        Reset::Done
    }

    fn reset_poll(&mut self, _cx: &mut Cx<'_>) -> Reset {
        Reset::Done
    }

    fn reset_deadline(&self) -> Option<Instant> {
        None
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        let arrived = cx.now;
        let mut init_at = arrived;
        for &b in bytes {
            let (axes, buttons) = (self.analog.num_channels(), self.buttons.num_buttons());
            let known = self.counts_known;
            let plausible = |e: &JsEvent| {
                let n = usize::from(e.number);
                e.init
                    || !known
                    || match e.kind {
                        Kind::Axis => n < axes,
                        Kind::Button => n < buttons,
                    }
            };
            let Some((ev, at)) = self.framer.push(b, arrived, plausible) else {
                continue;
            };
            self.counts_known |= ev.init;
            if !self.apply(&ev, cx) {
                continue;
            }
            cx.record(at);
            if ev.init {
                if !self.init_pending {
                    init_at = at;
                }
                self.init_pending = true;
            } else {
                self.init_pending = false;
                self.report(at);
            }
        }
        if std::mem::take(&mut self.init_pending) {
            self.report(init_at);
        }
    }

    fn stopped(&mut self) {
        self.framer.clear();
        self.init_pending = false;
    }

    /// C++'s text when the device fails.
    fn lost(&mut self, cx: &mut Cx<'_>) {
        cx.say(TextSeverity::Error, format_args!("{READ_ERROR}"));
    }
}
