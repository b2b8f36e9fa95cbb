// How the refinement lays its listed pixels out as a sample image for the shadow tracer:
// listed pixel `first_slot + s` becomes 4×4 tile s of the image (row-major, `tiles_x` tiles
// per row), every pixel of the tile a copy of its G-buffer texel, so that pixel (x, y) of
// the tile traces sample set (x mod 4) + 4 (y mod 4): the tile traces all 256 samples.
// Mirrors `RefineParams` in src/contract/layout.rs, 16 bytes; a naga test checks size and offsets.
struct RefineParams {
    tiles_x: u32,     // bytes 0..4: tiles per row of the sample image
    first_slot: u32,  // bytes 4..8: list slot of tile 0
    slots: u32,       // bytes 8..12: listed pixels in this sample image
    pad: u32,         // bytes 12..16
}
