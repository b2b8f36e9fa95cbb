// The status-buffer words of the Table 1 work counters, and the switch that turns counting on.
// Imported by the tracing kernels; mirrors src/contract/counters.rs (word layout) and is read back by the host.

// Counting is compiled in only when the pipeline sets COUNTERS = true: with
// false, every count is dead code. Counts are kept in private variables and
// added to the status buffer once per invocation (per-ray) or vector (lane 0).
override COUNTERS: bool = false;

const WORD_STATUS: u32 = 0u;                   // the kernel's own report
const WORD_NODES_VISITED: u32 = 1u;            // inner nodes visited
const WORD_BOX_TESTS: u32 = 2u;                // 16-wide (vector) or single-ray box tests
const WORD_TRIANGLES_ACCESSED: u32 = 3u;       // triangles fetched at leaves
const WORD_TRIANGLES_AFTER_CULLING: u32 = 4u;  // fetched triangles some frustum did not cull
const WORD_TRIANGLE_TESTS: u32 = 5u;           // 16-ray tests (vector) or ray-triangle tests
// Vectors (or rays) whose loop ended without finishing, suspending or running out of
// budget: the driver ended it (lavapipe after 65,535 iterations of all an invocation's
// loops). Their results are incomplete; the host turns a non-zero count into an error.
const WORD_LOOP_CUT: u32 = 6u;
