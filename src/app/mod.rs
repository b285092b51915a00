//! `hybrid-rt view`: the desktop viewer. A winit window with a Vulkan swapchain shows the
//! hybrid frame, or any named pass output full screen (the capture's names and PNG preview
//! mapping), under an egui overlay with per-pass GPU times, the backend and why, and the
//! tunables. A fly/orbit camera, the scene's cameras and animation control drive the renderer;
//! shaders-glsl is watched and hot-reloaded, keeping the old pipelines when a compile fails.
//!
//! One frame is in flight: `Renderer::render_frame` waits for its frame, then the chosen
//! output is drawn into the swapchain with the overlay on top (gpu::present draws; the egui
//! side is [`overlay_painter`]).
//! Scripts (`--script`, see [`script`]) make runs reproducible for tests.

mod camera;
mod chain_follow;
mod commands;
mod hot_reload;
mod input;
mod overlay_painter;
mod rebuild;
pub mod script;
mod tunables;
mod ui;

use crate::backend::{self, Backend, BackendChoice};
use crate::capture;
use crate::gpu::{Context, ContextOptions, Presenter, ShaderLibrary, Shown, Swapchain, vk};
use crate::graph::{Preview, Resource};
use crate::image_io;
use crate::render::{CameraChoice, Renderer, Settings};
use crate::scene::Scene;
use anyhow::{Context as _, Result, anyhow};
use camera::{Controller, Mode};
use glam::Vec3;
use input::Input;
use overlay_painter::OverlayFrame;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use script::Command;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

/// How the viewer starts.
pub struct ViewOptions {
    pub scene: Scene,
    /// The render size, and the window's first size.
    pub settings: Settings,
    pub backend: BackendChoice,
    pub validate: bool,
    pub camera: CameraChoice,
    /// Shaders compiled from here at start-up (else the embedded ones).
    pub shader_dir: Option<PathBuf>,
    /// The folder hot reload watches (`None`: no hot reload).
    pub watch: Option<PathBuf>,
    /// Run these commands, then stay interactive unless one was `quit`.
    pub script: Option<Vec<Command>>,
    pub vsync: bool,
    /// The output shown first, as the user typed it (`None`: the tonemapped image).
    pub view: Option<String>,
    pub ui: bool,
    /// Where screenshots and capture dumps go when no path is given.
    pub out_dir: PathBuf,
    pub force: bool,
}

/// Opens the window and runs until it is closed or a script quits.
pub fn run(opts: ViewOptions) -> Result<()> {
    let event_loop =
        EventLoop::new().map_err(|e| anyhow!("cannot open a window: {e} (is DISPLAY set and an X server running?)"))?;
    let mut app = App { opts: Some(opts), viewer: None, result: Ok(()) };
    event_loop.run_app(&mut app).map_err(|e| anyhow!("window event loop: {e}"))?;
    let App { viewer, result, .. } = app;
    let ctx = viewer.as_ref().map(|v| v.ctx.clone());
    // Everything made from the context goes before the context's last reference, so teardown
    // (and the validation layer's leak check) happens in finish_validation.
    drop(viewer);
    result?;
    match ctx {
        Some(ctx) => crate::gpu::finish_validation(ctx),
        None => Ok(()),
    }
}

struct App {
    opts: Option<ViewOptions>,
    viewer: Option<Viewer>,
    result: Result<()>,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.result.is_ok() {
            self.result = Err(e);
        }
        event_loop.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some(opts) = self.opts.take() else { return };
        match Viewer::new(event_loop, opts) {
            Ok(v) => self.viewer = Some(v),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(v) = self.viewer.as_mut() else { return };
        match v.window_event(event) {
            Ok(true) => {}
            Ok(false) => event_loop.exit(),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(v) = &self.viewer else { return };
        // Draw continuously (temporal passes converge, animations play); a minimised window
        // sleeps until an event.
        if v.swapchain.visible() {
            event_loop.set_control_flow(ControlFlow::Poll);
            v.window.request_redraw();
        } else {
            event_loop.set_control_flow(ControlFlow::Wait);
        }
    }
}

/// Animation time: `start_time + steps * frame_dt`, the renderer's own formula, so a viewer
/// that plays from the start sees exactly the times `render` sees.
struct Clock {
    playing: bool,
    steps: u32,
}

impl Clock {
    fn time(&self, s: &Settings) -> f32 {
        s.start_time + self.steps as f32 * s.frame_dt
    }
}

// Fields drop in this order: what draws into the window goes before the window, and
// everything made from the context before the context.
struct Viewer {
    presenter: Presenter,
    swapchain: Swapchain,
    renderer: Renderer,
    egui_state: egui_winit::State,
    egui: egui::Context,
    window: Window,
    shaders: ShaderLibrary,
    watcher: Option<hot_reload::Watcher>,
    ctx: Arc<Context>,
    backend: Backend,
    backend_why: String,
    camera: Controller,
    cameras: Vec<String>,
    clock: Clock,
    /// The overlay's copy of the settings, applied when it differs from the renderer's.
    edit: Settings,
    view: Resource,
    ui_visible: bool,
    script: Option<VecDeque<Command>>,
    frames_left: u32,
    input: Input,
    out_dir: PathBuf,
    force: bool,
    message: String,
    shader_error: Option<String>,
    pending_screenshot: Option<PathBuf>,
    frame_ms: f32,
    last_frame: Instant,
    /// When the window was last resized: the render size follows once it settles.
    resized_at: Option<Instant>,
    /// When the camera comes to rest, the shadows chain is ranked at its view.
    rest: chain_follow::RestWatch,
}

impl Viewer {
    fn new(event_loop: &ActiveEventLoop, opts: ViewOptions) -> Result<Self> {
        let (w, h) = (opts.settings.width, opts.settings.height);
        let attributes = Window::default_attributes()
            .with_title(format!("hybrid-rt — {}", opts.scene.name))
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = event_loop.create_window(attributes).context("create the window")?;
        let display = window.display_handle().map_err(|e| anyhow!("window display handle: {e}"))?.as_raw();
        let handle = window.window_handle().map_err(|e| anyhow!("window handle: {e}"))?.as_raw();
        let shaders = ShaderLibrary::from_dir_or_embedded(opts.shader_dir.as_deref())?;
        let ctx =
            Context::new(&ContextOptions { validate: opts.validate, window: Some(display), ..Default::default() })?;
        let (backend, backend_why) = backend::resolve(&ctx.caps, opts.backend)?;
        log::info!("ray backend: {} ({backend_why})", backend.variant());
        let cameras = opts.scene.cameras.iter().map(|c| c.name.clone()).collect();
        let edit = opts.settings.clone();
        let renderer = Renderer::new(&ctx, &shaders, opts.scene, opts.settings, &opts.camera, backend)?;
        let view = match &opts.view {
            Some(name) => renderer.graph.resource_named(name).context("--view")?,
            None => crate::render::DISPLAY_OUTPUT.into(),
        };
        let size = window.inner_size();
        let swapchain = Swapchain::new(&ctx, display, handle, (size.width, size.height), opts.vsync)?;
        let presenter = Presenter::new(&ctx, &shaders, swapchain.format)?;
        let egui = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.caps.max_image_dimension_2d as usize),
        );
        // Replaced by one at the current view when the user first moves (set_camera_mode).
        let camera =
            Controller::from_view(Mode::Scene, &renderer.view_of(&renderer.pose_of(0)), 1.0, (Vec3::ZERO, 1.0));
        let scripted = opts.script.is_some();
        Ok(Self {
            presenter,
            swapchain,
            renderer,
            egui_state,
            egui,
            window,
            shaders,
            watcher: opts.watch.as_deref().map(hot_reload::Watcher::new),
            ctx,
            backend,
            backend_why,
            camera,
            cameras,
            clock: Clock { playing: true, steps: 0 },
            edit,
            view,
            ui_visible: opts.ui,
            script: opts.script.map(VecDeque::from),
            frames_left: 0,
            input: Input::default(),
            out_dir: opts.out_dir,
            force: opts.force,
            message: if scripted { "scripted run".into() } else { String::new() },
            shader_error: None,
            pending_screenshot: None,
            frame_ms: 0.0,
            last_frame: Instant::now(),
            resized_at: None,
            rest: Default::default(),
        })
    }

    /// One redraw: a script step, or an interactive frame.
    fn redraw(&mut self) -> Result<bool> {
        let now = Instant::now();
        self.frame_ms = (now - self.last_frame).as_secs_f32() * 1000.0;
        self.last_frame = now;
        if !self.swapchain.visible() {
            return Ok(true);
        }
        if self.script.is_some() {
            return self.script_step();
        }
        self.hot_reload(false)?;
        self.follow_window_size()?;
        if !self.egui.is_using_pointer() {
            self.apply_settings();
        }
        self.move_camera();
        if self.rest.rested(self.camera.view_override(), now) {
            self.rank_chain();
        }
        self.render()?;
        let shot = self.pending_screenshot.take();
        if let Err(e) = self.present(shot.as_deref()) {
            // A failed screenshot is reported and the viewer goes on; anything else ends it.
            if shot.is_none() {
                return Err(e);
            }
            self.message = format!("screenshot failed: {e:#}");
        }
        Ok(true)
    }

    fn render(&mut self) -> Result<()> {
        self.renderer.set_view_override(self.camera.view_override());
        self.renderer.set_time(Some(self.clock.time(&self.renderer.settings)));
        self.renderer.render_frame()?;
        if self.clock.playing {
            self.clock.steps += 1;
        }
        Ok(())
    }

    /// Draws the current frame's shown output (and the overlay) into the window; with
    /// `screenshot`, also saves the window's pixels under the overlay there. `false` when
    /// nothing could be drawn this time.
    fn present(&mut self, screenshot: Option<&Path>) -> Result<bool> {
        if let Some(path) = screenshot {
            image_io::check_overwrite(path, self.force)?;
        }
        let name = self.view;
        let desc = self.renderer.graph.images.desc(name).ok_or_else(|| anyhow!("no pass output named {name}"))?;
        // The tonemap output is display-encoded RGBA8 already and is read in place; any other
        // output goes through the capture's preview, so it looks exactly like its PNG.
        let in_place = desc.preview == Preview::Display && desc.format == vk::Format::R8G8B8A8_UNORM;
        let cpu = if in_place {
            None
        } else {
            let preview = desc.preview;
            let img = self.renderer.read_output(name)?;
            Some((img.width, img.height, capture::preview(&img, preview)))
        };
        let (overlay, actions) = if self.ui_visible { self.run_ui() } else { (None, Vec::new()) };
        if self.presenter.format() != self.swapchain.format {
            self.presenter = Presenter::new(&self.ctx, &self.shaders, self.swapchain.format)?;
        }
        let shown = match &cpu {
            Some((width, height, texels)) => Shown::Rgba { width: *width, height: *height, texels },
            None => Shown::Graph(self.renderer.graph.image(name).expect("checked above")),
        };
        let overlay = overlay.as_ref().map(|(primitives, textures, ppp)| OverlayFrame::new(primitives, textures, *ppp));
        let overlay = overlay.as_ref().map(OverlayFrame::overlay);
        let presenter = &mut self.presenter;
        let drawn =
            self.swapchain.draw(|rec, target| presenter.record(rec, target, shown, overlay, screenshot.is_some()))?;
        for a in actions {
            self.ui_action(a);
        }
        let Some(shot) = drawn else { return Ok(false) };
        if let (Some(path), Some(shot)) = (screenshot, shot) {
            image_io::write_png_rgba8(path, shot.width, shot.height, &shot.rgba()?)?;
            self.message = format!("saved {}", path.display());
            println!("screenshot {} ({}x{}, {name})", path.display(), shot.width, shot.height);
        }
        Ok(true)
    }

    /// Runs the overlay for this frame: its tessellated triangles, texture changes and scale,
    /// and what the user asked for.
    #[allow(clippy::type_complexity)]
    fn run_ui(&mut self) -> (Option<(Vec<egui::ClippedPrimitive>, egui::TexturesDelta, f32)>, Vec<ui::Action>) {
        let raw = self.egui_state.take_egui_input(&self.window);
        let present_mode = format!("{:?}", self.swapchain.present_mode);
        let watched = self.watcher.as_ref().map(|w| w.dir.display().to_string());
        let info = ui::Info {
            device: &self.ctx.caps.device_name,
            backend: self.backend.variant(),
            backend_why: &self.backend_why,
            pass_times: &self.renderer.last_pass_times,
            frame_wall_ms: self.renderer.last_frame_wall_ms,
            outputs: &self.renderer.graph.output_order,
            view: self.view,
            cameras: &self.cameras,
            scene_camera: self.renderer.camera_index(),
            camera_mode: self.camera.mode,
            frame: self.renderer.frame_index,
            frame_ms: self.frame_ms,
            size: (self.renderer.settings.width, self.renderer.settings.height),
            vsync: self.swapchain.vsync,
            present_mode: &present_mode,
            playing: self.clock.playing,
            time: self.clock.time(&self.renderer.settings),
            shader_dir: watched.as_deref(),
            compiling: self.watcher.as_ref().is_some_and(|w| w.compiling()),
            shader_error: self.shader_error.as_deref(),
            message: &self.message,
            radiance_cache: self.renderer.radiance_cache_stats(),
        };
        let mut edit = self.edit.clone();
        let mut actions = Vec::new();
        let out = self.egui.run(raw, |ctx| actions = ui::draw(ctx, &info, &mut edit));
        self.edit = edit;
        self.egui_state.handle_platform_output(&self.window, out.platform_output);
        let primitives = self.egui.tessellate(out.shapes, out.pixels_per_point);
        (Some((primitives, out.textures_delta, out.pixels_per_point)), actions)
    }
}
