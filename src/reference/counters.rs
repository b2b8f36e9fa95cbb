//! The work counters, re-exported for the CPU twins (see [`crate::contract::counters`]).

pub use crate::contract::counters::{Counters, STATUS_WORDS};
