//! The HID trackers' lines: `vrpn_Tracker_SpacePoint NAME [INDEX]`,
//! `vrpn_Tracker_RazerHydra NAME`, `vrpn_Tracker_Wintracker NAME S0 S1 S2 EXT HEMI`.

use super::hydra::HydraDriver;
use super::SimpleTracker;
use crate::config::{ConfigError, ConfigLine};
use crate::devices::ServerDevice;
use crate::driver::registry::{BuildContext, DeviceSpec, Driver, Interface, Served};
use crate::error::Error;

/// The registry entry.
pub static DRIVER: Driver = Driver {
    keywords: &[
        "vrpn_Tracker_SpacePoint",
        "vrpn_Tracker_RazerHydra",
        "vrpn_Tracker_Wintracker",
    ],
    parse,
    hints: &[],
};

/// Which tracker, with its settings.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TrackerKind {
    /// SpacePoint number `index` (0 the first).
    SpacePoint {
        /// Which SpacePoint.
        index: usize,
    },
    /// Razer Hydra.
    RazerHydra,
    /// WinTracker III: the first character of each setting.
    Wintracker {
        /// Sensor activation states.
        sensors: [u8; 3],
        /// Range extender (`1` on).
        ext: u8,
        /// Hemisphere (`Z` upper).
        hemisphere: u8,
    },
}

/// A HID tracker's line.
#[derive(Clone, Debug)]
pub struct HidTrackerLine {
    /// Device name.
    pub name: String,
    /// Which tracker.
    pub kind: TrackerKind,
}

fn parse(line: &mut ConfigLine<'_, '_>) -> Result<Box<dyn DeviceSpec>, ConfigError> {
    let kind = match line.keyword() {
        "vrpn_Tracker_SpacePoint" => {
            line.need(1, "name, [index]")?;
            let index = match line.arg(1) {
                Some(_) => line.uint(1, "index", 0, 255)? as usize,
                None => 0,
            };
            TrackerKind::SpacePoint { index }
        }
        "vrpn_Tracker_RazerHydra" => {
            line.need(1, "name")?;
            TrackerKind::RazerHydra
        }
        _ => {
            line.need(6, "name, s0, s1, s2, ext, hemisphere")?;
            let c = |i: usize| line.word(i).map(|w| w.as_bytes()[0]);
            TrackerKind::Wintracker {
                sensors: [c(1)?, c(2)?, c(3)?],
                ext: c(4)?,
                hemisphere: c(5)?,
            }
        }
    };
    Ok(Box::new(HidTrackerLine {
        name: line.name(0)?,
        kind,
    }))
}

impl DeviceSpec for HidTrackerLine {
    fn name(&self) -> &str {
        &self.name
    }

    fn served(&self) -> Vec<Served<'_>> {
        let v: &[Interface] = match self.kind {
            TrackerKind::SpacePoint { .. } => &[Interface::Tracker, Interface::Button],
            TrackerKind::RazerHydra => &[Interface::Tracker, Interface::Analog, Interface::Button],
            TrackerKind::Wintracker { .. } => &[Interface::Tracker],
        };
        Served::all(&self.name, v)
    }

    fn build(&self, cx: &BuildContext<'_>) -> Result<Vec<Box<dyn ServerDevice>>, Error> {
        let conn = cx.conn();
        Ok(vec![match self.kind {
            TrackerKind::SpacePoint { index } => {
                crate::hid::serve(SimpleTracker::spacepoint(&self.name, index, conn)?, cx)
            }
            TrackerKind::RazerHydra => crate::hid::serve(HydraDriver::new(&self.name, conn)?, cx),
            TrackerKind::Wintracker {
                sensors,
                ext,
                hemisphere,
            } => crate::hid::serve(
                SimpleTracker::wintracker(&self.name, sensors, ext, hemisphere, conn)?,
                cx,
            ),
        }])
    }
}
