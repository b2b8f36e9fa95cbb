//! The `penumbra` binary end to end: commands, outputs and the errors bad input gives.

#[path = "../support/mod.rs"]
mod support;

mod big_render;
mod compare;
mod errors;
mod quality;
mod render;
