//! Devices attached to a station: an IS-900 wand (joystick and six buttons), an IS-900
//! stylus (two buttons) or a genuine Fastrak stylus (one button). Each is served under its own
//! device name, from the station's records.

use super::config::{StationDevice, WandClip};
use super::record::{joystick_raw, ButtonFormat, Record};
use crate::{AnalogServer, ButtonServer, Connection, Error, TimeVal};

/// Buttons of an IS-900 wand.
pub const WAND_BUTTONS: usize = 6;
/// Buttons of an IS-900 stylus.
pub const STYLUS_BUTTONS: usize = 2;
/// Buttons of a Fastrak stylus.
pub const FASTRAK_STYLUS_BUTTONS: usize = 1;
/// Joystick channels of a wand (x, then y).
pub const WAND_CHANNELS: usize = 2;

/// Maps a raw joystick value through a wand channel's clip values: inside the dead zone
/// `low_zero..=high_zero` it is 0; at or beyond `min` / `max` it is -1 / +1; in between it is
/// scaled linearly from the edge of the dead zone. The checks run in that order, so an
/// (invalid) overlapping setting behaves as in C++.
pub fn clip(v: f64, c: &WandClip) -> f64 {
    if c.low_zero <= v && v <= c.high_zero {
        0.0
    } else if v <= c.min {
        -1.0
    } else if v >= c.max {
        1.0
    } else if v > c.low_zero {
        (v - c.high_zero) / (c.max - c.high_zero)
    } else {
        (v - c.low_zero) / (c.low_zero - c.min)
    }
}

/// The servers of one station's device.
pub struct StationServers {
    buttons: ButtonServer,
    wand: Option<(AnalogServer, [WandClip; 2])>,
}

impl StationServers {
    /// Creates the servers `device` exports on `conn`.
    pub fn new(device: &StationDevice, conn: &Connection) -> Result<StationServers, Error> {
        Ok(match device {
            StationDevice::Wand { name, clip, .. } => StationServers {
                wand: Some((AnalogServer::new(name, conn, WAND_CHANNELS)?, *clip)),
                buttons: ButtonServer::new(name, conn, WAND_BUTTONS)?,
            },
            StationDevice::Stylus { name, .. } => StationServers {
                buttons: ButtonServer::new(name, conn, STYLUS_BUTTONS)?,
                wand: None,
            },
            StationDevice::FtStylus { name, .. } => StationServers {
                buttons: ButtonServer::new(name, conn, FASTRAK_STYLUS_BUTTONS)?,
                wand: None,
            },
        })
    }

    /// Whether the station's records carry joystick bytes.
    pub fn has_joystick(&self) -> bool {
        self.wand.is_some()
    }

    /// The button server.
    pub fn buttons(&self) -> &ButtonServer {
        &self.buttons
    }

    /// The wand's analog server, if this is a wand.
    pub fn analog(&self) -> Option<&AnalogServer> {
        self.wand.as_ref().map(|(a, _)| a)
    }

    /// Sends what changed in `record`, stamped `time`: button Change messages first, then the
    /// joystick's Analog Channel message (both only on change), as C++ orders them before
    /// the pose.
    pub fn report(&mut self, record: &Record, format: ButtonFormat, time: TimeVal) {
        if let Some(bits) = record.buttons {
            let n = match format {
                ButtonFormat::FastrakStylus => 1,
                _ => self.buttons.num_buttons().min(8),
            };
            for i in 0..n {
                self.buttons.set_button(i, bits & (1 << i) != 0);
            }
            self.buttons.set_timestamp(time);
            let _ = self.buttons.report_changes();
        }
        if let (Some((analog, clips)), Some(joy)) = (&mut self.wand, record.joystick) {
            analog.set_channel(0, clip(joystick_raw(joy[0]), &clips[0]));
            analog.set_channel(1, clip(joystick_raw(joy[1]), &clips[1]));
            // A failed send is the connection's business (it reports and drops the peer).
            let _ = analog.report_changes(Some(time));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNIT: WandClip = WandClip {
        min: -1.0,
        low_zero: 0.0,
        high_zero: 0.0,
        max: 1.0,
    };

    #[test]
    fn clip_follows_the_order_of_checks() {
        assert_eq!(clip(0.0, &UNIT), 0.0);
        assert_eq!(clip(0.5, &UNIT), 0.5);
        assert_eq!(clip(-0.25, &UNIT), -0.25);
        assert_eq!(clip(-2.0, &UNIT), -1.0);
        assert_eq!(clip(1.0, &UNIT), 1.0);
        let dead = WandClip {
            min: -0.8,
            low_zero: -0.1,
            high_zero: 0.2,
            max: 0.6,
        };
        assert_eq!(clip(0.15, &dead), 0.0);
        assert_eq!(clip(-0.1, &dead), 0.0);
        assert!((clip(0.4, &dead) - 0.5).abs() < 1e-12);
        assert!((clip(-0.45, &dead) - -0.5).abs() < 1e-12);
        assert_eq!(clip(0.7, &dead), 1.0);
        assert_eq!(clip(-0.9, &dead), -1.0);
    }
}
