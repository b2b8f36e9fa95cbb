//! Work counters of the traversal kernels, counted as Table 1 of the MFT paper
//! counts them, shared by the CPU twins and the GPU kernels' counter words.

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

/// The GPU kernels' status words: `[0]` is the kernel's own status (suspended
/// tiles, failed rays); the counters follow when the kernel's `COUNTERS`
/// override is on.
pub const STATUS_WORDS: usize = 8;

impl Counters {
    /// The counters from a kernel's status words (`words[1..6]`: nodes visited, box tests,
    /// triangles accessed, triangles after culling, triangle tests).
    pub fn from_status_words(words: &[u32]) -> Counters {
        Counters {
            nodes_visited: words[1].into(),
            box_tests: words[2].into(),
            triangles_accessed: words[3].into(),
            triangles_after_culling: words[4].into(),
            triangle_tests: words[5].into(),
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
