//! The work counters, re-exported for the CPU twins (see [`crate::counters`]).

pub use crate::counters::{Counters, STATUS_WORDS};
