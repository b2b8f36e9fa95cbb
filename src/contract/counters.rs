//! Work counters of the tracing kernels, counted the way Table 1 of the
//! multi-frusta paper counts them, and the layout of the status buffer that
//! the kernels add them to.
//!
//! A kernel built with its `COUNTERS` override on counts in private
//! variables and adds its totals once, at the end, to words 1..6 of its status
//! buffer (`array<atomic<u32>>`, [`STATUS_WORDS`] words); with the override off
//! (the default) the counting code is dead and compiled away. Word 0 keeps the
//! kernel's own meaning (for the primary kernels: pixels whose rays ran out of
//! loop iterations). The CPU twins count the same events the same way, so a
//! test can compare the two exactly.
//!
//! What one count means for each kind of kernel:
//!
//! | word | field | 16-wide vector (MFT) | one ray per invocation (per-ray) |
//! |------|-------|----------------------|----------------------------------|
//! | 1 | [`nodes_visited`](Counters::nodes_visited) | inner nodes visited by the vector | inner nodes visited by the ray |
//! | 2 | [`box_tests`](Counters::box_tests) | box vs all 16 frusta: 2 per inner node + 1 for the root | ray–box tests: 2 per inner node + 1 for the root |
//! | 3 | [`triangles_accessed`](Counters::triangles_accessed) | triangles fetched by the vector (once per leaf visit) | triangles fetched by the ray |
//! | 4 | [`triangles_after_culling`](Counters::triangles_after_culling) | of those, triangles at least one frustum did not cull | = word 3 (no culling) |
//! | 5 | [`triangle_tests`](Counters::triangle_tests) | (triangle, frustum) pairs that survived culling: 16-ray tests | ray–triangle tests (= word 3) |
//!
//! Word 6 ([`WORD_LOOP_CUT`]) counts loops the driver ended early, whatever `COUNTERS`.
//!
//! Per-ray counts are scalar; comparing them with 16-wide ones (the paper's
//! "16-wide AABB tests" for a packet-less tracer) divides them by 16, which is
//! the reporting side's job. Words are `u32` and wrap past 2³²: at 1024×1024
//! a per-ray primary pass does ~10⁸ box tests, well below that.

/// Words of a kernel's status buffer (32 bytes).
pub const STATUS_WORDS: usize = 8;
/// Status word: the kernel's own report (primary kernels: pixels out of loop iterations).
pub const WORD_STATUS: usize = 0;
/// Status word of [`Counters::nodes_visited`].
pub const WORD_NODES_VISITED: usize = 1;
/// Status word of [`Counters::box_tests`].
pub const WORD_BOX_TESTS: usize = 2;
/// Status word of [`Counters::triangles_accessed`].
pub const WORD_TRIANGLES_ACCESSED: usize = 3;
/// Status word of [`Counters::triangles_after_culling`].
pub const WORD_TRIANGLES_AFTER_CULLING: usize = 4;
/// Status word of [`Counters::triangle_tests`].
pub const WORD_TRIANGLE_TESTS: usize = 5;
/// Status word: vectors (or rays) whose loop ended without finishing, suspending or
/// running out of budget — the driver ended it (lavapipe after 65,535 iterations of all
/// an invocation's loops), so their results are incomplete. The passes turn a non-zero
/// count into an error ([`crate::Error::LoopCut`]).
pub const WORD_LOOP_CUT: usize = 6;

/// Work done by a tracer, summed over vectors (MFT: a 4×4 tile's 16 frusta;
/// packet: one pixel's 16 rays).
///
/// "16-wide" means one test of the whole vector: one box against all 16 frusta
/// (or rays), one triangle against one frustum's 16 rays (or the packet's).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Counters {
    /// Loop iterations of the vector (inner nodes, leaf triangles and stack pops).
    pub traversal_steps: u64,
    /// Inner nodes visited.
    pub nodes_visited: u64,
    /// 16-wide box tests: the root, then both children of every inner node visited.
    pub box_tests: u64,
    /// Triangles read at leaves, once per vector ("#tris" in Table 1).
    pub triangles_accessed: u64,
    /// Triangles that at least one frustum (ray) did not cull ("+culling" in Table 1).
    pub triangles_after_culling: u64,
    /// 16-wide triangle tests ("#isec"): (frustum, triangle) pairs that survived culling.
    pub triangle_tests: u64,
    /// Times a vector ran out of its iteration budget and was resumed.
    pub suspensions: u64,
}

impl Counters {
    /// The counters from a kernel's status words (`words[1..6]`: nodes visited, box tests,
    /// triangles accessed, triangles after culling, triangle tests).
    pub fn from_status_words(words: &[u32]) -> Counters {
        Counters {
            nodes_visited: words[WORD_NODES_VISITED].into(),
            box_tests: words[WORD_BOX_TESTS].into(),
            triangles_accessed: words[WORD_TRIANGLES_ACCESSED].into(),
            triangles_after_culling: words[WORD_TRIANGLES_AFTER_CULLING].into(),
            triangle_tests: words[WORD_TRIANGLE_TESTS].into(),
            ..Counters::default()
        }
    }

    /// The counters a GPU kernel reports (it does not count loop iterations or suspensions).
    pub fn gpu_view(&self) -> Counters {
        Counters {
            traversal_steps: 0,
            suspensions: 0,
            ..*self
        }
    }
}

impl std::ops::AddAssign for Counters {
    fn add_assign(&mut self, o: Counters) {
        self.traversal_steps += o.traversal_steps;
        self.nodes_visited += o.nodes_visited;
        self.box_tests += o.box_tests;
        self.triangles_accessed += o.triangles_accessed;
        self.triangles_after_culling += o.triangles_after_culling;
        self.triangle_tests += o.triangle_tests;
        self.suspensions += o.suspensions;
    }
}
