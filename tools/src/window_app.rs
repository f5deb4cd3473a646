//! The windowed target: a winit window whose swapchain shows a scene's HDR
//! image through the present pass, with resize and minimise handled, the
//! per-pass timings printed once a second, input handed to the scene and
//! the scene's text overlay drawn on top.

use std::sync::Arc;
use std::time::{Duration, Instant};

use inlay_engine::graph::FrameGraph;
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::timing::FrameTimings;
use inlay_engine::window::{PresentMode, WindowTarget};
use inlay_engine::{Context, ContextOptions, Renderer, WindowHandles, DEFAULT_FRAMES_IN_FLIGHT};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

use crate::headless::Scene;
use crate::overlay::OverlayPass;
use crate::present::PresentPipeline;
use crate::timings_table::format_table;

/// How to open the window.
#[derive(Debug, Clone)]
pub struct WindowOptions {
    /// Vulkan context options (validation, device).
    pub context: ContextOptions,
    /// Title bar text.
    pub title: String,
    /// Initial size in pixels.
    pub size: (u32, u32),
    /// Presentation pacing.
    pub present_mode: PresentMode,
    /// Close after this many frames (for tests and scripted runs).
    pub frames: Option<u64>,
    /// Exposure multiplier before tonemapping.
    pub exposure: f32,
}

/// Why the window could not run.
#[derive(Debug, thiserror::Error)]
pub enum WindowError {
    /// No display to open a window on (headless machine).
    #[error("no display available: {0}")]
    NoDisplay(String),
    /// Anything else.
    #[error(transparent)]
    Other(#[from] anyhow::Error),
}

/// What the window should do after the scene saw an input event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Response {
    /// Nothing beyond drawing the next frame.
    Continue,
    /// Close the window.
    Quit,
    /// Wait for the frames in flight, then call [`WindowScene::rebuild`]
    /// (the scene's pipelines or resources change).
    Rebuild,
}

/// What the overlay can show about the frames so far.
pub struct HudStats<'a> {
    /// Frames per second over the last second.
    pub fps: f64,
    /// The last completed frames' timings, oldest first.
    pub recent: &'a [FrameTimings],
    /// The drawable size in pixels.
    pub extent: (u32, u32),
    /// The device's name.
    pub device: &'a str,
}

/// A scene shown in the window, optionally interactive: it takes input,
/// rebuilds itself on request and writes the overlay's lines.
pub trait WindowScene {
    /// The scene to render.
    fn scene(&mut self) -> &mut dyn Scene;

    /// Sees a window event (`extent`: the drawable size).
    fn input(&mut self, _event: &WindowEvent, _extent: (u32, u32)) -> Response {
        Response::Continue
    }

    /// Rebuilds what [`Response::Rebuild`] asked for; no frame is in flight.
    fn rebuild(&mut self, _ctx: &Arc<Context>, _lib: &ShaderLibrary) -> anyhow::Result<()> {
        Ok(())
    }

    /// The overlay's lines (none: no overlay pass).
    fn hud(&mut self, _stats: &HudStats<'_>) -> Vec<String> {
        Vec::new()
    }

    /// Called after frame `frame` (0-based) was presented.
    fn presented(&mut self, _frame: u64) {}
}

/// A scene that only renders.
pub struct Passive(pub Box<dyn Scene>);

impl WindowScene for Passive {
    fn scene(&mut self) -> &mut dyn Scene {
        &mut *self.0
    }
}

/// Builds a scene once the context exists.
pub type SceneFactory =
    Box<dyn FnOnce(&Arc<Context>, &ShaderLibrary) -> anyhow::Result<Box<dyn WindowScene>>>;

// Field order is drop order: Vulkan objects go before the window.
struct Running {
    present: PresentPipeline,
    overlay: OverlayPass,
    scene: Box<dyn WindowScene>,
    target: WindowTarget,
    renderer: Renderer,
    ctx: Arc<Context>,
    window: Arc<Window>,
    started: Instant,
    last_report: Instant,
    frames: u64,
    fps: f64,
    fps_window: (Instant, u64),
    minimised: bool,
}

struct App {
    options: WindowOptions,
    library: ShaderLibrary,
    factory: Option<SceneFactory>,
    running: Option<Running>,
    error: Option<anyhow::Error>,
    timings: Vec<FrameTimings>,
}

/// Opens the window and renders `factory`'s scene until closed (or for
/// `options.frames` frames). Returns the completed frames' timings.
pub fn run_window(
    options: WindowOptions,
    library: ShaderLibrary,
    factory: SceneFactory,
) -> Result<Vec<FrameTimings>, WindowError> {
    if std::env::var_os("DISPLAY").is_none() {
        return Err(WindowError::NoDisplay("DISPLAY is not set".into()));
    }
    let event_loop = EventLoop::new().map_err(|e| WindowError::NoDisplay(e.to_string()))?;
    let mut app = App {
        options,
        library,
        factory: Some(factory),
        running: None,
        error: None,
        timings: Vec::new(),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| WindowError::Other(e.into()))?;
    match app.error {
        Some(e) => Err(WindowError::Other(e)),
        None => Ok(app.timings),
    }
}

impl App {
    fn start(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let (w, h) = self.options.size;
        let window = Arc::new(
            event_loop.create_window(
                Window::default_attributes()
                    .with_title(self.options.title.clone())
                    .with_inner_size(PhysicalSize::new(w, h)),
            )?,
        );
        let handles = WindowHandles {
            display: window.display_handle()?.as_raw(),
            window: window.window_handle()?.as_raw(),
        };
        let ctx = Context::new(&self.options.context, Some(handles))?;
        let size = window.inner_size();
        let target = WindowTarget::new(
            &ctx,
            (size.width, size.height),
            self.options.present_mode,
            DEFAULT_FRAMES_IN_FLIGHT,
        )?;
        let present = PresentPipeline::new(&ctx, &self.library, target.format(), target.is_srgb())?;
        let overlay = OverlayPass::new(&ctx, &self.library, target.format())?;
        let factory = self
            .factory
            .take()
            .ok_or_else(|| anyhow::anyhow!("window started twice"))?;
        let scene = factory(&ctx, &self.library)?;
        let renderer = Renderer::new(&ctx, DEFAULT_FRAMES_IN_FLIGHT)?;
        let position = window
            .inner_position()
            .map(|p| (p.x, p.y))
            .unwrap_or((0, 0));
        println!(
            "window: {} on {} ({:?}), present mode {:?}, {}x{} at ({}, {})",
            self.options.title,
            ctx.info().name,
            ctx.info().kind,
            target.present_mode(),
            size.width,
            size.height,
            position.0,
            position.1
        );
        let now = Instant::now();
        self.running = Some(Running {
            present,
            overlay,
            scene,
            target,
            renderer,
            ctx,
            window,
            started: now,
            last_report: now,
            frames: 0,
            fps: 0.0,
            fps_window: (now, 0),
            minimised: false,
        });
        Ok(())
    }

    fn frame(&mut self) -> anyhow::Result<bool> {
        let Some(r) = self.running.as_mut() else {
            return Ok(false);
        };
        let token = r.renderer.begin_frame()?;
        let Some(acquired) = r.target.acquire(token)? else {
            r.minimised = r.target.extent().0 == 0 || r.target.extent().1 == 0;
            return Ok(false);
        };
        r.minimised = false;
        if r.present.format() != r.target.format() {
            r.present =
                PresentPipeline::new(&r.ctx, &self.library, r.target.format(), r.target.is_srgb())?;
            r.overlay = OverlayPass::new(&r.ctx, &self.library, r.target.format())?;
        }
        let (w, h) = r.target.extent();
        let time = r.started.elapsed().as_secs_f32();
        let recent: Vec<FrameTimings> = r
            .renderer
            .timings()
            .iter()
            .rev()
            .take(30)
            .rev()
            .cloned()
            .collect();
        let device = r.ctx.info().name.clone();
        let lines = r.scene.hud(&HudStats {
            fps: r.fps,
            recent: &recent,
            extent: (w, h),
            device: &device,
        });
        let mut graph = FrameGraph::new();
        let hdr = r.scene.scene().build(&mut graph, w, h, time)?;
        let swapchain = r.target.import(&mut graph, acquired);
        let shown = r
            .present
            .add_pass(&mut graph, hdr, swapchain, self.options.exposure);
        r.overlay
            .add(&mut graph, shown, &lines, 1 + (h >= 600) as u32);
        r.renderer.submit(graph, &r.target.submit_sync(acquired))?;
        r.target.present(acquired)?;
        r.scene.presented(r.frames);
        r.frames += 1;
        let since = r.fps_window.0.elapsed().as_secs_f64();
        if since >= 1.0 {
            r.fps = (r.frames - r.fps_window.1) as f64 / since;
            r.fps_window = (Instant::now(), r.frames);
        }
        if r.last_report.elapsed() >= Duration::from_secs(1) {
            let recent: Vec<FrameTimings> = r
                .renderer
                .timings()
                .iter()
                .rev()
                .take(60)
                .rev()
                .cloned()
                .collect();
            let fps = r.frames as f64 / r.started.elapsed().as_secs_f64();
            print!(
                "{:.1} fps average, {w}x{h}\n{}",
                fps,
                format_table(&recent, &r.ctx.info().name)
            );
            r.last_report = Instant::now();
        }
        r.ctx.check_validation()?;
        Ok(self.options.frames.is_some_and(|n| r.frames >= n))
    }

    /// Hands `event` to the scene; true when the window should close.
    fn input(&mut self, event: &WindowEvent) -> anyhow::Result<bool> {
        let Some(r) = self.running.as_mut() else {
            return Ok(false);
        };
        match r.scene.input(event, r.target.extent()) {
            Response::Continue => Ok(false),
            Response::Quit => Ok(true),
            Response::Rebuild => {
                r.renderer.finish()?;
                r.scene.rebuild(&r.ctx, &self.library)?;
                Ok(false)
            }
        }
    }

    fn stop(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(mut r) = self.running.take() {
            if r.renderer.finish().is_ok() {
                self.timings = r.renderer.timings().to_vec();
            }
            if let Err(e) = r.ctx.check_validation() {
                self.error.get_or_insert(e.into());
            }
        }
        event_loop.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.running.is_none() && self.factory.is_some() {
            if let Err(e) = self.start(event_loop) {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => self.stop(event_loop),
            WindowEvent::Resized(size) => {
                if let Some(r) = self.running.as_mut() {
                    r.target.resize((size.width, size.height));
                }
            }
            WindowEvent::RedrawRequested => match self.frame() {
                Ok(true) => self.stop(event_loop),
                Ok(false) => {}
                Err(e) => {
                    self.error = Some(e);
                    self.stop(event_loop);
                }
            },
            other => match self.input(&other) {
                Ok(true) => self.stop(event_loop),
                Ok(false) => {}
                Err(e) => {
                    self.error = Some(e);
                    self.stop(event_loop);
                }
            },
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(r) = &self.running {
            if r.minimised {
                // Nothing to draw to: poll the size now and then instead of spinning.
                event_loop.set_control_flow(ControlFlow::WaitUntil(
                    Instant::now() + Duration::from_millis(100),
                ));
            } else {
                event_loop.set_control_flow(ControlFlow::Poll);
            }
            r.window.request_redraw();
        }
    }

    fn exiting(&mut self, _event_loop: &ActiveEventLoop) {
        self.running = None;
    }
}
