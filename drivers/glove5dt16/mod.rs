//! 5DT Data Glove 16 on a serial line (C++ `vrpn_5dt16`): its `vrpn.cfg` line ([`config`]),
//! its [`Protocol`], and a device simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_5dt16 NAME PORT BAUD
//! ```
//!
//! The line is 8N1 at `BAUD` (19200 for the glove). The glove streams by itself; nothing is
//! ever written to it.
//!
//! # Reset
//!
//! The glove is listened to until its first packet, at most [`LISTEN_TIME`]. C++ waits for an
//! information packet (`<I`) only; here a data packet proves as well that the glove is there
//! at the right speed, so start-up takes one packet time. Information packets, whenever they
//! come, are announced in texts (hardware version, hand, wired or wireless), as C++ announces
//! the one its reset reads.
//!
//! # What is sent
//!
//! An Analog with seventeen channels: channels 0–15 the sixteen sensors' raw values
//! ([`packet::channels`]), channel 16 always 0 (as C++). One `vrpn_Analog Channel` message per
//! data packet if a channel changed, stamped with the arrival of the packet's first byte.
//!
//! # Supervision
//!
//! More than 2 s without a packet sends two error texts and the driver listens again (the
//! reset). Packets are found byte by byte ([`packet`]); skipped bytes are reported at most once
//! a second. A port that fails is reopened every second.
//!
//! # Differences from C++ VRPN
//!
//! * The reset ends at the first packet of either kind, without C++'s 0.1 s sleeps; it never
//!   blocks the server.
//! * An information packet among the data costs nothing (C++ shifts its buffer by seven bytes
//!   and hopes), and garbage costs only itself.
//! * A reset does not zero the channels (a reset never invents data).

pub mod config;
pub mod packet;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::packet::{Framer, Kind, Packet, CHANNELS};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::{AnalogServer, Connection, Error};

pub use self::config::Glove5dt16;

/// The registry entry: `vrpn_5dt16`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_5dt16"],
    parse: config::parse,
    hints: &[],
};

/// How long the reset listens for a first packet.
pub const LISTEN_TIME: Duration = Duration::from_secs(2);

/// The glove's protocol. See the module documentation.
pub struct Glove16Protocol {
    baud: u32,
    analog: AnalogServer,
    framer: Framer,
    deadline: Option<Instant>,
    /// The information last announced (since the last reset).
    announced: Option<[u8; 5]>,
}

impl Glove16Protocol {
    /// The protocol of a `vrpn_5dt16` entry, with its Analog on `conn`.
    pub fn new(cfg: &Glove5dt16, conn: &Connection) -> Result<Glove16Protocol, Error> {
        Ok(Glove16Protocol {
            baud: cfg.baud,
            analog: AnalogServer::new(&cfg.name, conn, CHANNELS)?,
            framer: Framer::new(),
            deadline: None,
            announced: None,
        })
    }

    /// Bytes skipped looking for packets, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    fn handle(&mut self, p: &Packet, cx: &mut Cx<'_>) {
        cx.record(p.first_byte);
        let b = p.bytes();
        match p.kind {
            Kind::Data => {
                self.analog
                    .channels_mut()
                    .copy_from_slice(&packet::channels(b));
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.analog.report_changes(Some(p.first_byte.wall));
            }
            Kind::Info => {
                let info = [b[2], b[3], b[4], b[5], b[6]];
                if self.announced == Some(info) {
                    return;
                }
                self.announced = Some(info);
                cx.say(
                    TextSeverity::Normal,
                    format_args!("Hardware Version {}.0{}", info[0], info[1]),
                );
                let hand = if info[2] & 1 != 0 { "right" } else { "left" };
                cx.say(
                    TextSeverity::Normal,
                    format_args!("A {hand} glove is ready"),
                );
                let link = if info[3] & 1 != 0 {
                    "no wireless glove"
                } else {
                    "wireless glove"
                };
                cx.say(TextSeverity::Normal, format_args!("{link}"));
            }
        }
    }

    fn take(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> usize {
        let mut n = 0;
        for &b in bytes {
            if let Some(p) = self.framer.push(b, cx.now) {
                let skipped = self.framer.take_skipped();
                cx.skipped(skipped, "5DT glove 16", format_args!(""));
                self.handle(&p, cx);
                n += 1;
            }
        }
        n
    }
}

impl Protocol for Glove16Protocol {
    const KIND: &'static str = "5DT glove 16";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        Supervision {
            on_silence: Recovery::Reset,
            ..Supervision::TRACKER
        }
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        // What waited in the port's buffer was sent before now: it cannot be stamped.
        cx.flush_input();
        self.framer.clear();
        self.announced = None;
        self.deadline = Some(cx.now.mono + LISTEN_TIME);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        if self.take(bytes, cx) == 0 {
            return Reset::Working;
        }
        self.deadline = None;
        Reset::Done
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.deadline = None;
        cx.say(
            TextSeverity::Error,
            format_args!("vrpn_5dt16: Timeout during reset (no packet from the glove)"),
        );
        Reset::Failed(Retry::Now)
    }

    fn reset_deadline(&self) -> Option<Instant> {
        self.deadline
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.take(bytes, cx);
    }

    fn stopped(&mut self) {
        self.framer.clear();
        self.deadline = None;
    }
}
