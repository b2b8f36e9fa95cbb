//! How good an image is: error metrics against a reference ([`metrics`]), where the
//! error sits ([`error_regions`]) and what the filter's windows did there
//! ([`filter_windows`]); `penumbra quality` and the tests report them.

pub mod error_regions;
pub mod filter_windows;
pub mod metrics;
