// How the refinement lays its listed pixels out as a sample image for the shadow tracer:
// each 4×4 tile of the image (row-major, `tiles_x` tiles per row) holds 16 / sets listed
// pixels: slot `first_slot + e` goes to tile e / (16 / sets), block j = e mod (16 / sets), and
// tile pixel t = x + 4 y, which traces sample set t, is a copy of its G-buffer texel when
// t / sets == j. A listed pixel traces sets j·sets .. (j + 1)·sets (16 sets: all 256 samples).
// Mirrors `RefineParams` in src/contract/layout.rs, 16 bytes; a naga test checks size and offsets.
struct RefineParams {
    tiles_x: u32,     // bytes 0..4: tiles per row of the sample image
    first_slot: u32,  // bytes 4..8: list slot of tile 0
    slots: u32,       // bytes 8..12: listed pixels in this sample image
    sets: u32,        // bytes 12..16: sample sets each listed pixel traces (1..=16)
}
