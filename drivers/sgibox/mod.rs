//! The SGI dial and button boxes on a serial line, without SGI's GL library
//! (`vrpn_raw_SGIBox`): its `vrpn.cfg` line ([`config`]), its bytes ([`record`]), its
//! [`Protocol`] run by the shared [`Lifecycle`](crate::driver::Lifecycle), and a device
//! simulator (`sim`, with the `sim` feature).
//!
//! # Configuration line served
//!
//! ```text
//! vrpn_raw_SGIBox NAME PORT [BUTTON ...]
//! ```
//!
//! The line is 8N1 at 9600 baud. Each listed button (0-31) is a toggle, initially off; its
//! light shows its state.
//!
//! # What is sent
//!
//! `NAME` is a Button with 32 buttons, an Analog with 8 channels and a Dial with 8 dials. A
//! button byte sends a `vrpn_Button Change` (toggle modes applied, with Alerts, as C++'s
//! `vrpn_Button_Filter`); a dial turn sends a `vrpn_Analog Channel` message with all eight
//! channels if one changed (each dial a saturating value in −0.5…0.5, 400 counts wide, whose
//! middle follows the dial past either end) and a `vrpn_Dial update` with the revolutions
//! turned (200 counts a turn). All stamped with the arrival of the event's first byte.
//!
//! # Reset and supervision
//!
//! `0x20` twice (1 ms apart: C++ writes every byte 1 ms after the last); the boxes answer
//! `0x20` each. Then the dials are enabled, the buttons enabled and activated twice, and the
//! lights set, one byte a millisecond. C++ sleeps 1 s for the answers; here the first answer
//! (and 20 ms for the second) is enough; events of boxes that were still enabled, before the
//! answers, are reported (C++ fails the reset for them), and so are events that share the
//! answers' read (a slow reader takes several arrivals at once). No answer within 1 s is a warning
//! text and another attempt after 1 s. An unexpected `0x20` (the boxes were reset) resets them
//! again. Whenever a toggle changes (a press, or a client's request), the lights follow.
//! The boxes send only on events, so there is no watchdog. A port that fails is reopened by
//! the serial layer, then the boxes reset.
//!
//! # Differences from C++ VRPN
//!
//! * No 1 s sleep, and no reset of the boxes when the first client connects (C++ resets them
//!   then, sleeping 1 s more).
//! * A byte that is no event is skipped and reported once a second; C++ resets the boxes for
//!   it. A dial turn whose last bytes do not come within 1 s is dropped (C++: 10 ms, then a
//!   reset).
//! * A dial whose 16-bit counter wraps turns by a step, not by a whole range backwards.
//! * Reports carry the event's first-byte arrival; the reset zeroes the dials' bookkeeping
//!   (the boxes' counters restart) but reports nothing (a reset never invents data; C++ zeroes
//!   its values without telling clients either).

pub mod config;
pub mod record;
#[cfg(any(test, feature = "sim"))]
pub mod sim;

#[cfg(test)]
mod tests;

use std::cell::Cell;
use std::rc::Rc;
use std::time::{Duration, Instant};

use self::record::{
    button_event, lights, DialState, ACTIVATE_BUTTONS, BUTTONS, DIALS, ENABLE_BUTTONS,
    ENABLE_DIALS, RESET,
};
use crate::devices::button::TOGGLE_ON;
use crate::devices::text::TextSeverity;
use crate::driver::{Cx, Driver, Hint, Protocol, Reset, Retry, Supervision};
use crate::serial::{PortKind, PortSettings};
use crate::time::Now;
use crate::{AnalogServer, ButtonServer, Connection, DialServer, Error, SenderFilter};

pub use self::config::SgiBox;

/// The registry entry: `vrpn_raw_SGIBox`.
pub static DRIVER: Driver = Driver {
    keywords: &["vrpn_raw_SGIBox"],
    parse: config::parse,
    hints: &[Hint {
        keyword: "vrpn_SGIBOX",
        text: "the boxes through SGI's GL library exist only on SGI machines; use \
               vrpn_raw_SGIBox NAME PORT [toggles] on the serial line",
    }],
};

/// The line's speed (fixed, as in C++).
pub const BAUD: u32 = 9600;
/// Time between two bytes written (C++ writes each byte 1 ms after the last).
pub const BYTE_GAP: Duration = Duration::from_millis(1);
/// Time the boxes have to answer the reset.
pub const ANSWER_LIMIT: Duration = Duration::from_secs(1);
/// Time for the second box's answer after the first's.
pub const SECOND_ANSWER: Duration = Duration::from_millis(20);
/// Pause before another attempt after a failed reset.
pub const RETRY_DELAY: Duration = Duration::from_secs(1);
/// Time for a dial turn's last bytes. Generous: they follow within 3 ms on the line, but a
/// loaded machine can hand them over much later, and the limit only matters for a stray dial
/// byte before silence.
pub const DIAL_LIMIT: Duration = Duration::from_secs(1);

/// Bytes written one at a time, [`BYTE_GAP`] apart.
#[derive(Clone, Debug)]
struct Paced {
    queue: [u8; 64],
    head: usize,
    len: usize,
    next: Option<Instant>,
}

impl Default for Paced {
    fn default() -> Paced {
        Paced {
            queue: [0; 64],
            head: 0,
            len: 0,
            next: None,
        }
    }
}

impl Paced {
    fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
        self.next = None;
    }

    fn push(&mut self, bytes: &[u8], now: Instant) {
        self.queue.copy_within(self.head..self.len, 0);
        self.len -= self.head;
        self.head = 0;
        let room = self.queue.len() - self.len;
        let n = bytes.len().min(room);
        self.queue[self.len..self.len + n].copy_from_slice(&bytes[..n]);
        self.len += n;
        self.next.get_or_insert(now);
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        if self.next.is_some_and(|t| cx.now.mono >= t) && self.head < self.len {
            cx.write(&self.queue[self.head..self.head + 1]);
            self.head += 1;
            self.next = (self.head < self.len).then(|| cx.now.mono + BYTE_GAP);
        }
    }
}

/// Where the reset is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Step {
    Idle,
    Answer { by: Instant, answers: u32 },
}

/// The SGI boxes' protocol. See the module documentation.
pub struct SgiBoxProtocol {
    buttons: ButtonServer,
    analog: AnalogServer,
    dials: DialServer,
    dial_state: [DialState; DIALS],
    /// A dial turn being read: dial, first-byte time, the position's first byte if in.
    partial: Option<(usize, Now, Option<u8>)>,
    paced: Paced,
    step: Step,
    /// Set when a toggle changed (the button server's Alert): the lights must follow.
    lights_stale: Rc<Cell<bool>>,
    lights_sent: Option<u32>,
    last_now: Option<Instant>,
}

impl SgiBoxProtocol {
    /// The protocol of a `vrpn_raw_SGIBox` entry, with its servers on `conn`.
    pub fn new(cfg: &SgiBox, conn: &Connection) -> Result<SgiBoxProtocol, Error> {
        let buttons = ButtonServer::new(&cfg.name, conn, BUTTONS)?;
        buttons.set_alerts(true);
        let lights_stale = Rc::new(Cell::new(true));
        let alert = conn.register_type(crate::wire::payload::button::ALERT)?;
        let stale = lights_stale.clone();
        conn.register_handler(alert, SenderFilter::Only(buttons.sender()), move |_| {
            stale.set(true)
        });
        for &b in &cfg.toggles {
            buttons.set_mode(b as i32, crate::devices::button::TOGGLE_OFF);
        }
        Ok(SgiBoxProtocol {
            buttons,
            analog: AnalogServer::new(&cfg.name, conn, DIALS)?,
            dials: DialServer::new(&cfg.name, conn, DIALS)?,
            dial_state: [DialState::default(); DIALS],
            partial: None,
            paced: Paced::default(),
            step: Step::Idle,
            lights_stale,
            lights_sent: None,
            last_now: None,
        })
    }

    /// The button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// The analog server.
    pub fn analog(&self) -> &AnalogServer {
        &self.analog
    }

    /// The dial server.
    pub fn dials(&self) -> &DialServer {
        &self.dials
    }

    /// The lights last sent (bit *i* is light *i*).
    pub fn lights_sent(&self) -> Option<u32> {
        self.lights_sent
    }

    /// The lights the toggles call for.
    fn lights_wanted(&self) -> u32 {
        (0..BUTTONS)
            .filter(|&i| self.buttons.mode(i) == TOGGLE_ON)
            .fold(0, |acc, i| acc | 1 << i)
    }

    fn send_lights(&mut self, now: Instant) {
        self.lights_stale.set(false);
        let want = self.lights_wanted();
        if self.lights_sent != Some(want) {
            self.lights_sent = Some(want);
            self.paced.push(&lights(want), now);
        }
    }

    fn enable(&mut self, now: Instant) {
        self.dial_state = [DialState::default(); DIALS];
        self.paced.push(&ENABLE_DIALS, now);
        for _ in 0..2 {
            self.paced.push(&ENABLE_BUTTONS, now);
            self.paced.push(&ACTIVATE_BUTTONS, now);
        }
        self.lights_sent = None;
        self.send_lights(now);
        self.step = Step::Idle;
    }

    fn skip(&mut self, n: u64, cx: &mut Cx<'_>) {
        cx.skipped(n, "vrpn_raw_SGIBox", format_args!(""));
    }

    /// One byte while streaming; false when the boxes must be reset.
    fn byte(&mut self, b: u8, cx: &mut Cx<'_>) -> bool {
        if let Some((dial, first, high)) = self.partial {
            match high {
                None => self.partial = Some((dial, first, Some(b))),
                Some(h) => {
                    self.partial = None;
                    self.turn(dial, i16::from_be_bytes([h, b]), first, cx);
                }
            }
            return true;
        }
        match b {
            RESET => {
                cx.say(
                    TextSeverity::Warning,
                    format_args!(
                        "vrpn_raw_SGIBox: Got reset response when we didn't expect it, resetting"
                    ),
                );
                cx.reset();
                false
            }
            0x30..=0x37 => {
                self.partial = Some((usize::from(b - 0x30), cx.now, None));
                true
            }
            _ => {
                match button_event(b) {
                    Some((button, pressed)) => {
                        cx.record(cx.now);
                        self.buttons.set_button(button, pressed);
                        self.buttons.set_timestamp(cx.now.wall);
                        // A failed send is the connection's business (it drops the peer).
                        let _ = self.buttons.report_changes();
                    }
                    None => self.skip(1, cx),
                }
                true
            }
        }
    }

    fn turn(&mut self, dial: usize, position: i16, first: Now, cx: &mut Cx<'_>) {
        cx.record(first);
        let (channel, turned) = self.dial_state[dial].turn(position);
        self.analog.set_channel(dial, channel);
        let _ = self.analog.report_changes(Some(first.wall));
        self.dials.set_timestamp(first.wall);
        self.dials.add_rotation(dial, turned);
        let _ = self.dials.report_changes();
    }
}

impl Protocol for SgiBoxProtocol {
    const KIND: &'static str = "vrpn_raw_SGIBox";

    fn port_kind(&self) -> PortKind {
        PortKind::Serial(PortSettings::n81(BAUD))
    }

    fn supervision(&self) -> Supervision {
        Supervision::QUIET
    }

    fn start_reset(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        cx.flush_input();
        self.paced.clear();
        self.paced.push(&[RESET, RESET], cx.now.mono);
        self.paced.poll(cx);
        self.step = Step::Answer {
            by: cx.now.mono + ANSWER_LIMIT,
            answers: 0,
        };
        Reset::Working
    }

    fn reset_received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) -> Reset {
        let Step::Answer {
            mut by,
            mut answers,
        } = self.step
        else {
            return Reset::Working;
        };
        self.last_now = Some(cx.now.mono);
        for (i, &b) in bytes.iter().enumerate() {
            if b != RESET || self.partial.is_some() {
                // Events of boxes still enabled (the answer follows them): reported.
                self.byte(b, cx);
                continue;
            }
            answers += 1;
            if answers == 1 {
                // The boxes' counters restarted when they heard the reset.
                self.dial_state = [DialState::default(); DIALS];
                by = by.min(cx.now.mono + SECOND_ANSWER);
            }
            if answers == 2 {
                self.enable(cx.now.mono);
                self.paced.poll(cx);
                // Events right after the answers can share their read: they are events.
                self.received(&bytes[i + 1..], cx);
                return Reset::Done;
            }
        }
        self.step = Step::Answer { by, answers };
        Reset::Working
    }

    fn reset_poll(&mut self, cx: &mut Cx<'_>) -> Reset {
        self.last_now = Some(cx.now.mono);
        self.paced.poll(cx);
        match self.step {
            Step::Answer { by, answers } if cx.now.mono >= by => {
                if answers == 0 {
                    cx.say(
                        TextSeverity::Warning,
                        format_args!(
                            "vrpn_raw_SGIBox: no answer to the reset command (are the boxes \
                             on?), retrying"
                        ),
                    );
                    self.step = Step::Idle;
                    return Reset::Failed(Retry::After(RETRY_DELAY));
                }
                self.enable(cx.now.mono);
                self.paced.poll(cx);
                Reset::Done
            }
            _ => Reset::Working,
        }
    }

    fn reset_deadline(&self) -> Option<Instant> {
        let answer = match self.step {
            Step::Answer { by, .. } => Some(by),
            Step::Idle => None,
        };
        [answer, self.paced.next].into_iter().flatten().min()
    }

    fn received(&mut self, bytes: &[u8], cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        for &b in bytes {
            if !self.byte(b, cx) {
                return;
            }
        }
        if self.lights_stale.get() {
            self.send_lights(cx.now.mono);
            self.paced.poll(cx);
        }
    }

    fn deadline(&self) -> Option<Instant> {
        let dial = self.partial.map(|(_, first, _)| first.mono + DIAL_LIMIT);
        // A toggle a client changed: the lights at the next pass.
        let lights = self.lights_stale.get().then_some(self.last_now).flatten();
        [dial, self.paced.next, lights].into_iter().flatten().min()
    }

    fn poll(&mut self, cx: &mut Cx<'_>) {
        self.last_now = Some(cx.now.mono);
        if let Some((_, first, high)) = self.partial {
            if cx.now.mono >= first.mono + DIAL_LIMIT {
                self.partial = None;
                self.skip(1 + u64::from(high.is_some()), cx);
            }
        }
        if self.lights_stale.get() {
            self.send_lights(cx.now.mono);
        }
        self.paced.poll(cx);
    }

    fn stopped(&mut self) {
        self.partial = None;
        self.paced.clear();
        self.step = Step::Idle;
        self.lights_sent = None;
    }
}
