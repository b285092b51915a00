//! The `hybrid-rt` binary: logging set up, then the command line (src/cli).

#![deny(unsafe_code)]

use std::process::ExitCode;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    hybrid_rt::cli::main()
}
