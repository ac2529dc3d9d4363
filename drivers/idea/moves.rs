//! A move as C++ `vrpn_IDEA` writes one: the input-interrupt set-up (`i`), the limit-switch
//! check, then the move (`M`), pure.
//!
//! `i` takes twelve numbers: the edge of inputs 1–4 that interrupts (2: rising, 0: none), the
//! program address each calls (1024 for the high limit, 2048 for the low one), and their
//! priorities (all 1). Only the limit switch in the direction of travel is armed. `M` takes
//! the target in 1/64 steps, then the run, start and end speeds, acceleration, deceleration,
//! run, hold, acceleration and deceleration currents, the hold delay and the microstepping;
//! everything but the run speed, the delay and the microstepping is scaled by the move's
//! fraction (the reset's gentle moves), truncated as C++ truncates.

use super::answer::Command;
use super::config::Idea;

/// What became of a move asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// `i` and `M` were written.
    Sent,
    /// The limit switch in the direction of travel is closed: only `i` was written.
    IntoLimit,
}

/// `v × scale` truncated toward zero, as C++'s `static_cast<int>`.
fn scaled(v: i32, scale: f64) -> i64 {
    (f64::from(v) * scale) as i64
}

/// Writes a move from `from` to `to` (steps) with `inputs` the last input bits read.
pub fn write_move(
    cfg: &Idea,
    from: f64,
    inputs: u8,
    to: f64,
    scale: f64,
    write: &mut dyn FnMut(&[u8]),
) -> Outcome {
    let mut edge = [0u32; 4];
    let mut address = [0u32; 4];
    let forward_limit = cfg.high_limit.filter(|_| to > from);
    let backward_limit = cfg.low_limit.filter(|_| to < from);
    if let Some(i) = forward_limit {
        edge[usize::from(i) - 1] = 2;
        address[usize::from(i) - 1] = 1024;
    }
    if let Some(i) = backward_limit {
        edge[usize::from(i) - 1] = 2;
        address[usize::from(i) - 1] = 2048;
    }
    if let Some(c) = Command::new(format_args!(
        "i{},{},{},{},{},{},{},{},1,1,1,1",
        edge[0], edge[1], edge[2], edge[3], address[0], address[1], address[2], address[3]
    )) {
        write(c.bytes());
    }
    let closed = |i: Option<u8>| i.is_some_and(|i| inputs & (1 << (i - 1)) != 0);
    if closed(forward_limit) || closed(backward_limit) {
        return Outcome::IntoLimit;
    }
    let m = &cfg.motion;
    if let Some(c) = Command::new(format_args!(
        "M{},{},{},{},{},{},{},{},{},{},{},{}",
        (to * 64.0) as i64,
        m.run_speed,
        scaled(m.start_speed, scale),
        scaled(m.end_speed, scale),
        scaled(m.accel, scale),
        scaled(m.decel, scale),
        scaled(m.run_current, scale),
        scaled(m.hold_current, scale),
        scaled(m.accel_current, scale),
        scaled(m.decel_current, scale),
        m.delay,
        m.step
    )) {
        write(c.bytes());
    }
    Outcome::Sent
}

/// The `O` command's value: bit 4+k says output k+1 is set, bit k what to.
pub fn outputs_value(outputs: &[Option<bool>; 4]) -> u32 {
    outputs
        .iter()
        .enumerate()
        .filter_map(|(k, o)| o.map(|on| (1 << (4 + k)) | (u32::from(on) << k)))
        .sum()
}
