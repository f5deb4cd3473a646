//! The windowed target: a winit window whose swapchain shows a scene's HDR
//! image through the present pass, with resize and minimise handled and the
//! per-pass timings printed once a second.

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

/// Builds a scene once the context exists.
pub type SceneFactory =
    Box<dyn FnOnce(&Arc<Context>, &ShaderLibrary) -> anyhow::Result<Box<dyn Scene>>>;

// Field order is drop order: Vulkan objects go before the window.
struct Running {
    present: PresentPipeline,
    scene: Box<dyn Scene>,
    target: WindowTarget,
    renderer: Renderer,
    ctx: Arc<Context>,
    window: Arc<Window>,
    started: Instant,
    last_report: Instant,
    frames: u64,
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
        let factory = self
            .factory
            .take()
            .ok_or_else(|| anyhow::anyhow!("window started twice"))?;
        let scene = factory(&ctx, &self.library)?;
        let renderer = Renderer::new(&ctx, DEFAULT_FRAMES_IN_FLIGHT)?;
        println!(
            "window: {} on {} ({:?}), present mode {:?}",
            self.options.title,
            ctx.info().name,
            ctx.info().kind,
            target.present_mode()
        );
        let now = Instant::now();
        self.running = Some(Running {
            present,
            scene,
            target,
            renderer,
            ctx,
            window,
            started: now,
            last_report: now,
            frames: 0,
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
        }
        let (w, h) = r.target.extent();
        let time = r.started.elapsed().as_secs_f32();
        let mut graph = FrameGraph::new();
        let hdr = r.scene.build(&mut graph, w, h, time)?;
        let swapchain = r.target.import(&mut graph, acquired);
        r.present
            .add_pass(&mut graph, hdr, swapchain, self.options.exposure);
        r.renderer.submit(graph, &r.target.submit_sync(acquired))?;
        r.target.present(acquired)?;
        r.frames += 1;
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
            _ => {}
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
