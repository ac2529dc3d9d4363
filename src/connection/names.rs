//! The names every connection registers first, and why a name may be refused.

pub use crate::proto::names::{
    NameLimit, CONTROL_SENDER, DROPPED_CONNECTION, DROPPED_LAST_CONNECTION, GOT_CONNECTION,
    GOT_FIRST_CONNECTION,
};
