//! The ordered descent of a 16-wide vector into an inner node's children, shared
//! by the CPU twins of the vector kernels (twin of `shaders/shared/descend.wgsl`).

/// Where a vector goes from an inner node whose children `l` and `l + 1` the lanes
/// in `ml` and `mr` want.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Descent {
    /// The child to enter now and the lanes that enter it; `None`: pop the stack.
    pub now: Option<(u32, u32)>,
    /// The child to push for later and the lanes that want it.
    pub later: Option<(u32, u32)>,
}

/// Both children wanted: `right_first` picks the one entered now (the kernel's order
/// heuristic), the other waits; one child wanted: that one; none: pop.
pub fn descend(l: u32, ml: u32, mr: u32, right_first: bool) -> Descent {
    let (left, right) = ((l, ml), (l + 1, mr));
    match (ml != 0, mr != 0) {
        (true, true) if right_first => Descent {
            now: Some(right),
            later: Some(left),
        },
        (true, true) => Descent {
            now: Some(left),
            later: Some(right),
        },
        (true, false) => Descent {
            now: Some(left),
            later: None,
        },
        (false, true) => Descent {
            now: Some(right),
            later: None,
        },
        (false, false) => Descent {
            now: None,
            later: None,
        },
    }
}
