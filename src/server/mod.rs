//! The generic VRPN server (`vrpn_server`): configuration now, device hosting later.

pub mod config;
