//! The viewer in a real window: a virtual X server (Xvfb), lavapipe (or whatever Vulkan device
//! there is), the validation layer on. A script renders frames, switches the shown output and
//! saves screenshots read back from the swapchain; they must equal the headless `render` of the
//! same frame (the tonemapped PNG, and the capture's preview PNG of a pass output).
//!
//! Without Xvfb the tests skip with a note, or fail under CI=true.

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};

/// A private X server on a display number it picks itself; killed on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Option<Self> {
        let spawned = Command::new("Xvfb")
            // -displayfd: Xvfb chooses a free display and writes its number to fd 1, so tests
            // running at once never collide.
            .args(["-displayfd", "1", "-screen", "0", "640x480x24", "-nolisten", "tcp"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn();
        let mut child = match spawned {
            Ok(c) => c,
            Err(e) => return unavailable(&format!("cannot start Xvfb ({e}); tools/setup.sh installs it")),
        };
        let mut line = String::new();
        let read = BufReader::new(child.stdout.take().expect("piped")).read_line(&mut line);
        match (read, line.trim().parse::<u32>()) {
            (Ok(_), Ok(n)) => Some(Self { child, display: format!(":{n}") }),
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                unavailable("Xvfb started but reported no display")
            }
        }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// No X server: a failure under CI, a skip elsewhere.
fn unavailable(why: &str) -> Option<Xvfb> {
    if std::env::var("CI").as_deref() == Ok("true") {
        panic!("{why}: CI must be able to run the window test");
    }
    eprintln!("skipping: {why} (set CI=true to make this a failure)");
    None
}

fn hybrid_rt(args: &[&str], display: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
    c.args(args);
    match display {
        Some(d) => c.env("DISPLAY", d),
        None => c.env_remove("DISPLAY"),
    };
    // The window is X11; a Wayland session beside it must not be picked instead.
    c.env_remove("WAYLAND_DISPLAY");
    c.output().expect("run hybrid-rt")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn rgba(path: &Path) -> (u32, u32, Vec<u8>) {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgba8();
    (img.width(), img.height(), img.into_raw())
}

/// Mean absolute difference over the RGB channels, in 8-bit steps, and the largest one.
fn difference(a: &Path, b: &Path) -> (f64, u8) {
    let (wa, ha, pa) = rgba(a);
    let (wb, hb, pb) = rgba(b);
    assert_eq!((wa, ha), (wb, hb), "{} and {} differ in size", a.display(), b.display());
    let (mut sum, mut max, mut n) = (0u64, 0u8, 0u64);
    for (x, y) in pa.chunks_exact(4).zip(pb.chunks_exact(4)) {
        for c in 0..3 {
            let d = x[c].abs_diff(y[c]);
            sum += d as u64;
            max = max.max(d);
            n += 1;
        }
    }
    (sum as f64 / n as f64, max)
}

/// Distinct colours: a blank or uniform screenshot would make any comparison meaningless.
fn distinct_colours(path: &Path) -> usize {
    let (_, _, p) = rgba(path);
    p.chunks_exact(4).map(|c| [c[0], c[1], c[2]]).collect::<std::collections::HashSet<_>>().len()
}

const SIZE: &str = "320x240";
const FRAMES: &str = "8";

#[test]
fn scripted_window_matches_the_headless_render() {
    let Some(x) = Xvfb::start() else { return };
    let dir = common::temp_dir("viewer");
    let (render_png, dump) = (dir.join("render.png"), dir.join("dump"));
    let o = hybrid_rt(
        &[
            "render",
            "--size",
            SIZE,
            "--frames",
            FRAMES,
            "--validate",
            "--out",
            render_png.to_str().unwrap(),
            "--dump-passes",
            dump.to_str().unwrap(),
        ],
        None,
    );
    assert!(o.status.success(), "headless render: {}", text(&o));

    let (shot_color, shot_normal, shot_ids) =
        (dir.join("shot_color.png"), dir.join("shot_normal.png"), dir.join("shot_ids.png"));
    let script = format!(
        "frames={FRAMES}, screenshot={}, view=gbuffer.normal, screenshot={}, view=gbuffer.ids, screenshot={}, quit",
        shot_color.display(),
        shot_normal.display(),
        shot_ids.display()
    );
    let o = hybrid_rt(&["view", "--size", SIZE, "--validate", "--script", &script], Some(&x.display));
    assert!(o.status.success(), "viewer: {}", text(&o));

    // The G-buffer is deterministic: its previews must match exactly. The colour goes through
    // the stochastic passes, whose statistics images sum with atomics in no fixed order: a
    // tenth of an 8-bit step on average is allowed there (measured: 0, exact).
    for (shot, headless, allowed) in [
        (&shot_color, render_png.clone(), 0.1),
        (&shot_normal, dump.join("gbuffer.normal.png"), 0.0),
        (&shot_ids, dump.join("gbuffer.ids.png"), 0.0),
    ] {
        let (mean, max) = difference(shot, &headless);
        println!("{} vs {}: mean |difference| {mean:.4}, max {max} (8-bit steps)", shot.display(), headless.display());
        assert!(mean <= allowed, "{} differs from {}: mean {mean}, max {max}", shot.display(), headless.display());
        assert!(distinct_colours(shot) > 8, "{} is nearly uniform", shot.display());
    }
    // The view switch took effect: the outputs look nothing alike.
    let (mean, _) = difference(&shot_color, &shot_normal);
    assert!(mean > 10.0, "the colour and normal screenshots are alike (mean difference {mean})");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
#[cfg_attr(
    not(feature = "shader-compiler"),
    ignore = "compiles GLSL at run time: needs --features shader-compiler (tools/test.sh)"
)]
fn a_broken_shader_keeps_the_old_pipelines() {
    let Some(x) = Xvfb::start() else { return };
    let dir = common::temp_dir("viewer-reload");
    let shaders = dir.join("shaders-glsl");
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders-glsl"), &shaders);
    let tonemap = shaders.join("tonemap.comp");
    let broken = std::fs::read_to_string(&tonemap).unwrap().replace("void main() {", "void main() { undefined_call();");
    std::fs::write(&tonemap, broken).unwrap();
    let (after, headless) = (dir.join("after.png"), dir.join("headless.png"));
    let script = format!("frames=2, reload, frames=1, screenshot={}, quit", after.display());
    let o = hybrid_rt(
        &[
            "view",
            "--size",
            "64x48",
            "--validate",
            "--no-taa",
            "--watch-shaders",
            shaders.to_str().unwrap(),
            "--script",
            &script,
        ],
        Some(&x.display),
    );
    let out = text(&o);
    assert!(o.status.success(), "viewer: {out}");
    assert!(
        out.contains("shader reload failed") && out.contains("tonemap.comp") && out.contains("undefined_call"),
        "the compile error names the file and the problem: {out}"
    );
    // Still drawing with the previous (embedded) shaders: the third frame is the headless
    // render's third frame.
    let o = hybrid_rt(
        &["render", "--size", "64x48", "--frames", "3", "--no-taa", "--validate", "--out", headless.to_str().unwrap()],
        None,
    );
    assert!(o.status.success(), "headless render: {}", text(&o));
    let (mean, max) = difference(&after, &headless);
    println!("after a failed reload vs headless: mean |difference| {mean:.4}, max {max}");
    assert!(mean <= 0.1, "the frame after a failed reload differs from the headless one (mean {mean}, max {max})");
    assert!(distinct_colours(&after) > 8, "the frame after the failed reload is blank");
    let _ = std::fs::remove_dir_all(&dir);
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let target = to.join(e.file_name());
        if e.path().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}
