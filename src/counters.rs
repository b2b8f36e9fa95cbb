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
//! | 1 | [`traversal_steps`](TraceCounters::traversal_steps) | inner nodes visited by the vector | inner nodes visited by the ray |
//! | 2 | [`box_tests`](TraceCounters::box_tests) | box vs all 16 frusta: 2 per inner node + 1 for the root | ray–box tests: 2 per inner node + 1 for the root |
//! | 3 | [`triangles_accessed`](TraceCounters::triangles_accessed) | triangles fetched by the vector (once per leaf visit) | triangles fetched by the ray |
//! | 4 | [`triangles_after_culling`](TraceCounters::triangles_after_culling) | of those, triangles at least one frustum did not cull | = word 3 (no culling) |
//! | 5 | [`triangle_tests`](TraceCounters::triangle_tests) | (triangle, frustum) pairs that survived culling: 16-ray tests | ray–triangle tests (= word 3) |
//!
//! Per-ray counts are scalar; comparing them with 16-wide ones (the paper's
//! "16-wide AABB tests" for a packet-less tracer) divides them by 16, which is
//! the reporting side's job. Words are `u32` and wrap past 2³²: at 1024×1024
//! a per-ray primary pass does ~10⁸ box tests, well below that.

/// Words of a kernel's status buffer (32 bytes).
pub const STATUS_WORDS: usize = 8;
/// Status word: the kernel's own report (primary kernels: pixels out of loop iterations).
pub const WORD_STATUS: usize = 0;
/// Status word of [`TraceCounters::traversal_steps`].
pub const WORD_TRAVERSAL_STEPS: usize = 1;
/// Status word of [`TraceCounters::box_tests`].
pub const WORD_BOX_TESTS: usize = 2;
/// Status word of [`TraceCounters::triangles_accessed`].
pub const WORD_TRIANGLES_ACCESSED: usize = 3;
/// Status word of [`TraceCounters::triangles_after_culling`].
pub const WORD_TRIANGLES_AFTER_CULLING: usize = 4;
/// Status word of [`TraceCounters::triangle_tests`].
pub const WORD_TRIANGLE_TESTS: usize = 5;

/// Work done by a tracing kernel (or its CPU twin); see the module docs for
/// what each count means for vector and per-ray kernels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceCounters {
    /// Inner nodes visited.
    pub traversal_steps: u64,
    /// Box tests: 16-wide for vector kernels, single rays for per-ray kernels.
    pub box_tests: u64,
    /// Triangles fetched at leaves.
    pub triangles_accessed: u64,
    /// Triangles fetched that at least one frustum did not cull.
    pub triangles_after_culling: u64,
    /// 16-ray tests (vector kernels) or ray–triangle tests (per-ray kernels).
    pub triangle_tests: u64,
}

impl TraceCounters {
    /// The counters in a status buffer read back from the GPU ([`STATUS_WORDS`] words).
    pub fn from_status(words: &[u32; STATUS_WORDS]) -> TraceCounters {
        TraceCounters {
            traversal_steps: u64::from(words[WORD_TRAVERSAL_STEPS]),
            box_tests: u64::from(words[WORD_BOX_TESTS]),
            triangles_accessed: u64::from(words[WORD_TRIANGLES_ACCESSED]),
            triangles_after_culling: u64::from(words[WORD_TRIANGLES_AFTER_CULLING]),
            triangle_tests: u64::from(words[WORD_TRIANGLE_TESTS]),
        }
    }
}

impl std::ops::AddAssign for TraceCounters {
    fn add_assign(&mut self, o: TraceCounters) {
        self.traversal_steps += o.traversal_steps;
        self.box_tests += o.box_tests;
        self.triangles_accessed += o.triangles_accessed;
        self.triangles_after_culling += o.triangles_after_culling;
        self.triangle_tests += o.triangle_tests;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_words_map_to_fields() {
        let c = TraceCounters::from_status(&[9, 1, 2, 3, 4, 5, 0, 0]);
        assert_eq!(
            c,
            TraceCounters {
                traversal_steps: 1,
                box_tests: 2,
                triangles_accessed: 3,
                triangles_after_culling: 4,
                triangle_tests: 5,
            }
        );
    }
}
