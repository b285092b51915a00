//! Nothing the user had is lost. For every file the command line writes (render PNG and EXR,
//! pass dumps and their manifest, bench JSON, the reference EXR and its preview):
//! - an existing file is not replaced without --force, and stays as it was;
//! - a write that fails part way (injected through `HYBRID_RT_FAIL_WRITE`, see
//!   src/image_io.rs: the temporary file is cut to half, then the write fails) leaves the old
//!   file as it was and no temporary file behind;
//! - a crash part way (the same hook with `:abort`; for an image and a JSON file) leaves the
//!   old file as it was: the new one only ever takes the name by a rename of the complete file;
//! - with --force the file is replaced by a complete, readable one.
//!
//! (A read-only folder would be the natural failure, but tests may run as root, which writes
//! there anyway; the hook fails the same code path on any machine.)

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn hybrid_rt(args: &[String], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hybrid-rt"));
    c.args(args);
    c.env_remove("HYBRID_RT_FAIL_WRITE");
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("run hybrid-rt")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

const OLD: &[u8] = b"the user's old file";

/// One file the program writes: the command that writes it (without --force) and a check that
/// a written file is complete.
struct Writer {
    what: &'static str,
    target: PathBuf,
    args: Vec<String>,
    complete: fn(&Path),
}

fn args(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

fn png_complete(p: &Path) {
    image::open(p).unwrap_or_else(|e| panic!("{}: not a readable PNG: {e}", p.display()));
}

fn exr_complete(p: &Path) {
    hybrid_rt::image_io::read_exr_channels(p).unwrap_or_else(|e| panic!("{}: not a readable EXR: {e:#}", p.display()));
}

fn json_complete(p: &Path) {
    let bytes = std::fs::read(p).unwrap();
    serde_json::from_slice::<serde_json::Value>(&bytes)
        .unwrap_or_else(|e| panic!("{}: not complete JSON: {e}", p.display()));
}

fn writers(dir: &Path) -> Vec<Writer> {
    let p = |name: &str| dir.join(name);
    let s = |path: &Path| path.to_str().unwrap().to_string();
    let scene = "builtin:gbuffer-test";
    let render = |out: &Path| {
        let mut a = args(&["render", scene, "--size", "8x8", "--backend", "compute", "--out"]);
        a.push(s(out));
        a
    };
    let dump = p("dump");
    let mut dump_args = render(&p("for-dump.png"));
    dump_args.extend(["--dump-passes".to_string(), s(&dump)]);
    let mut dumped_file_args = render(&p("for-dumped-file.png"));
    dumped_file_args.extend(["--dump-passes".to_string(), s(&p("dump2"))]);
    let reference = |out: &Path| {
        let mut a = args(&["reference", scene, "--size", "8x8", "--spp", "1", "--backend", "compute", "--out"]);
        a.push(s(out));
        a
    };
    let mut preview_args = reference(&p("for-preview.exr"));
    preview_args.extend(["--preview".to_string(), s(&p("preview.png"))]);
    let mut rays_args =
        args(&["bench", "rays", scene, "--size", "8x8", "--incoherent", "64", "--repeats", "1", "--backend"]);
    rays_args.extend(["compute".to_string(), "--out".to_string(), s(&p("rays.json"))]);
    let mut soak_args = args(&["bench", "soak", scene, "--size", "8x8", "--frames", "3", "--warmup", "1"]);
    soak_args.extend(["--every", "1", "--backend", "compute", "--out"].iter().map(|a| a.to_string()));
    soak_args.push(s(&p("soak.json")));
    vec![
        Writer { what: "render PNG", target: p("render.png"), args: render(&p("render.png")), complete: png_complete },
        Writer { what: "render EXR", target: p("render.exr"), args: render(&p("render.exr")), complete: exr_complete },
        Writer {
            what: "capture manifest",
            target: dump.join("manifest.json"),
            args: dump_args,
            complete: json_complete,
        },
        // A folder with no manifest that holds a file the capture would write.
        Writer {
            what: "captured image",
            target: p("dump2").join("tonemap.color.png"),
            args: dumped_file_args,
            complete: png_complete,
        },
        Writer { what: "reference EXR", target: p("ref.exr"), args: reference(&p("ref.exr")), complete: exr_complete },
        Writer { what: "reference preview", target: p("preview.png"), args: preview_args, complete: png_complete },
        Writer { what: "bench rays JSON", target: p("rays.json"), args: rays_args, complete: json_complete },
        Writer { what: "bench soak JSON", target: p("soak.json"), args: soak_args, complete: json_complete },
    ]
}

/// Temporary files (`.NAME.partial-PID.EXT`) left in `dir`.
fn partials(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".partial-"))
        .collect()
}

#[test]
fn no_file_is_replaced_silently_or_left_half_written() {
    let dir = common::temp_dir("nothing-lost");
    for w in writers(&dir) {
        let folder = w.target.parent().unwrap();
        std::fs::create_dir_all(folder).unwrap();
        std::fs::write(&w.target, OLD).unwrap();
        let intact = |when: &str| {
            assert_eq!(std::fs::read(&w.target).unwrap(), OLD, "{}: the old file changed {when}", w.what);
        };
        let name = w.target.file_name().unwrap().to_str().unwrap().to_string();
        let mut forced = w.args.clone();
        forced.push("--force".into());

        let refused = hybrid_rt(&w.args, &[]);
        assert!(!refused.status.success() && text(&refused).contains("--force"), "{}: {}", w.what, text(&refused));
        intact("when refused");

        let failed = hybrid_rt(&forced, &[("HYBRID_RT_FAIL_WRITE", &name)]);
        assert_eq!(failed.status.code(), Some(1), "{}: {}", w.what, text(&failed));
        assert!(text(&failed).contains("injected") && !text(&failed).contains("panicked"), "{}", text(&failed));
        intact("by a failed write");
        assert!(partials(folder).is_empty(), "{}: a failed write left {:?}", w.what, partials(folder));

        // Every writer goes through the same write_atomic (the failed write above shows it), so
        // a crash is simulated for two of them, an image and a JSON file.
        if matches!(w.what, "render PNG" | "capture manifest") {
            let crashed = hybrid_rt(&forced, &[("HYBRID_RT_FAIL_WRITE", &format!("{name}:abort"))]);
            assert_eq!(crashed.status.code(), None, "{}: the process should have died: {}", w.what, text(&crashed));
            intact("by a crash");
            // A crash cannot clean up: what it leaves is the hidden temporary name, never the
            // target.
            for leftover in partials(folder) {
                assert!(leftover.starts_with(&format!(".{name}.partial-")), "{}: {leftover}", w.what);
                std::fs::remove_file(folder.join(leftover)).unwrap();
            }
        }

        let replaced = hybrid_rt(&forced, &[]);
        assert!(replaced.status.success(), "{}: {}", w.what, text(&replaced));
        assert_ne!(std::fs::read(&w.target).unwrap(), OLD, "{}: --force must replace the file", w.what);
        (w.complete)(&w.target);
        assert!(partials(folder).is_empty(), "{}: {:?}", w.what, partials(folder));
    }
}
