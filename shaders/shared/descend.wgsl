// The ordered descent of a 16-wide vector into the children `l` and `l + 1` of an inner
// node, shared by the vector kernels (shadow_mft, shadow_packet, primary_mft).
// Twin: reference::descend.

// Where a vector goes from an inner node whose children the lanes in `ml` and `mr` want.
struct Descent {
    node: u32,        // the child to enter, when `mask` != 0
    mask: u32,        // the lanes that enter it; 0: no child is wanted, pop the stack
    later: u32,       // the child to push for later, when `later_mask` != 0
    later_mask: u32,  // the lanes that want it; 0: nothing to push
}

// Both children wanted: `right_first` picks the one entered now (the kernel's order
// heuristic), the other waits; one child wanted: that one; none: pop.
fn descend(l: u32, ml: u32, mr: u32, right_first: bool) -> Descent {
    if ml != 0u && mr != 0u {
        return Descent(
            select(l, l + 1u, right_first),
            select(ml, mr, right_first),
            select(l + 1u, l, right_first),
            select(mr, ml, right_first),
        );
    }
    if ml != 0u {
        return Descent(l, ml, 0u, 0u);
    }
    return Descent(l + 1u, mr, 0u, 0u);
}
