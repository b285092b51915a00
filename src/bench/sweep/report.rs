//! A sweep as a table for the terminal.

use super::{Config, Point, SceneSweep};

/// A table of a sweep's points for the terminal; `*` marks the Pareto front.
pub fn table(s: &SceneSweep) -> String {
    let mut t = format!(
        "{} ({}x{}, {} backend, {} frames, {} timing round(s), reference {} spp{}; reference noise FLIP {:.4})\n",
        s.scene_name,
        s.width,
        s.height,
        s.backend,
        s.frames,
        s.rounds.max(1),
        s.reference.made.spp,
        if s.reference.cached { ", cached" } else { "" },
        s.reference.made.noise_flip
    );
    t += &format!(
        "  {:<16} {:>9} {:>9} {:>8} {:>9} {:>7}\n",
        "configuration", "frame ms", "stamp ms", "FLIP", "PSNR dB", "SSIM"
    );
    let mut order: Vec<&Point> = s.points.iter().collect();
    order.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
    for p in order {
        let psnr = p.psnr_db.map_or("inf".to_string(), |v| format!("{v:.2}"));
        t += &format!(
            "{} {:<16} {:>9.2} {:>9.2} {:>8.4} {:>9} {:>7.4}\n",
            if p.pareto { "*" } else { " " },
            p.name,
            p.frame_ms,
            p.timestamp_ms,
            p.flip,
            psnr,
            p.ssim
        );
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
