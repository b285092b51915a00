//! Benchmarks: `hybrid-rt bench rays` (ray throughput of both backends on the same rays) and
//! `hybrid-rt bench sweep` (frame time against error for many configurations, with a chart).
//! Results go to the terminal as a table and to disk as JSON.

pub mod chart;
pub mod frame;
pub mod rays;
pub mod soak;
pub mod stability;
pub mod sweep;
pub mod target;

use std::path::PathBuf;

/// A default output path that never collides with an earlier run: `out/bench/NAME-SECONDS.json`.
pub fn default_output(name: &str) -> PathBuf {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    PathBuf::from(format!("out/bench/{name}-{secs}.json"))
}

/// Median of a non-empty list.
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        return f64::NAN;
    }
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// `s` lowercased with every run of other characters than ASCII letters and digits turned
/// into one `-`: a device or camera name as part of a file name.
pub fn slug(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.is_empty() && !out.ends_with('-') {
            out.push('-');
        }
    }
    out.trim_end_matches('-').to_string()
}
