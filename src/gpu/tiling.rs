//! Images larger than one storage-buffer binding are rendered in square tiles with a
//! margin for the filter and pasted together: the tile geometry and the pasting.

use super::{Frame, ShadowStats};
use crate::contract::layout::GBufferTexel;

/// Bytes of the largest per-pixel buffer (the G-buffer).
const LARGEST_PIXEL_BYTES: u64 = size_of::<GBufferTexel>() as u64;
/// Margin around a tile, for the filter's window (reaches 2 pixels out; a multiple of 4: sample sets).
const TILE_MARGIN: u32 = 4;

/// The largest tile side (a multiple of 4) whose margined G-buffer fits `limit` bytes.
pub(super) fn tile_side(limit: u64) -> u32 {
    let side = ((limit / LARGEST_PIXEL_BYTES) as f64).sqrt() as u32;
    (side.saturating_sub(2 * TILE_MARGIN) / 4 * 4).max(4)
}

/// A tile: the pixels `[x, x + w) × [y, y + h)` rendered (margin included), of which
/// `[keep_x0, keep_x1) × [keep_y0, keep_y1)` (image coordinates) go into the image.
#[derive(Clone, Copy, Debug)]
pub(super) struct TileRegion {
    pub(super) x: u32,
    pub(super) y: u32,
    pub(super) w: u32,
    pub(super) h: u32,
    pub(super) keep_x0: u32,
    pub(super) keep_x1: u32,
    pub(super) keep_y0: u32,
    pub(super) keep_y1: u32,
}

/// Tiles of side `side` covering a `width`×`height` image, each with its margin.
pub(super) fn tile_regions(width: u32, height: u32, side: u32) -> Vec<TileRegion> {
    let mut out = Vec::new();
    for y0 in (0..height).step_by(side as usize) {
        for x0 in (0..width).step_by(side as usize) {
            let (x1, y1) = ((x0 + side).min(width), (y0 + side).min(height));
            let (rx, ry) = (x0.saturating_sub(TILE_MARGIN), y0.saturating_sub(TILE_MARGIN));
            let (rx1, ry1) = ((x1 + TILE_MARGIN).min(width), (y1 + TILE_MARGIN).min(height));
            out.push(TileRegion {
                x: rx,
                y: ry,
                w: rx1 - rx,
                h: ry1 - ry,
                keep_x0: x0,
                keep_x1: x1,
                keep_y0: y0,
                keep_y1: y1,
            });
        }
    }
    out
}

impl Frame {
    /// A `width`×`height` frame with nothing in it yet, to paste tiles into.
    pub(super) fn empty(width: u32, height: u32, keep_gbuffer: bool) -> Frame {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            masks: vec![0; n],
            unfiltered: vec![[0.0; 4]; n],
            filtered: vec![[0.0; 4]; n],
            refined: vec![false; n],
            brdf: vec![[0.0; 4]; n],
            gbuffer: keep_gbuffer.then(|| vec![GBufferTexel::default(); n]),
            timings: Vec::new(),
            shadow_stats: ShadowStats::default(),
            primary_counters: crate::contract::counters::Counters::default(),
            primary_fallback_pixels: 0,
        }
    }

    /// Copies the kept part of `tile` (rendered over `r`) into this frame, and adds
    /// its timings and statistics.
    pub(super) fn paste(&mut self, tile: &Frame, r: &TileRegion) {
        let (w, tw) = (self.width as usize, r.w as usize);
        for y in r.keep_y0..r.keep_y1 {
            let src = (y - r.y) as usize * tw + (r.keep_x0 - r.x) as usize;
            let dst = y as usize * w + r.keep_x0 as usize;
            let n = (r.keep_x1 - r.keep_x0) as usize;
            self.masks[dst..dst + n].copy_from_slice(&tile.masks[src..src + n]);
            self.unfiltered[dst..dst + n].copy_from_slice(&tile.unfiltered[src..src + n]);
            self.filtered[dst..dst + n].copy_from_slice(&tile.filtered[src..src + n]);
            self.refined[dst..dst + n].copy_from_slice(&tile.refined[src..src + n]);
            self.brdf[dst..dst + n].copy_from_slice(&tile.brdf[src..src + n]);
            if let (Some(g), Some(t)) = (self.gbuffer.as_mut(), tile.gbuffer.as_ref()) {
                g[dst..dst + n].copy_from_slice(&t[src..src + n]);
            }
        }
        self.timings.extend(tile.timings.iter().cloned());
        self.shadow_stats.dispatches += tile.shadow_stats.dispatches;
        self.shadow_stats.suspensions += tile.shadow_stats.suspensions;
        self.shadow_stats.counters += tile.shadow_stats.counters;
        self.primary_counters += tile.primary_counters;
        self.primary_fallback_pixels += tile.primary_fallback_pixels;
    }
}
