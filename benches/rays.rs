//! `cargo bench --bench rays`: runs `hybrid-rt bench rays` with its defaults (both backends on
//! MetalRoughSpheresNoTextures, DamagedHelmet and the Cornell box; table on the terminal, JSON
//! under out/bench/). The bench profile is release-based, so the first `cargo bench` builds
//! everything (libshaderc included) once more; `hybrid-rt bench rays` from the dev build
//! measures the same GPU work.

fn main() -> std::process::ExitCode {
    hybrid_rt::cli::main_with(["hybrid-rt", "bench", "rays"])
}
