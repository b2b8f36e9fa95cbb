// Workgroup sizes of the non-vector kernels; the host dispatches in these units.
// Mirrors `src/contract/groups.rs` (a naga test checks the values and each kernel's @workgroup_size).

// Side of the square workgroups of the per-pixel kernels (one invocation per pixel).
const PIXEL_GROUP: u32 = 8u;
// Invocations of the one-dimensional workgroups (rays, list slots, nodes).
const LINE_GROUP: u32 = 64u;
