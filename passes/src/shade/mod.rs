//! The object's SG shading pass (`object-shade`, compute; METHOD.md eq. 5)
//! over the G-buffer, with the brute-force CPU reference it is judged by
//! ([`shade_probe_reference`]). One dispatch per object shades that
//! object's pixels with its own fitted lobes; the output is the object's
//! radiance I_v with coverage in alpha, before any shadow. With
//! `[shading] field_light` the fitted lobes' diffuse light at each point
//! is scaled by the field's light there ([`field_light`]).

pub mod field_light;
mod reference;

pub use reference::{shade_probe_reference, shade_reference_with};

use crate::frame::meta::{Effect, EffectSwitch, PassInfo, Table1Module};
use std::sync::Arc;

use inlay_engine::graph::{BufferHandle, Dispatch, FrameGraph};
use inlay_engine::shader::ShaderLibrary;
use inlay_engine::{vk, Buffer, ComputePipeline, Context, ImageDesc};

use crate::brdf::NdfLobes;
use crate::camera::{CameraFrame, CameraRays};
use crate::composite::ObjectLayer;
use crate::field::GpuGridField;
use crate::gbuffer::GBuffer;
use crate::lighting::LightLobes;
use crate::march::MarchKnobs;
use crate::shadow::{shadow_defines, SsdfBindings};
use inlay_engine::shader::Define;

inlay_engine::gpu_struct! {
    /// `ShadePush` of `shaders/shade/shade_body.wgsl`.
    pub struct ShadePush = "shade/shade.wgsl" : "ShadePush" {
        /// The camera.
        pub camera: CameraRays,
        /// The object shaded by this dispatch (its G-buffer index).
        pub object_index: f32,
        /// Whether this dispatch writes zero at the pixels no object
        /// covers (the field light's gain pass; the shading clears its
        /// image first).
        pub write_empty: u32,
        /// Lobes that light the object.
        pub light_count: u32,
        /// Direct lobes at the end of those.
        pub direct_lobes: u32,
        /// Rays per direct lobe.
        pub direct_rays: u32,
        /// Local lights at the end of the direct lobes.
        pub local_count: u32,
        /// Side of each local light's visibility rays.
        pub local_side: u32,
        /// The field's march step (world units).
        pub march_step: f32,
        /// The march's early-termination transmittance.
        pub march_termination: f32,
        /// Side of the field-light rays per tile (0: off).
        pub field_side: u32,
        /// Lobes of L_env in `env_lobes` (what the field-light rays see
        /// past the field).
        pub env_count: u32,
        /// The first 8 × 8 tile the dispatch covers, x | y << 16: a
        /// self-shadowed object's shading and field light cover the tiles
        /// its bounding sphere can cover; 0 where a dispatch covers the
        /// image. The field light's gain pass counts it in its own tiles,
        /// of 8 · `field_scale` pixels.
        pub tile_origin: u32,
        /// The field light's tiles are this many times 8 pixels a side,
        /// each invocation of the gain pass taking its square of pixels
        /// ([`field_light::TileScale`]).
        pub field_scale: u32,
        /// The object's field light tiles: the first, x | y << 16 (in
        /// those tiles of 8 · `field_scale` pixels).
        pub field_origin: u32,
        /// How many of them: columns | rows << 16.
        pub field_tiles: u32,
        /// Padding.
        pub pad0: u32,
    }
}

/// The object-shade pass: its name, Table 1 module and effect switch.
pub const OBJECT_SHADE_INFO: PassInfo = PassInfo {
    name: "object-shade",
    module: Table1Module::Rendering,
    switch: Some(SELF_SHADOW_SWITCH),
};

/// The shading pass's name in the frame graph (and in timings).
pub const OBJECT_SHADE: &str = OBJECT_SHADE_INFO.name;

/// The field light's pass ([`field_light`]), run before `object-shade`
/// when `[shading] field_light` is on: each tile's rays and its table of
/// their sums. Its name, Table 1 module and switch.
pub const OBJECT_FIELD_LIGHT_INFO: PassInfo = PassInfo {
    name: "object-field-light",
    module: Table1Module::Rendering,
    switch: Some(SELF_SHADOW_SWITCH),
};

/// The field light's pass's name in the frame graph.
pub const OBJECT_FIELD_LIGHT: &str = OBJECT_FIELD_LIGHT_INFO.name;

/// The switch that leaves the objects' self-shadows out (eq. 9).
pub const SELF_SHADOW_SWITCH: EffectSwitch = EffectSwitch {
    effect: Effect::SelfShadow,
    name: "self-shadow",
    key: "F2",
};

/// Format of the object radiance image.
pub const OBJECT_COLOUR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// One object's self-shadow inputs for [`ShadePass::add`]: the f_h table
/// and its SSDF field's bindings.
#[derive(Debug, Clone, Copy)]
pub struct SelfShadow {
    /// The f_h table.
    pub fh_table: BufferHandle,
    /// The object's SSDF field and per-frame block.
    pub ssdf: SsdfBindings,
    /// The pixels the object can cover, (x0, y0, x1, y1) exclusive
    /// ([`crate::camera::CameraFrame::sphere_pixels`]; None: any): its
    /// shading and its field light's gain run over their tiles alone.
    pub pixels: Option<[u32; 4]>,
}

/// The shading pipelines (without self-shadows; with them from the SSDF;
/// with them from the SSDF and, for direct lobes or the field's light at
/// the point, from rays) and the NDF mixture they use.
pub struct ShadePass {
    pipeline: Arc<ComputePipeline>,
    /// Zero over the whole image, the shading pass's first dispatch.
    clear: Arc<ComputePipeline>,
    self_shadowed: Arc<ComputePipeline>,
    self_shadowed_direct: Arc<ComputePipeline>,
    /// The field light's tables (`field_light_tables`), run as their own
    /// pass before the shading when the field light is on.
    field_tables: Arc<ComputePipeline>,
    /// The gain the shading takes from the tables, alone
    /// (`field_gain_only`), for [`Self::new_field_gain`].
    field_gain: Arc<ComputePipeline>,
    /// Whether [`Self::add`] returns the gain pass's image instead of the
    /// shading ([`Self::new_field_gain`]).
    gain_only: bool,
    ndf: Arc<Buffer>,
    ndf_lobes: NdfLobes,
    march: MarchKnobs,
    /// Side of the field-light rays per tile (0: the paper's shading).
    field_side: u32,
    /// The field light's tiles (8 pixels a side times the scale).
    field_scale: field_light::TileScale,
    /// Bound as the direct lobes' rays, local lights and environment lobes
    /// where an object's light has none but the rays' variant runs.
    no_direct: Arc<Buffer>,
}

impl ShadePass {
    /// Compiles the pass for an `ndf_lobes`-lobe GGX mixture; local lights'
    /// visibility marches the field with `march`.
    pub fn new(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        ndf_lobes: u32,
        march: MarchKnobs,
    ) -> anyhow::Result<Self> {
        Self::build(ctx, lib, ndf_lobes, march)
    }

    /// A pass whose output, at the pixels of self-shadowed objects, is the
    /// gain [`field_light`] puts on the fitted lobes' diffuse light with
    /// `side`² rays per tile, in rgb with 1 in alpha, as the shading takes
    /// it from the tables the frame's `object-field-light` pass writes over
    /// the tiles of each object's [`SelfShadow::pixels`] (0 at their other
    /// pixels, the rest unwritten): for its test against the CPU mirror,
    /// and for inspection.
    pub fn new_field_gain(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        march: MarchKnobs,
        side: u32,
    ) -> anyhow::Result<Self> {
        let mut pass = Self::build(ctx, lib, 1, march)?.with_field_light(side);
        pass.gain_only = true;
        Ok(pass)
    }

    /// Scales the fitted lobes' diffuse light at each point of a
    /// self-shadowed object by the field's light there, from `side`² rays
    /// per tile ([`field_light`]; 0: off, the paper's shading). It rides
    /// with the self-shadowed variant (its rays start off the surface by
    /// the SSDF's radius): an object drawn without self-shadows is lit by
    /// its lobes alone.
    pub fn with_field_light(mut self, side: u32) -> Self {
        self.field_side = side.min(field_light::MAX_SIDE);
        self
    }

    /// The field light's tiles at `scale` (8 pixels a side until this is
    /// called; a fixed scale is kept within 1..=[`field_light::MAX_TILE_SCALE`]).
    pub fn with_field_light_scale(mut self, scale: field_light::TileScale) -> Self {
        self.field_scale = match scale {
            field_light::TileScale::Fixed(k) => {
                field_light::TileScale::Fixed(k.clamp(1, field_light::MAX_TILE_SCALE))
            }
            auto => auto,
        };
        self
    }

    fn build(
        ctx: &Arc<Context>,
        lib: &ShaderLibrary,
        ndf_lobes: u32,
        march: MarchKnobs,
    ) -> anyhow::Result<Self> {
        let ndf = NdfLobes::new(ndf_lobes).map_err(|m| anyhow::anyhow!("ndf_lobes: {m}"))?;
        let bytes: Vec<u8> = ndf.packed().iter().flat_map(|x| x.to_le_bytes()).collect();
        let mut defines = shadow_defines();
        defines.push(Define::Bool("SKIP_EMPTY", march.skip_empty));
        let shadowed = |file: &str, entry: &str| lib.compute_pipeline(ctx, file, entry, &defines);
        Ok(Self {
            pipeline: lib.compute_pipeline(ctx, "shade/shade.wgsl", "main", &[])?,
            clear: lib.compute_pipeline(ctx, "shade/shade.wgsl", "clear", &[])?,
            self_shadowed: shadowed("shade/shade_self_shadow.wgsl", "main")?,
            self_shadowed_direct: shadowed("shade/shade_self_shadow_direct.wgsl", "main")?,
            field_tables: shadowed("shade/shade_self_shadow_direct.wgsl", "field_light_tables")?,
            field_gain: shadowed("shade/shade_self_shadow_direct.wgsl", "field_gain_only")?,
            gain_only: false,
            ndf: Arc::new(Buffer::with_data(
                ctx,
                "ndf lobes",
                &bytes,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?),
            ndf_lobes: ndf,
            march,
            field_side: 0,
            field_scale: field_light::TileScale::Fixed(1),
            no_direct: Arc::new(Buffer::with_data(
                ctx,
                "no direct lobes",
                &[0u8; 32],
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )?),
        })
    }

    /// The NDF mixture it shades with.
    pub fn ndf_lobes(&self) -> &NdfLobes {
        &self.ndf_lobes
    }

    /// Adds `object-shade`: object i's pixels (index i in the G-buffer) are
    /// shaded with `lobes[i]` (an SG fit's lobe buffer), self-shadowed
    /// (eq. 9) where `self_shadow[i]` is given; local lights are seen
    /// through `field`. With the field light on, `object-field-light`
    /// comes first, writing each self-shadowed object's tables over the
    /// tiles of its [`SelfShadow::pixels`] into a buffer the shading reads
    /// (a pass of its own: its workgroup barriers would make lavapipe run
    /// the whole shading as coroutines). The image is cleared and shaded
    /// over `region` alone (the pixels the objects can cover, x0, y0, x1,
    /// y1; None: the whole image), and left undefined beyond it: the
    /// returned layer says so, and the compositing takes it as
    /// transparent there.
    #[allow(clippy::too_many_arguments)]
    pub fn add(
        &self,
        graph: &mut FrameGraph,
        camera: &CameraFrame,
        gbuffer: &GBuffer,
        field: &GpuGridField,
        lobes: &[LightLobes],
        self_shadow: &[Option<SelfShadow>],
        region: Option<[u32; 4]>,
    ) -> ObjectLayer {
        let (width, height) = (camera.width, camera.height);
        let out = graph.create_image(
            "object-colour",
            ImageDesc {
                width,
                height,
                format: OBJECT_COLOUR_FORMAT,
            },
        );
        let ndf = graph.import_buffer(&self.ndf, None);
        let mut out = out;
        let grid = field.import(graph);
        let no_direct = graph.import_buffer(&self.no_direct, None);
        let scale = self.field_scale.at(width, height);
        let field_tile = field_light::TILE * scale;
        let setups: Vec<ObjectSetup> = lobes
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let shadow = self_shadow.get(i).copied().flatten();
                let field_light = self.field_side > 0 && shadow.is_some();
                let local = l.direct.map(|d| d.local);
                let pixels = shadow.and_then(|s| s.pixels);
                let (origin, threads) = object_tiles(pixels, width, height, 8);
                // The object's field light tiles.
                let (field_origin, field_threads) = object_tiles(pixels, width, height, field_tile);
                let field_tiles = [field_threads[0] / 8, field_threads[1] / 8];
                ObjectSetup {
                    light: *l,
                    shadow,
                    field_light,
                    threads,
                    field_threads,
                    push: ShadePush {
                        camera: camera.rays(),
                        object_index: i as f32,
                        write_empty: 0,
                        light_count: l.count,
                        direct_lobes: l.direct.map_or(0, |d| d.lobes),
                        direct_rays: l.direct.map_or(0, |d| d.rays_per_lobe),
                        local_count: local.map_or(0, |x| x.count),
                        local_side: local.map_or(1, |x| x.side),
                        march_step: self.march.step(field.diagonal) as f32,
                        march_termination: self.march.termination as f32,
                        field_side: if field_light { self.field_side } else { 0 },
                        env_count: l.environment.filter(|_| field_light).map_or(0, |e| e.count),
                        tile_origin: origin,
                        field_scale: scale,
                        field_origin,
                        field_tiles: field_tiles[0] | (field_tiles[1] << 16),
                        pad0: 0,
                    },
                }
            })
            .collect();
        let common = CommonInputs {
            grid,
            gbuffer: *gbuffer,
            ndf,
            no_direct,
        };
        // The field light's tables first, in their own pass (its workgroup
        // barriers would slow the whole shading on lavapipe); a buffer per
        // object, each at most its image region's tiles (8 KiB a tile: at
        // most 7.2 MiB at 1280 × 720, 64 MiB at 3840 × 2160, under
        // lavapipe's 128 MiB storage binding however many objects the
        // frame holds).
        let mut field_tables: Vec<Option<BufferHandle>> = setups
            .iter()
            .map(|o| {
                (o.field_light && !o.off_screen()).then(|| {
                    let [x, y, _] = o.field_threads.map(|t| u64::from(t / 8));
                    let bytes = x * y * u64::from(field_light::TABLE_STRIDE) * 16;
                    graph.create_buffer("field-light-tiles", bytes)
                })
            })
            .collect();
        if field_tables.iter().any(Option::is_some) {
            let mut pass = graph.compute_pass(OBJECT_FIELD_LIGHT);
            for (o, buffer) in setups.iter().zip(field_tables.iter_mut()) {
                let Some(buffer) = buffer else {
                    continue;
                };
                // Tiles of 8 · scale pixels over the object's, each
                // invocation taking scale² pixels.
                let push = ShadePush {
                    tile_origin: o.push.field_origin,
                    ..o.push
                };
                common
                    .bind(pass.dispatch(&self.field_tables), o)
                    .write("field_light_tiles", buffer)
                    .push(&push)
                    .threads(o.field_threads);
            }
            pass.finish();
        }
        if self.gain_only {
            let mut gain = graph.create_image(
                "field-gain",
                ImageDesc {
                    width,
                    height,
                    format: OBJECT_COLOUR_FORMAT,
                },
            );
            let mut pass = graph.compute_pass("field-light-gain");
            let lit = setups
                .iter()
                .zip(&field_tables)
                .filter(|(o, _)| o.field_light);
            for (k, (o, tables)) in lit.enumerate() {
                if o.off_screen() {
                    continue;
                }
                let push = ShadePush {
                    write_empty: (k == 0) as u32,
                    ..o.push
                };
                common
                    .bind(pass.dispatch(&self.field_gain), o)
                    .read_opt("field_light_tiles", *tables)
                    .write("out_object", &mut gain)
                    .push(&push)
                    .threads(o.threads);
            }
            pass.finish();
            return ObjectLayer {
                image: gain,
                region: None,
            };
        }
        // The region's tiles cleared, then each object shaded: a
        // self-shadowed one over the tiles its bounding sphere can cover
        // alone. Lavapipe gives every invocation of the self-shadowed
        // shaders a fixed cost (their size), even one that returns at
        // once: over the whole image that was most of the pass
        // (docs/benchmarks.md, issue 26's fifth pass).
        let mut pass = graph.compute_pass(OBJECT_SHADE);
        let (origin, threads) = object_tiles(region, width, height, 8);
        let clear = ShadePush {
            camera: camera.rays(),
            tile_origin: origin,
            ..bytemuck::Zeroable::zeroed()
        };
        pass.dispatch(&self.clear)
            .write("out_object", &mut out)
            .push(&clear)
            .threads(threads);
        for (o, tables) in setups.iter().zip(&field_tables) {
            let rays = o.light.direct.is_some() || o.field_light;
            let pipeline = match (o.shadow, rays) {
                (Some(_), true) => &self.self_shadowed_direct,
                (Some(_), false) => &self.self_shadowed,
                (None, _) => &self.pipeline,
            };
            if o.off_screen() {
                continue;
            }
            // Where the field light is off the shader reads no table; the
            // binding takes L_env's filler.
            common
                .bind(pass.dispatch(pipeline), o)
                .read("field_light_tiles", tables.unwrap_or(no_direct))
                .write("out_object", &mut out)
                .push(&o.push)
                .threads(o.threads);
        }
        pass.finish();
        ObjectLayer { image: out, region }
    }
}

/// A dispatch over the `tile` × `tile` tiles holding `pixels` (x0, y0,
/// x1, y1; None: the whole `width` × `height`), 8 × 8 invocations a tile:
/// its first tile (x | y << 16) and its invocations.
fn object_tiles(pixels: Option<[u32; 4]>, width: u32, height: u32, tile: u32) -> (u32, [u32; 3]) {
    let [x0, y0, x1, y1] = pixels.unwrap_or([0, 0, width, height]);
    let (x1, y1) = (x1.min(width), y1.min(height));
    let (tx0, ty0) = (x0 / tile, y0 / tile);
    let (tx1, ty1) = (x1.div_ceil(tile), y1.div_ceil(tile));
    (
        tx0 | (ty0 << 16),
        [tx1.saturating_sub(tx0) * 8, ty1.saturating_sub(ty0) * 8, 1],
    )
}

/// One object's shading inputs and push constants for a frame.
struct ObjectSetup {
    light: LightLobes,
    shadow: Option<SelfShadow>,
    field_light: bool,
    /// The invocations of its dispatches: over the tiles of its
    /// [`SelfShadow::pixels`] (from `push.tile_origin`), or the image.
    threads: [u32; 3],
    /// The invocations of its field light tables' dispatch: 8 × 8 a tile
    /// of its field light tiles (from `push.field_origin`).
    field_threads: [u32; 3],
    push: ShadePush,
}

impl ObjectSetup {
    /// Whether its tiles are empty (its bounding sphere is off screen).
    fn off_screen(&self) -> bool {
        self.threads[0] == 0 || self.threads[1] == 0
    }
}

/// What every object's dispatch binds alike.
struct CommonInputs {
    grid: crate::field::GridBindings,
    gbuffer: GBuffer,
    ndf: BufferHandle,
    no_direct: BufferHandle,
}

impl CommonInputs {
    /// Binds the G-buffer, the object's lobes, the NDF mixture, and where
    /// it is self-shadowed its SSDF and mesh and, for the rays' variant,
    /// its direct lobes' rays, local lights and L_env's lobes (fillers
    /// where it has none).
    fn bind<'p, 'g>(&self, dispatch: Dispatch<'p, 'g>, o: &ObjectSetup) -> Dispatch<'p, 'g> {
        let l = &o.light;
        let rays = l.direct.is_some() || o.field_light;
        let filler = (o.shadow.is_some() && rays && l.direct.is_none()).then_some(self.no_direct);
        let mut d = self
            .grid
            .bind(dispatch)
            .read("normal_roughness", self.gbuffer.normal_roughness)
            .read("albedo_metallic", self.gbuffer.albedo_metallic)
            .read("distance_id", self.gbuffer.distance_id)
            .read("light_lobes", l.buffer)
            .read("ndf_lobes", self.ndf);
        if let Some(s) = o.shadow {
            d = d
                .read("fh_table", s.fh_table)
                .read("ssdf", s.ssdf.object)
                .read("objects", s.ssdf.records)
                .read("ssdf_rows", s.ssdf.rows)
                .read("ssdf_coefs", s.ssdf.coefs)
                .read("bvh_nodes", s.ssdf.bvh_nodes)
                .read("bvh_triangles", s.ssdf.bvh_triangles);
        }
        let env = (o.shadow.is_some() && rays).then(|| {
            l.environment
                .filter(|_| o.field_light)
                .map_or(self.no_direct, |e| e.buffer)
        });
        let local = l.direct.map(|d| d.local);
        d.read_opt("sharp_rays", l.direct.map(|r| r.rays).or(filler))
            .read_opt("local_lights", local.map(|x| x.lights).or(filler))
            .read_opt("env_lobes", env)
    }
}
