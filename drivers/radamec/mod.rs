//! The Radamec Serial Position Interface (a camera-tracking head for virtual sets) on a
//! serial line: its `vrpn.cfg` line ([`config`]), its blocks ([`record`]), its [`Protocol`]
//! run by the shared [`Lifecycle`](crate::driver::Lifecycle), and a device simulator
//! (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Radamec_SPI NAME PORT BAUD
//! ```
//!
//! The line is 8 data bits, **odd parity**, 1 stop bit at `BAUD` (38400 is the only rate the
//! device supports in normal operation).
//!
//! # What is sent
//!
//! `NAME` is an Analog. Each data block sends one `vrpn_Analog Channel` message (LOW_LATENCY,
//! whether or not a value changed: the device is absolute), stamped with the arrival of the
//! block's first byte: channels 0 pan and 1 tilt in degrees, 2 zoom, 3 focus (raw counts), and
//! with the longer blocks 4 height (raw), 5 X and 6 Y in metres, 7 orientation in degrees (see
//! [`record`]). A client turns them into poses with a `vrpn_Tracker_AnalogFly`.
//!
//! # Reset and supervision
//!
//! The reset writes C++'s two commands, "which camera?" to every camera and "stream mode" to
//! the camera last heard from (0xFF before any), and is done: the device does not answer
//! them (it streams regardless), and its echoes, if any, are ignored; the warning text
//! `reset complete (this is good)` says so, as in C++. More than 2 s without a
//! block sends C++'s `Timeout... current_time=…, timestamp=…` (error) and resets it on the
//! open port. Blocks are found byte by byte with their check byte; a wrong one costs the
//! candidate's first byte only, and dropped bytes are reported once a second. A block of a
//! type the driver never asks for (0xA3, 0xA5) sends C++'s error text `vrpn_Radamec_SPI:
//! Unhandled command (0xNN), resetting` and resets the device. A port that fails is reopened
//! by the serial layer.
//!
//! # Differences from C++ VRPN
//!
//! * C++ always sends four channels (it never updates its channel count), so the height, X,
//!   Y and orientation of the longer blocks never reach a client; here a report has as many
//!   channels as its block has values (4, 5 or 8).
//! * A wrong check byte costs one byte, not the whole candidate: the block after a stray type
//!   byte is kept.
//! * Reports carry the first byte's arrival (C++ reads the clock when it sees the first byte,
//!   possibly a pass later).

pub mod config;
pub mod record;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::time::{Duration, Instant};

use self::record::{channels, command, Framed, Framer, ASK_CAMERA, COMMAND, MAX_CHANNELS, STREAM};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Protocol, Recovery, Reset, Supervision};
use crate::serial::{Parity, PortKind, PortSettings};
use crate::time::Now;
use crate::{AnalogServer, Connection, Error};

pub use self::config::Radamec;

/// The registry entry: `vrpn_Radamec_SPI`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Radamec_SPI"],
    parse: config::parse,
    hints: &[],
};

/// Longest silence before the device is reset (C++'s 2 s).
pub const WATCHDOG: Duration = Duration::from_secs(2);

/// The Radamec SPI's protocol. See the module documentation.
pub struct RadamecProtocol {
    baud: u32,
    analog: AnalogServer,
    framer: Framer,
    camera: u8,
}

impl RadamecProtocol {
    /// The protocol of a `vrpn_Radamec_SPI` entry, with its Analog on `conn`.
    pub fn new(cfg: &Radamec, conn: &Connection) -> Result<RadamecProtocol, Error> {
        let mut analog = AnalogServer::new(&cfg.name, conn, MAX_CHANNELS)?;
        // Four until a block says otherwise (C++'s count).
        analog.set_num_channels(4);
        Ok(RadamecProtocol {
            baud: cfg.baud,
            analog,
            framer: Framer::new(),
            camera: 0xFF,
        })
    }

    /// The analog server.
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }

    /// The camera id last heard (0xFF before any block).
    pub fn camera(&self) -> u8 {
        self.camera
    }

    /// Bytes skipped while looking for blocks, since construction.
    pub fn skipped_bytes(&self) -> u64 {
        self.framer.total_skipped()
    }

    /// Reports one block; false when it asks for a reset.
    fn block(&mut self, f: &Framed, cx: &mut Cx<'_>) -> bool {
        if f.skipped > 0 {
            let bad = f.bad_checks;
            cx.skipped(
                u64::from(f.skipped),
                "vrpn_Radamec_SPI",
                format_args!(" ({bad} with a bad check byte)"),
            );
        }
        let block = f.block();
        self.camera = block[1];
        cx.record(f.first_byte);
        match channels(block) {
            Some((values, n)) => {
                self.analog.set_num_channels(n);
                self.analog.channels_mut().copy_from_slice(&values[..n]);
                // A failed send is the connection's business (it reports and drops the peer).
                let _ = self.analog.report(Some(f.first_byte.wall));
                true
            }
            // Echoes of our commands.
            None if block[0] == COMMAND => true,
            None => {
                cx.say(
                    TextSeverity::Error,
                    format_args!(
                        "vrpn_Radamec_SPI: Unhandled command (0x{:02x}), resetting",
                        block[0]
                    ),
                );
                cx.reset();
                false
            }
        }
    }
}

impl Protocol for RadamecProtocol {
    const KIND: &'static str = "vrpn_Radamec_SPI";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings {
            baud: self.baud,
            data_bits: 8,
            parity: Parity::Odd,
            stop_bits: 1,
            rts_cts: false,
        })
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
        cx.write(&ASK_CAMERA);
        cx.write(&command(self.camera, STREAM));
        cx.say(
            TextSeverity::Warning,
            format_args!("reset complete (this is good)"),
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
        let mut go_on = true;
        for &b in bytes {
            let mut found = [None; 8];
            let mut n = 0;
            self.framer.push(b, cx.now, |f| {
                if n < found.len() {
                    found[n] = Some(f);
                    n += 1;
                }
            });
            for f in found.iter().flatten() {
                go_on = go_on && self.block(f, cx);
            }
            if !go_on {
                // The rest of the read comes before the reset's flush.
                return;
            }
        }
    }

    fn stopped(&mut self) {
        self.framer.clear();
    }

    fn silent(&mut self, last_record: Now, cx: &mut Cx<'_>) {
        let (cur, ts) = (cx.now.wall, last_record.wall);
        cx.say(
            TextSeverity::Error,
            format_args!(
                "Timeout... current_time={}:{}, timestamp={}:{}",
                cur.sec, cur.usec, ts.sec, ts.usec
            ),
        );
    }
}
