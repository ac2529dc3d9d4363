//! `vrpn_server`: command-line options and the server loop.

pub mod options;
pub mod run;

pub use options::{parse_args, ServerOptions, SleepPolicy};
pub use run::ServerLoop;
