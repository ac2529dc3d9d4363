//! A.R.T. DTrack / DTrack2 / DTRACK3 optical tracking, received as ASCII UDP frames from the
//! controller: its `vrpn.cfg` line ([`config`]), the frame parser ([`frame`], [`numbers`]),
//! the conversion to VRPN reports ([`report`]), the device in the server's reactor, and a
//! controller simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_Tracker_DTrack NAME CONNECTION [TIME_TO_REACH_JOY [BODIES FLYSTICKS [IDS...]]] [3d] [-]
//! ```
//!
//! `CONNECTION` is `PORT` (frames sent to this UDP port), `GROUP:PORT` (a multicast group,
//! joined on the default interface and on loopback) or `HOST:PORT:fw` (the controller at
//! `HOST` is sent `fw4vrpndt` at its port 50107 from `PORT`, so that a stateful firewall lets
//! its frames in; repeated every 5 s while no frame arrives). See docs/DRIVERS.md.
//!
//! # What is sent
//!
//! Under `NAME`: a tracker (bodies as sensors 0.., then Flysticks, then `3d` markers), a
//! button (8 per Flystick) and an analog (2 per Flystick), as C++ VRPN numbers them. Each
//! frame's reports carry its time stamp computed as C++ does ([`report::report_time`]).
//!
//! # Supervision
//!
//! A datagram that does not parse, is too long, or repeats or precedes (by up to 64 frames)
//! the last frame's counter is counted and skipped whole; a warning text says how many, at
//! most once a second.

pub mod config;
pub mod frame;
pub mod numbers;
pub mod report;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use self::config::DTrack;
use self::frame::{Header, Malformed, Targets};
use self::report::{Reporter, MAX_SENSORS};
use crate::config::ConfigLine;
use crate::devices::analog::AnalogServer;
use crate::devices::button::ButtonServer;
use crate::devices::text::TextSeverity;
use crate::devices::tracker::TrackerServer;
use crate::devices::ServerDevice;
use crate::driver::registry::{DeviceSpec, Driver};
use crate::driver::text::with_text;
use crate::driver::udp::{Datagram, UdpSource};
use crate::error::Error;
use crate::time::Now;
use crate::Connection;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_Tracker_DTrack"],
    parse: parse_line,
    hints: &[],
};

fn parse_line(
    line: &mut ConfigLine<'_, '_>,
) -> Result<Box<dyn DeviceSpec>, crate::config::ConfigError> {
    config::parse(line)
}

/// Receive buffer: C++'s 20000 bytes; a datagram that fills it is too long.
pub const DATAGRAM_MAX: usize = 20_000;
/// A frame whose counter is at most this many frames behind the last one is late (skipped);
/// further back, the controller is taken to have restarted its count.
pub const REORDER_WINDOW: u32 = 64;
/// How often skipped datagrams are reported.
const WARNING_INTERVAL: Duration = Duration::from_secs(1);
/// How often the firewall message is repeated while no frame arrives.
const FIREWALL_REPEAT: Duration = Duration::from_secs(5);
/// The stateful-firewall message (with its terminating NUL, as C++ sends it).
pub const FIREWALL_MESSAGE: &[u8] = b"fw4vrpndt\0";

/// Counts kept by the device.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DTrackStats {
    /// Frames reported.
    pub frames: u64,
    /// Datagrams that did not parse (or were empty).
    pub malformed: u64,
    /// Datagrams longer than the receive buffer.
    pub too_long: u64,
    /// Frames skipped for a counter not after the last one.
    pub out_of_order: u64,
}

/// Everything a datagram changes (apart from the socket, so both can be borrowed at once).
struct Stream {
    name: String,
    tracker: TrackerServer,
    button: ButtonServer,
    analog: AnalogServer,
    targets: Targets,
    scratch: Targets,
    reporter: Reporter,
    last_frame: Option<u32>,
    stats: DTrackStats,
    tracing: bool,
    /// Skipped since the last warning, and the last reason.
    unreported: u64,
    last_problem: &'static str,
    last_warning: Option<Instant>,
    last_datagram: Option<Instant>,
}

/// The running device: the UDP socket in the server's reactor and the stream it feeds.
pub struct DTrackDevice {
    source: UdpSource,
    buf: Box<[u8]>,
    stream: Stream,
    firewall: Option<SocketAddr>,
    firewall_at: Option<Instant>,
}

impl DTrackDevice {
    /// Binds the configured port on `conn`'s reactor and serves `NAME` on `conn`.
    pub fn new(cfg: &DTrack, conn: &Connection) -> Result<DTrackDevice, Error> {
        let group = match cfg.source {
            config::Source::Multicast(g, _) => Some(g),
            _ => None,
        };
        let firewall = cfg.firewall_target()?;
        let reactor = conn.reactor();
        let source = UdpSource::bind(cfg.source.port(), group, reactor.as_ref()).map_err(|e| {
            Error::io(
                format!("DTrack {}: UDP port {}", cfg.name, cfg.source.port()),
                e,
            )
        })?;
        let mut analog = AnalogServer::new(&cfg.name, conn, 0)?;
        analog.set_num_channels(0);
        Ok(DTrackDevice {
            source,
            buf: vec![0u8; DATAGRAM_MAX].into_boxed_slice(),
            stream: Stream {
                name: cfg.name.clone(),
                tracker: TrackerServer::new(&cfg.name, conn, MAX_SENSORS)?,
                button: ButtonServer::new(&cfg.name, conn, 0)?,
                analog,
                targets: Targets::default(),
                scratch: Targets::default(),
                reporter: Reporter::new(cfg.fixed.clone(), cfg.markers, cfg.time_to_reach_joy),
                last_frame: None,
                stats: DTrackStats::default(),
                tracing: cfg.tracing,
                unreported: 0,
                last_problem: "",
                last_warning: None,
                last_datagram: None,
            },
            firewall,
            firewall_at: None,
        })
    }

    /// The local UDP port (the configured one, or the one chosen for port 0 in tests).
    pub fn local_port(&self) -> u16 {
        self.source.local_port()
    }

    /// What was received so far.
    pub fn stats(&self) -> DTrackStats {
        self.stream.stats
    }
}

impl Stream {
    fn text(&self, severity: TextSeverity, args: std::fmt::Arguments<'_>) {
        send_text(&self.tracker, severity, args);
    }

    fn skipped(&mut self, problem: &'static str, now: Instant) {
        self.unreported += 1;
        self.last_problem = problem;
        self.warn_due(now);
    }

    fn warn_due(&mut self, now: Instant) {
        if self.unreported == 0 {
            return;
        }
        if self
            .last_warning
            .is_some_and(|t| now.duration_since(t) < WARNING_INTERVAL)
        {
            return;
        }
        self.last_warning = Some(now);
        let (n, problem) = (self.unreported, self.last_problem);
        self.unreported = 0;
        self.text(
            TextSeverity::Warning,
            format_args!(
                "vrpn_Tracker_DTrack {}: skipped {n} datagram(s) ({problem})",
                self.name
            ),
        );
    }

    fn datagram(&mut self, d: Datagram<'_>) {
        let mono = d.arrived.mono;
        self.last_datagram = Some(mono);
        if d.too_long {
            self.stats.too_long += 1;
            return self.skipped("longer than 20000 bytes", mono);
        }
        self.scratch.copy_from(&self.targets);
        let h = match frame::parse(d.bytes, &mut self.scratch) {
            Ok(h) => h,
            Err(m) => {
                self.stats.malformed += 1;
                return self.skipped(malformed_text(m), mono);
            }
        };
        if let (Some(n), Some(last)) = (h.frame, self.last_frame) {
            if last.wrapping_sub(n) <= REORDER_WINDOW {
                self.stats.out_of_order += 1;
                return self.skipped("frame counter not after the last frame's", mono);
            }
        }
        self.last_frame = h.frame;
        std::mem::swap(&mut self.targets, &mut self.scratch);
        self.stats.frames += 1;
        self.report(&h, d.arrived);
    }

    fn report(&mut self, h: &Header, arrived: Now) {
        if self.reporter.take_no_bodycal_warning(h) {
            self.text(
                TextSeverity::Warning,
                format_args!(
                    "vrpn_Tracker_DTrack {}: no DTrack '6dcal' data available (targets are \
                     numbered as they appear)",
                    self.name
                ),
            );
        }
        let out = self.reporter.frame(h, &self.targets, arrived.wall);
        for p in &out.poses {
            let _ = self.tracker.report_pose(p.sensor, out.time, p.pos, p.quat);
        }
        self.analog.set_num_channels(out.num_channels);
        self.analog
            .channels_mut()
            .copy_from_slice(&out.channels[..out.num_channels]);
        let _ = self.analog.report_changes(Some(out.time));
        self.button.set_num_buttons(out.num_buttons);
        for (i, &b) in out.buttons[..out.num_buttons].iter().enumerate() {
            self.button.set_button(i, b);
        }
        self.button.set_timestamp(out.time);
        let _ = self.button.report_changes();
        if self.tracing && self.stats.frames % 10 == 0 {
            let (time, poses, beyond) = (out.time, out.poses.len(), out.beyond);
            send_text(
                &self.tracker,
                TextSeverity::Normal,
                format_args!(
                    "frame {} at {}.{:06}: {poses} poses, {} buttons, {} channels, {beyond} \
                     targets beyond VRPN's numbering",
                    h.frame.unwrap_or(0),
                    time.sec,
                    time.usec,
                    out.num_buttons,
                    out.num_channels,
                ),
            );
        }
    }
}

/// A text message from the device, formatted on the stack.
fn send_text(tracker: &TrackerServer, severity: TextSeverity, args: std::fmt::Arguments<'_>) {
    with_text(args, |t| {
        let _ = tracker.send_text(severity, 0, t);
    });
}

fn malformed_text(m: Malformed) -> &'static str {
    match m {
        Malformed::Frame => "a bad 'fr' line",
        Malformed::Timestamp => "a bad 'ts' or 'ts2' line",
        Malformed::Calibrated => "a bad '6dcal' line",
        Malformed::Bodies => "a bad '6d' line",
        Malformed::Flysticks => "a bad '6df' or '6df2' line",
        Malformed::Tools => "a bad '6dmt' line",
        Malformed::Markers => "a bad '3d' line",
        Malformed::TooMany => "an id or count above 255",
        Malformed::Empty => "an empty datagram",
        Malformed::NoDTrackLine => "no DTrack line in it",
    }
}

impl ServerDevice for DTrackDevice {
    fn name(&self) -> &str {
        &self.stream.name
    }

    fn mainloop(&mut self, now: Now) {
        if let Some(to) = self.firewall {
            if self.firewall_at.map_or(true, |t| now.mono >= t) {
                match self.stream.last_datagram {
                    // Frames are coming: look again when they would have been silent long.
                    Some(t) if now.mono.duration_since(t) < FIREWALL_REPEAT => {
                        self.firewall_at = Some(t + FIREWALL_REPEAT);
                    }
                    _ => {
                        let _ = self.source.send_to(FIREWALL_MESSAGE, to);
                        self.firewall_at = Some(now.mono + FIREWALL_REPEAT);
                    }
                }
            }
        }
        let stream = &mut self.stream;
        if let Err(e) = self
            .source
            .drain(&mut self.buf, now, |d| stream.datagram(d))
        {
            stream.text(
                TextSeverity::Error,
                format_args!("vrpn_Tracker_DTrack {}: receive error: {e}", stream.name),
            );
        }
        stream.warn_due(now.mono);
    }

    fn next_deadline(&self) -> Option<Instant> {
        let warning = (self.stream.unreported > 0)
            .then(|| self.stream.last_warning.map(|t| t + WARNING_INTERVAL))
            .flatten();
        warning.into_iter().chain(self.firewall_at).min()
    }
}
