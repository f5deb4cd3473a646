//! The shadow passes on lavapipe: the SSDF bake kernel against its f64
//! CPU mirror.

mod common;

use std::sync::Arc;

use inlay_passes::object::ObjectMesh;
use inlay_passes::shaders::embedded_library;
use inlay_passes::ssdf::{bake_reference, grid_for, lookup_points, object_scene, SsdfBaker};

use common::bundled_object as bundled;

/// The bake kernel (f32) against the f64 CPU mirror on a 4³ grid with
/// 8 × 8 directions: the same silhouettes and the same signs, so the
/// values agree to f32 rounding of the angles (10⁻⁴ rad), except where an
/// edge's silhouette test or a ray grazes a triangle edge and f32 decides
/// otherwise than f64 (allowed for 1 % of the samples).
#[test]
fn bake_kernel_matches_cpu_mirror() {
    let ctx = common::gpu();
    let lib = embedded_library();
    let baker = SsdfBaker::new(&ctx, &lib).unwrap();
    for file in ["checker-cube.gltf", "toy.glb"] {
        let mesh = bundled(file);
        let grid = grid_for(&mesh, 4);
        let scene = object_scene(&mesh);
        let points = lookup_points(&scene, &grid);
        let gpu = baker
            .run(&ctx, &mesh, &scene, &points, 8, &|_, _| {})
            .unwrap()
            .0;
        let cpu = bake_reference(&mesh, &scene, &points, 8);
        assert_eq!(gpu.len(), cpu.len());
        let off: Vec<(usize, f64)> = gpu
            .iter()
            .zip(&cpu)
            .enumerate()
            .map(|(i, (g, c))| (i, (*g as f64 - c).abs()))
            .filter(|(_, e)| *e > 1e-4)
            .collect();
        assert!(
            off.len() * 100 <= cpu.len(),
            "{file}: {} of {} differ, e.g. {:?}",
            off.len(),
            cpu.len(),
            &off[..off.len().min(5)]
        );
        assert!(cpu.iter().any(|v| *v < 0.0) && cpu.iter().any(|v| *v > 0.5));
        common::assert_no_validation_errors(&ctx);
    }
}

use glam::DVec3;
use inlay_engine::{vk, Buffer, ImageDesc, Readback};
use inlay_passes::camera::{CameraFrame, CameraSpec};
use inlay_passes::composite::{
    composite_over, composite_shade_field, CompositePass, Layering, ObjectLayer, COMPOSITE_FORMAT,
};
use inlay_passes::field::GpuGridField;
use inlay_passes::geometry::MeshScene;
use inlay_passes::geometry::Ray;
use inlay_passes::lighting::local::Emission;
use inlay_passes::lighting::{lobe_rays, DirectRays, LightLobes, LocalLight, LocalLightBindings};
use inlay_passes::march::{MarchKnobs, MarchPass, MARCH_COLOUR_FORMAT, MARCH_DEPTH_FORMAT};
use inlay_passes::object::{ObjectRecords, PlacedObject};
use inlay_passes::probe::EnvironmentLobes;
use inlay_passes::rng::Pcg32;
use inlay_passes::sg::Sg64;
use inlay_passes::shadow::{
    cast_shadow_factor, hemisphere_integral, self_shadow_factors, shadow_point, CastScale,
    CastShadowPass, DirectOcclusion, GpuFhTable, GpuSsdf, SHADOW_FORMAT,
};
use inlay_passes::ssdf::reference::{hits, ssdf_by_ray_casting};
use inlay_passes::ssdf::{OutsideMode, SsdfField, SsdfKnobs};
use std::f64::consts::PI;

/// An SSDF field baked on the GPU at test size.
fn small_field(
    ctx: &Arc<inlay_engine::Context>,
    mesh: &Arc<ObjectMesh>,
    grid: u32,
    directions: u32,
) -> SsdfField {
    let lib = embedded_library();
    let knobs = SsdfKnobs {
        grid,
        directions,
        components: 16,
        ..SsdfKnobs::default()
    };
    let samples = SsdfBaker::new(ctx, &lib)
        .unwrap()
        .bake(ctx, mesh, &knobs, &|_, _| {})
        .unwrap();
    SsdfField::compress(&samples, knobs.components)
}

fn random_unit(rng: &mut Pcg32) -> DVec3 {
    let [u, v] = rng.next_2d();
    let z = 2.0 * u - 1.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f64::consts::TAU * v;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Sampled S against ray casting on the toy (a 10³ grid of 16² directions,
/// 16 components): inside the grid (trilinear) the mean error is that of
/// the grid and PCA; outside, the corrected mode beats clamping, and
/// truncating to +∞ misses every shadowing direction (its error is the
/// whole gap to π).
#[test]
fn sampled_ssdf_matches_ray_casting_per_mode() {
    let ctx = common::gpu();
    let mesh = bundled("toy.glb");
    let field = small_field(&ctx, &mesh, 10, 16);
    let scene = object_scene(&mesh);
    let (c, r) = mesh.bounding_sphere();
    let mut rng = Pcg32::new(5, 1);
    let mut errors: std::collections::HashMap<(&str, &str), Vec<f64>> = Default::default();
    let mut n = 0;
    while n < 120 {
        let outside = n % 2 == 1;
        let dist = if outside {
            r * (2.7 + 7.0 * rng.next_f64())
        } else {
            r * (1.05 + 0.4 * rng.next_f64())
        };
        let x = c + random_unit(&mut rng) * dist;
        if scene.inside(x) || field.grid.contains(x) == outside {
            continue;
        }
        // Directions towards the object, where shadows come from.
        let d = ((c + random_unit(&mut rng) * r * 0.8) - x).normalize();
        let truth = ssdf_by_ray_casting(&scene, x, d, 64, 0.02);
        let region = if outside { "outside" } else { "inside" };
        for mode in OutsideMode::ALL {
            let s = field.sample(x, d, mode).min(std::f64::consts::PI);
            errors
                .entry((region, mode.name()))
                .or_default()
                .push((s - truth).abs());
        }
        n += 1;
    }
    let mean = |k: (&str, &str)| errors[&k].iter().sum::<f64>() / errors[&k].len() as f64;
    for (k, v) in &errors {
        eprintln!("{k:?}: mean |ΔS| {:.4} rad over {}", mean(*k), v.len());
    }
    // Measured: inside 0.076 rad; outside correct 0.059, clamp 0.108,
    // infinity 3.16. Inside, every mode samples the same trilinear field.
    assert!(
        mean(("inside", "correct")) < 0.08,
        "{}",
        mean(("inside", "correct"))
    );
    assert!(mean(("outside", "correct")) < 0.8 * mean(("outside", "clamp")));
    assert!(
        mean(("outside", "correct")) < 0.08,
        "{}",
        mean(("outside", "correct"))
    );
    assert!(mean(("outside", "infinity")) > 1.0);
    common::assert_no_validation_errors(&ctx);
}

/// Light lobes in the SG fit's buffer layout (slot 0 of 2).
fn lobe_buffer(ctx: &Arc<inlay_engine::Context>, lobes: &[Sg64]) -> Arc<Buffer> {
    let mut v: Vec<f32> = Vec::new();
    for slot in 0..2 {
        for g in lobes {
            let p = g.direction.normalize();
            let s = if slot == 0 { 1.0 } else { 0.0 };
            v.extend([p.x as f32, p.y as f32, p.z as f32, g.sharpness as f32]);
            v.extend([
                (g.amplitude.x * s) as f32,
                (g.amplitude.y * s) as f32,
                (g.amplitude.z * s) as f32,
                0.0,
            ]);
        }
    }
    let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    Arc::new(
        Buffer::with_data(
            ctx,
            "test lobes",
            &bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )
        .unwrap(),
    )
}

/// A sun-like lobe, a warm broad one and a dim sky.
fn test_lobes() -> Vec<Sg64> {
    vec![
        Sg64 {
            direction: DVec3::new(-0.2, 1.0, 0.6).normalize(),
            sharpness: 300.0,
            amplitude: DVec3::new(400.0, 380.0, 300.0),
        },
        Sg64 {
            direction: DVec3::new(-0.5, 0.8, 0.2).normalize(),
            sharpness: 8.0,
            amplitude: DVec3::new(2.0, 1.5, 1.0),
        },
        Sg64 {
            direction: DVec3::Y,
            sharpness: 1.0,
            amplitude: DVec3::new(0.3, 0.4, 0.6),
        },
    ]
}

/// ρ by brute force: ∫ L' (ω·n)+ / ∫ L (ω·n)+ over a 96² octahedral map,
/// one ray cast against the placed object per direction; L' is L where
/// the ray escapes and, where it hits the mesh, the radiance of a
/// Lambertian surface of the hit's albedo and shading normal lit by the
/// lobes (what the cast shadow's bounce models with the bounding sphere's
/// cap), capped at 1 as the model is.
fn rho_brute_force(scene: &MeshScene, lobes: &[Sg64], x: DVec3, n: DVec3) -> DVec3 {
    rho_brute_force_over(scene, lobes, x, n, 96)
}

/// [`rho_brute_force`] over a `side`² octahedral map.
fn rho_brute_force_over(scene: &MeshScene, lobes: &[Sg64], x: DVec3, n: DVec3, side: u32) -> DVec3 {
    let map =
        inlay_passes::probe::DirectionMap::new(inlay_passes::probe::MapKind::Octahedral, side);
    let (mut num, mut den) = (DVec3::ZERO, DVec3::ZERO);
    for t in 0..map.texels() as u32 {
        let (tx, ty) = (t % map.width, t / map.width);
        let w = map.direction(tx, ty);
        let cos = w.dot(n);
        if cos <= 0.0 {
            continue;
        }
        let l: DVec3 = lobes.iter().map(|g| g.eval(w)).sum();
        let e = l * cos * map.solid_angle(tx, ty);
        den += e;
        let ray = Ray {
            origin: x + n * 1e-4,
            dir: w,
        };
        match scene.intersect(&ray, 0.0, f64::INFINITY) {
            None => num += e,
            Some(hit) => {
                let s = scene.surface(&ray, &hit);
                let facing = Sg64::clamped_cosine(s.normal);
                let irradiance: DVec3 = lobes
                    .iter()
                    .map(|g| {
                        let p = g.product(&facing);
                        p.amplitude * hemisphere_integral(p.sharpness)
                    })
                    .sum();
                num += s.material.albedo * irradiance / PI * cos * map.solid_angle(tx, ty);
            }
        }
    }
    (num / den).min(DVec3::ONE)
}

/// How the cast shadow of one configuration compares.
struct CastComparison {
    /// Largest |ρ_gpu − ρ_cpu| over the pixels whose rays agree.
    worst_mirror: f64,
    /// Share of pixels where the GPU and the mirror differ by more than
    /// 2e-3 (a direct lobe's ray grazing an edge may go either way in f32
    /// and f64: each such ray moves ρ by its lobe's share / rays).
    off_mirror: f64,
    /// Mean and largest |ρ − brute force| at the sampled pixels.
    mean: f64,
    worst: f64,
    /// Pixels sampled, and how many of them brute force finds shadowed.
    sampled: usize,
    shadowed: usize,
    /// Pixels whose point at D̂/Ô lies off any surface (marched again to
    /// the surface behind), left unshadowed there and shadowed.
    off_surface: (usize, usize),
}

impl CastComparison {
    /// The pixels within 2e-3 of the f64 mirror (f32 against f64
    /// positions, normals and SSDF reads: measured 1.0e-4): all of them
    /// where `off_limit` is 0, else all but a share under `off_limit`;
    /// and a shadow to compare: at least five sampled pixels that brute
    /// force finds shadowed.
    fn assert_on_mirror_and_shadowed(&self, off_limit: f64) {
        assert!(
            self.off_mirror == 0.0 || self.off_mirror < off_limit,
            "{} of pixels off the mirror",
            self.off_mirror
        );
        assert!(
            self.worst_mirror < 2e-3,
            "worst |ρ_gpu − ρ_cpu| {}",
            self.worst_mirror
        );
        assert!(self.shadowed >= 5, "{} shadowed pixels", self.shadowed);
    }
}

/// BOOKS' first object over a small bake of its field, with its SSDF, the
/// f_h table and a camera looking down at it: what the cast-shadow tests
/// share.
struct CastScene {
    grid_field: inlay_passes::field::GridField,
    gpu_field: GpuGridField,
    placed: PlacedObject,
    ssdf: GpuSsdf,
    fh: GpuFhTable,
    march_knobs: MarchKnobs,
    spec: CameraSpec,
}

fn cast_scene(ctx: &Arc<inlay_engine::Context>) -> CastScene {
    let scene = common::bundled_scene("books.toml");
    let grid_field = common::bake_small(&scene, 64, 2, 0);
    let gpu_field = GpuGridField::upload(ctx, &grid_field).unwrap();
    let placed: PlacedObject = scene.objects[0].clone();
    let field = Arc::new(small_field(ctx, &placed.mesh, 8, 16));
    let ssdf = GpuSsdf::upload(ctx, field, &placed.mesh).unwrap();
    let fh = GpuFhTable::new(ctx).unwrap();
    let (c, _) = placed.sphere();
    let spec = CameraSpec {
        name: None,
        position: c + DVec3::new(0.0, 0.5, 0.45),
        look_at: c - DVec3::new(0.0, 0.1, 0.0),
        up: DVec3::Y,
        fov_y: 40.0,
    };
    let march_knobs = MarchKnobs {
        skip_empty: false,
        ..scene.march
    };
    CastScene {
        grid_field,
        gpu_field,
        placed,
        ssdf,
        fh,
        march_knobs,
        spec,
    }
}

/// The cast-shadow pass on BOOKS (its gold sphere on the white book, seen
/// from above) under `lobes`, the last `direct` of them shadowed by rays
/// cast against the mesh: the kernel against its CPU mirror at every field
/// pixel, and ρ against brute-force visibility integration at the 30 most
/// shadowed pixels and 30 spread over the rest.
/// With `local`, the last lobe is that local light's (after the `direct`
/// sharp ones), its shadow cast by rays to its disk.
fn compare_cast_shadow(
    lobes: &[Sg64],
    direct: usize,
    local: Option<(LocalLight, Emission)>,
) -> CastComparison {
    let ctx = common::gpu();
    let lib = embedded_library();
    let CastScene {
        grid_field,
        gpu_field,
        placed,
        ssdf,
        fh,
        march_knobs,
        spec,
    } = cast_scene(&ctx);
    let lobe_buf = lobe_buffer(&ctx, lobes);
    let locals = local.map_or(0, |_| 1);
    let sharp_end = lobes.len() - locals;
    let rays: Vec<Vec<DVec3>> = lobes[sharp_end - direct..sharp_end]
        .iter()
        .map(|g| lobe_rays(g, 6))
        .collect();
    let ray_buf = ray_buffer(&ctx, &rays);
    let local_list: Vec<(LocalLight, Emission)> = local.into_iter().collect();
    let local_buf = local_light_buffer(&ctx, &local_list);
    let object_scene = inlay_passes::ssdf::object_scene(&placed.mesh);
    let occlusion = DirectOcclusion {
        scene: &object_scene,
        rays: &rays,
        local: &local_list,
        local_side: 3,
        field: Some((&grid_field, march_knobs)),
    };
    let direct_total = direct + locals;
    let (w, h) = (48u32, 36u32);
    let cam = CameraFrame::new(&spec, w, h);
    let march = MarchPass::new(&ctx, &lib, march_knobs).unwrap();
    let cast = CastShadowPass::new(&ctx, &lib, march_knobs, CastScale::Fixed(1), 1.0).unwrap();
    let desc = |format| ImageDesc {
        width: w,
        height: h,
        format,
    };
    let rb = [
        Readback::new(&ctx, desc(MARCH_COLOUR_FORMAT)).unwrap(),
        Readback::new(&ctx, desc(MARCH_DEPTH_FORMAT)).unwrap(),
        Readback::new(&ctx, desc(SHADOW_FORMAT)).unwrap(),
    ];
    common::run_frame(&ctx, |graph| {
        let m = march.add(graph, &gpu_field, &cam, None);
        let light = LightLobes {
            environment: None,
            buffer: graph.import_buffer(&lobe_buf, None),
            count: lobes.len() as u32,
            direct: (direct_total > 0).then(|| {
                let rays = graph.import_buffer(&ray_buf, None);
                DirectRays {
                    lobes: direct_total as u32,
                    rays,
                    rays_per_lobe: 36,
                    local: LocalLightBindings {
                        lights: graph.import_buffer(&local_buf, None),
                        count: locals as u32,
                        side: 3,
                    },
                }
            }),
        };
        let table = fh.import(graph);
        let records = ObjectRecords::upload(graph, [&placed]);
        let s = ssdf.import(graph, &placed, (records, 0), OutsideMode::Correct);
        let rho = cast.add(graph, &gpu_field, &cam, &m, light, table, s, None);
        rb[0].add_to_graph(graph, m.colour_opacity);
        rb[1].add_to_graph(graph, m.depth);
        rb[2].add_to_graph(graph, rho);
    });
    let [colour, depth, rho] = rb.map(|r| r.read().unwrap());
    let mesh_scene = MeshScene::new(std::slice::from_ref(&placed));
    let (mut worst_mirror, mut checked, mut off) = (0.0f64, 0, 0);
    let mut off_surface = (0, 0);
    let mut brute = Vec::new();
    let mut candidates = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let o = colour.pixels[i][3] as f64;
            let g = DVec3::from_array(std::array::from_fn(|c| rho.pixels[i][c] as f64));
            if o < 0.5 {
                assert_eq!(g, DVec3::ONE, "({x},{y})");
                continue;
            }
            let ray = cam.pixel_ray(x, y);
            let premultiplied =
                DVec3::from_array(std::array::from_fn(|c| colour.pixels[i][c] as f64));
            let Some(sp) = shadow_point(
                &grid_field,
                &ray,
                (premultiplied, depth.pixels[i][0] as f64, o),
                &march_knobs,
            ) else {
                assert_eq!(g, DVec3::ONE, "({x},{y}): no surface, yet shadowed");
                continue;
            };
            let (p, n) = (sp.point, sp.normal);
            let radiance = premultiplied / o;
            let factor = |radiance| {
                cast_shadow_factor(
                    &ssdf.field,
                    &placed,
                    &fh.table,
                    lobes,
                    p,
                    n,
                    radiance,
                    OutsideMode::Correct,
                    (direct_total > 0).then_some(occlusion),
                    &ssdf.reflectance,
                )
            };
            let shared = DVec3::ONE - (DVec3::ONE - factor(radiance)) * sp.share;
            if sp.point != ray.at(depth.pixels[i][0] as f64 / o) {
                if shared == DVec3::ONE {
                    off_surface.0 += 1;
                } else {
                    off_surface.1 += 1;
                }
            }
            let diff = (shared - g).abs().max_element();
            if diff > 2e-3 {
                off += 1;
            } else {
                worst_mirror = worst_mirror.max(diff);
            }
            checked += 1;
            // The brute force knows only the lobes: compared without the
            // field's irradiance floor; not at field points inside the
            // mesh (the sphere sinks into the small bake's book), hidden
            // by the object, where its rays meet the mesh from within.
            if !mesh_scene.inside(p) {
                candidates.push((factor(DVec3::ZERO), p, n));
            }
        }
    }
    candidates.sort_by(|a, b| a.0.y.total_cmp(&b.0.y));
    let step = (candidates.len() / 30).max(1);
    for (i, (mirror, p, n)) in candidates.iter().enumerate() {
        if i < 30 || i % step == 0 {
            brute.push((*mirror, rho_brute_force(&mesh_scene, lobes, *p, *n)));
        }
    }
    assert!(checked > 500, "{checked}");
    common::assert_no_validation_errors(&ctx);
    let errors: Vec<f64> = brute.iter().map(|(m, t)| (m.y - t.y).abs()).collect();
    CastComparison {
        worst_mirror,
        off_mirror: off as f64 / checked as f64,
        mean: errors.iter().sum::<f64>() / errors.len() as f64,
        worst: errors.iter().copied().fold(0.0, f64::max),
        sampled: brute.len(),
        shadowed: brute.iter().filter(|(_, t)| t.y < 0.9).count(),
        off_surface,
    }
}

/// One frame of BOOKS' cast scene (`scene`, from `cast_scene`) under
/// `test_lobes` at `w` × `h`, read back: the march's colour and depth, ρ at full
/// resolution (`reference`), and `pass`'s ρ at its scale (`low`) and
/// after its `finish` (`fine`), as the cast-shadow tests at a scale
/// compare them; and the frame as `pass` composites it with its last
/// level blended in `composite` (`CastShadowPass::composite`): the
/// shadowed field alone (`field_only`), and over an object layer, for
/// which the march's own colour stands in over the middle of the image
/// (`region`; transparent beyond it: `layered`).
struct ScaledCast {
    colour: Vec<[f32; 4]>,
    depth: Vec<[f32; 4]>,
    reference: Vec<[f32; 4]>,
    low: Vec<[f32; 4]>,
    fine: Vec<[f32; 4]>,
    field_only: Vec<[f32; 4]>,
    layered: Vec<[f32; 4]>,
    width: u32,
    region: [u32; 4],
}

fn run_scaled_cast(
    ctx: &Arc<inlay_engine::Context>,
    scene: &CastScene,
    pass: &CastShadowPass,
    (w, h): (u32, u32),
) -> ScaledCast {
    let lib = embedded_library();
    let CastScene {
        gpu_field,
        placed,
        ssdf,
        fh,
        march_knobs,
        spec,
        ..
    } = scene;
    let march_knobs = *march_knobs;
    let lobes = test_lobes();
    let lobe_buf = lobe_buffer(ctx, &lobes);
    let (lw, lh) = inlay_passes::shadow::upsample::low_size(w, h, pass.scale_at(w, h));
    let cam = CameraFrame::new(spec, w, h);
    let march = MarchPass::new(ctx, &lib, march_knobs).unwrap();
    let full = CastShadowPass::new(ctx, &lib, march_knobs, CastScale::Fixed(1), 1.0).unwrap();
    let desc = |width, height, format| ImageDesc {
        width,
        height,
        format,
    };
    let rb = [
        Readback::new(ctx, desc(w, h, MARCH_COLOUR_FORMAT)).unwrap(),
        Readback::new(ctx, desc(w, h, MARCH_DEPTH_FORMAT)).unwrap(),
        Readback::new(ctx, desc(w, h, SHADOW_FORMAT)).unwrap(),
        Readback::new(ctx, desc(lw, lh, SHADOW_FORMAT)).unwrap(),
        Readback::new(ctx, desc(w, h, SHADOW_FORMAT)).unwrap(),
        Readback::new(ctx, desc(w, h, COMPOSITE_FORMAT)).unwrap(),
        Readback::new(ctx, desc(w, h, COMPOSITE_FORMAT)).unwrap(),
    ];
    let composite = CompositePass::new(ctx, &lib).unwrap();
    let region = [w / 4, h / 4, 3 * w / 4, 3 * h / 4];
    common::run_frame(ctx, |graph| {
        let m = march.add(graph, gpu_field, &cam, None);
        let light = LightLobes {
            environment: None,
            buffer: graph.import_buffer(&lobe_buf, None),
            count: lobes.len() as u32,
            direct: None,
        };
        let table = fh.import(graph);
        let records = ObjectRecords::upload(graph, [placed]);
        let s = ssdf.import(graph, placed, (records, 0), OutsideMode::Correct);
        let reference = full.add(graph, gpu_field, &cam, &m, light, table, s, None);
        let low = pass.add(graph, gpu_field, &cam, &m, light, table, s, None);
        let inputs = inlay_passes::shadow::cast::CastInputs {
            lobes: light,
            fh_table: table,
            ssdf: s,
        };
        let fine = pass.finish(graph, gpu_field, &cam, &m, low, &[inputs]);
        let mut composited = |object| {
            let layers = (object, Layering::FieldOverObject);
            pass.composite(
                graph,
                gpu_field,
                &cam,
                &m,
                (low, &[inputs]),
                &composite,
                layers,
            )
        };
        let field_only = composited(None);
        let layered = composited(Some(ObjectLayer {
            image: m.colour_opacity,
            region: Some(region),
        }));
        rb[0].add_to_graph(graph, m.colour_opacity);
        rb[1].add_to_graph(graph, m.depth);
        rb[2].add_to_graph(graph, reference);
        rb[3].add_to_graph(graph, low);
        rb[4].add_to_graph(graph, fine);
        rb[5].add_to_graph(graph, field_only);
        rb[6].add_to_graph(graph, layered);
    });
    let [colour, depth, reference, low, fine, field_only, layered] =
        rb.map(|r| r.read().unwrap().pixels);
    let c = ScaledCast {
        colour,
        depth,
        reference,
        low,
        fine,
        field_only,
        layered,
        width: w,
        region,
    };
    c.assert_composited_as_finished();
    c
}

/// ρ of a read-back pixel.
fn rgb(p: &[f32; 4]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

impl ScaledCast {
    /// The frame composited with the last level blended in `composite`
    /// (and the flagged pixels refined and composited again) is the frame
    /// composited with `finish`'s full-resolution ρ: the same f32 blend
    /// and flags in another shader, so the same values (1e-6 relative);
    /// the object layer only inside its region.
    fn assert_composited_as_finished(&self) {
        let mut shadowed = 0;
        let [x0, y0, x1, y1] = self.region;
        for (i, (field, rho)) in self.colour.iter().zip(&self.fine).enumerate() {
            let (x, y) = (i as u32 % self.width, i as u32 / self.width);
            let inside = (x0..x1).contains(&x) && (y0..y1).contains(&y);
            let object = if inside { *field } else { [0.0; 4] };
            let shaded = composite_shade_field(*field, [rho[0], rho[1], rho[2]]);
            let layered = composite_over(shaded, object);
            for (got, want) in [(self.field_only[i], shaded), (self.layered[i], layered)] {
                for c in 0..4 {
                    let tol = 1e-6 * want[c].abs().max(1e-3);
                    assert!(
                        (got[c] - want[c]).abs() <= tol,
                        "pixel {i}: composited {got:?}, finished {want:?}"
                    );
                }
            }
            shadowed += (rho[1] < 0.9) as usize;
        }
        assert!(shadowed > 0, "no shadowed pixel to composite");
    }

    /// Each pixel's depth along its ray (None where the field is empty),
    /// as the upsampling weighs blocks by.
    fn depths(&self) -> Vec<Option<f64>> {
        self.colour
            .iter()
            .zip(&self.depth)
            .map(|(c, d)| (c[3] > 1e-4).then(|| d[0] as f64 / c[3] as f64))
            .collect()
    }
}

/// At half resolution (`[shadows] cast_scale = 2`): each block's ρ is the
/// full-resolution pass's at the block's source pixel (the same kernel at
/// the same point: 1e-6), and `shadow-upsample` is its f64 mirror
/// (`shadow::upsample_shadow`, 1e-5: f32 weights). With `cast_refine`,
/// `shadow-refine` gives the full-resolution pass's ρ at the pixels the
/// mirror flags (`upsample_with_flags`) and the upsampled ρ elsewhere; a
/// pixel whose flag f32 decides otherwise (a spread or depth gap at the
/// threshold) may take the other, and only that.
#[test]
fn half_resolution_cast_shadow_matches_the_full_one_and_its_mirror() {
    use inlay_passes::shadow::upsample::{low_size, source_pixel};
    let ctx = common::gpu();
    let lib = embedded_library();
    let (w, h) = (47u32, 35u32);
    let (lw, lh) = low_size(w, h, 2);
    let spread = 0.02;
    let scene = cast_scene(&ctx);
    let knobs = scene.march_knobs;
    let pass = |s| CastShadowPass::new(&ctx, &lib, knobs, CastScale::Fixed(2), s).unwrap();
    let (half, refined) = (pass(1.0), pass(spread));
    assert!(!half.refines() && refined.refines());
    assert!(CastShadowPass::new(&ctx, &lib, knobs, CastScale::Fixed(9), 1.0).is_err());
    let plain = run_scaled_cast(&ctx, &scene, &half, (w, h));
    let fine = run_scaled_cast(&ctx, &scene, &refined, (w, h)).fine;
    let (reference, low, up) = (&plain.reference, &plain.low, &plain.fine);
    let mut shadowed = 0;
    for y in 0..lh {
        for x in 0..lw {
            let (sx, sy) = source_pixel(x, y, 2, w, h);
            let a = rgb(&low[(y * lw + x) as usize]);
            let b = rgb(&reference[(sy * w + sx) as usize]);
            assert!((a - b).abs().max_element() < 1e-6, "({x}, {y}): {a} vs {b}");
            shadowed += (a.y < 0.9) as u32;
        }
    }
    assert!(shadowed >= 3, "{shadowed} shadowed blocks");
    let z = plain.depths();
    let low_rho: Vec<DVec3> = low.iter().map(rgb).collect();
    let mirror = inlay_passes::shadow::upsample_shadow(&low_rho, &z, w, h, 2);
    for (i, m) in mirror.iter().enumerate() {
        let g = rgb(&up[i]);
        assert!((g - *m).abs().max_element() < 1e-5, "pixel {i}: {g} vs {m}");
    }
    let flags = inlay_passes::shadow::upsample::upsample_with_flags(&low_rho, &z, w, h, 2, spread);
    let (mut flagged, mut other) = (0, 0);
    for (i, (m, flag)) in flags.iter().enumerate() {
        let g = rgb(&fine[i]);
        let exact = rgb(&reference[i]);
        let near = |a: DVec3, b: DVec3, tol: f64| (a - b).abs().max_element() < tol;
        let (expect, alternative) = if *flag { (exact, *m) } else { (*m, exact) };
        flagged += *flag as u32;
        if !near(g, expect, 1e-5) {
            assert!(
                near(g, alternative, 1e-5),
                "pixel {i}: {g}, flag {flag}, exact {exact}, upsampled {m}"
            );
            other += 1;
        }
    }
    let n = (w * h) as usize;
    assert!(
        other * 100 <= n,
        "{other} pixels flagged otherwise than the mirror"
    );
    // The shadow's edges are refined, not the whole image.
    assert!(
        flagged >= 5 && (flagged as usize) * 2 < n,
        "{flagged} of {n} pixels refined"
    );
    eprintln!("refined {flagged} of {n} pixels ({other} by f32 otherwise than the mirror)");
    common::assert_no_validation_errors(&ctx);
}

/// At a quarter of the resolution with refinement (`cast_scale = 4`), the
/// shadow is brought to scale 2, refined, then to full resolution and
/// refined again (`shadow::upsample::refine_levels`, the f64 mirror, with
/// the full-resolution pass's ρ as the exact value at each flagged point):
/// the GPU gives the mirror's image (1e-5: f32 weights) but where f32
/// decides a flag otherwise (at most 2 % of the pixels: a flag at one
/// level moves the blends below it), and takes fewer points exactly than
/// one step from 4 to 1 would.
#[test]
fn cast_shadow_refined_a_level_at_a_time_matches_its_mirror() {
    use inlay_passes::shadow::upsample::{refine_levels, upsample_with_flags};
    let ctx = common::gpu();
    let lib = embedded_library();
    let (w, h, scale, spread) = (61u32, 45u32, 4u32, 0.02);
    let scene = cast_scene(&ctx);
    let pass = CastShadowPass::new(
        &ctx,
        &lib,
        scene.march_knobs,
        CastScale::Fixed(scale),
        spread,
    )
    .unwrap();
    let c = run_scaled_cast(&ctx, &scene, &pass, (w, h));
    let z = c.depths();
    let low_rho: Vec<DVec3> = c.low.iter().map(rgb).collect();
    let taken = std::cell::Cell::new(0usize);
    let exact = |x: u32, y: u32| {
        taken.set(taken.get() + 1);
        rgb(&c.reference[(y * w + x) as usize])
    };
    let mirror = refine_levels(&low_rho, &z, (w, h), scale, spread, exact);
    let n = (w * h) as usize;
    let (mut other, mut shadowed) = (0, 0);
    for (i, m) in mirror.iter().enumerate() {
        let g = rgb(&c.fine[i]);
        other += ((g - *m).abs().max_element() >= 1e-5) as usize;
        shadowed += (rgb(&c.reference[i]).y < 0.9) as usize;
    }
    assert!(shadowed >= 20, "{shadowed} shadowed pixels");
    assert!(other * 50 <= n, "{other} of {n} pixels off the mirror");
    let one_step = upsample_with_flags(&low_rho, &z, w, h, scale, spread)
        .iter()
        .filter(|(_, f)| *f)
        .count();
    assert!(
        taken.get() > 0 && taken.get() < one_step,
        "{} points taken exactly by levels, {one_step} in one step",
        taken.get()
    );
    eprintln!(
        "levels took {} points exactly (one step: {one_step}); {other} of {n} pixels off the mirror",
        taken.get()
    );
    common::assert_no_validation_errors(&ctx);
}

/// The cast shadow under a sun, a broad lobe and a sky, all from the SSDF.
#[test]
fn cast_shadow_matches_mirror_and_brute_force() {
    let c = compare_cast_shadow(&test_lobes(), 0, None);
    eprintln!(
        "SSDF: ρ vs brute force over {} pixels ({} shadowed): mean |Δρ| {:.4}, worst {:.4}; mirror worst {:.2e}",
        c.sampled, c.shadowed, c.mean, c.worst, c.worst_mirror
    );
    c.assert_on_mirror_and_shadowed(0.0);
    // The book's edges put points off any surface, some in the shadow and
    // some not (2 and 8 of them): both of pixel_factor's ways there, the
    // second march and its skip where ρ is 1, are held to the mirror.
    assert!(
        c.off_surface.0 >= 1 && c.off_surface.1 >= 1,
        "off-surface pixels (unshadowed, shadowed): {:?}",
        c.off_surface
    );
    // Measured on lavapipe: mean 0.0098, worst 0.077 (the half-space model
    // at the penumbra's edge, an 8³ grid of 16² directions; the bounce's
    // cap against the mesh's own faces; and the model's bounce takes the
    // lobes' light from below x's plane as the shadowed field around x,
    // where here it is distant light: 0.0092 and 0.082 without that).
    // Without the bounce in the model the umbra's 30 pixels alone miss
    // the brute force by 0.05–0.1 each.
    assert!(c.mean < 0.025, "mean |Δρ| {}", c.mean);
    assert!(c.worst < 0.15, "worst |Δρ| {}", c.worst);
}

/// The cast shadow keeps the fitted lobes a point's SSDF is read for as the
/// bits of two words, lobes 0–31 and 32–63 (`shaders/shadow/cast_body.wgsl`
/// `cast_factor`): 37 faint broad lobes spread over the sky come first here,
/// so that the three of `test_lobes`, which make the shadow, are lobes
/// 37–39, and the mirror, which has one loop over them all, must still
/// agree at every pixel.
#[test]
fn cast_shadow_over_more_than_32_lobes_matches_mirror() {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut lobes: Vec<Sg64> = (0..37)
        .map(|i| {
            let y = 1.0 - (i as f64 + 0.5) / 37.0;
            let r = (1.0 - y * y).sqrt();
            let phi = i as f64 * golden;
            Sg64 {
                direction: DVec3::new(r * phi.cos(), y, r * phi.sin()),
                sharpness: 2.0 + (i % 5) as f64,
                amplitude: DVec3::new(0.02, 0.025, 0.03),
            }
        })
        .collect();
    lobes.extend(test_lobes());
    let c = compare_cast_shadow(&lobes, 0, None);
    eprintln!(
        "40 lobes: mirror worst {:.2e}, {} of {} sampled shadowed",
        c.worst_mirror, c.shadowed, c.sampled
    );
    c.assert_on_mirror_and_shadowed(0.0);
}

/// Far from the object (3–8 bounding radii), where the half-space model
/// of f_h says little and the cap on each lobe's occlusion decides: CUPS'
/// cube (it covers about half of its bounding sphere's disc) seen from the
/// table around it (normal up: the cube near the horizon) and from walls
/// facing it, ρ from the model against brute force over a 384² map (the
/// cube covers about 300–2000 of its texels). Against Blender Cycles the cap as the
/// lobe's peak over the sphere's cone, times the cone, darkened CUPS'
/// far field by 0.43 % where Cycles' darkens 0.22 %; the light over the
/// cone (`shadow::ConeQuadrature`) takes it to 0.15 % (docs/fidelity.md).
#[test]
fn far_points_lose_what_the_silhouette_blocks() {
    let ctx = common::gpu();
    let scene = common::bundled_scene("cups.toml");
    let placed: PlacedObject = scene.objects[0].clone();
    let field = Arc::new(small_field(&ctx, &placed.mesh, 8, 16));
    let ssdf = GpuSsdf::upload(&ctx, field, &placed.mesh).unwrap();
    let fh = GpuFhTable::new(&ctx).unwrap();
    let mesh_scene = MeshScene::new(std::slice::from_ref(&placed));
    let lobes = test_lobes();
    let (c, r) = placed.sphere();
    let to_world = placed.world_to_object().inverse();
    let bottom = placed
        .mesh
        .vertices
        .iter()
        .map(|v| to_world.transform_point3(v.position.as_dvec3()).y)
        .fold(f64::INFINITY, f64::min);
    let (mut model, mut truth, mut worst) = (0.0, 0.0, 0.0f64);
    let mut points = 0;
    for k in 0..8 {
        let azimuth = k as f64 * PI / 4.0 + 0.3;
        let away = DVec3::new(azimuth.cos(), 0.0, azimuth.sin());
        for radii in [3.0, 5.0, 8.0] {
            let on_table = DVec3::new(c.x, bottom, c.z) + away * radii * r;
            let on_wall = c + away * radii * r;
            for (x, n) in [(on_table, DVec3::Y), (on_wall, -away)] {
                let rho = cast_shadow_factor(
                    &ssdf.field,
                    &placed,
                    &fh.table,
                    &lobes,
                    x,
                    n,
                    DVec3::ZERO,
                    OutsideMode::Correct,
                    None,
                    &ssdf.reflectance,
                );
                let brute = rho_brute_force_over(&mesh_scene, &lobes, x, n, 384);
                model += 1.0 - rho.y;
                truth += 1.0 - brute.y;
                worst = worst.max((rho.y - brute.y).abs());
                points += 1;
            }
        }
    }
    eprintln!(
        "far field over {points} points: mean darkening model {:.5}, brute force {:.5}, worst |Δρ| {:.5}",
        model / points as f64,
        truth / points as f64,
        worst
    );
    // Measured: the model darkens these points 1.36× as much as brute
    // force (with the sphere's bound alone, 7.7×; with the cone but each
    // lobe weighted by its product with the cosine's SG, 1.64×). What is
    // left: the mesh's mean fill of its sphere's disc, 0.63, where the
    // cube seen side-on covers 0.42–0.60 (the sky lobe alone: 1.10×), and
    // the light its faces send back, which the model takes from one
    // Lambertian face towards the point (the broad lobe alone: 1.37×).
    assert!(truth > 0.0);
    assert!(
        model / truth > 0.8 && model / truth < 2.0,
        "model / brute force {}",
        model / truth
    );
}

/// The same with the sun shaded directly (as a lobe of L_env too sharp for
/// the fit is): its shadow ray-cast against the mesh, 36 rays of the lobe
/// per pixel. The brute force's error falls to the rays' stratification.
#[test]
fn direct_lobe_shadow_matches_mirror_and_brute_force() {
    let mut lobes = test_lobes();
    lobes.rotate_left(1);
    let c = compare_cast_shadow(&lobes, 1, None);
    eprintln!(
        "rays: ρ vs brute force over {} pixels ({} shadowed): mean |Δρ| {:.4}, worst {:.4}; mirror worst {:.2e}, {:.2} % of pixels off it",
        c.sampled, c.shadowed, c.mean, c.worst, c.worst_mirror, 100.0 * c.off_mirror
    );
    // A ray grazing an edge may go either way in f32 and f64.
    c.assert_on_mirror_and_shadowed(0.01);
    // Measured on lavapipe: mean 0.0092, worst 0.039 (SSDF: 0.0098,
    // 0.077); the bounce's light from below x's plane, taken at x's ratio,
    // is here distant light, unshadowed.
    assert!(c.mean < 0.02, "mean |Δρ| {}", c.mean);
    assert!(c.worst < 0.1, "worst |Δρ| {}", c.worst);
}

/// World directions, one vec4 each, for a [`DirectRays`] buffer.
fn ray_buffer(ctx: &Arc<inlay_engine::Context>, rays: &[Vec<DVec3>]) -> Arc<Buffer> {
    let mut bytes: Vec<u8> = rays
        .iter()
        .flatten()
        .flat_map(|d| [d.x as f32, d.y as f32, d.z as f32, 0.0])
        .flat_map(f32::to_le_bytes)
        .collect();
    bytes.resize(bytes.len().max(16), 0);
    Arc::new(
        Buffer::with_data(
            ctx,
            "test rays",
            &bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )
        .unwrap(),
    )
}

/// Γ_k on the object's surface (the toy, self-shadowing under its cap)
/// against brute force: the visible share of each lobe's light above the
/// surface, ∫ G_k max(n·ω, 0) V / ∫ G_k max(n·ω, 0) (shading already
/// takes the cosine and the horizon), over a 96² octahedral map with one
/// ray per direction.
#[test]
fn self_shadow_factors_match_brute_force() {
    let ctx = common::gpu();
    let mesh = bundled("toy.glb");
    let field = small_field(&ctx, &mesh, 12, 16);
    let placed = PlacedObject {
        name: "toy".into(),
        mesh: mesh.clone(),
        pose: Default::default(),
        material: Default::default(),
    };
    let scene = MeshScene::new(std::slice::from_ref(&placed));
    let table = inlay_passes::shadow::FhTable::new();
    let lobes = test_lobes();
    // The sun-like lobe (first) as a direct lobe: last, with its rays.
    let mut direct_lobes = lobes.clone();
    direct_lobes.rotate_left(1);
    let rays = vec![lobe_rays(&lobes[0], 6)];
    let object_scene = inlay_passes::ssdf::object_scene(&mesh);
    let occlusion = DirectOcclusion {
        scene: &object_scene,
        rays: &rays,
        local: &[],
        local_side: 1,
        field: None,
    };
    let map = inlay_passes::probe::DirectionMap::new(inlay_passes::probe::MapKind::Octahedral, 96);
    let (c, r) = mesh.bounding_sphere();
    let mut rng = Pcg32::new(9, 2);
    let mut errors = Vec::new();
    let mut direct_errors = Vec::new();
    while errors.len() < 90 {
        let o = c + random_unit(&mut rng) * 3.0 * r;
        let ray = inlay_passes::geometry::Ray {
            origin: o,
            dir: ((c + random_unit(&mut rng) * 0.5 * r) - o).normalize(),
        };
        let Some(hit) = scene.intersect(&ray, 0.0, f64::INFINITY) else {
            continue;
        };
        let surf = scene.surface(&ray, &hit);
        let n = surf.normal;
        // Off the surface on the side the shading normal faces (some of the
        // toy's triangles wind against their vertex normals: off along the
        // face normal, the point was inside and brute force saw nothing).
        let x = surf.point + surf.face_normal * (1e-4 * surf.face_normal.dot(n).signum());
        let model = self_shadow_factors(
            &field,
            &placed,
            &table,
            &lobes,
            x,
            n,
            OutsideMode::Correct,
            None,
        );
        let direct = self_shadow_factors(
            &field,
            &placed,
            &table,
            &direct_lobes,
            x,
            n,
            OutsideMode::Correct,
            Some(occlusion),
        );
        for (k, (g, m)) in lobes.iter().zip(model).enumerate() {
            let (mut vis, mut all) = (0.0, 0.0);
            for t in 0..map.texels() as u32 {
                let (tx, ty) = (t % map.width, t / map.width);
                let w = map.direction(tx, ty);
                let e = g.weight(w) * n.dot(w).max(0.0) * map.solid_angle(tx, ty);
                all += e;
                if !hits(&scene, x, w) {
                    vis += e;
                }
            }
            if all > 1e-9 * g.integral().max_element() {
                errors.push((m, vis / all, g.sharpness));
                // Below the horizon a lobe adds nothing to the shading and
                // its rays keep Γ = 1: compared where its axis is above.
                if k == 0 && n.dot(g.direction) > 0.0 {
                    direct_errors.push((direct[2] - vis / all).abs());
                }
            }
        }
    }
    let mean = errors.iter().map(|(m, t, _)| (m - t).abs()).sum::<f64>() / errors.len() as f64;
    let sharp: Vec<_> = errors.iter().filter(|e| e.2 > 100.0).collect();
    let sharp_mean = sharp.iter().map(|(m, t, _)| (m - t).abs()).sum::<f64>() / sharp.len() as f64;
    eprintln!(
        "Γ vs brute force: mean |ΔΓ| {mean:.4} over {}, sharp lobe {sharp_mean:.4}",
        errors.len()
    );
    // Measured: 0.0185 over all lobes and 0.0183 for the sun-like lobe
    // (0.083 and 0.095 while the test put two of its points inside the toy,
    // where brute force sees nothing: those figures were mostly that). Γ
    // taken as q(S) of the raw lobe, without the tangent plane's own
    // visibility divided out, was off by 0.159 over all lobes against the
    // flawed truth.
    assert!(mean < 0.04, "{mean}");
    assert!(sharp_mean < 0.04, "{sharp_mean}");
    // The same lobe shadowed by its 36 rays cast against the mesh (as a
    // direct lobe, too sharp for the fit, is): the error is the rays'
    // stratification and their neglect of the cosine within the lobe.
    let direct_mean = direct_errors.iter().sum::<f64>() / direct_errors.len() as f64;
    eprintln!(
        "Γ of the sharp lobe by ray casting: mean |ΔΓ| {direct_mean:.4} over {}",
        direct_errors.len()
    );
    // Measured: 0.0016.
    assert!(direct_errors.len() >= 20);
    assert!(direct_mean < 0.01, "{direct_mean}");
    common::assert_no_validation_errors(&ctx);
}

use inlay_passes::brdf::{shade_sg_split, NdfLobes, SurfaceMaterial};
use inlay_passes::gbuffer::{
    GBufferPass, ObjectDraw, ALBEDO_METALLIC_FORMAT, DISTANCE_ID_FORMAT, NORMAL_ROUGHNESS_FORMAT,
};
use inlay_passes::object::GpuObject;
use inlay_passes::shade::{SelfShadow, ShadePass, OBJECT_COLOUR_FORMAT};

/// The toy seen close up for the shading tests: its mesh with its SSDF
/// (12³, 16²) and f_h table on the GPU, the G-buffer pass and the camera.
struct ToyView {
    ctx: Arc<inlay_engine::Context>,
    lib: inlay_engine::shader::ShaderLibrary,
    ssdf_field: Arc<SsdfField>,
    placed: PlacedObject,
    ssdf: GpuSsdf,
    fh: GpuFhTable,
    gpu_object: GpuObject,
    gbuffer: GBufferPass,
    cam: CameraFrame,
}

/// One pixel of the toy as [`ToyView::shade`] rendered it.
struct ShadedPixel {
    /// Its column and row.
    pixel: (u32, u32),
    ray: Ray,
    /// The G-buffer's surface point, normal and material.
    point: DVec3,
    normal: DVec3,
    material: SurfaceMaterial,
    /// What the shading kernel wrote.
    gpu: DVec3,
}

impl ToyView {
    fn new() -> Self {
        let ctx = common::gpu();
        let lib = embedded_library();
        let mesh = bundled("toy.glb");
        let ssdf_field = Arc::new(small_field(&ctx, &mesh, 12, 16));
        let placed = PlacedObject {
            name: "toy".into(),
            mesh: mesh.clone(),
            pose: Default::default(),
            material: Default::default(),
        };
        let (c, r) = mesh.bounding_sphere();
        let spec = CameraSpec {
            name: None,
            position: c + DVec3::new(0.4, 0.5, 2.2) * r,
            look_at: c,
            up: DVec3::Y,
            fov_y: 40.0,
        };
        Self {
            ssdf: GpuSsdf::upload(&ctx, ssdf_field.clone(), &mesh).unwrap(),
            fh: GpuFhTable::new(&ctx).unwrap(),
            gpu_object: GpuObject::upload(&ctx, &mesh).unwrap(),
            gbuffer: GBufferPass::new(&ctx, &lib).unwrap(),
            cam: CameraFrame::new(&spec, 48, 40),
            ssdf_field,
            placed,
            ctx,
            lib,
        }
    }

    /// Renders the toy's G-buffer and `shade`'s output over `field`, lit by
    /// what `lights` imports, self-shadowed; returns the toy's pixels and
    /// the brightest value written.
    fn shade(
        &self,
        shade: &ShadePass,
        field: &GpuGridField,
        lights: impl Fn(&mut inlay_engine::graph::FrameGraph) -> LightLobes,
    ) -> (Vec<ShadedPixel>, f64) {
        let (w, h) = (self.cam.width, self.cam.height);
        let rb = [
            NORMAL_ROUGHNESS_FORMAT,
            ALBEDO_METALLIC_FORMAT,
            DISTANCE_ID_FORMAT,
            OBJECT_COLOUR_FORMAT,
        ]
        .map(|format| {
            Readback::new(
                &self.ctx,
                ImageDesc {
                    width: w,
                    height: h,
                    format,
                },
            )
            .unwrap()
        });
        common::run_frame(&self.ctx, |graph| {
            let records = ObjectRecords::upload(graph, [&self.placed]);
            let g = self
                .gbuffer
                .add(
                    graph,
                    &self.cam,
                    &[ObjectDraw {
                        placed: &self.placed,
                        gpu: &self.gpu_object,
                        record: 0,
                    }],
                    records,
                )
                .unwrap();
            let light = lights(graph);
            let self_shadow = SelfShadow {
                fh_table: self.fh.import(graph),
                ssdf: self
                    .ssdf
                    .import(graph, &self.placed, (records, 0), OutsideMode::Correct),
                pixels: {
                    let (c, r) = self.placed.sphere();
                    self.cam.sphere_pixels(c, r)
                },
            };
            let out = shade
                .add(
                    graph,
                    &self.cam,
                    &g,
                    field,
                    &[light],
                    &[Some(self_shadow)],
                    None,
                )
                .image;
            rb[0].add_to_graph(graph, g.normal_roughness);
            rb[1].add_to_graph(graph, g.albedo_metallic);
            rb[2].add_to_graph(graph, g.distance_id);
            rb[3].add_to_graph(graph, out);
        });
        let [nr, am, di, colour] = rb.map(|r| r.read().unwrap());
        let peak = colour
            .pixels
            .iter()
            .map(|p| p[0].max(p[1]).max(p[2]) as f64)
            .fold(0.0, f64::max);
        let mut pixels = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                if di.pixels[i][1] < 0.0 {
                    continue;
                }
                let ray = self.cam.pixel_ray(x, y);
                let g = nr.pixels[i].map(f64::from);
                let a = am.pixels[i].map(f64::from);
                pixels.push(ShadedPixel {
                    pixel: (x, y),
                    point: ray.at(di.pixels[i][0] as f64),
                    normal: DVec3::new(g[0], g[1], g[2]).normalize(),
                    material: SurfaceMaterial {
                        albedo: DVec3::new(a[0], a[1], a[2]),
                        roughness: g[3],
                        metallic: a[3],
                    },
                    gpu: DVec3::from_array(std::array::from_fn(|c| colour.pixels[i][c] as f64)),
                    ray,
                });
            }
        }
        (pixels, peak)
    }
}

/// The self-shadowed shading kernels (`shade/shade_self_shadow.wgsl`, and
/// `shade/shade_self_shadow_direct.wgsl` whose last lobe is a direct one,
/// its Γ ray-cast against the mesh) against their f64 mirror: Γ from
/// `self_shadow_factors`, shading from `shade_sg_split`, at every pixel of
/// the toy (which shadows itself under its cap), from the G-buffer's own
/// point, normal and material. Tolerance: f32 rounding, 10⁻⁴ of the pixel
/// plus 10⁻⁵ of the brightest (these lobes are at most λ 300; measured:
/// within 18 % of that); a ray grazing an edge may go either way in f32 and
/// f64, so up to 1 % of the pixels may differ by a ray's share of the
/// direct lobe (measured: none).
#[test]
fn self_shadowed_shading_matches_its_mirror() {
    let view = ToyView::new();
    let ctx = &view.ctx;
    let shade = ShadePass::new(ctx, &view.lib, 1, MarchKnobs::default()).unwrap();
    let gpu_field = common::empty_field(ctx);
    let ndf = NdfLobes::new(1).unwrap();
    let mut lobes = test_lobes();
    lobes.rotate_left(1);
    let lobe_buf = lobe_buffer(ctx, &lobes);
    let rays = vec![lobe_rays(lobes.last().unwrap(), 6)];
    let ray_buf = ray_buffer(ctx, &rays);
    let object_scene = inlay_passes::ssdf::object_scene(&view.placed.mesh);
    let occlusion = DirectOcclusion {
        scene: &object_scene,
        rays: &rays,
        local: &[],
        local_side: 1,
        field: None,
    };
    for direct in [false, true] {
        let (pixels, peak) = view.shade(&shade, &gpu_field, |graph| LightLobes {
            environment: None,
            buffer: graph.import_buffer(&lobe_buf, None),
            count: lobes.len() as u32,
            direct: direct.then(|| {
                let rays = graph.import_buffer(&ray_buf, None);
                DirectRays {
                    lobes: 1,
                    rays,
                    rays_per_lobe: 36,
                    local: no_local_lights(rays),
                }
            }),
        });
        let (mut off, mut worst, mut shadowed) = (0, 0.0f64, 0);
        for px in &pixels {
            let gamma = self_shadow_factors(
                &view.ssdf_field,
                &view.placed,
                &view.fh.table,
                &lobes,
                px.point,
                px.normal,
                OutsideMode::Correct,
                direct.then_some(occlusion),
            );
            if gamma.iter().any(|&g| g < 0.5) {
                shadowed += 1;
            }
            let cpu =
                shade_sg_split(&lobes, &gamma, px.normal, -px.ray.dir, &px.material, &ndf).total();
            let err = ((px.gpu - cpu).abs() / (cpu.abs() * 1e-4 + 1e-5 * peak)).max_element();
            if err > 1.0 {
                off += 1;
            } else {
                worst = worst.max(err);
            }
        }
        let shaded = pixels.len();
        eprintln!(
            "self-shadowed shading, direct lobe {direct}: {shaded} pixels, {shadowed} shadowed, {off} off the mirror, worst {worst:.3} of the tolerance"
        );
        assert!(shaded > 300 && shadowed > 20, "{shaded} {shadowed}");
        let allowed = if direct { shaded / 100 } else { 0 };
        assert!(off <= allowed, "{off} of {shaded} pixels off the mirror");
    }
    common::assert_no_validation_errors(ctx);
}

/// No local lights: any storage buffer stands in for their (unread) buffer.
fn no_local_lights(
    buffer: inlay_engine::graph::BufferHandle,
) -> inlay_passes::lighting::LocalLightBindings {
    inlay_passes::lighting::LocalLightBindings {
        lights: buffer,
        count: 0,
        side: 1,
    }
}

/// A field around the toy (its bounding sphere `c`, `r`): a glowing ball
/// up and to one side, and a slab of thin medium between it and part of
/// the toy, so the ball is clear from some shaded points, half hidden
/// from others and behind the cap from the rest.
fn lamp_field(c: DVec3, r: f64) -> (inlay_passes::field::GridField, LocalLight) {
    let n = 40u32;
    let bounds = inlay_passes::geometry::Aabb {
        min: c - DVec3::splat(4.0 * r),
        max: c + DVec3::splat(4.0 * r),
    };
    let lamp = c + DVec3::new(1.5, 2.6, 1.0) * r;
    let h = bounds.size() / (n - 1) as f64;
    let mut nodes = Vec::with_capacity((n * n * n) as usize);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = bounds.min + DVec3::new(i as f64, j as f64, k as f64) * h;
                let q = (p - c) / r;
                let node = if p.distance(lamp) < 0.35 * r {
                    [30.0, 25.0, 20.0, 200.0 / r as f32]
                } else if (0.2..1.1).contains(&q.x) && (1.3..1.8).contains(&q.y) {
                    [0.1, 0.2, 0.1, 1.6 / r as f32]
                } else {
                    [0.0; 4]
                };
                nodes.push(node);
            }
        }
    }
    let field = inlay_passes::field::GridField::new(glam::UVec3::splat(n), bounds, nodes, 4);
    let light = LocalLight {
        centre: lamp,
        radius: 0.5 * r,
        emission: None,
    };
    (field, light)
}

/// The lamp field around the toy ([`lamp_field`]) and the toy's light in
/// it: the test lobes, then the lamp's lobe as the centre sees it (which
/// the per-pixel shading replaces), with the buffers the shading binds.
struct LampLights {
    field: inlay_passes::field::GridField,
    gpu_field: GpuGridField,
    light: LocalLight,
    emission: Emission,
    lobes: Vec<Sg64>,
    /// Broad lobes standing for L_env past the field.
    environment: Vec<Sg64>,
    lobe_buf: Arc<Buffer>,
    local_buf: Arc<Buffer>,
    ray_buf: Arc<Buffer>,
    env_buf: Arc<Buffer>,
}

impl LampLights {
    fn new(view: &ToyView) -> Self {
        use inlay_passes::lighting::local;
        let ctx = &view.ctx;
        let (c, r) = view.placed.mesh.bounding_sphere();
        let (field, light) = lamp_field(c, r);
        let emission = Emission {
            intensity: DVec3::new(0.8, 0.6, 0.5) * r * r,
            radius: 0.3 * r,
        };
        let mut lobes = test_lobes();
        let to = light.centre - c;
        lobes.push(local::sphere_lobe(
            to.normalize(),
            to.length(),
            emission.radius,
            emission.intensity,
        ));
        // Half the fitted lobes: where nothing in the field is in the way,
        // the field's light at the surface is half what the lobes say.
        let environment: Vec<Sg64> = test_lobes()
            .into_iter()
            .map(|g| Sg64 {
                amplitude: 0.5 * g.amplitude,
                ..g
            })
            .collect();
        Self {
            gpu_field: GpuGridField::upload(ctx, &field).unwrap(),
            env_buf: lobe_buffer(ctx, &environment),
            environment,
            lobe_buf: lobe_buffer(ctx, &lobes),
            local_buf: local_light_buffer(ctx, &[(light, emission)]),
            ray_buf: ray_buffer(ctx, &[vec![DVec3::Y]]),
            field,
            light,
            emission,
            lobes,
        }
    }

    /// The lobes as a frame binds them: one direct lobe, the local light,
    /// its visibility from `side`² rays.
    fn bind(&self, graph: &mut inlay_engine::graph::FrameGraph, side: u32) -> LightLobes {
        LightLobes {
            environment: Some(EnvironmentLobes {
                buffer: graph.import_buffer(&self.env_buf, None),
                count: self.environment.len() as u32,
            }),
            buffer: graph.import_buffer(&self.lobe_buf, None),
            count: self.lobes.len() as u32,
            direct: Some(DirectRays {
                lobes: 1,
                rays: graph.import_buffer(&self.ray_buf, None),
                rays_per_lobe: 1,
                local: LocalLightBindings {
                    lights: graph.import_buffer(&self.local_buf, None),
                    count: 1,
                    side,
                },
            }),
        }
    }
}

/// The per-pixel shading of a local light (`shade/shade_self_shadow_direct.wgsl`:
/// its lobe from each shaded point, Γ from its rays through the field and
/// past the mesh) against its f64 mirror (`lighting::local::sphere_lobe`
/// and `visibility`), with the other lobes' Γ from the SSDF as in
/// [`self_shadowed_shading_matches_its_mirror`]. Tolerance as there, plus
/// the march in f32 (3e-4 of the transmittance); a ray grazing the mesh
/// may go either way in f32 and f64, so up to 2 % of the pixels may differ
/// by one of the light's 9 rays.
#[test]
fn local_light_shading_matches_its_mirror() {
    use inlay_passes::lighting::local;
    let view = ToyView::new();
    let ctx = &view.ctx;
    let march = MarchKnobs {
        samples_per_ray: 256,
        ..MarchKnobs::default()
    };
    let shade = ShadePass::new(ctx, &view.lib, 1, march).unwrap();
    let ndf = NdfLobes::new(1).unwrap();
    let side = 3u32;
    let lamp = LampLights::new(&view);
    let (field, light, emission, lobes) = (&lamp.field, lamp.light, lamp.emission, &lamp.lobes);
    let object_scene = inlay_passes::ssdf::object_scene(&view.placed.mesh);
    let (pixels, peak) = view.shade(&shade, &lamp.gpu_field, |graph| lamp.bind(graph, side));
    let fitted = lobes.len() - 1;
    let to_object = view.placed.world_to_object();
    let (mut off, mut worst) = (0, 0.0f64);
    let (mut clear, mut partial, mut hidden) = (0, 0, 0);
    for px in &pixels {
        let (p, n) = (px.point, px.normal);
        let mut gamma = self_shadow_factors(
            &view.ssdf_field,
            &view.placed,
            &view.fh.table,
            &lobes[..fitted],
            p,
            n,
            OutsideMode::Correct,
            None,
        );
        let lifted = p + n * (inlay_passes::shadow::DIRECT_RAY_OFFSET * view.placed.sphere().1);
        let v = local::visibility(
            field,
            &object_scene,
            to_object,
            &light,
            emission,
            lifted,
            n,
            side,
            &march,
        );
        let facing = (light.centre - p).normalize().dot(n) > 0.2;
        match v {
            _ if !facing => {}
            v if v < 0.05 => hidden += 1,
            v if v < 0.5 => partial += 1,
            _ => clear += 1,
        }
        gamma.push(v);
        let mut here = lobes.clone();
        let to = light.centre - p;
        here[fitted] = local::sphere_lobe(
            to.normalize(),
            to.length(),
            emission.radius,
            emission.intensity,
        );
        let cpu = shade_sg_split(&here, &gamma, n, -px.ray.dir, &px.material, &ndf).total();
        let err = ((px.gpu - cpu).abs() / (cpu.abs() * 3e-4 + 1e-5 * peak)).max_element();
        if err > 1.0 {
            off += 1;
        } else {
            worst = worst.max(err);
        }
    }
    let shaded = pixels.len();
    eprintln!(
        "local light shading: {shaded} pixels ({clear} facing it clear, {partial} partly hidden, {hidden} hidden), {off} off the mirror, worst {worst:.3} of the tolerance"
    );
    assert!(shaded > 300, "{shaded}");
    assert!(
        clear > 20 && partial > 10 && hidden > 10,
        "{clear} {partial} {hidden}"
    );
    assert!(
        off <= shaded / 50,
        "{off} of {shaded} pixels off the mirror"
    );
    common::assert_no_validation_errors(ctx);
}

/// The field's light at the object's surface (`shade/field_light.wgsl`,
/// entries `field_light_tables` and `field_gain_only`) against its f64
/// mirror (`shade::field_light`): each 8 × 8 tile's pick, its rays through
/// the lamp field (the lamp's own light taken off, the slab of medium
/// dimming some of them) from the G-buffer's point, their sums at the
/// table's normals, and each pixel's gain blended from the tables of the
/// tiles around it, read at its own normal (most pixels blend several
/// tiles: a table read at the wrong tile or normal fails it). The field
/// sends no light but the lamp's, which is taken off, and past it L_env is
/// half the fitted lobes, so the gains are about half the share of the
/// lobes' light the slab lets through: near 0.5 where it is not in the
/// way (the slab's own glow and the lamp's just past its sphere add a
/// little), less where it is (measured 0.323–0.511, blended). Tolerance:
/// the march in f32 (3·10⁻⁴ of the transmittance, as above) and the lobes'
/// sums in f32, 2·10⁻³ of the gain plus 10⁻⁴. At scale 2 (tiles of 16
/// pixels, each invocation taking four) the picks and rays are the
/// mirror's at that size.
#[test]
fn field_light_gain_matches_its_mirror() {
    field_light_gain_at_scale(1);
    field_light_gain_at_scale(2);
}

fn field_light_gain_at_scale(scale: u32) {
    use inlay_passes::shade::field_light::{
        blend_tiles, blended_gain, ray_origin, tile_footprint, tile_pick, tile_rays, tile_table,
        RayLight, TileScale, TILE,
    };
    use std::collections::HashMap;
    let view = ToyView::new();
    let ctx = &view.ctx;
    let march = MarchKnobs {
        samples_per_ray: 256,
        ..MarchKnobs::default()
    };
    let side = 6u32;
    let shade = ShadePass::new_field_gain(ctx, &view.lib, march, side)
        .unwrap()
        .with_field_light_scale(TileScale::Fixed(scale));
    let tile_side = TILE * scale;
    let lamp = LampLights::new(&view);
    let (field, light, lobes) = (&lamp.field, lamp.light, &lamp.lobes);
    let (pixels, _) = view.shade(&shade, &lamp.gpu_field, |graph| lamp.bind(graph, 3));
    let fitted = &lobes[..lobes.len() - 1];
    let at: HashMap<(u32, u32), &ShadedPixel> = pixels.iter().map(|p| (p.pixel, p)).collect();
    let (w, h) = (view.cam.width, view.cam.height);
    let radius = view.placed.sphere().1;
    let mut tiles: HashMap<(u32, u32), Vec<&ShadedPixel>> = HashMap::new();
    for p in &pixels {
        tiles
            .entry((p.pixel.0 / tile_side, p.pixel.1 / tile_side))
            .or_default()
            .push(p);
    }
    let (mut off, mut worst) = (0, 0.0f64);
    let (mut low, mut high) = (f64::INFINITY, 0.0f64);
    let diffuse = |x, y| {
        at.get(&(x, y))
            .is_some_and(|p: &&ShadedPixel| p.material.clamped().diffuse() != DVec3::ZERO)
    };
    // Each tile's table: a tile without diffuse pixels casts no rays.
    let tables: HashMap<(u32, u32), _> = tiles
        .keys()
        .filter_map(|&tile| {
            let pick = tile_pick(tile, tile_side, w, h, diffuse)?;
            let source = at[&pick];
            let origin = ray_origin(source.point, source.normal, radius);
            let light_in = RayLight {
                fitted,
                environment: &lamp.environment,
            };
            let rays = tile_rays(field, &march, origin, light_in, &[light], side);
            Some((tile, tile_table(source.point, &rays)))
        })
        .collect();
    let mut blended_tiles = 0;
    for p in &pixels {
        let around: Vec<_> = blend_tiles(p.pixel, tile_side)
            .into_iter()
            .filter_map(|((x, y), weight)| {
                let tile = (u32::try_from(x).ok()?, u32::try_from(y).ok()?);
                tables.get(&tile).map(|t| (t, weight))
            })
            .collect();
        if around.len() > 1 {
            blended_tiles += 1;
        }
        let centre = (p.pixel.0 as f64 + 0.5, p.pixel.1 as f64 + 0.5);
        let footprint = tile_footprint(view.cam.origin, p.point, centre, tile_side, |x, y| {
            view.cam.ray(x, y).dir
        });
        let cpu = blended_gain(p.normal, p.point, footprint, around);
        low = low.min(cpu.min_element());
        high = high.max(cpu.max_element());
        let err = ((p.gpu - cpu).abs() / (cpu.abs() * 2e-3 + 1e-4)).max_element();
        if err > 1.0 {
            off += 1;
        } else {
            worst = worst.max(err);
        }
    }
    assert!(
        blended_tiles > pixels.len() / 2,
        "{blended_tiles} of {} pixels blend tiles",
        pixels.len()
    );
    eprintln!(
        "field light gain at scale {scale}: {} pixels in {} tiles, gains {low:.3}..{high:.3}, {off} off the mirror, worst {worst:.3} of the tolerance",
        pixels.len(),
        tiles.len()
    );
    assert!(
        pixels.len() > 300 && tiles.len() > 8 / scale as usize,
        "{} {}",
        pixels.len(),
        tiles.len()
    );
    assert!(low < 0.4 && high > 0.5 && high < 0.6, "gains {low}..{high}");
    assert_eq!(off, 0, "{off} of {} pixels off the mirror", pixels.len());
    common::assert_no_validation_errors(ctx);
}

/// Local lights as the direct-light pass writes them: (centre, radius),
/// (intensity, the radius it shines from); one zero vec4 when none.
fn local_light_buffer(
    ctx: &Arc<inlay_engine::Context>,
    lights: &[(LocalLight, Emission)],
) -> Arc<Buffer> {
    let mut bytes: Vec<u8> = lights
        .iter()
        .flat_map(|(l, e)| {
            [
                l.centre.x,
                l.centre.y,
                l.centre.z,
                l.radius,
                e.intensity.x,
                e.intensity.y,
                e.intensity.z,
                e.radius,
            ]
        })
        .flat_map(|v| (v as f32).to_le_bytes())
        .collect();
    bytes.resize(bytes.len().max(16), 0);
    Arc::new(
        Buffer::with_data(
            ctx,
            "local-lights",
            &bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )
        .unwrap(),
    )
}

/// The cast shadow of a local light above BOOKS' sphere: the kernel's rays
/// to the light's disk against their mirror
/// (`lighting::local::mesh_clear_fraction`), with the sun and sky as
/// before; the brute force knows distant light only, so only the mirror
/// and the shadow's presence are checked.
#[test]
fn local_light_shadow_matches_its_mirror() {
    let scene = common::bundled_scene("books.toml");
    let (c, r) = scene.objects[0].sphere();
    let light = LocalLight {
        centre: c + DVec3::new(0.3, 3.0, 0.2) * r,
        radius: 0.4 * r,
        emission: None,
    };
    let emission = Emission {
        intensity: DVec3::splat(6.0) * r * r,
        radius: 0.3 * r,
    };
    let mut lobes = test_lobes();
    let to = light.centre - c;
    lobes.push(inlay_passes::lighting::local::sphere_lobe(
        to.normalize(),
        to.length(),
        emission.radius,
        emission.intensity,
    ));
    let result = compare_cast_shadow(&lobes, 0, Some((light, emission)));
    eprintln!(
        "local light: mirror worst {:.2e}, {:.2} % of pixels off it, {} of {} sampled shadowed",
        result.worst_mirror,
        100.0 * result.off_mirror,
        result.shadowed,
        result.sampled
    );
    // A ray grazing the silhouette may go either way in f32 and f64 (one
    // ninth of the light at that pixel); measured: no pixel. A disk of
    // the sphere's radius instead of the emitter's moves 0.5 %.
    result.assert_on_mirror_and_shadowed(0.003);
}
