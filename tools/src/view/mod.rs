//! `inlay view SCENE`: the interactive viewer. A window shows the field
//! with the scene's objects inserted; the mouse orbits, pans and zooms the
//! camera (or flies it), picks an object and drags it across the field's
//! surfaces; keys rotate and scale it, edit its material, switch effects
//! and quality presets; an overlay shows the frame rate and per-module GPU
//! times. Without a display it renders headless and writes a PNG.

mod controls;
pub mod hud;
pub mod orbit;
pub mod picking;
pub mod presets;

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::window::PresentMode;
use inlay_engine::{Context, ContextOptions};
use inlay_passes::camera::CameraSpec;
use inlay_passes::field::{GpuGridField, GridField};
use inlay_passes::scene::{load_scene, Scene};

use crate::field_source::scene_field;
use crate::insertion_view::{Effects, InsertionView};
use crate::scene_view::view_over_gpu_field;
use crate::window_app::{run_window, WindowError, WindowOptions};
use controls::Controls;
use orbit::OrbitCamera;
use presets::Preset;

/// Options of `view`.
#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// The scene file.
    pub scene: PathBuf,
    /// Camera index or name to start from.
    #[arg(long, default_value = "0")]
    pub camera: String,
    /// Window width in pixels (small by default so a CPU device keeps up).
    #[arg(long, default_value_t = 480)]
    pub width: u32,
    /// Window height in pixels.
    #[arg(long, default_value_t = 270)]
    pub height: u32,
    /// Quality preset to start with (default: fast on a CPU device, the
    /// scene's knobs on a GPU).
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// Close after this many frames (scripted runs and tests).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Exposure multiplier before tonemapping.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Image written when no display exists (rendered headless instead).
    #[arg(long, default_value = "inlay-view.png")]
    pub out: PathBuf,
    /// Bake again even where a cached field or SSDF exists.
    #[arg(long)]
    pub no_cache: bool,
    /// Presentation mode: fifo (vsync), mailbox or immediate.
    #[arg(long, value_enum, default_value_t = PresentArg::Fifo)]
    pub present_mode: PresentArg,
    /// What the overlay shows at start (O cycles): full, compact (one line) or off.
    #[arg(long, value_enum, default_value_t = hud::Overlay::Full)]
    pub overlay: hud::Overlay,
}

/// How frames are paced on the window.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PresentArg {
    /// Wait for vertical blank.
    Fifo,
    /// Replace the queued image, never wait.
    Mailbox,
    /// Present at once (may tear).
    Immediate,
}

/// The viewer's state: the scene as authored, the field, the view built
/// from them at the current preset, and the input controls.
pub struct Viewer {
    authored: Scene,
    field: GridField,
    /// The field on the GPU, shared by the views of every preset.
    gpu_field: GpuGridField,
    view: InsertionView,
    preset: Preset,
    /// The views of the other presets built so far, kept so that stepping
    /// through the presets compiles each pipeline once (a CPU device keeps
    /// about 1 MiB of every pipeline it compiles, even once destroyed).
    parked: Vec<(Preset, InsertionView)>,
    use_cache: bool,
    controls: Controls,
}

impl Viewer {
    /// Opens `args.scene` at `preset`.
    pub fn open(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        args: &ViewArgs,
        preset: Preset,
    ) -> anyhow::Result<Self> {
        let authored = load_scene(&args.scene)?;
        let camera = authored.camera(&args.camera)?.clone();
        Self::over_scene(
            ctx,
            lib,
            authored,
            camera,
            preset,
            !args.no_cache,
            args.overlay,
        )
    }

    /// Opens the scene `authored` (as loaded, perhaps edited) from `camera`
    /// at `preset`; bakes are cached when `use_cache`.
    pub fn over_scene(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        mut authored: Scene,
        camera: CameraSpec,
        preset: Preset,
        use_cache: bool,
        overlay: hud::Overlay,
    ) -> anyhow::Result<Self> {
        let effects = Effects::of_scene(&authored.shadows);
        // Load the SSDF fields even when the scene draws no shadows, so
        // shadows can be switched on.
        authored.shadows.self_shadow = true;
        authored.shadows.cast = true;
        let field = scene_field(&authored, None, use_cache, Some(ctx.info()))?;
        let sky = crate::field_source::scene_sky(&authored, None)?;
        let seen = crate::field_source::scene_seen_lights(&authored, None)?;
        crate::field_source::light_with_sky(&mut authored, sky.as_ref())?;
        authored.seen_lights = seen.clone();
        let gpu_field = GpuGridField::upload(ctx, &field)?
            .with_sky(sky.map(Arc::new))
            .with_seen_lights(seen);
        let scene = preset.apply(&authored);
        let mut view = view_over_gpu_field(
            ctx,
            lib,
            &scene,
            scene.march,
            gpu_field.clone(),
            camera.clone(),
            use_cache,
        )?;
        // The camera holds still while an object is dragged: the field's
        // march is kept between such frames, and the dragged object's
        // lighting is traced and fitted in turn.
        view.frame.set_viewer_pacing(ctx, true);
        view.set_effects(effects);
        Ok(Self {
            controls: Controls::new(OrbitCamera::from_spec(&camera), &authored, overlay),
            authored,
            field,
            gpu_field,
            view,
            preset,
            parked: Vec::new(),
            use_cache,
        })
    }

    /// The view being drawn.
    pub fn view(&self) -> &InsertionView {
        &self.view
    }

    /// The view being drawn, to move objects or switch effects.
    pub fn view_mut(&mut self) -> &mut InsertionView {
        &mut self.view
    }

    /// The quality preset the view is built at.
    pub fn preset(&self) -> Preset {
        self.preset
    }

    /// Switches to the view of `preset` (built on first use, kept after),
    /// carrying over the camera, the effects and the objects' placements.
    fn switch_to(
        &mut self,
        preset: Preset,
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
    ) -> anyhow::Result<()> {
        let camera = self.controls.camera.spec();
        let mut view = match self.parked.iter().position(|(p, _)| *p == preset) {
            Some(i) => self.parked.swap_remove(i).1,
            None => {
                let scene = preset.apply(&self.authored);
                let mut view = view_over_gpu_field(
                    ctx,
                    lib,
                    &scene,
                    scene.march,
                    self.gpu_field.clone(),
                    camera.clone(),
                    self.use_cache,
                )?;
                view.frame.set_viewer_pacing(ctx, true);
                view
            }
        };
        view.set_camera(camera);
        view.set_effects(self.view.effects());
        for i in 0..self.view.objects().len() {
            if let Some(p) = self.view.placed(i) {
                view.set_placed(i, p);
            }
        }
        let previous = std::mem::replace(&mut self.view, view);
        self.parked.push((self.preset, previous));
        self.preset = preset;
        Ok(())
    }
}

impl crate::window_app::WindowScene for Viewer {
    fn scene(&mut self) -> &mut dyn crate::headless::Scene {
        &mut self.view
    }

    fn input(
        &mut self,
        event: &winit::event::WindowEvent,
        extent: (u32, u32),
    ) -> crate::window_app::Response {
        self.controls
            .handle(event, extent, &mut self.view, &self.field)
    }

    fn rebuild(&mut self, ctx: &Arc<Context>, lib: &ShaderLibrary) -> anyhow::Result<()> {
        self.switch_to(self.preset.next(), ctx, lib)?;
        println!("view: quality preset {}", self.preset.name());
        Ok(())
    }

    fn hud(&mut self, stats: &crate::window_app::HudStats<'_>) -> Vec<String> {
        self.controls.extent = stats.extent;
        self.controls.built_edits = self.controls.edits;
        let state = hud::HudState {
            preset: self.preset.name(),
            fly: self.controls.fly,
            effects: self.view.effects(),
            selected: self.controls.selected.and_then(|i| self.view.placed(i)),
            help: if self.controls.help {
                controls::help()
            } else {
                Vec::new()
            },
        };
        hud::hud_lines(stats, &state, self.controls.overlay)
    }

    fn presented(&mut self, frame: u64) {
        let (w, h) = self.controls.extent;
        if frame == 0 {
            let cam = self.view.frame(w.max(1), h.max(1));
            for i in 0..self.view.objects().len() {
                if let Some(p) = self.view.placed(i) {
                    let at = cam.project(p.sphere().0);
                    println!(
                        "view: first frame presented; object `{}` at pixel {}",
                        p.name,
                        at.map_or("(off screen)".into(), |(x, y)| format!("({x:.1}, {y:.1})"))
                    );
                }
            }
        }
        let built = self.controls.built_edits;
        if built > self.controls.announced_edits && !self.controls.dragging() {
            self.controls.announced_edits = built;
            println!("view: frame {frame} shows {built} edit(s)");
        }
    }
}

/// Runs `view`: the window, or a headless render when there is no display.
pub fn run(options: &ContextOptions, args: &ViewArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.exposure.is_finite() && args.exposure > 0.0,
        "--exposure must be a positive number, got {}",
        args.exposure
    );
    crate::outputs::check_image_output("--out", &args.out)?;
    let library = inlay_passes::shaders::library()?;
    let window = WindowOptions {
        context: options.clone(),
        title: format!("inlay view {}", args.scene.display()),
        size: (args.width.clamp(1, 16384), args.height.clamp(1, 16384)),
        present_mode: match args.present_mode {
            PresentArg::Fifo => PresentMode::Fifo,
            PresentArg::Mailbox => PresentMode::Mailbox,
            PresentArg::Immediate => PresentMode::Immediate,
        },
        frames: args.frames,
        exposure: args.exposure,
    };
    let view_args = args.clone();
    let factory = Box::new(
        move |ctx: &Arc<Context>,
              lib: &ShaderLibrary|
              -> anyhow::Result<Box<dyn crate::window_app::WindowScene>> {
            let preset = view_args.preset.unwrap_or(default_preset(ctx));
            Ok(Box::new(Viewer::open(ctx, lib, &view_args, preset)?))
        },
    );
    match run_window(window, library.clone(), factory) {
        Ok(timings) => {
            print!(
                "{}",
                crate::timings_table::format_table(&timings, "the window's device")
            );
            return Ok(());
        }
        Err(WindowError::NoDisplay(why)) => eprintln!("inlay: {why}; rendering headless instead"),
        Err(WindowError::Other(e)) => return Err(e),
    }
    let ctx = Context::new(options, None)?;
    let preset = args.preset.unwrap_or(default_preset(&ctx));
    let mut viewer = Viewer::open(&ctx, &library, args, preset)?;
    let frames = args.frames.unwrap_or(1).clamp(1, 1000) as u32;
    let run = crate::headless::run_headless(
        &ctx,
        &mut viewer.view,
        args.width,
        args.height,
        frames,
        0.0,
    )?;
    let bad = run.image.non_finite_count();
    anyhow::ensure!(bad == 0, "the frame has {bad} non-finite pixels");
    run.report(&ctx, std::slice::from_ref(&args.out), args.exposure)
}

/// Fast on a CPU device, the scene's own knobs on a GPU.
fn default_preset(ctx: &Context) -> Preset {
    if ctx.info().kind == inlay_engine::device_choice::DeviceKind::Cpu {
        Preset::Fast
    } else {
        Preset::Scene
    }
}
