//! Rebuilding the frame while the viewer runs: hot-reloaded shaders (the old ones stay when a
//! compile fails), changed settings, and a window that settled at a new size.

use super::{Viewer, tunables};
use crate::gpu::{Presenter, ShaderLibrary};
use anyhow::{Result, bail};
use std::time::Duration;

impl Viewer {
    /// Polls the shader folder (interactive runs) or, when `now`, recompiles it and waits
    /// (scripts and the reload button's scripted twin).
    pub(super) fn hot_reload(&mut self, now: bool) -> Result<()> {
        let Some(w) = self.watcher.as_mut() else {
            if now {
                bail!("reload: no shader folder is watched (--watch-shaders DIR)");
            }
            return Ok(());
        };
        let result = if now {
            w.start_compile();
            w.wait()
        } else {
            if w.poll_changes() {
                w.start_compile();
            }
            w.finished()
        };
        if let Some(result) = result {
            self.shaders_compiled(result);
        }
        Ok(())
    }

    /// A compile finished: with new shaders the frame and the presenter are rebuilt; on any
    /// failure the old library and pipelines stay and the error is shown.
    pub(super) fn shaders_compiled(&mut self, result: Result<ShaderLibrary>) {
        let built = result.and_then(|lib| {
            let presenter = Presenter::new(&self.ctx, &lib, self.swapchain.format)?;
            let old = std::mem::replace(&mut self.shaders, lib);
            match self.renderer.rebuild_frame(&self.shaders) {
                Ok(()) => {
                    self.presenter = presenter;
                    Ok(())
                }
                Err(e) => {
                    self.shaders = old;
                    Err(e)
                }
            }
        });
        match built {
            Ok(()) => {
                self.shader_error = None;
                self.message = "shaders reloaded".into();
                self.fall_back_view();
            }
            Err(e) => {
                // Also on stderr: a terminal (or a test) sees it without the overlay.
                eprintln!("shader reload failed, the previous shaders stay in use: {e:#}");
                self.shader_error = Some(format!("{e:#}"));
            }
        }
    }

    /// The shown output may be gone after a rebuild (TAA off removes `taa.color`).
    pub(super) fn fall_back_view(&mut self) {
        if self.renderer.graph.image(self.view).is_none() {
            self.view = crate::render::DISPLAY_OUTPUT.into();
        }
    }

    /// Applies the overlay's (or a script's) settings; returns the error when the frame
    /// could not be rebuilt with them (the old settings then stay).
    pub(super) fn apply_settings(&mut self) -> Option<String> {
        let current = &self.renderer.settings;
        let changed: Vec<_> = tunables::ALL.iter().filter(|t| (t.get)(current) != (t.get)(&self.edit)).collect();
        if changed.is_empty() {
            return None;
        }
        let rebuild = changed.iter().any(|t| t.rebuild);
        let old = std::mem::replace(&mut self.renderer.settings, self.edit.clone());
        if rebuild && let Err(e) = self.renderer.rebuild_frame(&self.shaders) {
            self.renderer.settings = old.clone();
            self.edit = old;
            let e = format!("{e:#}");
            self.message = format!("settings not applied: {e}");
            return Some(e);
        }
        self.fall_back_view();
        None
    }

    /// Interactive runs render at the window's size once it has stopped changing (every size
    /// rebuilds the frame's images).
    pub(super) fn follow_window_size(&mut self) -> Result<()> {
        let Some(at) = self.resized_at else { return Ok(()) };
        if at.elapsed() < Duration::from_millis(300) {
            return Ok(());
        }
        self.resized_at = None;
        let size = self.window.inner_size();
        let s = &self.renderer.settings;
        if size.width == 0 || size.height == 0 || (size.width, size.height) == (s.width, s.height) {
            return Ok(());
        }
        let old = self.renderer.settings.clone();
        self.renderer.settings.width = size.width;
        self.renderer.settings.height = size.height;
        if let Err(e) = self.renderer.rebuild_frame(&self.shaders) {
            self.renderer.settings = old;
            self.message = format!("kept the render size: {e:#}");
        }
        self.edit.width = self.renderer.settings.width;
        self.edit.height = self.renderer.settings.height;
        Ok(())
    }
}
