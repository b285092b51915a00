//! Deterministic mutation fuzzing of the glTF loader: hostile scene files must fail cleanly.
//!
//! Seeds are every .gltf/.glb under ../shared/scenes, the default Cornell box and the committed
//! corpus in tests/corpus/gltf. Each case applies one to three random mutations to a seed (byte
//! flips, truncation, GLB chunk edits, JSON-aware edits such as extreme numbers, deleted keys,
//! duplicated arrays, deep nesting, odd `data:` URIs, node cycles and one big accessor referenced
//! from many places) and loads the result from memory with `load_gltf_bytes`, under the seed's
//! own path so that its external buffers and images resolve.
//!
//! The loader must answer Ok or Err. The test fails when a case panics, when one load takes
//! longer than `CASE_TIME_LIMIT`, or when the process's peak resident memory (VmHWM) exceeds
//! `MEMORY_BOUND_MIB`; each failing input is written to `CARGO_TARGET_TMPDIR/fuzz-failures` so it
//! can be replayed and added to the corpus. fuzz/README.md describes the coverage-guided
//! cargo-fuzz target that complements this harness.
//!
//! `HYBRID_RT_FUZZ_CASES` sets the number of mutated cases (default `DEFAULT_CASES`: about 30
//! cases/s in the dev profile on two idle cores, so 35 s) and `HYBRID_RT_FUZZ_SEED` the random
//! seed (default 1): the same pair always runs the same cases.

use base64::Engine;
use hybrid_rt::scene::{Limits, LoadOptions, Scene, SceneError, load_gltf_bytes};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc;
use std::time::{Duration, Instant};

const DEFAULT_CASES: u64 = 1000;

/// Far above any sane load: the largest seed loads in well under a second, so a case this slow
/// is a hang or a quadratic blow-up, not a slow machine.
const CASE_TIME_LIMIT: Duration = Duration::from_secs(10);

/// Peak resident memory of the whole test process. Everything `fuzz_limits` allows at once
/// comes to about 700 MiB: 64 MiB of vertices (1 Mi x 64 B) and as much again of accessor
/// reads, 128 MiB of decoded texels and up to 128 MiB of decoder scratch per core, 256 MiB of
/// buffers and images from URIs, 64 MiB of animation keys, 8 MiB of instances. Runs stay near
/// 400 MiB; a case above this bound allocates something the limits fail to bound.
const MEMORY_BOUND_MIB: u64 = 1024;

/// Hard cap on the test process's address space, so that a runaway allocation aborts the test
/// instead of pushing the machine into swap or the OOM killer. Well above `MEMORY_BOUND_MIB`:
/// every thread reserves address space it never touches.
const ADDRESS_SPACE_CAP_GIB: u64 = 8;

/// Limits scaled down from the defaults, which allow a 200-byte file to ask for 64 M vertices
/// (4 GiB): with these, `MEMORY_BOUND_MIB` catches allocations the limits fail to bound. Every
/// seed still loads. fuzz/fuzz_targets/gltf_load.rs uses the same values.
fn fuzz_limits() -> Limits {
    Limits {
        max_triangles: 1 << 20,
        max_vertices: 1 << 20,
        max_texture_dimension: 4096,
        max_texture_pixels_total: 32 << 20,
        max_buffer_bytes: 64 << 20,
        max_total_bytes: 256 << 20,
        max_node_depth: 64,
        max_nodes: 1 << 16,
        max_data_uri_bytes: 16 << 20,
        max_instances: 1 << 20,
        max_animation_keys: 4 << 20,
        max_joints: 1 << 12,
    }
}

// ---------------------------------------------------------------------------------------------
// The test.

#[test]
fn mutated_scene_files_fail_cleanly() {
    cap_address_space();
    let seeds = load_seeds();
    let cases = env_u64("HYBRID_RT_FUZZ_CASES", DEFAULT_CASES);
    let rng_seed = env_u64("HYBRID_RT_FUZZ_SEED", 1);
    let mut run = Run::new(cases);

    // The unmutated seeds first: the scenes must load, or the mutations below would mostly
    // exercise the first error path rather than the loader.
    for seed in &seeds {
        let outcome = run.case(&seed.bytes, &seed.path, "unmutated seed");
        assert!(!seed.must_load || outcome, "seed {} does not load under fuzz_limits", seed.path.display());
    }
    for case in 0..cases {
        let mut rng = Rng::new(rng_seed ^ case.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let seed = pick_seed(&mut rng, &seeds);
        let (bytes, what) = mutate(&mut rng, seed, &seeds);
        run.case(&bytes, &seed.path, &what);
    }
    run.report();
}

/// What each committed corpus file must do under `fuzz_limits`: load with a warning
/// containing the text (Ok), or fail with an error containing it (Err). Each of them hung or
/// exhausted memory before the fix its name describes; tests/corpus/gltf/README.md has more.
const CORPUS: [(&str, Result<&str, &str>); 3] = [
    ("mikktspace_corners_at_one_position.glb", Ok("too many triangle corners share a position")),
    ("animation_channels_share_big_accessors.glb", Err("exceeds the limit max_animation_keys")),
    ("instances_nodes_times_primitives.glb", Err("exceeds the limit max_instances")),
];

#[test]
fn corpus_files_load_or_fail_as_expected() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus/gltf");
    let files = scene_files(&dir);
    for (name, _) in CORPUS {
        assert!(files.contains(&dir.join(name)), "{name} is missing from {}", dir.display());
    }
    for path in files {
        let name = path.file_name().unwrap_or_default().to_string_lossy().into_owned();
        let expected = CORPUS.iter().find(|(n, _)| *n == name).map(|(_, e)| *e);
        let expected = expected.unwrap_or_else(|| panic!("{name}: say in CORPUS what it must do"));
        let bytes = std::fs::read(&path).unwrap();
        let Ok(result) = load_with_deadline(&bytes, &path) else {
            panic!("{name}: panicked or took over {CASE_TIME_LIMIT:?}");
        };
        match (result, expected) {
            (Ok(scene), Ok(warning)) => {
                let warned = scene.warnings.iter().any(|w| w.contains(warning));
                assert!(warned, "{name}: no warning '{warning}' in {:?}", scene.warnings);
            }
            (Err(e), Err(problem)) => assert!(e.to_string().contains(problem), "{name}: expected '{problem}': {e}"),
            (Ok(_), Err(problem)) => panic!("{name}: loaded, expected an error '{problem}'"),
            (Err(e), Ok(_)) => panic!("{name}: expected to load: {e}"),
        }
    }
}

/// A seed file and whether it must load unmutated (the committed corpus holds broken files).
struct Seed {
    path: PathBuf,
    bytes: Vec<u8>,
    must_load: bool,
}

fn load_seeds() -> Vec<Seed> {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut seeds = vec![seed(manifest.join("assets/default/cornell.gltf"), true)];
    if let Some(dir) = shared_scenes() {
        seeds.extend(scene_files(&dir).into_iter().map(|p| seed(p, true)));
    }
    let corpus = manifest.join("tests/corpus/gltf");
    seeds.extend(scene_files(&corpus).into_iter().map(|p| seed(p, false)));
    seeds
}

/// A random seed, files over 1 MiB half as often as the others: their textures take most of
/// the time of every case that gets as far as decoding them.
fn pick_seed<'a>(rng: &mut Rng, seeds: &'a [Seed]) -> &'a Seed {
    loop {
        let seed = rng.pick(seeds);
        if seed.bytes.len() <= 1 << 20 || rng.chance(50) {
            return seed;
        }
    }
}

fn seed(path: PathBuf, must_load: bool) -> Seed {
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("cannot read seed {}: {e}", path.display()));
    Seed { path, bytes, must_load }
}

/// concat!(CARGO_MANIFEST_DIR, "/../shared/scenes"); when missing the test fails under CI=true
/// and otherwise fuzzes only the repository's own files.
fn shared_scenes() -> Option<PathBuf> {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/scenes"));
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(std::env::var("CI").as_deref() != Ok("true"), "{} is missing: CI must provide it", dir.display());
    eprintln!("note: {} is missing; fuzzing only the repository's own scenes", dir.display());
    None
}

/// Every .gltf and .glb below `dir`, sorted so that runs are reproducible.
fn scene_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "gltf" || e == "glb") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

fn env_u64(name: &str, default: u64) -> u64 {
    match std::env::var(name) {
        Ok(v) => v.parse().unwrap_or_else(|_| panic!("{name}={v}: expected a non-negative integer")),
        Err(_) => default,
    }
}

/// Limits this process's address space with prlimit(1) (no unsafe code needed); where
/// prlimit is unavailable the memory bound is still checked, only after the fact.
fn cap_address_space() {
    let pid = std::process::id().to_string();
    let cap = (ADDRESS_SPACE_CAP_GIB << 30).to_string();
    let status = std::process::Command::new("prlimit").args(["--pid", &pid, &format!("--as={cap}")]).status();
    if !status.is_ok_and(|s| s.success()) {
        eprintln!("note: prlimit failed; the address space is not capped");
    }
}

/// Peak resident set size of this process, in KiB.
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

// ---------------------------------------------------------------------------------------------
// Running cases.

/// Why a load gave no answer.
enum Stuck {
    Panicked,
    TimedOut,
}

/// Counts outcomes per mutation and collects failures.
struct Run {
    started: Instant,
    cases: u64,
    done: u64,
    /// Mutation name -> (loaded, refused).
    tally: BTreeMap<String, (u64, u64)>,
    failures: Vec<String>,
}

impl Run {
    fn new(cases: u64) -> Self {
        Self { started: Instant::now(), cases, done: 0, tally: BTreeMap::new(), failures: Vec::new() }
    }

    /// Loads one input; true when it loaded. Panics are collected, a timeout fails at once
    /// (the stuck thread cannot be stopped).
    fn case(&mut self, bytes: &[u8], path: &Path, what: &str) -> bool {
        let outcome = load_with_deadline(bytes, path);
        self.done += 1;
        let loaded = matches!(outcome, Ok(Ok(_)));
        for name in what.split(" + ") {
            let entry = self.tally.entry(name.to_string()).or_default();
            if loaded { entry.0 += 1 } else { entry.1 += 1 }
        }
        match outcome {
            Err(Stuck::Panicked) => {
                let saved = save_failure(bytes, path, self.done);
                self.failures.push(format!("{} ({what}) panicked; input saved to {saved}", path.display()));
            }
            Err(Stuck::TimedOut) => {
                let saved = save_failure(bytes, path, self.done);
                panic!("{} ({what}) took over {CASE_TIME_LIMIT:?}; input saved to {saved}", path.display());
            }
            Ok(_) => {}
        }
        self.check_memory(bytes, path, what);
        loaded
    }

    fn check_memory(&self, bytes: &[u8], path: &Path, what: &str) {
        let Some(peak) = peak_rss_kib() else {
            return;
        };
        if peak > MEMORY_BOUND_MIB << 10 {
            let saved = save_failure(bytes, path, self.done);
            panic!(
                "{} ({what}): peak memory {} MiB exceeds the bound {MEMORY_BOUND_MIB} MiB; input saved to {saved}",
                path.display(),
                peak >> 10
            );
        }
    }

    fn report(&self) {
        let secs = self.started.elapsed().as_secs_f64();
        let peak = peak_rss_kib().map_or("unknown".into(), |k| format!("{} MiB", k >> 10));
        eprintln!(
            "{} loads ({} mutated) in {secs:.1} s, {:.0}/s; peak memory {peak}",
            self.done,
            self.cases,
            self.done as f64 / secs
        );
        for (name, (loaded, refused)) in &self.tally {
            eprintln!("  {name:<24} loaded {loaded:>6}  refused {refused:>6}");
        }
        assert!(self.failures.is_empty(), "{} case(s) panicked:\n{}", self.failures.len(), self.failures.join("\n"));
    }
}

/// Loads `bytes` as if read from `path`, on a thread so that a hang is detected.
fn load_with_deadline(bytes: &[u8], path: &Path) -> Result<Result<Scene, SceneError>, Stuck> {
    let (tx, rx) = mpsc::channel();
    let input: Arc<[u8]> = bytes.into();
    let path = path.to_path_buf();
    let opts = LoadOptions { allow_outside_uris: false, limits: fuzz_limits() };
    let worker = std::thread::Builder::new().name("fuzz-case".into()).spawn(move || {
        // The receiver only goes away after a timeout, when the result no longer matters.
        let _ = tx.send(load_gltf_bytes(&input, &path, &opts));
    });
    let worker = worker.expect("spawn a loader thread");
    match rx.recv_timeout(CASE_TIME_LIMIT) {
        Ok(result) => Ok(result),
        // The sender was dropped without sending: the thread panicked.
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            let _ = worker.join();
            Err(Stuck::Panicked)
        }
        Err(mpsc::RecvTimeoutError::Timeout) => Err(Stuck::TimedOut),
    }
}

fn save_failure(bytes: &[u8], seed: &Path, case: u64) -> String {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-failures");
    let ext = seed.extension().and_then(|e| e.to_str()).unwrap_or("bin");
    let stem = seed.file_stem().and_then(|e| e.to_str()).unwrap_or("seed");
    let file = dir.join(format!("{stem}-case{case}.{ext}"));
    let saved = std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&file, bytes));
    match saved {
        Ok(()) => file.display().to_string(),
        Err(e) => format!("nowhere ({e})"),
    }
}

// ---------------------------------------------------------------------------------------------
// Random numbers: splitmix64, so that a (seed, case) pair always means the same input.

struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Self(seed)
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A number in 0..n; 0 when n is 0.
    fn below(&mut self, n: usize) -> usize {
        if n == 0 { 0 } else { (self.next() % n as u64) as usize }
    }

    fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

// ---------------------------------------------------------------------------------------------
// Mutation.

/// A mutated copy of `seed` and a description of what was done to it.
fn mutate(rng: &mut Rng, seed: &Seed, seeds: &[Seed]) -> (Vec<u8>, String) {
    let mut done = Vec::new();
    let mut bytes = match split_scene(&seed.bytes).filter(|_| rng.chance(70)) {
        Some((mut json, bin)) => {
            for _ in 0..1 + rng.below(3) {
                let (name, mutation) = *rng.pick(JSON_MUTATIONS);
                mutation(rng, &mut json);
                done.push(name.to_string());
            }
            encode_scene(&json, bin.as_deref())
        }
        None => seed.bytes.clone(),
    };
    if done.is_empty() || rng.chance(25) {
        for _ in 0..1 + rng.below(2) {
            let (name, mutation) = *rng.pick(BYTE_MUTATIONS);
            let other = &rng.pick(seeds).bytes;
            mutation(rng, &mut bytes, other);
            done.push(name.to_string());
        }
    }
    (bytes, done.join(" + "))
}

const GLB_HEADER: usize = 12;
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
}

/// The JSON and, for a GLB, its BIN chunk (empty when it has none); `None` when the JSON does
/// not parse.
fn split_scene(bytes: &[u8]) -> Option<(Value, Option<Vec<u8>>)> {
    if !bytes.starts_with(b"glTF") {
        return Some((serde_json::from_slice(bytes).ok()?, None));
    }
    let json_len = le_u32(bytes, GLB_HEADER)? as usize;
    let json_end = GLB_HEADER + 8 + json_len;
    let json = serde_json::from_slice(bytes.get(GLB_HEADER + 8..json_end)?).ok()?;
    let bin = le_u32(bytes, json_end).and_then(|len| bytes.get(json_end + 8..json_end + 8 + len as usize));
    Some((json, Some(bin.unwrap_or_default().to_vec())))
}

/// glTF JSON text, or a GLB when `bin` is given, with the markers of [`text_marker`] replaced
/// by text serde_json cannot produce.
fn encode_scene(json: &Value, bin: Option<&[u8]>) -> Vec<u8> {
    let mut text = serde_json::to_string(json).unwrap_or_default();
    for (marker, replacement) in TEXT_MARKERS {
        text = text.replace(&format!("\"{marker}\""), &replacement());
    }
    match bin {
        Some(bin) => glb(text.as_bytes(), bin),
        None => text.into_bytes(),
    }
}

fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |b: &[u8], fill: u8| {
        let mut v = b.to_vec();
        v.resize(b.len().div_ceil(4) * 4, fill);
        v
    };
    let (json, bin) = (pad(json, b' '), pad(bin, 0));
    let total = GLB_HEADER + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    push_chunk(&mut out, CHUNK_JSON, &json);
    if !bin.is_empty() {
        push_chunk(&mut out, CHUNK_BIN, &bin);
    }
    out
}

fn push_chunk(out: &mut Vec<u8>, kind: u32, data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(&kind.to_le_bytes());
    out.extend_from_slice(data);
}

// ---- JSON-aware mutations -------------------------------------------------------------------

type JsonMutation = fn(&mut Rng, &mut Value);

const JSON_MUTATIONS: &[(&str, JsonMutation)] = &[
    ("extreme_number", extreme_number),
    ("non_finite_number", non_finite_number),
    ("swap_numbers", swap_numbers),
    ("delete_key", delete_key),
    ("duplicate_array", duplicate_array),
    ("deep_nesting", deep_nesting),
    ("huge_count", huge_count),
    ("data_uri", data_uri),
    ("node_cycle", node_cycle),
    ("retype", retype),
    ("string_edit", string_edit),
    ("one_accessor_many_uses", one_accessor_many_uses),
    ("sparse", sparse),
    ("gpu_instancing", gpu_instancing),
    ("texture_transform", texture_transform),
    ("required_extension", required_extension),
];

/// Numbers at the edges of every integer and float type the loader converts to.
fn extreme() -> [Value; 16] {
    [
        json!(-1),
        json!(0),
        json!(1),
        json!(3),
        json!(0.5),
        json!(1e-45),
        json!(65535),
        json!(65536),
        json!(16_777_217),
        json!(2_147_483_648u64),
        json!(4_294_967_295u64),
        json!(4_294_967_296u64),
        json!(9_007_199_254_740_993u64),
        json!(u64::MAX),
        json!(i64::MIN),
        json!(1e300),
    ]
}

/// JSON pointers to every value in `v`, root first.
fn pointers(v: &Value) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![(String::new(), v)];
    while let Some((ptr, v)) = stack.pop() {
        match v {
            Value::Array(items) => stack.extend(items.iter().enumerate().map(|(i, c)| (format!("{ptr}/{i}"), c))),
            Value::Object(map) => stack.extend(map.iter().map(|(k, c)| (format!("{ptr}/{}", escape(k)), c))),
            _ => {}
        }
        out.push(ptr);
    }
    out
}

fn escape(key: &str) -> String {
    key.replace('~', "~0").replace('/', "~1")
}

/// Pointers to the values for which `keep` holds.
fn pointers_where(v: &Value, keep: impl Fn(&Value) -> bool) -> Vec<String> {
    pointers(v).into_iter().filter(|p| v.pointer(p).is_some_and(&keep)).collect()
}

/// Replaces a random value for which `keep` holds; false when there is none.
fn replace_random(rng: &mut Rng, json: &mut Value, keep: impl Fn(&Value) -> bool, new: Value) -> bool {
    let candidates = pointers_where(json, keep);
    if candidates.is_empty() {
        return false;
    }
    let ptr = rng.pick(&candidates).clone();
    if let Some(slot) = json.pointer_mut(&ptr) {
        *slot = new;
    }
    true
}

fn extreme_number(rng: &mut Rng, json: &mut Value) {
    let new = rng.pick(&extreme()).clone();
    replace_random(rng, json, Value::is_number, new);
}

type Replacement = fn() -> String;

/// Strings serde_json will not write; `encode_scene` swaps them for the marker strings.
const TEXT_MARKERS: [(&str, Replacement); 7] = [
    ("@nan@", || "NaN".into()),
    ("@inf@", || "Infinity".into()),
    ("@huge@", || "1e999".into()),
    ("@tiny@", || "-1e-999".into()),
    ("@deep_arrays@", || format!("{}0{}", "[".repeat(100_000), "]".repeat(100_000))),
    // serde_json refuses nesting beyond 128 levels; 120 gets through to the loader.
    ("@deep_objects@", || format!("{}0{}", "{\"a\":".repeat(129), "}".repeat(129))),
    ("@nested@", || format!("{}0{}", "[".repeat(120), "]".repeat(120))),
];

fn text_marker(rng: &mut Rng, markers: &[usize]) -> Value {
    Value::String(TEXT_MARKERS[*rng.pick(markers)].0.into())
}

fn non_finite_number(rng: &mut Rng, json: &mut Value) {
    let new = text_marker(rng, &[0, 1, 2, 3]);
    replace_random(rng, json, Value::is_number, new);
}

fn swap_numbers(rng: &mut Rng, json: &mut Value) {
    let numbers = pointers_where(json, Value::is_number);
    if numbers.len() < 2 {
        return;
    }
    let (a, b) = (rng.pick(&numbers).clone(), rng.pick(&numbers).clone());
    let (Some(va), Some(vb)) = (json.pointer(&a).cloned(), json.pointer(&b).cloned()) else {
        return;
    };
    for (ptr, value) in [(a, vb), (b, va)] {
        if let Some(slot) = json.pointer_mut(&ptr) {
            *slot = value;
        }
    }
}

fn delete_key(rng: &mut Rng, json: &mut Value) {
    let objects = pointers_where(json, |v| v.as_object().is_some_and(|m| !m.is_empty()));
    if objects.is_empty() {
        return;
    }
    let ptr = rng.pick(&objects).clone();
    if let Some(map) = json.pointer_mut(&ptr).and_then(Value::as_object_mut) {
        let key = map.keys().nth(rng.below(map.len())).cloned().unwrap_or_default();
        map.remove(&key);
    }
}

/// Repeats an array's elements up to 16 times (at most 4096 elements): duplicated children,
/// primitives, channels, buffers, scene roots.
fn duplicate_array(rng: &mut Rng, json: &mut Value) {
    let arrays = pointers_where(json, |v| v.as_array().is_some_and(|a| !a.is_empty() && a.len() <= 256));
    if arrays.is_empty() {
        return;
    }
    let times = 1 << (1 + rng.below(4));
    let ptr = rng.pick(&arrays).clone();
    if let Some(items) = json.pointer_mut(&ptr).and_then(Value::as_array_mut) {
        let copy = items.clone();
        for _ in 1..times {
            items.extend(copy.iter().cloned());
        }
    }
}

fn deep_nesting(rng: &mut Rng, json: &mut Value) {
    let new = text_marker(rng, &[4, 5, 6]);
    replace_random(rng, json, |_| true, new);
}

/// Sizes and counts at or just beyond the fuzz limits, and at integer edges.
fn huge_count(rng: &mut Rng, json: &mut Value) {
    const KEYS: [&str; 4] = ["count", "byteLength", "byteStride", "byteOffset"];
    let key = *rng.pick(&KEYS);
    let candidates: Vec<String> = pointers(json).into_iter().filter(|p| p.rsplit('/').next() == Some(key)).collect();
    let values = [json!(1 << 20), json!((1 << 20) + 1), json!(3 << 20), json!(64 << 20), json!(u32::MAX)];
    let new = if rng.chance(50) { rng.pick(&values).clone() } else { rng.pick(&extreme()).clone() };
    if let Some(slot) = candidates.get(rng.below(candidates.len())).and_then(|p| json.pointer_mut(p)) {
        *slot = new;
    }
}

/// A buffer or image whose URI becomes a `data:` URI of an odd size, header or payload.
fn data_uri(rng: &mut Rng, json: &mut Value) {
    let array = if rng.chance(50) { "buffers" } else { "images" };
    let items = array_mut(json, array);
    if items.is_empty() || rng.chance(20) {
        items.push(json!({}));
    }
    let i = rng.below(items.len());
    let (uri, decoded_len) = odd_data_uri(rng);
    *field(&mut items[i], &["uri"]) = json!(uri);
    if array == "buffers" {
        let delta = *rng.pick(&[-1i64, 0, 0, 1]);
        *field(&mut items[i], &["byteLength"]) = json!((decoded_len as i64 + delta).max(0));
    }
}

/// The value at `keys` below `v`, turning whatever is in the way into objects: earlier
/// mutations may have left any type anywhere, and indexing a non-object would panic.
fn field<'a>(v: &'a mut Value, keys: &[&str]) -> &'a mut Value {
    keys.iter().fold(v, |v, key| {
        if !v.is_object() {
            *v = json!({});
        }
        &mut v[*key]
    })
}

/// `json[key]` as an array, made one if it is not.
fn array_mut<'a>(json: &'a mut Value, key: &str) -> &'a mut Vec<Value> {
    let slot = field(json, &[key]);
    if !slot.is_array() {
        *slot = json!([]);
    }
    slot.as_array_mut().expect("an array was just put there")
}

fn odd_data_uri(rng: &mut Rng) -> (String, usize) {
    const SIZES: [usize; 12] = [0, 1, 2, 3, 4, 5, 63, 64, 65, 1023, 4096, 100_000];
    const HEADERS: [&[u8]; 4] = [b"", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR", b"\xff\xd8\xff\xe0", b"GIF89a"];
    let len = *rng.pick(&SIZES);
    let mut payload = rng.pick(&HEADERS).to_vec();
    payload.extend((0..len).map(|_| rng.next() as u8));
    payload.truncate(len);
    let mut encoded = base64::engine::general_purpose::STANDARD.encode(&payload);
    match rng.below(5) {
        0 => encoded = encoded.trim_end_matches('=').to_string(),
        1 => encoded.insert(encoded.len() / 2, '!'),
        _ => {}
    }
    let prefix = *rng.pick(&[
        "data:application/octet-stream;base64,",
        "data:image/png;base64,",
        "data:;base64,",
        "data:application/octet-stream,",
        "data:base64",
    ]);
    (format!("{prefix}{encoded}"), payload.len())
}

/// A child link that may close a cycle, give a node two parents, point at itself, point out
/// of range, or list a child as a scene root.
fn node_cycle(rng: &mut Rng, json: &mut Value) {
    let n = array_mut(json, "nodes").len();
    if n == 0 {
        return;
    }
    let parent = rng.below(n);
    let child = if rng.chance(10) { n + rng.below(3) } else { rng.below(n) };
    if rng.chance(20) {
        let scenes = array_mut(json, "scenes");
        if scenes.is_empty() {
            scenes.push(json!({}));
        }
        array_mut(&mut scenes[0], "nodes").push(json!(child));
        return;
    }
    array_mut(&mut array_mut(json, "nodes")[parent], "children").push(json!(child));
}

fn retype(rng: &mut Rng, json: &mut Value) {
    let new = rng.pick(&[json!("x"), json!({}), json!([]), json!(true), json!(null), json!([0, 1])]).clone();
    replace_random(rng, json, |_| true, new);
}

fn string_edit(rng: &mut Rng, json: &mut Value) {
    let strings = [
        "VEC4",
        "MAT4",
        "SCALAR",
        "",
        "../../../../../etc/passwd",
        "/etc/passwd",
        "%zz",
        "a%2F..%2F..%2Fx.bin",
        "file:///etc/passwd",
        "data:",
        "image/png",
        "image/ktx2",
        "BLEND",
        "MASK",
        "CUBICSPLINE",
        "weights",
        "1.0",
    ];
    let new = if rng.chance(10) { "é".repeat(50_000) } else { rng.pick(&strings).to_string() };
    replace_random(rng, json, Value::is_string, json!(new));
}

/// Adds accessors of up to `max_vertices` zero elements (they need no bufferView, so each costs
/// a few bytes of JSON) and refers to them from many places: animation channels, instancing,
/// vertex attributes. Each use is within the limits; all of them together must be bounded too.
fn one_accessor_many_uses(rng: &mut Rng, json: &mut Value) {
    let count = *rng.pick(&[1000u64, 1 << 19, 1 << 20]);
    let accessors = array_mut(json, "accessors");
    let first = accessors.len();
    for ty in ["SCALAR", "VEC2", "VEC3", "VEC4"] {
        accessors.push(json!({"componentType": 5126, "count": count, "type": ty}));
    }
    let [scalar, vec2, vec3, vec4] = [first, first + 1, first + 2, first + 3];
    let uses = 1 + rng.below(64);
    match rng.below(3) {
        0 => {
            let (path, output) = *rng.pick(&[("translation", vec3), ("rotation", vec4), ("scale", vec3)]);
            let samplers: Vec<Value> = (0..uses).map(|_| json!({"input": scalar, "output": output})).collect();
            let channels: Vec<Value> =
                (0..uses).map(|s| json!({"sampler": s, "target": {"node": 0, "path": path}})).collect();
            array_mut(json, "animations").push(json!({"samplers": samplers, "channels": channels}));
        }
        1 => {
            add_used_extension(json, "EXT_mesh_gpu_instancing");
            let nodes = array_mut(json, "nodes");
            for node in nodes.iter_mut().take(uses) {
                *field(node, &["extensions", "EXT_mesh_gpu_instancing", "attributes", "TRANSLATION"]) = json!(vec3);
            }
        }
        _ => {
            let attributes = json!({"POSITION": vec3, "NORMAL": vec3, "TEXCOORD_0": vec2, "TANGENT": vec4});
            for ptr in pointers_where(json, |v| v.get("attributes").is_some_and(Value::is_object)).iter().take(uses) {
                if let Some(primitive) = json.pointer_mut(ptr) {
                    primitive["attributes"] = attributes.clone();
                }
            }
        }
    }
}

fn add_used_extension(json: &mut Value, name: &str) {
    array_mut(json, "extensionsUsed").push(json!(name));
}

fn sparse(rng: &mut Rng, json: &mut Value) {
    let accessors = array_mut(json, "accessors");
    if accessors.is_empty() {
        return;
    }
    let i = rng.below(accessors.len());
    let small = [0, 1, 2, 3, 7];
    *field(&mut accessors[i], &["sparse"]) = json!({
        "count": rng.pick(&extreme()).clone(),
        "indices": {"bufferView": rng.pick(&small), "componentType": rng.pick(&[5121, 5123, 5125, 5126]),
                    "byteOffset": rng.pick(&extreme()).clone()},
        "values": {"bufferView": rng.pick(&small), "byteOffset": rng.pick(&[0, 1, 4, 1 << 20])},
    });
}

fn gpu_instancing(rng: &mut Rng, json: &mut Value) {
    add_used_extension(json, "EXT_mesh_gpu_instancing");
    let accessors = json["accessors"].as_array().map_or(1, Vec::len);
    let nodes = array_mut(json, "nodes");
    if nodes.is_empty() {
        return;
    }
    let node = rng.below(nodes.len());
    let attributes = field(&mut nodes[node], &["extensions", "EXT_mesh_gpu_instancing", "attributes"]);
    for name in ["TRANSLATION", "ROTATION", "SCALE"] {
        if rng.chance(60) {
            *field(attributes, &[name]) = json!(rng.below(accessors + 1));
        }
    }
}

fn texture_transform(rng: &mut Rng, json: &mut Value) {
    add_used_extension(json, "KHR_texture_transform");
    let materials = array_mut(json, "materials");
    if materials.is_empty() {
        return;
    }
    let m = rng.below(materials.len());
    let number = |rng: &mut Rng| rng.pick(&extreme()).clone();
    let texture = field(&mut materials[m], &["pbrMetallicRoughness", "baseColorTexture"]);
    if texture.get("index").is_none() {
        *field(texture, &["index"]) = json!(0);
    }
    *field(texture, &["extensions", "KHR_texture_transform"]) = json!({
        "offset": [number(rng), number(rng)],
        "rotation": number(rng),
        "scale": [number(rng), number(rng)],
        "texCoord": rng.below(3),
    });
}

fn required_extension(rng: &mut Rng, json: &mut Value) {
    let name = *rng.pick(&["KHR_draco_mesh_compression", "KHR_texture_transform", "", "EXT_mesh_gpu_instancing"]);
    array_mut(json, "extensionsRequired").push(json!(name));
}

// ---- Byte-level mutations -------------------------------------------------------------------

/// A mutation of the file's bytes; the third argument is another seed, for splicing.
type ByteMutation = fn(&mut Rng, &mut Vec<u8>, &[u8]);

const BYTE_MUTATIONS: &[(&str, ByteMutation)] = &[
    ("flip_bits", |rng, bytes, _| flip_bits(rng, bytes)),
    ("interesting_bytes", |rng, bytes, _| interesting_bytes(rng, bytes)),
    ("truncate", truncate),
    ("delete_range", delete_range),
    ("duplicate_range", duplicate_range),
    ("splice", splice),
    ("glb_length", |rng, bytes, _| glb_length(rng, bytes)),
    ("glb_chunk_length", |rng, bytes, _| glb_chunk_length(rng, bytes)),
    ("glb_chunk_type", |rng, bytes, _| glb_chunk_type(rng, bytes)),
    ("glb_extra_chunk", glb_extra_chunk),
];

fn flip_bits(rng: &mut Rng, bytes: &mut [u8]) {
    for _ in 0..1 + rng.below(8) {
        let i = rng.below(bytes.len());
        if let Some(b) = bytes.get_mut(i) {
            *b ^= 1 << rng.below(8);
        }
    }
}

fn interesting_bytes(rng: &mut Rng, bytes: &mut [u8]) {
    const BYTES: &[u8] = b"\x00\xff\x7f\x80{}[]\"\\09-e,:";
    for _ in 0..1 + rng.below(4) {
        let i = rng.below(bytes.len());
        let b = *rng.pick(BYTES);
        if let Some(slot) = bytes.get_mut(i) {
            *slot = b;
        }
    }
}

fn truncate(rng: &mut Rng, bytes: &mut Vec<u8>, _: &[u8]) {
    let len = rng.below(bytes.len());
    bytes.truncate(len);
}

/// A random range: start and length, within `len`.
fn range(rng: &mut Rng, len: usize) -> (usize, usize) {
    let start = rng.below(len);
    (start, rng.below((len - start).min(4096) + 1))
}

fn delete_range(rng: &mut Rng, bytes: &mut Vec<u8>, _: &[u8]) {
    let (start, len) = range(rng, bytes.len());
    bytes.drain(start..start + len);
}

fn duplicate_range(rng: &mut Rng, bytes: &mut Vec<u8>, _: &[u8]) {
    let (start, len) = range(rng, bytes.len());
    let copy = bytes[start..start + len].to_vec();
    let at = rng.below(bytes.len() + 1);
    bytes.splice(at..at, copy);
}

/// This file's head with another file's tail.
fn splice(rng: &mut Rng, bytes: &mut Vec<u8>, other: &[u8]) {
    let head = rng.below(bytes.len() + 1);
    let tail = rng.below(other.len() + 1);
    bytes.truncate(head);
    bytes.extend_from_slice(&other[tail..]);
}

fn set_u32(bytes: &mut [u8], at: usize, value: u32) {
    if let Some(word) = bytes.get_mut(at..at + 4) {
        word.copy_from_slice(&value.to_le_bytes());
    }
}

/// Lengths around `len` and at the edges of u32.
fn odd_length(rng: &mut Rng, len: usize) -> u32 {
    let len = len as u32;
    *rng.pick(&[0, 1, 3, 11, 12, len.wrapping_sub(1), len.wrapping_add(1), len.wrapping_add(8), u32::MAX, u32::MAX - 7])
}

fn glb_length(rng: &mut Rng, bytes: &mut [u8]) {
    let len = odd_length(rng, bytes.len());
    set_u32(bytes, 8, len);
}

/// Offsets of the chunk headers, following each chunk's own length.
fn chunk_offsets(bytes: &[u8]) -> Vec<usize> {
    let mut offsets = Vec::new();
    let mut at = GLB_HEADER;
    while let Some(len) = le_u32(bytes, at) {
        offsets.push(at);
        at = at.saturating_add(8).saturating_add(len as usize);
    }
    offsets
}

fn glb_chunk_length(rng: &mut Rng, bytes: &mut [u8]) {
    let chunks = chunk_offsets(bytes);
    if let Some(&at) = chunks.get(rng.below(chunks.len())) {
        let len = odd_length(rng, le_u32(bytes, at).unwrap_or(0) as usize);
        set_u32(bytes, at, len);
    }
}

fn glb_chunk_type(rng: &mut Rng, bytes: &mut [u8]) {
    let chunks = chunk_offsets(bytes);
    if let Some(&at) = chunks.get(rng.below(chunks.len())) {
        let kind = *rng.pick(&[CHUNK_JSON, CHUNK_BIN, 0, u32::MAX]);
        set_u32(bytes, at + 4, kind);
    }
}

/// Appends a chunk (a second JSON or BIN chunk, or an unknown one) and fixes the header length.
fn glb_extra_chunk(rng: &mut Rng, bytes: &mut Vec<u8>, _: &[u8]) {
    let kind = *rng.pick(&[CHUNK_JSON, CHUNK_BIN, 0x1234_5678]);
    let data: Vec<u8> = (0..rng.below(64)).map(|_| rng.next() as u8).collect();
    push_chunk(bytes, kind, &data);
    let len = bytes.len() as u32;
    set_u32(bytes, 8, len);
}
