//! The figures `penumbra bench` reports (printed and as JSON) and their printing.

use penumbra::gpu::animate::AnimationReport;
use penumbra::reference::counters::Counters;
use serde::Serialize;

/// One tracer's figures in one case.
#[derive(Debug, Serialize)]
pub(super) struct TracerResult {
    pub(super) tracer: String,
    pub(super) shadow_ms: Vec<f64>,
    pub(super) shadow_ms_min: f64,
    pub(super) shadow_ms_median: f64,
    pub(super) mrays_per_s: f64,
    /// MFT's median speedup over this tracer (1 for MFT itself).
    pub(super) mft_speedup: f64,
    pub(super) counters: Option<Counters>,
}

/// A frame's passes (GPU ms, medians over the runs) and its wall time (ms, from the start
/// of `Renderer::render` to the frame read back).
#[derive(Debug, Serialize)]
pub(super) struct FrameResult {
    pub(super) primary_ms_median: f64,
    pub(super) shadow_ms_median: f64,
    pub(super) shade_ms_median: f64,
    pub(super) filter_ms_median: f64,
    pub(super) wall_ms: Vec<f64>,
    pub(super) wall_ms_min: f64,
    pub(super) wall_ms_median: f64,
    /// The same frame with `--refine`: the refinement's GPU ms (its select, gather,
    /// shadow and resolve dispatches), the frame's wall ms, and the pixels refined; `None`
    /// with `--no-refine`.
    pub(super) refine_ms_median: Option<f64>,
    pub(super) refined_wall_ms_median: Option<f64>,
    pub(super) refined_pixels: Option<usize>,
}

/// One primary tracer's figures in one case.
#[derive(Debug, Serialize)]
pub(super) struct PrimaryResult {
    pub(super) tracer: String,
    pub(super) primary_ms: Vec<f64>,
    pub(super) primary_ms_min: f64,
    pub(super) primary_ms_median: f64,
    /// MFT primary's median speedup over this tracer.
    pub(super) mft_speedup: f64,
    pub(super) counters: Option<Counters>,
    /// Pixels whose vectors ran out of loop iterations (MFT only); then it has no times.
    pub(super) ran_out_pixels: u32,
}

/// The moving-object case: CPU milliseconds per frame.
#[derive(Debug, Serialize)]
pub(super) struct AnimationResult {
    pub(super) instance: u32,
    pub(super) instance_triangles: usize,
    pub(super) frames: usize,
    pub(super) refit_frames: usize,
    pub(super) refit_ms_mean: f64,
    pub(super) rebuild_frames: usize,
    pub(super) rebuild_ms_mean: f64,
    pub(super) upload_ms_mean: f64,
    pub(super) bytes_per_frame_mean: f64,
}

impl AnimationResult {
    pub(super) fn of(r: &AnimationReport) -> AnimationResult {
        let mean = |v: Vec<f64>| {
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        let refits: Vec<f64> = r
            .frames
            .iter()
            .filter(|f| !f.update.rebuilt)
            .map(|f| f.update.bvh_ms)
            .collect();
        let rebuilds: Vec<f64> = r
            .frames
            .iter()
            .filter(|f| f.update.rebuilt)
            .map(|f| f.update.bvh_ms)
            .collect();
        AnimationResult {
            instance: r.instance,
            instance_triangles: r.instance_triangles,
            frames: r.frames.len(),
            refit_frames: refits.len(),
            refit_ms_mean: mean(refits),
            rebuild_frames: rebuilds.len(),
            rebuild_ms_mean: mean(rebuilds),
            upload_ms_mean: mean(r.frames.iter().map(|f| f.update.upload_ms).collect()),
            bytes_per_frame_mean: mean(r.frames.iter().map(|f| f.update.bytes_uploaded as f64).collect()),
        }
    }
}

/// One case's figures.
#[derive(Debug, Serialize)]
pub(super) struct CaseResult {
    pub(super) scene: String,
    pub(super) view: String,
    pub(super) triangles: usize,
    pub(super) leaf_size: u32,
    pub(super) bvh_nodes: usize,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) shadow_rays: u64,
    pub(super) primary_ms_median: f64,
    /// The whole frame as `render` makes it with MFT shadows (default settings: filter on,
    /// no refinement): every pass's GPU time and the wall time.
    pub(super) frame: FrameResult,
    pub(super) primary: Vec<PrimaryResult>,
    pub(super) tracers: Vec<TracerResult>,
    /// Embree's BVH build ms when it was benched (its times leave it out).
    pub(super) embree_build_ms: Option<f64>,
    /// The driver's BLAS + TLAS build ms (wall, with the wait) when ray-query was benched.
    pub(super) ray_query_build_ms: Option<f64>,
    /// The moving-object case, when the scene has an object to move.
    pub(super) animation: Option<AnimationResult>,
    /// Counter reductions of MFT against the packet tracer (packet / MFT).
    pub(super) reductions_vs_packet: Option<Reductions>,
}

/// Packet counts over MFT counts, as Table 1 reports them.
#[derive(Debug, Serialize)]
pub(super) struct Reductions {
    pub(super) triangles_accessed: f64,
    pub(super) triangles_after_culling: f64,
    pub(super) box_tests: f64,
    pub(super) triangle_tests: f64,
}

/// Everything a bench run measured.
#[derive(Debug, Serialize)]
pub(super) struct BenchReport {
    pub(super) adapter: String,
    pub(super) driver: String,
    pub(super) vector: String,
    pub(super) runs: u32,
    pub(super) cases: Vec<CaseResult>,
    /// The lights of each view file with several, added up ([`light_totals`]).
    pub(super) light_totals: Vec<LightTotal>,
}

/// The cases of one view file's lights (`FILE, light N`, same scene and leaf size) added
/// up: what a frame with all of them costs in shadow rays and each tracer's shadow time.
#[derive(Debug, Serialize)]
pub(super) struct LightTotal {
    pub(super) scene: String,
    pub(super) view: String,
    pub(super) leaf_size: u32,
    pub(super) lights: usize,
    pub(super) shadow_rays: u64,
    pub(super) tracers: Vec<TracerTotal>,
}

/// One tracer's sum over the lights of a [`LightTotal`].
#[derive(Debug, Serialize)]
pub(super) struct TracerTotal {
    pub(super) tracer: String,
    /// The sum of the lights' median shadow times.
    pub(super) shadow_ms_median: f64,
    pub(super) mrays_per_s: f64,
}

/// Groups the cases named `FILE, light N` by scene, file and leaf size (in the order they
/// first appear) and adds each group up; a tracer counts where every light of the group has it.
pub(super) fn light_totals(cases: &[CaseResult]) -> Vec<LightTotal> {
    // (scene, view file, leaf size) and the cases of its lights.
    type Group<'a> = ((&'a str, &'a str, u32), Vec<&'a CaseResult>);
    let mut groups: Vec<Group<'_>> = Vec::new();
    for c in cases {
        let Some((file, n)) = c.view.rsplit_once(", light ") else {
            continue;
        };
        if n.parse::<u32>().is_err() {
            continue;
        }
        let key = (c.scene.as_str(), file, c.leaf_size);
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, members)) => members.push(c),
            None => groups.push((key, vec![c])),
        }
    }
    groups
        .into_iter()
        .filter(|(_, members)| members.len() > 1)
        .map(|((scene, file, leaf_size), members)| {
            let shadow_rays = members.iter().map(|c| c.shadow_rays).sum();
            let tracers = members[0]
                .tracers
                .iter()
                .filter_map(|t| {
                    let times: Option<Vec<f64>> = members
                        .iter()
                        .map(|c| {
                            c.tracers
                                .iter()
                                .find(|u| u.tracer == t.tracer)
                                .map(|u| u.shadow_ms_median)
                        })
                        .collect();
                    let ms: f64 = times?.iter().sum();
                    Some(TracerTotal {
                        tracer: t.tracer.clone(),
                        shadow_ms_median: ms,
                        mrays_per_s: shadow_rays as f64 / (ms * 1e3),
                    })
                })
                .collect();
            LightTotal {
                scene: scene.to_owned(),
                view: file.to_owned(),
                leaf_size,
                lights: members.len(),
                shadow_rays,
                tracers,
            }
        })
        .collect()
}

/// One line per [`LightTotal`].
pub(super) fn print_light_total(t: &LightTotal) {
    let tracers: Vec<String> = t
        .tracers
        .iter()
        .map(|u| {
            format!(
                "{} {:.1} ms ({:.2} Mrays/s)",
                u.tracer, u.shadow_ms_median, u.mrays_per_s
            )
        })
        .collect();
    outln!();
    outln!(
        "{} — {}, all {} lights, leaf ≤ {} — {:.2} M shadow rays; shadow (sum of medians): {}",
        t.scene,
        t.view,
        t.lights,
        t.leaf_size,
        t.shadow_rays as f64 / 1e6,
        tracers.join(", ")
    );
}

pub(super) fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        (s[n / 2 - 1] + s[n / 2]) / 2.0
    }
}

pub(super) fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 { f64::NAN } else { a as f64 / b as f64 }
}

/// The cases to bench: the scenes named, or the built-ins plus the shared scenes found.
pub(super) fn print_case(r: &CaseResult) {
    outln!();
    outln!(
        "{} — {} — {} tris, leaf ≤ {}, {} nodes, {}x{}, {:.2} M shadow rays, primary {:.1} ms",
        r.scene,
        r.view,
        r.triangles,
        r.leaf_size,
        r.bvh_nodes,
        r.width,
        r.height,
        r.shadow_rays as f64 / 1e6,
        r.primary_ms_median
    );
    let f = &r.frame;
    outln!(
        "  frame (mft, filtered): primary {:.1} + shadow {:.1} + shade {:.1} + filter {:.1} ms GPU; \
         wall {:.1} ms min, {:.1} ms median (with readback)",
        f.primary_ms_median,
        f.shadow_ms_median,
        f.shade_ms_median,
        f.filter_ms_median,
        f.wall_ms_min,
        f.wall_ms_median
    );
    if let (Some(ms), Some(px), Some(wall)) = (f.refine_ms_median, f.refined_pixels, f.refined_wall_ms_median)
    {
        outln!("  refined frame (--refine): refinement {ms:.1} ms GPU at {px} px; wall {wall:.1} ms median");
    }
    outln!(
        "  {:<8} {:>10} {:>10} {:>8} {:>9} {:>11} {:>11} {:>11} {:>11}",
        "tracer",
        "min ms",
        "median ms",
        "Mrays/s",
        "MFT is",
        "tris",
        "+culling",
        "AABB tests",
        "tri tests"
    );
    for t in &r.tracers {
        let c = |f: fn(&Counters) -> u64| {
            t.counters
                .map_or("-".to_owned(), |c| format!("{:.0}K", f(&c) as f64 / 1e3))
        };
        outln!(
            "  {:<8} {:>10.1} {:>10.1} {:>8.2} {:>8.2}x {:>11} {:>11} {:>11} {:>11}",
            t.tracer,
            t.shadow_ms_min,
            t.shadow_ms_median,
            t.mrays_per_s,
            t.mft_speedup,
            c(|c| c.triangles_accessed),
            c(|c| c.triangles_after_culling),
            c(|c| c.box_tests),
            c(|c| c.triangle_tests),
        );
    }
    outln!(
        "  {:<8} {:>10} {:>10} {:>8} {:>9} {:>11} {:>11} {:>11} {:>11}",
        "primary",
        "min ms",
        "median ms",
        "",
        "MFT is",
        "tris",
        "+culling",
        "AABB tests",
        "tri tests"
    );
    for p in &r.primary {
        if p.ran_out_pixels > 0 {
            outln!(
                "  {:<8} the vectors of {} pixels ran out of loop iterations at this size (not timed)",
                p.tracer,
                p.ran_out_pixels
            );
            continue;
        }
        // Per-ray counts are single-ray tests; Table 1 compares 16-wide ones.
        let scale = if p.tracer == "mft" { 1.0 } else { 16.0 };
        let c = |f: fn(&Counters) -> u64| {
            p.counters
                .map_or("-".to_owned(), |c| format!("{:.0}K", f(&c) as f64 / scale / 1e3))
        };
        outln!(
            "  {:<8} {:>10.1} {:>10.1} {:>8} {:>8.2}x {:>11} {:>11} {:>11} {:>11}",
            p.tracer,
            p.primary_ms_min,
            p.primary_ms_median,
            "",
            p.mft_speedup,
            c(|c| c.triangles_accessed),
            c(|c| c.triangles_after_culling),
            c(|c| c.box_tests),
            c(|c| c.triangle_tests),
        );
    }
    outln!("  (per-ray primary counts shown /16, as 16-wide equivalents)");
    if let Some(a) = &r.animation {
        outln!(
            "  moving instance {} ({} tris), {} frames: refit {} x {:.3} ms, rebuild {} x {:.2} ms, \
             upload {:.3} ms and {:.0} KB per frame (CPU)",
            a.instance,
            a.instance_triangles,
            a.frames,
            a.refit_frames,
            a.refit_ms_mean,
            a.rebuild_frames,
            a.rebuild_ms_mean,
            a.upload_ms_mean,
            a.bytes_per_frame_mean / 1e3
        );
    }
    if let Some(red) = &r.reductions_vs_packet {
        outln!(
            "  packet/MFT: tris {:.2}x, +culling {:.2}x, AABB tests {:.2}x, triangle tests {:.2}x",
            red.triangles_accessed,
            red.triangles_after_culling,
            red.box_tests,
            red.triangle_tests
        );
    }
}
