//! The Wanda (Brown University's wand with a joystick ball and three buttons) on a serial
//! line: its `vrpn.cfg` line ([`config`]), its records ([`record`]), its [`Protocol`] run by
//! the shared [`Lifecycle`](crate::driver::Lifecycle), and a device simulator (`sim`, with
//! the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Wanda NAME PORT BAUD MIN_UPDATE_RATE
//! ```
//!
//! The line is 7 data bits, no parity, 1 stop bit at `BAUD` (the Wanda runs at 1200).
//! `MIN_UPDATE_RATE` is read and, as in C++, not used.
//!
//! # What is sent
//!
//! `NAME` is an Analog with two channels and a Button with three buttons (0 blue, 1 yellow,
//! 2 red). For each record, stamped with the arrival of its first byte: one `vrpn_Button
//! Change` per changed blue or red button, then a `vrpn_Analog Channel` message if a channel
//! changed (channel 0 = −X / 34, channel 1 = Y / 34, each clamped to −1..1). The optional
//! fourth byte of a record sends a `vrpn_Button Change` for the yellow button if it changed.
//! Toggle modes a client asks for are kept but not applied, as in C++.
//!
//! The Wanda sends records only while the ball is pushed or a button changes; when no record
//! has come for [`CENTRE_AFTER`] while a channel is not zero, both channels are set to zero
//! and reported (C++'s rule for "the ball was let go"), stamped with that moment.
//!
//! # Supervision
//!
//! There is no reset: opening the port flushes what the line held before, and the first two
//! bytes, if they are `M3` (what a Wanda sends when it powers up), are taken for the init
//! message and announced. Silence is normal (nobody is touching it), so there is no
//! watchdog. A port that fails is reopened by the serial layer.
//!
//! # Differences from C++ VRPN
//!
//! * Reports carry the arrival time of their record's first byte. (C++ never sets its
//!   timestamps, so its reports carry the time the server started.)
//! * The channels are centred [`CENTRE_AFTER`] after the last *record*; C++ counts from the
//!   last *changed* value, so a ball held still in one position flickers to zero.
//! * The first two bytes are skipped only if they are `M3`; C++ skips any two.
//! * Bytes with bit 7 set (impossible on a seven-bit line) and broken records are skipped and
//!   reported once a second; nothing is printed on the server's standard error.

pub mod config;
pub mod record;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::record::{blue_red, channels, Found, Framer, BUTTONS, CHANNELS, INIT_MESSAGE};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Reset, Supervision};
use crate::serial::{Parity, PortKind, PortSettings};
use crate::time::{Now, TimeVal};
use crate::{AnalogServer, ButtonServer, Connection, Error};

pub use self::config::Wanda;

/// The registry entry: `vrpn_Wanda`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Wanda"],
    parse: config::parse,
    hints: &[],
};

/// Time without a record after which the channels are set back to zero (C++'s 0.2 s).
pub const CENTRE_AFTER: Duration = Duration::from_millis(200);

/// The init message at the start of the stream: not looked for yet, its first byte seen, or
/// done with.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Init {
    Waiting,
    GotM(Now),
    Done,
}

/// The Wanda's protocol. See the module documentation.
pub struct WandaProtocol {
    baud: u32,
    analog: AnalogServer,
    buttons: ButtonServer,
    framer: Framer,
    init: Init,
    centre_at: Option<Instant>,
    init_messages: u64,
}

impl WandaProtocol {
    /// The protocol of a `vrpn_Wanda` entry, with its servers on `conn`.
    pub fn new(cfg: &Wanda, conn: &Connection) -> Result<WandaProtocol, Error> {
        Ok(WandaProtocol {
            baud: cfg.baud,
            analog: AnalogServer::new(&cfg.name, conn, CHANNELS)?,
            buttons: ButtonServer::new(&cfg.name, conn, BUTTONS)?,
            framer: Framer::new(),
            init: Init::Waiting,
            centre_at: None,
            init_messages: 0,
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

    /// Init messages (`M3`) seen since construction.
    pub fn init_messages(&self) -> u64 {
        self.init_messages
    }

    fn push(&mut self, b: u8, at: Now, cx: &mut Cx<'_>) {
        match self.framer.push(b, at) {
            None => {}
            Some(Found::Record {
                bytes,
                first_byte,
                skipped,
            }) => {
                cx.skipped(u64::from(skipped), "Wanda", format_args!(""));
                cx.record(first_byte);
                let (blue, red) = blue_red(bytes);
                self.buttons.set_button(0, blue);
                self.buttons.set_button(2, red);
                let values = channels(bytes);
                for (i, v) in values.into_iter().enumerate() {
                    self.analog.set_channel(i, v);
                }
                self.send(first_byte.wall);
                self.centre_at = values
                    .iter()
                    .any(|&v| v != 0.0)
                    .then(|| first_byte.mono + CENTRE_AFTER);
            }
            Some(Found::Yellow {
                pressed,
                first_byte,
            }) => {
                self.buttons.set_button(1, pressed);
                self.send(first_byte.wall);
            }
        }
    }

    fn send(&mut self, time: TimeVal) {
        // A failed send is the connection's business (it reports and drops the peer).
        self.buttons.set_timestamp(time);
        let _ = self.buttons.report_changes_unfiltered();
        let _ = self.analog.report_changes(Some(time));
    }
}

impl Protocol for WandaProtocol {
    const KIND: &'static str = "Wanda";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings {
            baud: self.baud,
            data_bits: 7,
            parity: Parity::None,
            stop_bits: 1,
            rts_cts: false,
        })
    }

    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        // What the line held before it was opened is stale.
        cx.flush_input();
        self.init = Init::Waiting;
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
        let at = cx.now;
        for &b in bytes {
            match self.init {
                Init::Done => self.push(b, at, cx),
                Init::Waiting if b == INIT_MESSAGE[0] => self.init = Init::GotM(at),
                Init::Waiting => {
                    self.init = Init::Done;
                    self.push(b, at, cx);
                }
                Init::GotM(m_at) => {
                    self.init = Init::Done;
                    if b == INIT_MESSAGE[1] {
                        self.init_messages += 1;
                        cx.say(
                            TextSeverity::Normal,
                            format_args!("Wanda: read the init message (M3)"),
                        );
                    } else {
                        self.push(INIT_MESSAGE[0], m_at, cx);
                        self.push(b, at, cx);
                    }
                }
            }
        }
    }

    fn deadline(&self) -> Option<Instant> {
        self.centre_at
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        if self.centre_at.is_some_and(|t| cx.now.mono >= t) {
            self.centre_at = None;
            self.analog.channels_mut().fill(0.0);
            let _ = self.analog.report_changes(Some(cx.now.wall));
        }
    }

    fn stopped(&mut self) {
        self.framer.clear();
        self.centre_at = None;
        self.init = Init::Waiting;
    }
}
