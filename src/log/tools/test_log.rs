//! A small log built in memory for the tools' unit tests: two devices, poses, a button change,
//! analog reports and an undescribed type.

use crate::log::format::encode_entry;
use crate::log::LogReader;
use crate::time::TimeVal;
use crate::wire::payload::{analog, button, tracker};
use crate::wire::system::encode_description;
use crate::wire::Cookie;

/// A log image built entry by entry.
pub(crate) struct Builder(pub(crate) Vec<u8>);

impl Builder {
    pub(crate) fn new() -> Builder {
        Builder(Cookie::ours(0).to_bytes().to_vec())
    }
    pub(crate) fn entry(
        &mut self,
        type_id: i32,
        sender: i32,
        t: TimeVal,
        payload: &[u8],
    ) -> &mut Self {
        let mut buf = vec![0u8; 24 + payload.len()];
        let n = encode_entry(&mut buf, type_id, sender, t, payload).unwrap();
        self.0.extend_from_slice(&buf[..n]);
        self
    }
    pub(crate) fn describe(&mut self, type_id: i32, id: i32, name: &str) -> &mut Self {
        let mut p = [0u8; 128];
        let n = encode_description(&mut p, name);
        self.entry(type_id, id, TimeVal::new(1, 0), &p[..n])
    }
    pub(crate) fn reader(&self) -> LogReader {
        LogReader::from_bytes(self.0.clone(), "test.vrpn").unwrap()
    }
}

pub(crate) fn pose(sensor: i32, x: f64) -> Vec<u8> {
    let mut p = [0u8; 64];
    tracker::PosQuat::new(sensor, [x, 0.5, -1.0], [0.0, 0.0, 0.0, 1.0]).encode(&mut p);
    p.to_vec()
}

pub(crate) fn sample() -> Builder {
    let mut b = Builder::new();
    b.describe(-1, 1, "Tracker0")
        .describe(-2, 4, tracker::POS_QUAT)
        .describe(-1, 2, "Button0")
        .describe(-2, 5, button::CHANGE)
        .describe(-2, 6, analog::CHANNEL);
    b.entry(4, 1, TimeVal::new(10, 0), &pose(0, 0.1))
        .entry(4, 1, TimeVal::new(10, 500_000), &pose(1, 0.2))
        .entry(4, 1, TimeVal::new(11, 0), &pose(0, 0.3));
    b.entry(5, 2, TimeVal::new(10, 250_000), &[0, 0, 0, 1, 0, 0, 0, 1]);
    let mut a = [0u8; 32];
    let n = analog::encode_channels(&[0.25, -0.5, 1e-3], &mut a);
    b.entry(6, 2, TimeVal::new(10, 300_000), &a[..n]);
    let n = analog::encode_channels(&[0.75], &mut a);
    b.entry(6, 2, TimeVal::new(10, 400_000), &a[..n]);
    b.entry(99, 1, TimeVal::new(10, 1), &[0xde, 0xad]);
    b
}
