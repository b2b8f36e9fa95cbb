//! How good an image is: error metrics against a reference ([`metrics`]) and where the
//! error sits ([`error_regions`]); `penumbra quality` and the tests report both.

pub mod error_regions;
pub mod metrics;
