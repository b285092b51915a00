//! Shader hot reload: the viewer polls the modification times under a shaders-glsl folder
//! (cheap: a few dozen files, twice a second; no platform watcher needed) and recompiles the
//! whole library on a background thread when any changed, so the window keeps drawing with the
//! old pipelines meanwhile. A library that fails to compile is reported and dropped: the old
//! one stays in use.

use crate::gpu::ShaderLibrary;
use anyhow::Result;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant, SystemTime};

const POLL_EVERY: Duration = Duration::from_millis(500);

pub struct Watcher {
    pub dir: PathBuf,
    stamps: BTreeMap<PathBuf, SystemTime>,
    last_poll: Instant,
    compiling: Option<Receiver<Result<ShaderLibrary>>>,
}

impl Watcher {
    pub fn new(dir: &Path) -> Self {
        Self { dir: dir.to_path_buf(), stamps: scan(dir), last_poll: Instant::now(), compiling: None }
    }

    /// True when files changed since the last poll (at most one look per `POLL_EVERY`).
    pub fn poll_changes(&mut self) -> bool {
        if self.last_poll.elapsed() < POLL_EVERY {
            return false;
        }
        self.last_poll = Instant::now();
        let now = scan(&self.dir);
        let changed = now != self.stamps;
        self.stamps = now;
        changed
    }

    /// Starts compiling the folder in the background (a compile already running is left to
    /// finish; its result is dropped in favour of this one).
    pub fn start_compile(&mut self) {
        let (tx, rx) = channel();
        let dir = self.dir.clone();
        std::thread::spawn(move || {
            // The receiver may be gone (the viewer closed); nothing to report then.
            let _ = tx.send(ShaderLibrary::from_dir(&dir));
        });
        self.compiling = Some(rx);
    }

    pub fn compiling(&self) -> bool {
        self.compiling.is_some()
    }

    /// The finished compile's result, if one finished.
    pub fn finished(&mut self) -> Option<Result<ShaderLibrary>> {
        let result = self.compiling.as_ref()?.try_recv().ok()?;
        self.compiling = None;
        Some(result)
    }

    /// Waits for the running compile (scripted runs, which must be reproducible).
    pub fn wait(&mut self) -> Option<Result<ShaderLibrary>> {
        let result = self.compiling.take()?.recv().ok()?;
        Some(result)
    }
}

/// Modification time of every file under `dir`, recursively.
fn scan(dir: &Path) -> BTreeMap<PathBuf, SystemTime> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        for e in entries.flatten() {
            let path = e.path();
            match e.metadata() {
                Ok(m) if m.is_dir() => stack.push(path),
                Ok(m) => {
                    out.insert(path, m.modified().unwrap_or(SystemTime::UNIX_EPOCH));
                }
                Err(_) => {}
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sees_new_changed_and_removed_files() {
        let dir = std::env::temp_dir().join(format!("hybrid-rt-watch-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("common")).unwrap();
        std::fs::write(dir.join("a.comp"), "x").unwrap();
        let mut w = Watcher::new(&dir);
        w.last_poll -= POLL_EVERY;
        assert!(!w.poll_changes());
        std::fs::write(dir.join("common/b.glsl"), "y").unwrap();
        w.last_poll -= POLL_EVERY;
        assert!(w.poll_changes(), "a new include is a change");
        std::fs::remove_file(dir.join("a.comp")).unwrap();
        assert!(!w.poll_changes(), "polls are rate-limited");
        w.last_poll -= POLL_EVERY;
        assert!(w.poll_changes(), "a removed file is a change");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
