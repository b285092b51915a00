//! The progress bar shown for long work (reference renders, sweeps, soak). A leaf module, so
//! both the command line and the benches below it can show one.

use std::io::IsTerminal;

/// A progress bar on stderr for long work; hidden when stderr is not a terminal or the work
/// is a single step.
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    if len <= 1 || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    let style = indicatif::ProgressStyle::with_template(&format!(
        "{{bar:40}} {{pos}}/{{len}} {what} [{{elapsed_precise}} elapsed, {{eta}} left] {{msg}}"
    ))
    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    bar.set_style(style);
    bar
}
