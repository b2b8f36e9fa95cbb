//! A rendered frame as the standalone renderer returns it: read back to the CPU, with its
//! timings and statistics.

use super::ShadowStats;
use crate::contract::layout::{GBufferTexel, MASK_SKY};

/// Light the image gets besides the traced quad lights, so that what they do not reach is
/// dark rather than black: an unshadowed ambient term and a background. It changes only
/// [`Frame::image`], never the visibility or the masks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ambient {
    /// Radiance of a uniform sky that every surface sees unoccluded (no ambient occlusion:
    /// it brightens shadows evenly); 0 turns it off.
    pub radiance: f32,
    /// Linear RGB radiance of pixels that see no geometry.
    pub background: [f32; 3],
}

impl Ambient {
    /// No ambient light, black background: the traced light alone.
    pub const NONE: Ambient = Ambient {
        radiance: 0.0,
        background: [0.0; 3],
    };
    /// The CLI's default radiance: with exposure 1 an unlit white surface shows as sRGB ≈ 0.24.
    pub const DEFAULT_RADIANCE: f32 = 0.05;
    /// The CLI's default background: a dark blue-grey (sRGB ≈ 0.19, 0.19, 0.22 at exposure 1).
    pub const DEFAULT_BACKGROUND: [f32; 3] = [0.03, 0.03, 0.04];
}

impl Default for Ambient {
    /// [`Ambient::DEFAULT_RADIANCE`] and [`Ambient::DEFAULT_BACKGROUND`].
    fn default() -> Ambient {
        Ambient {
            radiance: Ambient::DEFAULT_RADIANCE,
            background: Ambient::DEFAULT_BACKGROUND,
        }
    }
}

/// A rendered frame, read back to the CPU (row-major, row 0 at the top).
#[derive(Clone, Debug)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Shadow masks: bit j = ray j blocked; `1 << 16` marks sky pixels.
    pub masks: Vec<u32>,
    /// Shadowed irradiance (rgb) and visibility (a) before the filter.
    pub unfiltered: Vec<[f32; 4]>,
    /// The same after the filter (equal to `unfiltered` when the filter is off), and
    /// after the refinement at the refined pixels.
    pub filtered: Vec<[f32; 4]>,
    /// Per pixel, whether the refinement traced its 256 light samples (all false
    /// without [`super::FrameSettings::refine`]).
    pub refined: Vec<bool>,
    /// Diffuse BRDF, albedo / π (rgb; a unused); 0 for sky pixels.
    pub brdf: Vec<[f32; 4]>,
    /// The G-buffer, when [`super::FrameSettings::keep_gbuffer`] asked for it; positions are
    /// relative to [`GpuScene::origin`](crate::gpu::GpuScene::origin) (the world's for a scene
    /// near the origin).
    pub gbuffer: Option<Vec<GBufferTexel>>,
    /// GPU milliseconds per pass: `primary`, `shadow` (all its dispatches), `shade`, `filter`.
    pub timings: Vec<(String, f64)>,
    /// Dispatches and suspensions of the shadow pass.
    pub shadow_stats: ShadowStats,
    /// Work counted by the primary kernel (zero unless built with
    /// [`super::RendererOptions::counters`]).
    pub primary_counters: crate::contract::counters::Counters,
    /// Pixels whose multi-frusta primary vectors ran out of loop iterations, after which
    /// the per-ray kernel traced the frame's camera rays again (0: it did not happen).
    pub primary_fallback_pixels: u32,
}

impl Frame {
    /// Outgoing radiance per pixel: BRDF × filtered irradiance (the image).
    pub fn radiance(&self) -> Vec<[f32; 3]> {
        self.brdf
            .iter()
            .zip(&self.filtered)
            .map(|(b, e)| [b[0] * e[0], b[1] * e[1], b[2] * e[2]])
            .collect()
    }

    /// The image with light the shadow pass does not trace: BRDF × (filtered irradiance +
    /// π · `ambient.radiance`) where the pixel sees geometry (a uniform, unshadowed sky of
    /// that radiance: a surface reflects albedo × it), `ambient.background` where it
    /// does not. With [`Ambient::NONE`] this is [`Frame::radiance`].
    pub fn image(&self, ambient: &Ambient) -> Vec<[f32; 3]> {
        image_of_lights(std::slice::from_ref(self), ambient)
    }

    /// GPU milliseconds of the pass `name`, summed over its dispatches (0 when not timed).
    pub fn pass_ms(&self, name: &str) -> f64 {
        self.timed_ms(name).unwrap_or(0.0)
    }

    /// [`Frame::pass_ms`], or `None` when no dispatch of `name` was timed (the adapter has
    /// no timestamp queries, or the pass did not run).
    pub fn timed_ms(&self, name: &str) -> Option<f64> {
        let mut times = self.timings.iter().filter(|(n, _)| n == name).peekable();
        times.peek()?;
        Some(times.map(|(_, ms)| ms).sum())
    }
}

/// The image of several lights ([`super::Renderer::render_lights`]: one frame per light,
/// one G-buffer): BRDF × (the sum of the lights' filtered irradiance + π ·
/// `ambient.radiance`) where the pixel sees geometry, `ambient.background` where it does
/// not; the ambient counts once. For one frame this is [`Frame::image`].
///
/// Panics when `frames` is empty or the frames differ in size (a bug of the caller's).
pub fn image_of_lights(frames: &[Frame], ambient: &Ambient) -> Vec<[f32; 3]> {
    let first = &frames[0];
    assert!(
        frames.iter().all(|f| f.filtered.len() == first.filtered.len()),
        "image_of_lights: frames of different sizes"
    );
    let sky = std::f32::consts::PI * ambient.radiance;
    (0..first.brdf.len())
        .map(|i| {
            if first.masks[i] & MASK_SKY != 0 {
                return ambient.background;
            }
            let mut e = [0.0f32; 3];
            for f in frames {
                for (c, v) in e.iter_mut().zip(&f.filtered[i]) {
                    *c += v;
                }
            }
            let b = first.brdf[i];
            [b[0] * (e[0] + sky), b[1] * (e[1] + sky), b[2] * (e[2] + sky)]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::ToneMap;

    fn frame() -> Frame {
        Frame {
            width: 2,
            height: 1,
            masks: vec![0xff, MASK_SKY],
            unfiltered: vec![[0.5, 1.0, 2.0, 0.5]; 2],
            filtered: vec![[0.5, 1.0, 2.0, 0.5]; 2],
            refined: vec![false; 2],
            brdf: vec![[0.2, 0.1, 0.3, 0.0], [0.0; 4]],
            gbuffer: None,
            timings: Vec::new(),
            shadow_stats: ShadowStats::default(),
            primary_counters: crate::contract::counters::Counters::default(),
            primary_fallback_pixels: 0,
        }
    }

    #[test]
    fn the_image_adds_ambient_to_surfaces_and_background_to_the_sky() {
        let f = frame();
        assert_eq!(f.image(&Ambient::NONE), f.radiance());
        let a = Ambient {
            radiance: 0.5,
            background: [0.1, 0.2, 0.3],
        };
        let img = f.image(&a);
        let sky = std::f32::consts::PI * 0.5;
        assert_eq!(img[0], [0.2 * (0.5 + sky), 0.1 * (1.0 + sky), 0.3 * (2.0 + sky)]);
        assert_eq!(img[1], [0.1, 0.2, 0.3]);
    }

    #[test]
    fn the_image_of_two_lights_sums_their_irradiance_and_adds_ambient_once() {
        let a = frame();
        let mut b = frame();
        b.filtered[0] = [0.25, 0.5, 0.125, 0.75];
        let ambient = Ambient {
            radiance: 0.5,
            background: [0.1, 0.2, 0.3],
        };
        let img = image_of_lights(&[a.clone(), b], &ambient);
        let sky = std::f32::consts::PI * 0.5;
        // Sums of dyadic fractions: exact in f32.
        assert_eq!(img[0][0], 0.2 * (0.75 + sky));
        assert_eq!(img[0][1], 0.1 * (1.5 + sky));
        assert_eq!(img[0][2], 0.3 * (2.125 + sky));
        assert_eq!(img[1], [0.1, 0.2, 0.3]);
        assert_eq!(
            image_of_lights(std::slice::from_ref(&a), &ambient),
            a.image(&ambient)
        );
    }

    #[test]
    fn default_ambient_shows_as_documented() {
        // A white surface (BRDF 1/π) with no direct light reflects exactly the ambient radiance.
        let tone = ToneMap::default();
        let white = (1.0 / std::f32::consts::PI) * (std::f32::consts::PI * Ambient::DEFAULT_RADIANCE);
        assert_eq!(tone.apply(white), 62, "sRGB ≈ 0.24");
        assert_eq!(
            tone.apply_rgb(Ambient::DEFAULT_BACKGROUND),
            [48, 48, 56],
            "sRGB ≈ 0.19, 0.19, 0.22"
        );
    }
}
