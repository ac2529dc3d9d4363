//! Device payload layouts (DEVICES.md): one module per device type, each with plain structs
//! that `decode` from and `encode` into byte slices.

pub mod tracker;
