//! The shadows chain follows the viewer's camera. The plan gives the chain's four channels to
//! the lights that bring the most to the camera's views at the start (render::light_view); a
//! camera that flies into another room would keep those four and leave that room's lights to
//! gi's resampling. So where the camera comes to rest, and after a switch of scene cameras,
//! the chain is ranked again at the view (`Renderer::rank_chain_for`). Not while it moves: a
//! new chain restarts the frame's histories (and may rebuild its passes), which every step of
//! a walk would do.

use super::Viewer;
use crate::render::{Reranked, ViewOverride};
use std::time::{Duration, Instant};

/// How long the camera must hold still before the chain is ranked at its view.
const REST: Duration = Duration::from_millis(500);

/// Tells when the viewer's own camera has come to rest after moving.
#[derive(Default)]
pub(super) struct RestWatch {
    last: Option<ViewOverride>,
    moved_at: Option<Instant>,
}

impl RestWatch {
    /// Called every frame with the camera in use (`None`: a scene camera, which only a
    /// switch moves); true once per stop, when the camera has held still for `REST`.
    pub(super) fn rested(&mut self, view: Option<ViewOverride>, now: Instant) -> bool {
        if view != self.last {
            self.last = view;
            self.moved_at = Some(now);
            return false;
        }
        match self.moved_at {
            Some(t) if now.duration_since(t) >= REST => {
                self.moved_at = None;
                true
            }
            _ => false,
        }
    }
}

impl Viewer {
    /// Ranks the shadows chain at the camera's current view; a new chain is named in the
    /// overlay's message and the log, a failure leaves the old frame and says why.
    pub(super) fn rank_chain(&mut self) {
        self.renderer.set_view_override(self.camera.view_override());
        let view = self.renderer.view_of(&self.renderer.pose_of(self.renderer.frame_index));
        match self.renderer.rank_chain_for(&self.shaders, &view) {
            Ok(Reranked::Same) => {}
            Ok(_) => {
                self.message = format!("shadows chain ranked at this view: {}", self.renderer.chain_names());
                self.fall_back_view();
            }
            Err(e) => self.message = format!("shadows chain kept: {e:#}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f32) -> Option<ViewOverride> {
        Some(ViewOverride {
            view: glam::Mat4::from_translation(glam::Vec3::new(x, 0.0, 0.0)),
            yfov: 1.0,
            znear: 0.1,
            zfar: 100.0,
        })
    }

    #[test]
    fn a_camera_rests_once_per_stop() {
        let t0 = Instant::now();
        let ms = |n| t0 + Duration::from_millis(n);
        let mut w = RestWatch::default();
        // A scene camera that never moves is never a stop.
        assert!(!w.rested(None, ms(0)));
        assert!(!w.rested(None, ms(2000)));
        // Moving: no stop however long the walk.
        assert!(!w.rested(at(1.0), ms(2100)));
        assert!(!w.rested(at(2.0), ms(2700)));
        assert!(!w.rested(at(3.0), ms(3300)));
        // Still, but not yet for long enough; then once.
        assert!(!w.rested(at(3.0), ms(3600)));
        assert!(w.rested(at(3.0), ms(3800)));
        assert!(!w.rested(at(3.0), ms(5000)));
        // Back to the scene's camera is a move too.
        assert!(!w.rested(None, ms(5100)));
        assert!(w.rested(None, ms(5600)));
    }
}
