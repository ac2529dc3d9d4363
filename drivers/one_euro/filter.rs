//! The 1€ filter (Casiez, Roussel, Vogel 2012) on positions and on orientations, operation
//! for operation as C++ VRPN's `vrpn_OneEuroFilter.h` computes it, so that filtered reports
//! agree with C++'s to the last bit for the same input.
//!
//! Each sample is smoothed by a first-order low-pass filter whose cutoff rises with the
//! (itself low-pass filtered) speed: `cutoff = min_cutoff + beta * |dx/dt|`, `alpha = 1 / (1 +
//! tau / dt)` with `tau = 1 / (2π cutoff)`. Positions blend linearly; orientations by quatlib's
//! spherical interpolation, their speed being the angle of the rotation per second.

use crate::layered::{quat_invert, quat_mult};

/// quatlib's π.
const Q_PI: f64 = std::f64::consts::PI;

fn alpha(dt: f64, cutoff: f64) -> f64 {
    let tau = 1.0 / (2.0 * Q_PI * cutoff);
    1.0 / (1.0 + tau / dt)
}

pub use crate::layered::{quat_normalize, quat_slerp};

/// A first-order low-pass filter on `N` values (C++ `vrpn_LowPassFilter`).
#[derive(Clone, Copy, Debug)]
struct LowPass<const N: usize> {
    first: bool,
    prev: [f64; N],
}

impl<const N: usize> LowPass<N> {
    fn new() -> Self {
        LowPass {
            first: true,
            prev: [0.0; N],
        }
    }

    fn filter(&mut self, x: &[f64; N], alpha: f64) -> [f64; N] {
        if self.first {
            self.first = false;
            self.prev = *x;
        }
        let mut hat = [0.0; N];
        for i in 0..N {
            hat[i] = alpha * x[i] + (1.0 - alpha) * self.prev[i];
        }
        self.prev = hat;
        hat
    }
}

/// A low-pass filter on orientations (C++ `vrpn_LowPassFilterQuat`).
#[derive(Clone, Copy, Debug)]
struct LowPassQuat {
    first: bool,
    prev: [f64; 4],
}

impl LowPassQuat {
    fn new() -> Self {
        LowPassQuat {
            first: true,
            prev: [0.0; 4],
        }
    }

    fn filter(&mut self, x: &[f64; 4], alpha: f64) -> [f64; 4] {
        if self.first {
            self.first = false;
            self.prev = *x;
        }
        self.prev = quat_slerp(&self.prev, x, alpha);
        self.prev
    }
}

/// The filter's three parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Cutoff frequency at rest (Hz).
    pub min_cutoff: f64,
    /// How fast the cutoff rises with speed.
    pub beta: f64,
    /// Cutoff of the speed's own filter (Hz).
    pub derivative_cutoff: f64,
}

/// The 1€ filter on positions (C++ `vrpn_OneEuroFilterVec`).
#[derive(Clone, Copy, Debug)]
pub struct PositionFilter {
    first: bool,
    params: Params,
    x: LowPass<3>,
    dx: LowPass<3>,
}

impl PositionFilter {
    /// A filter that has seen nothing yet.
    pub fn new(params: Params) -> Self {
        PositionFilter {
            first: true,
            params,
            x: LowPass::new(),
            dx: LowPass::new(),
        }
    }

    /// The filtered position for sample `x`, `dt` seconds after the previous one.
    pub fn filter(&mut self, dt: f64, x: &[f64; 3]) -> [f64; 3] {
        let mut d = [0.0; 3];
        if self.first {
            self.first = false;
        } else {
            for i in 0..3 {
                d[i] = (x[i] - self.x.prev[i]) / dt;
            }
        }
        let fd = self.dx.filter(&d, alpha(dt, self.params.derivative_cutoff));
        let mut sq = 0.0;
        for v in fd {
            sq += v * v;
        }
        let cutoff = self.params.min_cutoff + self.params.beta * sq.sqrt();
        self.x.filter(x, alpha(dt, cutoff))
    }
}

/// The 1€ filter on orientations (C++ `vrpn_OneEuroFilterQuat`).
#[derive(Clone, Copy, Debug)]
pub struct OrientationFilter {
    first: bool,
    params: Params,
    x: LowPassQuat,
    dx: LowPassQuat,
}

impl OrientationFilter {
    /// A filter that has seen nothing yet.
    pub fn new(params: Params) -> Self {
        OrientationFilter {
            first: true,
            params,
            x: LowPassQuat::new(),
            dx: LowPassQuat::new(),
        }
    }

    /// The filtered orientation (not normalised) for sample `q` (x, y, z, w), `dt` seconds
    /// after the previous one.
    pub fn filter(&mut self, dt: f64, q: &[f64; 4]) -> [f64; 4] {
        let d = if self.first {
            self.first = false;
            [0.0, 0.0, 0.0, 1.0]
        } else {
            let rate = 1.0 / dt;
            let inverse = quat_invert(&self.x.prev);
            let mut d = quat_mult(q, &inverse);
            d[0] *= rate;
            d[1] *= rate;
            d[2] *= rate;
            d[3] = d[3] * rate + (1.0 - rate);
            quat_normalize(&d)
        };
        let fd = self.dx.filter(&d, alpha(dt, self.params.derivative_cutoff));
        let magnitude = 2.0 * fd[3].acos();
        let cutoff = self.params.min_cutoff + self.params.beta * magnitude;
        self.x.filter(q, alpha(dt, cutoff))
    }
}
