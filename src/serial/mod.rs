//! Serial devices: the sans-IO driver interface ([`driver`]), the port ([`port`]) and a driver
//! on a port in the server's reactor ([`device`]). (The simulated line and pseudo-terminal
//! devices the tests use are in `crate::sim`, with the `sim` feature.)
//!
//! A driver never touches a file descriptor or a clock. It is handed the bytes the port read
//! (with the time the poll woke for the first of them), the current time on each deadline, and
//! it answers with [`PortOps`]: bytes to write, input to flush, modem lines to
//! set, a reopen. The serial layer carries those out on a real port registered in the server's
//! poll; the test line carries them out on a device model.

pub mod device;
pub mod driver;
pub mod port;

pub use device::SerialDevice;
pub use driver::{Parity, PortKind, PortOp, PortOps, PortSettings, SerialDriver};
pub use port::Port;
