//! Text messages from the tracker, formatted on the stack (no allocation).

use std::fmt;

use crate::devices::text::TextSeverity;
use crate::driver::text::with_text;
use crate::TrackerServer;

/// Formats `args` into a fixed buffer and sends it as a text message from `tracker`.
pub fn say(tracker: &TrackerServer, severity: TextSeverity, args: fmt::Arguments<'_>) {
    // A failed send is the connection's business (it reports and drops the peer).
    with_text(args, |text| {
        let _ = tracker.send_text(severity, 0, text);
    });
}

/// The units a system-status answer shows as not accessible or not running, as
/// "address 2 not running, address 3 not accessible".
pub struct UnitsDown<'a> {
    /// The system-status bytes (one per bus address from 1).
    pub status: &'a [u8],
    /// Units that must be up (addresses 1..=units).
    pub units: u8,
}

impl fmt::Display for UnitsDown<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use super::reset::{UNIT_ACCESSIBLE, UNIT_RUNNING};
        let mut first = true;
        for (i, &s) in self.status.iter().take(usize::from(self.units)).enumerate() {
            let what = if s & UNIT_ACCESSIBLE == 0 {
                "not accessible"
            } else if s & UNIT_RUNNING == 0 {
                "not running"
            } else {
                continue;
            };
            if !first {
                f.write_str(", ")?;
            }
            first = false;
            write!(f, "address {} {what}", i + 1)?;
        }
        Ok(())
    }
}

/// Why a reset failed, in words.
pub struct FailureText {
    /// The failure.
    pub failure: super::reset::Failure,
    /// Units the status check covered.
    pub units: u8,
}

impl fmt::Display for FailureText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use super::reset::{Failure, STATUS_LEN};
        match self.failure {
            Failure::NoAnswer => f.write_str(
                "Flock reset failed: the master bird does not answer (check its power, the \
                 cable and the baud rate)",
            ),
            Failure::NeverQuiet => f.write_str(
                "Flock reset failed: the line kept sending after the stop command (check the \
                 baud rate)",
            ),
            Failure::StatusIncomplete(got) => write!(
                f,
                "Flock reset failed: received only {got} of {STATUS_LEN} bytes of the system \
                 status"
            ),
            Failure::UnitsDown(status) => write!(
                f,
                "Flock reset failed: {} (check that every unit is switched to FLY)",
                UnitsDown {
                    status: &status,
                    units: self.units,
                }
            ),
        }
    }
}
