//! GPU tests (lavapipe where there is no GPU): every kernel against its CPU twin, frames, tiling, refinement, moving objects, the embedded pass, and the peers (ray queries, Embree) as oracles. One binary, one device for all (and one more with ray queries where the adapter has them).

#[path = "../support/mod.rs"]
mod support;

mod alpha;
mod determinism;
mod embed;
mod far_from_origin;
mod frame;
mod lights;
mod loop_limit;
mod motion;
mod peers;
mod primary_mft;
mod refine;
mod shadow_mft;
mod shadow_tracers;
mod smoke;
mod tiles;
