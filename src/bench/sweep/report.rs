//! A sweep as a table for the terminal.

use super::{Config, Point, SceneSweep};

/// The path tracer's HDR-FLIP after `ms` of rendering, interpolated on its curve (log-log,
/// where error and time follow a power law); None outside the measured times.
pub fn path_tracer_flip_at(s: &SceneSweep, ms: f64) -> Option<f64> {
    let pts = &s.path_tracer;
    let first = pts.first()?;
    if ms < first.ms {
        return None;
    }
    if ms == first.ms {
        return Some(first.flip);
    }
    pts.windows(2).find(|w| w[0].ms <= ms && ms <= w[1].ms).map(|w| {
        let t = (ms.ln() - w[0].ms.ln()) / (w[1].ms.ln() - w[0].ms.ln());
        (w[0].flip.ln() + t * (w[1].flip.ln() - w[0].flip.ln())).exp()
    })
}

/// Where the reference's own noise (FLIP between its two halves) is at least half the smallest
/// error the table compares, its noise decides the comparisons as much as the images do: a
/// smooth frame and a noisy path-traced one both measure the reference's grain. Measured on the
/// default scene at 256x256: against 256 spp (noise 0.124) the hybrid frame read level with the
/// path tracer at equal time (1.02x), against 8192 spp (noise 0.043) 0.93x.
fn reference_noise_note(s: &SceneSweep) -> Option<String> {
    let noise = s.reference.made.noise_flip;
    let compared = s
        .points
        .iter()
        .flat_map(|p| [Some(p.flip), path_tracer_flip_at(s, s.frames as f64 * p.frame_ms)])
        .flatten()
        .fold(f64::INFINITY, f64::min);
    (compared.is_finite() && noise >= 0.5 * compared).then(|| {
        format!(
            "  note: the reference's own noise (FLIP {noise:.4} between its halves) is at least half the smallest \
             error compared here ({compared:.4}), so it weighs in every comparison; a reference with more \
             samples (--reference-spp; one made on a faster device serves through --cache-dir) would resolve them\n"
        )
    })
}

/// A table of a sweep's points for the terminal; `*` marks the Pareto front.
pub fn table(s: &SceneSweep) -> String {
    let mut t = format!(
        "{} ({}x{}, {} backend, {} frames, seed {}, {} timing round(s), reference {} spp{}; reference noise FLIP {:.4})\n",
        s.scene_name,
        s.width,
        s.height,
        s.backend,
        s.frames,
        s.seed,
        s.rounds.max(1),
        s.reference.made.spp,
        match (s.reference.cached, s.reference.made.device != s.device) {
            // A reference does not depend on the device (the backends agree hit for hit), but
            // the reader should know where it came from.
            (true, true) =>
                format!(", cached, made on {} ({} backend)", s.reference.made.device, s.reference.made.backend),
            (true, false) => ", cached".to_string(),
            _ => String::new(),
        },
        s.reference.made.noise_flip
    );
    t += &format!(
        "  {:<18} {:>9} {:>9} {:>8} {:>7} {:>9} {:>7} {:>14} {:>9} {:>10}\n",
        "configuration",
        "frame ms",
        "stamp ms",
        "FLIP",
        "energy",
        "PSNR dB",
        "SSIM",
        "PT FLIP @time",
        "FLIP cut",
        "FLIP first"
    );
    let mut order: Vec<&Point> = s.points.iter().collect();
    order.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
    for p in order {
        let psnr = p.psnr_db.map_or("inf".to_string(), |v| format!("{v:.2}"));
        let pt = path_tracer_flip_at(s, s.frames as f64 * p.frame_ms).map_or("-".to_string(), |f| format!("{f:.4}"));
        let cut = p.cut_flip.map_or("-".to_string(), |f| format!("{f:.4}"));
        let first = p.first_flip.map_or("-".to_string(), |f| format!("{f:.4}"));
        let energy = p.luminance_ratio.map_or("-".to_string(), |e| format!("{e:.4}"));
        t += &format!(
            "{} {:<18} {:>9.2} {:>9.2} {:>8.4} {:>7} {:>9} {:>7.4} {:>14} {:>9} {:>10}\n",
            if p.pareto { "*" } else { " " },
            p.name,
            p.frame_ms,
            p.timestamp_ms,
            p.flip,
            energy,
            psnr,
            p.ssim,
            pt,
            cut,
            first
        );
    }
    if !s.path_tracer.is_empty() {
        t += &format!(
            "  PT FLIP @time: the path tracer's error after the time {} frames of the configuration took \
             (static camera; '-' beyond its curve)\n  energy: the last frame's mean luminance over the reference's, lights seen directly left \
             out\n  FLIP cut: the frame after a camera cut at the end of \
             the run (no SVGF or TAA history; the radiance cache keeps its cells)\n  FLIP first: the run's \
             first frame (no history, an empty radiance cache)\n  path tracer \
             (progressive, same reference):\n",
            s.frames
        );
        for p in &s.path_tracer {
            t += &format!("    {:>5} spp {:>10.2} ms  FLIP {:.4}\n", p.spp, p.ms, p.flip);
        }
        let default = Config::default();
        if let (Some(one), Some(d)) = (s.path_tracer.first(), s.points.iter().find(|p| p.config == default)) {
            t += &format!(
                "  one frame of {} costs {:.2} ms, {:.2}x one path-traced sample per pixel ({:.2} ms)\n",
                d.name,
                d.frame_ms,
                d.frame_ms / one.ms * one.spp as f64,
                one.ms / one.spp as f64
            );
            if let (Some(cut), 1) = (d.cut_flip, one.spp) {
                t += &format!(
                    "  the first frame of {} after a camera cut: FLIP {:.4}, {:.2}x the path tracer's at 1 spp ({:.4})\n",
                    d.name,
                    cut,
                    cut / one.flip,
                    one.flip
                );
            }
            if let (Some(first), 1) = (d.first_flip, one.spp) {
                t += &format!(
                    "  the very first frame of {} (empty cache too): FLIP {:.4}, {:.2}x the path tracer's at 1 spp\n",
                    d.name,
                    first,
                    first / one.flip
                );
            }
        }
    }
    if let Some(note) = reference_noise_note(s) {
        t += &note;
    }
    for full in s.points.iter().filter(|p| p.config.full) {
        let planned = Config { full: false, ..full.config };
        if let Some(p) = s.points.iter().find(|p| p.config == planned) {
            let pass_names = |x: &Point| x.passes.iter().map(|m| m.pass.clone()).collect::<Vec<_>>();
            // Where the plan leaves nothing out the two run the same passes, and any
            // difference is the machine's noise.
            let note = if pass_names(p) == pass_names(full) {
                " (the plan leaves nothing out on this scene: the same passes ran, so this is noise)"
            } else {
                ""
            };
            t += &format!(
                "  frame plan ({}) against every pass ({}): {:+.1}% frame time, FLIP {:+.4}{note}\n",
                p.name,
                full.name,
                100.0 * (p.frame_ms / full.frame_ms - 1.0),
                p.flip - full.flip
            );
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::sweep::testing::sweep;

    #[test]
    fn the_first_frame_after_a_cut_is_set_against_one_path_traced_sample() {
        let mut s = sweep(&[("d0-s3-b1-r1", 10.0, 0.3, true), ("d4-s3-b1-r1", 12.0, 0.1, true)]);
        s.points[1].cut_flip = Some(0.2);
        s.points[1].first_flip = Some(0.25);
        s.points[1].luminance_ratio = Some(0.9812);
        let t = table(&s);
        assert!(t.contains("FLIP cut") && t.contains("FLIP first") && t.contains("energy"), "{t}");
        assert!(t.lines().any(|l| l.contains("d4-s3-b1-r1") && l.contains(" 0.9812 ")), "{t}");
        let row = t.lines().find(|l| l.contains("d4-s3-b1-r1") && l.contains("0.1000")).expect("the default's row");
        assert!(row.trim_end().ends_with("0.2000     0.2500"), "{row}");
        // A point measured without a cut shows none.
        let row = t.lines().find(|l| l.contains("d0-s3-b1-r1")).expect("the other row");
        assert!(row.trim_end().ends_with('-'), "{row}");
        assert!(t.contains("after a camera cut: FLIP 0.2000, 0.40x the path tracer's at 1 spp (0.5000)"), "{t}");
        assert!(t.contains("(empty cache too): FLIP 0.2500, 0.50x the path tracer's at 1 spp"), "{t}");
    }

    #[test]
    fn a_reference_as_noisy_as_the_errors_is_called_out() {
        let mut s = sweep(&[("d4-s3-b1-r1", 12.0, 0.1, true)]);
        assert!(!table(&s).contains("note: the reference's own noise"), "{}", table(&s));
        s.reference.made.noise_flip = 0.06;
        let t = table(&s);
        assert!(t.contains("note: the reference's own noise (FLIP 0.0600 between its halves)"), "{t}");
        assert!(t.contains("smallest error compared here (0.1000)"), "{t}");
    }

    #[test]
    fn a_cached_reference_from_another_device_says_where_it_was_made() {
        let mut s = sweep(&[("d4-s3-b1-r1", 12.0, 0.1, true)]);
        s.reference.cached = true;
        s.reference.made.device = "NVIDIA H200".into();
        assert!(table(&s).contains("cached, made on NVIDIA H200 (compute backend)"), "{}", table(&s));
        s.reference.made.device = s.device.clone();
        assert!(!table(&s).contains("made on"), "{}", table(&s));
    }
}
