//! The renderer: a scene on the GPU, the frame graph of passes, and the per-frame loop that
//! advances animation, updates the camera and records, submits and times one frame.

pub mod camera;
pub mod default_light;
pub mod frame;
pub mod light_view;
pub mod plan;
pub mod ray_batch;
pub mod sky;
pub mod sky_reach;

pub use camera::{CameraChoice, View};
// The environment setting belongs with the renderer's settings; the data it loads lives in
// world::environment beside the other GPU scene data.
pub use crate::world::environment::Environment;

use crate::backend::Backend;
use crate::gpu::{CommandPool, Context, Recorder, ShaderLibrary, vk};
use crate::graph::{Graph, Output, PassTime, Resource};
use crate::image_io::CpuImage;
use crate::passes::{self, PassBuilder};
use crate::scene::{Pose, Scene};
use crate::world::lights::{ChainLights, LightTables};
use crate::world::{FrameUniforms, SceneGpu, brdf, scene_gpu};
use anyhow::{Result, bail};
use glam::Vec2;
use std::sync::Arc;

/// What the frame looks like, independent of the scene.
#[derive(Clone, Debug)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    /// Exposure multiplier applied before tonemapping.
    pub exposure: f32,
    /// What rays and pixels that leave the scene see. The default, `DefaultLight`, lights a
    /// scene that brings no light of its own with a daylight sky (default_light.rs).
    pub environment: Environment,
    /// Animation time step between frames, seconds.
    pub frame_dt: f32,
    /// Animation time of frame 0, seconds.
    pub start_time: f32,
    /// Add the primary_rays pass (a check of the ray backends against the G-buffer).
    pub primary_rays: bool,
    /// Run every pass, ignoring the frame plan (see plan.rs).
    pub full: bool,
    /// Temporal anti-aliasing (jittered G-buffer) before tonemapping.
    pub taa: bool,
    /// Denoise the diffuse and specular signals with SVGF.
    pub denoiser: bool,
    /// The denoiser's settings.
    pub denoise: crate::passes::svgf::SvgfSettings,
    pub gi: crate::passes::gi::GiSettings,
    /// The radiance cache behind gi and reflections.
    pub radiance_cache: crate::passes::radiance_cache::RadianceCacheSettings,
    pub reflections: crate::passes::reflections::ReflectionSettings,
    /// Mixed into the random streams of the stochastic passes.
    pub seed: u32,
    /// The adaptive shadows' settings.
    pub shadows: crate::passes::shadows::ShadowSettings,
    /// Tests: a CPU-provided image `inject.signal` goes through an SVGF chain of its own.
    pub test_signal: bool,
    pub mode: RenderMode,
    /// How the material's diffuse and specular lobes share light (`--brdf`).
    pub brdf: brdf::BrdfModel,
    /// Draw the resampled lights from the light grid (world::light_grid). Off
    /// (`--no-light-grid`): by power from all of them, what the grid is checked against.
    pub light_grid: bool,
    /// Small plain emissive meshes take shadows chain channels, ranked with the punctual lights
    /// (world::lights::chain_lights). Off (`--no-mesh-lights`): every emissive triangle
    /// is resampled in gi, as before 2026-12-06.
    pub mesh_lights: bool,
    /// Where more lights compete for the shadows chain's channels than it has, rank them by
    /// the direct light they bring to the camera's views (camera::shot_views). Off
    /// (`--chain-by-power`): by the power they emit over the whole scene, as before 2026-12-06.
    pub chain_by_view: bool,
}

/// Which frame the renderer builds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RenderMode {
    /// The real-time frame: G-buffer, ray-traced passes, composite, tonemap.
    #[default]
    Hybrid,
    /// The progressive path tracer (pathtrace, tonemap) at a frozen pose: frame n adds
    /// sample n to every pixel.
    Reference {
        /// Mixed with the frame index into every pixel's random stream.
        seed: u32,
        /// Scattering events per path at most (1 = direct light only).
        max_bounces: u32,
    },
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 360,
            exposure: 1.0,
            environment: Environment::DefaultLight,
            frame_dt: 1.0 / 30.0,
            start_time: 0.0,
            primary_rays: false,
            full: false,
            taa: false,
            denoiser: true,
            denoise: Default::default(),
            gi: Default::default(),
            radiance_cache: Default::default(),
            reflections: Default::default(),
            seed: 0,
            shadows: Default::default(),
            test_signal: false,
            mode: RenderMode::Hybrid,
            brdf: brdf::BrdfModel::Gltf,
            light_grid: true,
            mesh_lights: true,
            chain_by_view: true,
        }
    }
}

/// The 8-bit, display-encoded image of a frame.
pub const DISPLAY_OUTPUT: Output = passes::tonemap::COLOR;

pub struct Renderer {
    /// What the frame leaves out for this scene, and why.
    pub plan: plan::FramePlan,
    /// Which environment lights the scene, and why (the default light or not).
    pub lighting: default_light::Lighting,
    /// The scene's lights as loaded, before the plan culled and ordered them: the shadows
    /// chain is ranked again from these (`rank_chain_for`).
    loaded_lights: Vec<crate::scene::Light>,
    /// The environment `scene_gpu` was uploaded with, which the light tables are made from
    /// again when the shadows chain is ranked again.
    environment: crate::world::environment::EnvironmentData,
    pub ctx: Arc<Context>,
    pool: CommandPool,
    pub scene: Scene,
    pub scene_gpu: SceneGpu,
    pub graph: Graph,
    pub settings: Settings,
    camera: Option<usize>,
    /// Frames rendered so far; the next frame's index.
    pub frame_index: u32,
    prev_view: Option<View>,
    /// The jitter the last frame was rasterised with (`FrameUniforms::prev_jitter`).
    prev_jitter: [f32; 2],
    /// The centre of the scene's bounds at the start: the distance at which the camera's motion is
    /// measured for TAA's jitter (`camera::image_motion`).
    scene_centre: glam::Vec3,
    pub last_view: Option<View>,
    pub last_pass_times: Vec<PassTime>,
    /// Wall-clock time of the last frame from recording to its fence, in ms. Benchmarks use
    /// it as the frame time: lavapipe's timestamps leave most compute dispatches out (at
    /// 256x256 their sum was ~38 ms where frames took several times that), so per-pass
    /// timestamps are kept only as the split between passes.
    pub last_frame_wall_ms: f64,
    /// Submit each pass on its own and time it to its fence (`PassTime::wall_ms`): slower
    /// frames, but per-pass costs where timestamps fall short (`bench frame`).
    pub profile_passes: bool,
    /// The ray-list tracer, made on first use.
    ray_batch: Option<ray_batch::RayBatch>,
    /// Images the CPU feeds into the frame (tests), by output name.
    injected: std::collections::HashMap<Output, passes::inject::Texels>,
    hdr_output: Output,
    /// The radiance cache of the hybrid frame, for its statistics.
    radiance_cache: Option<Arc<passes::radiance_cache::Cache>>,
    /// The next frame starts all temporal histories anew.
    cut_pending: bool,
    /// A camera set from outside (the viewer), in place of the scene's.
    view_override: Option<ViewOverride>,
    /// An animation time set from outside (the viewer's pause and step), in place of the
    /// frame index's.
    time_override: Option<f32>,
}

/// A camera pose and lens set from outside the scene (the viewer's fly and orbit cameras).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewOverride {
    /// World-to-view (right-handed, looking down -Z).
    pub view: glam::Mat4,
    /// Vertical field of view, radians.
    pub yfov: f32,
    pub znear: f32,
    /// May be infinite.
    pub zfar: f32,
}

/// The frame plan of `scene` (its lights as loaded) under `settings`; the shadows chain ranked
/// by what its lights bring to `views` where `settings.chain_by_view` asks for it.
fn frame_plan(scene: &Scene, settings: &Settings, views: &[View]) -> plan::FramePlan {
    let ranked_by = if settings.chain_by_view { views } else { &[] };
    if settings.full {
        plan::FramePlan::full(scene, settings.mesh_lights, ranked_by)
    } else {
        plan::FramePlan::for_scene(
            scene,
            settings.reflections.roughness_cutoff,
            settings.light_grid,
            settings.mesh_lights,
            ranked_by,
        )
    }
}

/// What ranking the shadows chain again changed (`Renderer::rank_chain_for`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reranked {
    /// The chain keeps its lights.
    Same,
    /// Other punctual lights hold the channels, with the same passes: the light tables were
    /// made again, the frame's passes kept.
    TablesRemade,
    /// The new lights need other passes (soft shadows on or off, mesh lights): the light
    /// tables were made again and the frame rebuilt.
    FrameRebuilt,
}

/// The instances of `plan`'s mesh lights, which the light tables flag (`ChainLights::meshes`).
fn chain_meshes(plan: &plan::FramePlan) -> Vec<u32> {
    plan.chain_emitters.iter().map(|c| c.0).collect()
}

/// The frame graph of `plan`'s passes under `settings` on `scene`, and what the passes hand
/// back besides: at start-up, on a rebuild (`Renderer::rebuild_frame`) and where the shadows
/// chain's new lights need other passes (`Renderer::rank_chain_for`).
fn build_frame(
    ctx: &Arc<Context>,
    shaders: &ShaderLibrary,
    scene: &SceneGpu,
    settings: &Settings,
    plan: &plan::FramePlan,
) -> Result<(Graph, frame::HybridFrame)> {
    let b = PassBuilder { ctx, shaders, scene };
    let mut parts = frame_parts(&b, settings, plan)?;
    let extent = vk::Extent2D { width: settings.width, height: settings.height };
    let graph = Graph::new(ctx, std::mem::take(&mut parts.passes), extent)?;
    Ok((graph, parts))
}

/// The passes of a frame for `settings`, the images the CPU feeds into it and its HDR output.
fn frame_parts(b: &PassBuilder, settings: &Settings, plan: &plan::FramePlan) -> Result<frame::HybridFrame> {
    Ok(match settings.mode {
        RenderMode::Hybrid => frame::hybrid(b, settings, plan)?,
        RenderMode::Reference { seed, max_bounces } => frame::HybridFrame {
            passes: vec![
                Box::new(passes::pathtrace::new(b, seed, max_bounces)?),
                Box::new(passes::tonemap::new(b, passes::pathtrace::COLOR.into())?),
            ],
            injected: Default::default(),
            hdr_output: passes::pathtrace::COLOR,
            radiance_cache: None,
        },
    })
}

impl Renderer {
    pub fn new(
        ctx: &Arc<Context>,
        shaders: &ShaderLibrary,
        mut scene: Scene,
        settings: Settings,
        camera: &CameraChoice,
        backend: Backend,
    ) -> Result<Self> {
        crate::accel::sort_triangles_spatially(&mut scene);
        // Decided on the scene as loaded: lights the plan culls below are still its own.
        let start = camera::start_position(&scene, camera)?;
        let (environment, lighting) = default_light::environment_data(&settings.environment, &scene, start)?;
        log::info!("lighting of {}: {}", scene.name, lighting.note);
        let glass = scene.materials.iter().filter(|m| m.is_transmissive()).count();
        if glass > 0 && !matches!(settings.mode, RenderMode::Reference { .. }) {
            log::info!(
                "{}: {glass} transmissive materials: the reflections pass traces one path per pixel through them",
                scene.name
            );
        }
        // The shadows chain's lights are ranked by what they bring to the camera's views.
        let views = camera::shot_views(&scene, camera, settings.width, settings.height)?;
        let plan = frame_plan(&scene, &settings, &views);
        let loaded_lights = scene.lights.clone();
        // The culled lights out, the rest in shading order (the shadowed ones first).
        scene.lights = plan.light_order.iter().map(|&i| loaded_lights[i].clone()).collect();
        let limit = ctx.caps.max_image_dimension_2d;
        if settings.width == 0 || settings.height == 0 || settings.width > limit || settings.height > limit {
            bail!(
                "image size {}x{} is outside what the device supports (1..={limit} per side)",
                settings.width,
                settings.height
            );
        }
        let camera = camera::resolve(&scene, camera)?;
        let pool = CommandPool::new(ctx)?;
        let pose = scene.evaluate(settings.start_time);
        let (lo, hi) = scene.bounds(&pose);
        let scene_centre = if lo.is_finite() && hi.is_finite() { (lo + hi) * 0.5 } else { glam::Vec3::ZERO };
        let scene_gpu = SceneGpu::upload(
            ctx,
            &pool,
            shaders,
            &scene,
            &pose,
            backend,
            &environment,
            settings.brdf,
            settings.light_grid,
            ChainLights { punctual: plan.chain_punctual, meshes: &chain_meshes(&plan) },
        )?;
        let (graph, parts) = build_frame(ctx, shaders, &scene_gpu, &settings, &plan)?;
        let (injected, hdr_output, radiance_cache) = (parts.injected, parts.hdr_output, parts.radiance_cache);
        Ok(Self {
            plan,
            lighting,
            loaded_lights,
            environment,
            ctx: ctx.clone(),
            pool,
            scene,
            scene_gpu,
            graph,
            settings,
            camera,
            frame_index: 0,
            prev_view: None,
            prev_jitter: [0.0; 2],
            last_view: None,
            scene_centre,
            last_pass_times: Vec::new(),
            last_frame_wall_ms: 0.0,
            profile_passes: false,
            ray_batch: None,
            injected,
            hdr_output,
            radiance_cache,
            cut_pending: false,
            view_override: None,
            time_override: None,
        })
    }

    /// The name of the shadow visibility the lighting reads this frame: the filtered one when
    /// the plan keeps soft shadows, the hard-shadow trace's otherwise.
    pub fn shadow_visibility(&self) -> Output {
        if self.plan.soft_shadows { passes::shadows::VISIBILITY } else { passes::shadows::HARD_VISIBILITY }
    }

    /// Rebuilds the frame's passes (pipelines and images) from `shaders` and `self.settings`,
    /// keeping the scene on the GPU: the viewer's settings changes, resizes and shader hot
    /// reload. On error the old frame stays as it was. Temporal histories start anew.
    pub fn rebuild_frame(&mut self, shaders: &ShaderLibrary) -> Result<()> {
        let s = &self.settings;
        let limit = self.ctx.caps.max_image_dimension_2d;
        if s.width == 0 || s.height == 0 || s.width > limit || s.height > limit {
            bail!("image size {}x{} is outside what the device supports (1..={limit} per side)", s.width, s.height);
        }
        let built = build_frame(&self.ctx, shaders, &self.scene_gpu, s, &self.plan)?;
        self.install_frame(built);
        self.camera_cut();
        Ok(())
    }

    /// Puts a frame `build_frame` made in place of the one in use.
    fn install_frame(&mut self, (graph, parts): (Graph, frame::HybridFrame)) {
        self.graph = graph;
        self.injected = parts.injected;
        self.hdr_output = parts.hdr_output;
        self.radiance_cache = parts.radiance_cache;
        self.last_pass_times.clear();
    }

    /// Ranks the shadows chain's lights again by what they bring to `view` (the plan ranked them
    /// by the camera's views at the start; the viewer asks again where its camera comes to
    /// rest, and after a switch of cameras). Where that gives the chain other lights, the
    /// scene's lights take the new shading order and their tables are made again (the rest of
    /// the scene stays on the GPU), and the frame's passes are rebuilt where the new lights
    /// need other ones (soft shadows on or off, mesh lights; `frame::same_passes`). Every
    /// temporal history starts anew. Says what changed;
    /// nothing does where the settings rank by power, or four lights or fewer compete. On
    /// error the old frame stays as it was.
    pub fn rank_chain_for(&mut self, shaders: &ShaderLibrary, view: &View) -> Result<Reranked> {
        if !self.settings.chain_by_view || matches!(self.settings.mode, RenderMode::Reference { .. }) {
            return Ok(Reranked::Same);
        }
        let start = std::time::Instant::now();
        let shown = std::mem::replace(&mut self.scene.lights, self.loaded_lights.clone());
        let plan = frame_plan(&self.scene, &self.settings, std::slice::from_ref(view));
        if plan.same_chain(&self.plan) {
            self.scene.lights = shown;
            return Ok(Reranked::Same);
        }
        self.scene.lights = plan.light_order.iter().map(|&i| self.loaded_lights[i].clone()).collect();
        let pose = self.pose_of(self.frame_index);
        // The scene stays on the GPU but for its light tables. The passes hold nothing of the
        // scene's but its descriptor set layout, which stays too: where the plan keeps the
        // same passes, they stay as well.
        let kept = frame::same_passes(&self.plan, &plan);
        let light_grid = self.settings.light_grid;
        let (ctx, pool, env) = (&self.ctx, &self.pool, &self.environment);
        let chain = ChainLights { punctual: plan.chain_punctual, meshes: &chain_meshes(&plan) };
        let built = LightTables::new(ctx, pool, &self.scene, &pose, env, light_grid, chain).and_then(|t| {
            let frame =
                if kept { None } else { Some(build_frame(ctx, shaders, &self.scene_gpu, &self.settings, &plan)?) };
            Ok((t, frame))
        });
        if built.is_err() {
            self.scene.lights = shown;
        }
        let (tables, frame) = built?;
        self.scene_gpu.set_light_tables(tables);
        log::info!(
            "shadows chain of {} ranked again at the view from {}: {} (light tables made again{} in {:.0} ms)",
            self.scene.name,
            view.position,
            plan.chain_names(&self.loaded_lights, &self.scene),
            if kept { ", frame kept" } else { " and frame rebuilt" },
            start.elapsed().as_secs_f64() * 1e3
        );
        if let Some(built) = frame {
            self.install_frame(built);
        }
        self.plan = plan;
        self.prev_view = None;
        self.camera_cut();
        Ok(if kept { Reranked::TablesRemade } else { Reranked::FrameRebuilt })
    }

    /// The names of the shadows chain's lights, punctual and mesh lights.
    pub fn chain_names(&self) -> String {
        self.plan.chain_names(&self.loaded_lights, &self.scene)
    }

    /// Replaces the scene's camera by `view` from the next frame on (`None`: the scene's
    /// camera again).
    pub fn set_view_override(&mut self, view: Option<ViewOverride>) {
        self.view_override = view;
    }

    /// Shows the scene through another of its cameras (a camera cut).
    pub fn set_camera(&mut self, choice: &CameraChoice) -> Result<()> {
        self.camera = camera::resolve(&self.scene, choice)?;
        self.view_override = None;
        self.camera_cut();
        Ok(())
    }

    /// The scene camera in use (`None`: the framing camera of a scene without cameras).
    pub fn camera_index(&self) -> Option<usize> {
        self.camera
    }

    /// Fixes the animation time of the next frames (`None`: the time follows the frame index,
    /// `start_time + frame * frame_dt`).
    pub fn set_time(&mut self, time: Option<f32>) {
        self.time_override = time;
    }

    pub fn time_of(&self, frame: u32) -> f32 {
        if let Some(t) = self.time_override {
            return t;
        }
        if let RenderMode::Reference { .. } = self.settings.mode {
            // Every sample of a reference must see the same scene.
            return self.settings.start_time;
        }
        self.settings.start_time + frame as f32 * self.settings.frame_dt
    }

    /// The linear HDR image of the frame (before tonemapping).
    pub fn hdr_output(&self) -> Output {
        self.hdr_output
    }

    /// Live and updated cells of the radiance cache in the last rendered frame (None: the
    /// frame has no cache).
    pub fn radiance_cache_stats(&self) -> Option<passes::radiance_cache::CacheStats> {
        let cache = self.radiance_cache.as_ref()?;
        Some(cache.stats(self.frame_index.checked_sub(1)?))
    }

    /// The next frame is a camera cut: temporal passes drop their history.
    pub fn camera_cut(&mut self) {
        self.cut_pending = true;
    }

    /// The RGBA texels an injected image (`inject.NAME`) will show from the next frame on.
    pub fn inject(&self, name: Output, texels: Vec<[f32; 4]>) -> Result<()> {
        let slot = self.injected.get(&name).ok_or_else(|| anyhow::anyhow!("no injected image named {name}"))?;
        *slot.lock().map_err(|_| anyhow::anyhow!("injected image poisoned"))? = texels;
        Ok(())
    }

    pub fn pose_of(&self, frame: u32) -> Pose {
        self.scene.evaluate(self.time_of(frame))
    }

    pub fn view_of(&self, pose: &Pose) -> View {
        let aspect = self.settings.width as f32 / self.settings.height as f32;
        if let Some(o) = self.view_override {
            let position = o.view.inverse().w_axis.truncate();
            return camera::perspective(o.view, position, o.yfov, aspect, o.znear, o.zfar);
        }
        camera::view_at(&self.scene, self.camera, pose, aspect)
    }

    /// Renders the next frame and waits for it.
    pub fn render_frame(&mut self) -> Result<()> {
        let frame = self.frame_index;
        let pose = self.pose_of(frame);
        let view = self.view_of(&pose);
        self.scene_gpu.update_pose(&self.scene, &pose)?;
        let uniforms = self.frame_uniforms(frame, pose.time, &view);
        self.scene_gpu.write_frame(&uniforms)?;
        let (graph, scene_gpu, ctx) = (&mut self.graph, &mut self.scene_gpu, &self.ctx);
        let start = std::time::Instant::now();
        let mut pass_wall_ms = Vec::new();
        if self.profile_passes {
            self.pool.run(|cmd| scene_gpu.record_update(&Recorder::new(ctx, cmd)))?;
            for i in 0..graph.pass_count() {
                let pass_start = std::time::Instant::now();
                self.pool.run(|cmd| graph.record_passes(&Recorder::new(ctx, cmd), scene_gpu, frame, i..i + 1))?;
                pass_wall_ms.push(pass_start.elapsed().as_secs_f64() * 1e3);
            }
        } else {
            self.pool.run(|cmd| {
                let rec = Recorder::new(ctx, cmd);
                scene_gpu.record_update(&rec)?;
                graph.record(&rec, scene_gpu, frame)
            })?;
        }
        self.last_frame_wall_ms = start.elapsed().as_secs_f64() * 1e3;
        self.last_pass_times = self.graph.pass_times();
        for (t, ms) in self.last_pass_times.iter_mut().zip(pass_wall_ms) {
            t.wall_ms = Some(ms);
        }
        self.cut_pending = false;
        self.prev_view = Some(view);
        self.prev_jitter = uniforms.jitter;
        self.last_view = Some(view);
        self.frame_index += 1;
        Ok(())
    }

    fn frame_uniforms(&self, frame: u32, time: f32, view: &View) -> FrameUniforms {
        let size = Vec2::new(self.settings.width as f32, self.settings.height as f32);
        let prev = self.prev_view.unwrap_or(*view);
        let vp = view.view_proj();
        let jitter = if self.settings.taa {
            let scale = passes::taa::jitter_scale(camera::image_motion(&prev, view, size, self.scene_centre));
            passes::taa::jitter(frame).map(|j| j * scale)
        } else {
            [0.0; 2]
        };
        let reset = frame == 0 || self.cut_pending;
        FrameUniforms {
            view: view.view.to_cols_array_2d(),
            proj: view.proj.to_cols_array_2d(),
            view_proj: vp.to_cols_array_2d(),
            inv_view_proj: vp.inverse().to_cols_array_2d(),
            inv_view: view.view.inverse().to_cols_array_2d(),
            prev_view_proj: prev.view_proj().to_cols_array_2d(),
            jittered_view_proj: view.jittered_view_proj(Vec2::from(jitter), size).to_cols_array_2d(),
            camera_pos: view.position.to_array(),
            znear: view.znear,
            prev_camera_pos: prev.position.to_array(),
            zfar: view.zfar.min(f32::MAX),
            size: [self.settings.width, self.settings.height],
            frame_index: frame,
            light_count: self.scene.lights.len() as u32,
            jitter,
            time,
            exposure: self.settings.exposure,
            sky_color: self.scene_gpu.light_tables.sky.to_array(),
            instance_count: self.scene.instances.len() as u32,
            flags: if reset { scene_gpu::FRAME_RESET_HISTORY } else { 0 }
                | if self.scene_gpu.lights_changed { scene_gpu::FRAME_LIGHTS_CHANGED } else { 0 },
            prev_jitter: self.prev_jitter,
            chain_punctual: self.plan.chain_punctual as u32,
        }
    }

    /// Reads outputs of the last frame back to the CPU.
    pub fn read_outputs<R: Into<Resource> + Copy>(&mut self, names: &[R]) -> Result<Vec<CpuImage>> {
        let names: Vec<Resource> = names.iter().map(|n| (*n).into()).collect();
        for n in &names {
            if self.graph.image(*n).is_none() {
                bail!("no pass output named {n}");
            }
        }
        let (graph, ctx) = (&mut self.graph, &self.ctx);
        let buffers = self.pool.run(|cmd| {
            let rec = Recorder::new(ctx, cmd);
            graph.prepare_readback(&rec, &names);
            names
                .iter()
                .map(|n| crate::graph::copy_to_host(ctx, &rec, graph.image(*n).expect("checked above")))
                .collect::<Result<Vec<_>>>()
        })?;
        names
            .iter()
            .zip(buffers)
            .map(|(n, buf)| {
                let img = self.graph.image(*n).expect("checked above");
                let bytes = buf.mapped().ok_or_else(|| anyhow::anyhow!("read-back buffer is not mapped"))?;
                CpuImage::from_raw(img.format, img.extent.width, img.extent.height, bytes)
            })
            .collect()
    }

    /// Traces a list of rays through the scene's ray backend (see [`ray_batch`]).
    pub fn trace_rays(
        &mut self,
        shaders: &ShaderLibrary,
        rays: &[crate::accel::bvh::rays::Ray],
        any_hit: bool,
        repeats: u32,
    ) -> Result<(Vec<ray_batch::HitRecord>, Vec<ray_batch::TraceTime>)> {
        if self.ray_batch.is_none() {
            self.ray_batch = Some(ray_batch::RayBatch::new(&self.ctx, shaders, &self.scene_gpu)?);
        }
        let batch = self.ray_batch.as_ref().expect("created above");
        batch.trace(&self.ctx, &self.pool, &mut self.scene_gpu, rays, any_hit, repeats)
    }

    pub fn read_output(&mut self, name: impl Into<Resource>) -> Result<CpuImage> {
        let name: Resource = name.into();
        Ok(self.read_outputs(&[name])?.remove(0))
    }
}
