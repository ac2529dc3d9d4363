//! The wireless dongle's protocol: every unit on it, one reset, records released on request.
//!
//! The reset: the dongle is put in manual-flush mode (`F7 B0 00`: records wait in it until
//! asked for) and every unit is told to stop streaming; [`SETTLE`] later the input is
//! flushed and each unit, in the order of its lines, gets its start-up commands (once after
//! the port opens) and the reset's commands one at a time, each answered by the dongle
//! (`00 id len` and data; a failure is `status id`; an ASCII command a line starting `0`).
//! A unit whose command fails or goes unanswered is said to be so (C++'s texts) and left
//! out; the others go on. The reset is done once every unit has been tried and one at least
//! streams (none: the reset is tried again). From then on, every [`poll_every`] the driver
//! asks the dongle to release one record of each streaming unit (`F7 B4 id`); each record
//! released is reported and that unit asked again at once, as C++ does, until the dongle has
//! none. A unit without a record for [`TIMEOUT`] (one left out, or one switched off) resets
//! the dongle, which tries it again; the records the others made meanwhile wait in the
//! dongle and are released after the reset.

use std::time::{Duration, Instant};

use super::command::{
    reset_steps, setup_steps, wired, wireless, Answer, Step, FLUSH_ONE, SET_WIRELESS_MODE,
    START_STREAMING, STOP_STREAMING,
};
use super::config::{Unit, YeiWireless};
use super::dongle::Framer;
use super::{say_timeout, supervision, UnitServers, ANSWER_WAIT, SETTLE, TIMEOUT};
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{Connection, Error};

/// The wait for the header of the dongle's answer to a command (C++'s); the data of an
/// answer that has some, once its header came, is given [`ANSWER_WAIT`].
pub const ACK_WAIT: Duration = Duration::from_millis(500);

/// Longest answer kept while waiting for its end (C++ reads at most 255 bytes).
const REPLY_MAX: usize = 256;

/// How often the dongle is asked for records when it had none: a quarter of the fastest
/// unit's interval, within 2–20 ms.
pub fn poll_every(units: &[Unit]) -> Duration {
    let fastest = units
        .iter()
        .map(|u| super::command::interval_us(u.frames_per_second))
        .min()
        .unwrap_or(0);
    Duration::from_micros(u64::from(fastest) / 4)
        .clamp(Duration::from_millis(2), Duration::from_millis(20))
}

struct WirelessUnit {
    id: u8,
    setup: Vec<Step>,
    reset: Vec<Step>,
    /// `F7 B4 id sum`: release one of its records.
    flush: [u8; 4],
    servers: UnitServers,
    /// Told to stream at the last reset.
    streaming: bool,
    /// Its last record's first byte (or the end of the reset).
    last: Option<Instant>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Idle,
    Settling(Instant),
    Command(Instant),
}

/// The dongle's protocol. See the module documentation.
pub struct WirelessProtocol {
    baud: u32,
    units: Vec<WirelessUnit>,
    setup_due: bool,
    phase: Phase,
    /// The reset's commands: unit index and step.
    queue: Vec<(usize, Step)>,
    next: usize,
    reply: Vec<u8>,
    out: Vec<u8>,
    framer: Framer,
    poll_all: Vec<u8>,
    poll_at: Option<Instant>,
    poll_every: Duration,
}

impl WirelessProtocol {
    /// The protocol of an entry, with every unit's servers on `conn`.
    pub fn new(cfg: &YeiWireless, conn: &Connection) -> Result<WirelessProtocol, Error> {
        let mut units = Vec::new();
        for u in &cfg.units {
            let mut flush = Vec::new();
            wired(&[FLUSH_ONE, u.logical_id], &mut flush);
            units.push(WirelessUnit {
                id: u.logical_id,
                setup: setup_steps(u),
                reset: reset_steps(u),
                flush: [flush[0], flush[1], flush[2], flush[3]],
                servers: UnitServers::new(&u.name, conn)?,
                streaming: false,
                last: None,
            });
        }
        Ok(WirelessProtocol {
            baud: cfg.baud,
            framer: Framer::new(cfg.units.iter().map(|u| u.logical_id)),
            poll_all: Vec::with_capacity(4 * units.len()),
            units,
            setup_due: true,
            phase: Phase::Idle,
            queue: Vec::new(),
            next: 0,
            reply: Vec::with_capacity(REPLY_MAX),
            out: Vec::with_capacity(256),
            poll_at: None,
            poll_every: poll_every(&cfg.units),
        })
    }

    /// The logical ids of the units streaming now.
    pub fn streaming_ids(&self) -> impl Iterator<Item = u8> + '_ {
        self.units.iter().filter(|u| u.streaming).map(|u| u.id)
    }

    fn send_next(&mut self, cx: &mut Cx<'_>) {
        let (u, step) = &self.queue[self.next];
        self.out.clear();
        step.wireless(self.units[*u].id, &mut self.out);
        cx.write(&self.out);
        self.reply.clear();
        self.phase = Phase::Command(cx.now.mono + ACK_WAIT);
    }

    /// Whether the reply holds the whole answer to the current command: `Some(Ok(used))`
    /// with the bytes it took, `Some(Err(..))` for a failure, `None` to wait for more.
    fn answer(&self) -> Option<Result<usize, String>> {
        let (u, step) = &self.queue[self.next];
        let id = self.units[*u].id;
        let r = &self.reply;
        match step.answer() {
            Answer::Line => {
                let end = r.iter().position(|&b| b == b'\n')?;
                if r[0] == b'0' {
                    Some(Ok(end + 1))
                } else {
                    let text = String::from_utf8_lossy(&r[..end]).trim_end().to_owned();
                    Some(Err(format!(
                        "vrpn_YEI_3Space_Sensor_Wireless::send_ascii_command: Command failed: \
                         response ({text})"
                    )))
                }
            }
            Answer::Data(n) => {
                if r.len() >= 2 && r[0] != 0 {
                    return Some(Err(format!(
                        "vrpn_YEI_3Space_Sensor_Wireless::send_binary_command: Error ({}) from \
                         ID {}",
                        r[0], r[1]
                    )));
                }
                if r.len() < 3 + n {
                    return None;
                }
                if r[1] != id || usize::from(r[2]) != n {
                    return Some(Err(format!(
                        "vrpn_YEI_3Space_Sensor_Wireless::send_binary_command: Got a response \
                         for ID {} of {} bytes where ID {id} and {n} were due",
                        r[1], r[2]
                    )));
                }
                Some(Ok(3 + n))
            }
        }
    }

    /// The unit of the current command failed: say why, leave it out, go on with the next
    /// unit (or end the reset).
    fn unit_failed(&mut self, why: &str, cx: &mut Cx<'_>) -> Reset {
        let u = self.queue[self.next].0;
        cx.say(TextSeverity::Error, format_args!("{why}"));
        cx.say(
            TextSeverity::Error,
            format_args!(
                "vrpn_YEI_3Space: Cannot reset! (logical ID {})",
                self.units[u].id
            ),
        );
        while self.next < self.queue.len() && self.queue[self.next].0 == u {
            self.next += 1;
        }
        self.go_on(cx)
    }

    /// Sends the next command, or ends the reset when none is left.
    fn go_on(&mut self, cx: &mut Cx<'_>) -> Reset {
        if self.next < self.queue.len() {
            self.send_next(cx);
            return Reset::Working;
        }
        self.phase = Phase::Idle;
        self.poll_all.clear();
        for u in &mut self.units {
            u.last = Some(cx.now.mono);
            if u.streaming {
                self.poll_all.extend_from_slice(&u.flush);
            }
        }
        if self.poll_all.is_empty() {
            return Reset::Failed(Retry::Now);
        }
        self.setup_due = false;
        self.poll_at = Some(cx.now.mono);
        Reset::Done
    }
}

impl Protocol for WirelessProtocol {
    const KIND: &'static str = "YEI 3-Space wireless dongle";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(self.baud))
    }

    fn supervision(&self) -> Supervision {
        supervision()
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.out.clear();
        wired(&[SET_WIRELESS_MODE, 0], &mut self.out);
        for u in &mut self.units {
            wireless(u.id, &[STOP_STREAMING], &mut self.out);
            u.streaming = false;
        }
        cx.write(&self.out);
        self.phase = Phase::Settling(cx.now.mono + SETTLE);
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        if !matches!(self.phase, Phase::Command(_)) {
            return Reset::Working; // answers to the stop commands, flushed
        }
        let before = self.reply.len();
        let room = REPLY_MAX.saturating_sub(before);
        self.reply
            .extend_from_slice(&bytes[..bytes.len().min(room)]);
        let used = match self.answer() {
            None => {
                // The header came: its data is given C++'s longer wait.
                if before < 3 && self.reply.len() >= 3 {
                    self.phase = Phase::Command(cx.now.mono + ANSWER_WAIT);
                }
                return Reset::Working;
            }
            Some(Err(why)) => return self.unit_failed(&why, cx),
            Some(Ok(used)) => used,
        };
        let (u, step) = &self.queue[self.next];
        if matches!(step, Step::Binary(c) if c[..] == [START_STREAMING]) {
            self.units[*u].streaming = true;
        }
        self.next += 1;
        let r = self.go_on(cx);
        if matches!(r, Reset::Done) {
            // Nothing was asked for after the last answer, but what follows it in its read
            // is handed to the framer all the same.
            let from = used.saturating_sub(before).min(bytes.len());
            self.received(&bytes[from..], cx);
        }
        r
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        match self.phase {
            Phase::Settling(t) if cx.now.mono >= t => {
                cx.flush_input();
                self.queue.clear();
                for (i, u) in self.units.iter().enumerate() {
                    if self.setup_due {
                        self.queue.extend(u.setup.iter().map(|s| (i, s.clone())));
                    }
                    self.queue.extend(u.reset.iter().map(|s| (i, s.clone())));
                }
                self.next = 0;
                self.go_on(cx)
            }
            Phase::Command(t) if cx.now.mono >= t => {
                let why = match self.queue[self.next].1.answer() {
                    Answer::Line => "vrpn_YEI_3Space_Sensor_Wireless::send_ascii_command: \
                                     Timeout waiting for command status"
                        .to_owned(),
                    Answer::Data(_) => format!(
                        "vrpn_YEI_3Space_Sensor_Wireless::send_binary_command: Timeout waiting \
                         for command status (got {} chars)",
                        self.reply.len()
                    ),
                };
                self.unit_failed(&why, cx)
            }
            _ => Reset::Working,
        }
    }

    fn reset_deadline(&self) -> Option<Instant> {
        match self.phase {
            Phase::Idle => None,
            Phase::Settling(t) | Phase::Command(t) => Some(t),
        }
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        for &b in bytes {
            self.framer.push(b, cx.now);
            while let Some(f) = self.framer.next_frame() {
                if let Some(why) = f.rejected {
                    cx.skipped(
                        u64::from(f.skipped),
                        "vrpn_YEI_3Space_Sensor_Wireless",
                        format_args!(" (the bytes held {why})"),
                    );
                }
                let Some(u) = self.units.iter_mut().find(|u| u.id == f.id) else {
                    continue;
                };
                cx.record(f.first_byte);
                u.last = Some(f.first_byte.mono);
                u.servers.report(&f.record, f.first_byte);
                // The dongle may hold more of this unit's records: ask again at once.
                cx.write(&u.flush);
            }
        }
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        let now = cx.now.mono;
        if let Some(u) = self
            .units
            .iter()
            .find(|u| u.last.is_some_and(|t| now >= t + TIMEOUT))
        {
            cx.say(
                TextSeverity::Error,
                format_args!(
                    "vrpn_YEI_3Space::mainloop: Timeout... no record from logical ID {} for {} \
                     ms: resetting the dongle",
                    u.id,
                    u.last.map_or(0, |t| (now - t).as_millis())
                ),
            );
            cx.reset();
            return;
        }
        if self.poll_at.is_some_and(|t| now >= t) {
            cx.write(&self.poll_all);
            self.poll_at = Some(now + self.poll_every);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        let watch = self
            .units
            .iter()
            .filter_map(|u| u.last)
            .min()
            .map(|t| t + TIMEOUT);
        self.poll_at.into_iter().chain(watch).min()
    }

    fn stopped(&mut self) {
        self.phase = Phase::Idle;
        self.reply.clear();
        self.framer.clear();
        self.poll_at = None;
        for u in &mut self.units {
            u.last = None;
            u.streaming = false;
        }
    }

    fn lost(&mut self, _cx: &mut Cx<'_>) {
        // Units that come back have forgotten their LED settings, calibration and tare.
        self.setup_due = true;
    }

    fn silent(&mut self, last_record: Now, cx: &mut Cx<'_>) {
        say_timeout(last_record, cx);
    }
}
