//! The NeRF march on the GPU (lavapipe) against its f64 CPU reference, with
//! and without empty-space skipping and with clipping at an object-depth
//! image; and the marched field against the path-traced ground truth of the
//! same camera.

mod common;

use std::sync::Arc;

use glam::DVec3;
use inlay_engine::graph::FrameGraph;
use inlay_engine::shader::{compile, ShaderStage};
use inlay_engine::{ComputePipeline, Context, HdrImage, ImageDesc, Push, Readback, Renderer};
use inlay_passes::bake::{render_reference, ReferenceOptions};
use inlay_passes::camera::CameraFrame;
use inlay_passes::field::{GpuGridField, GridField};
use inlay_passes::march::{
    march_image, MarchKnobs, MarchPass, MARCH_COLOUR_FORMAT, MARCH_DEPTH_FORMAT,
};
use inlay_passes::scene::Scene;

fn scene(name: &str) -> Scene {
    common::bundled_scene(name)
}

fn small_field(scene: &Scene, resolution: u32, samples: u32) -> GridField {
    common::bake_small(scene, resolution, samples, 0)
}

/// Runs the march pass once, compiled for the field
/// ([`GpuGridField::library`]); with `clip = Some((near, mid))`, an
/// object-depth image holds `near` in the left third, `mid` in the middle
/// third and no object on the right. Returns (Ĉ, Ô) and D̂.
fn gpu_march(
    ctx: &Arc<Context>,
    field: &GridField,
    camera: &CameraFrame,
    knobs: MarchKnobs,
    clip: Option<(f32, f32)>,
) -> (HdrImage, HdrImage) {
    let gpu_field = GpuGridField::upload(ctx, field).unwrap();
    gpu_march_with(
        ctx,
        &gpu_field.library(&common::test_library()),
        &gpu_field,
        camera,
        knobs,
        clip,
    )
}

/// [`gpu_march`] of an uploaded field with the passes compiled from `lib`.
fn gpu_march_with(
    ctx: &Arc<Context>,
    lib: &inlay_engine::shader::ShaderLibrary,
    gpu_field: &GpuGridField,
    camera: &CameraFrame,
    knobs: MarchKnobs,
    clip: Option<(f32, f32)>,
) -> (HdrImage, HdrImage) {
    let lib = lib.clone();
    let march = MarchPass::new(ctx, &lib, knobs).unwrap();
    let pattern = std::sync::Arc::new(
        ComputePipeline::new(
            ctx,
            &compile(
                &lib,
                "checks/object_depth_pattern.wgsl",
                "main",
                ShaderStage::Compute,
                &[],
            )
            .unwrap(),
        )
        .unwrap(),
    );
    let (w, h) = (camera.width, camera.height);
    let colour_rb = Readback::new(
        ctx,
        ImageDesc {
            width: w,
            height: h,
            format: MARCH_COLOUR_FORMAT,
        },
    )
    .unwrap();
    let depth_rb = Readback::new(
        ctx,
        ImageDesc {
            width: w,
            height: h,
            format: MARCH_DEPTH_FORMAT,
        },
    )
    .unwrap();
    let mut renderer = Renderer::new(ctx, 1).unwrap();
    renderer.begin_frame().unwrap();
    let mut graph = FrameGraph::new();
    let object_depth = clip.map(|(near, mid)| {
        let img = graph.create_image(
            "object-depth",
            ImageDesc {
                width: w,
                height: h,
                format: MARCH_DEPTH_FORMAT,
            },
        );
        let mut img = img;
        graph
            .compute("object-depth-pattern", &pattern)
            .write("out_depth", &mut img)
            .push(&Push::new().u32(w).u32(h).f32(near).f32(mid))
            .threads([w, h, 1]);
        img
    });
    let out = march.add(&mut graph, gpu_field, camera, object_depth);
    colour_rb.add_to_graph(&mut graph, out.colour_opacity);
    depth_rb.add_to_graph(&mut graph, out.depth);
    renderer
        .submit(graph, &inlay_engine::SubmitSync::none())
        .unwrap();
    renderer.finish().unwrap();
    common::assert_no_validation_errors(ctx);
    (colour_rb.read().unwrap(), depth_rb.read().unwrap())
}

/// Largest difference between GPU and CPU over the image, per quantity.
struct Diff {
    colour: f64,
    opacity: f64,
    depth: f64,
    max_colour: f64,
}

fn compare(
    field: &GridField,
    camera: &CameraFrame,
    knobs: &MarchKnobs,
    clip_of: &(dyn Fn(u32, u32) -> f64 + Sync),
    colour: &HdrImage,
    depth: &HdrImage,
) -> Diff {
    let cpu = march_image(field, camera, knobs, clip_of);
    let mut d = Diff {
        colour: 0.0,
        opacity: 0.0,
        depth: 0.0,
        max_colour: 0.0,
    };
    for y in 0..camera.height {
        for x in 0..camera.width {
            let c = &cpu[(y * camera.width + x) as usize];
            let g = colour.at(x, y);
            let gd = depth.at(x, y)[0] as f64;
            assert!(
                g.iter().all(|v| v.is_finite()) && gd.is_finite(),
                "non-finite at ({x}, {y})"
            );
            let gc = DVec3::new(g[0] as f64, g[1] as f64, g[2] as f64);
            d.colour = d.colour.max((gc - c.colour).abs().max_element());
            d.opacity = d.opacity.max((g[3] as f64 - c.opacity).abs());
            d.depth = d.depth.max((gd - c.depth).abs());
            d.max_colour = d.max_colour.max(c.colour.max_element());
        }
    }
    d
}

/// Tolerance: the GPU works in f32 (positions carry ~1e-7 relative error,
/// `exp` is accurate to a few ULP, the transmittance product accumulates
/// ≤ samples_per_ray roundings ≈ 512 · 6e-8 ≈ 3e-5 relative). The one
/// discrete difference is early termination: a ray whose transmittance
/// crosses `termination` = 1e-4 one sample earlier or later on the GPU
/// changes Ĉ by at most 1e-4 · max colour and Ô by 1e-4. So: colour within
/// 3e-4 of the brightest pixel, opacity within 3e-4, depth within 3e-4 of
/// the largest depth (≈ 4 scene units here).
fn assert_within_tolerance(d: &Diff, what: &str) {
    assert!(d.max_colour > 0.01, "{what}: the image is black");
    assert!(
        d.colour <= 3e-4 * d.max_colour,
        "{what}: colour differs by {} (max {})",
        d.colour,
        d.max_colour
    );
    assert!(
        d.opacity <= 3e-4,
        "{what}: opacity differs by {}",
        d.opacity
    );
    assert!(
        d.depth <= 3e-4 * 4.0,
        "{what}: depth differs by {}",
        d.depth
    );
}

#[test]
fn gpu_march_matches_the_cpu_reference_with_and_without_skipping() {
    let ctx = common::gpu();
    let s = scene("plants.toml");
    let field = small_field(&s, 24, 4);
    let camera = CameraFrame::new(&s.cameras[0], 48, 32);
    for skip_empty in [true, false] {
        march_matches_cpu(
            &ctx,
            &field,
            &camera,
            fine_march(skip_empty),
            &format!("skip_empty = {skip_empty}"),
        );
    }
}

/// 256 samples along the diagonal, with or without empty-space skipping.
fn fine_march(skip_empty: bool) -> MarchKnobs {
    MarchKnobs {
        samples_per_ray: 256,
        termination: 1e-4,
        skip_empty,
    }
}

/// A field whose empty nodes hold negative densities (a trained field's
/// empty space) marches on the GPU as on the CPU, the clamp at zero after
/// interpolation on both, and its edges are sharper than the same field's
/// with those nodes at zero: the negatives are read.
#[test]
fn gpu_march_matches_the_cpu_reference_with_negative_densities() {
    let ctx = common::gpu();
    let s = scene("plants.toml");
    let plain = small_field(&s, 24, 4);
    let mut field = plain.clone();
    let top = plain.nodes.iter().map(|n| n[3]).fold(0.0f32, f32::max);
    for n in &mut field.nodes {
        if n[3] == 0.0 {
            n[3] = -0.5 * top;
        }
    }
    let field = GridField::new(
        field.resolution,
        field.bounds,
        field.nodes,
        inlay_passes::field::DEFAULT_OCCUPANCY_BLOCK,
    );
    let camera = CameraFrame::new(&s.cameras[0], 48, 32);
    for skip_empty in [true, false] {
        let knobs = fine_march(skip_empty);
        let (sharp, max_colour) = march_matches_cpu(
            &ctx,
            &field,
            &camera,
            knobs,
            &format!("negative densities, skip_empty = {skip_empty}"),
        );
        let (soft, _) = gpu_march(&ctx, &plain, &camera, knobs, None);
        let moved = sharp
            .pixels
            .iter()
            .zip(&soft.pixels)
            .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0f32, f32::max))
            .fold(0.0f32, f32::max);
        assert!(
            moved as f64 > 0.05 * max_colour,
            "the negative densities changed the image by only {moved}"
        );
    }
    common::assert_no_validation_errors(&ctx);
}

/// Marches `field` unclipped on the GPU, checks it against the CPU within
/// [`assert_within_tolerance`], and returns (Ĉ, Ô) and the largest colour.
fn march_matches_cpu(
    ctx: &Arc<Context>,
    field: &GridField,
    camera: &CameraFrame,
    knobs: MarchKnobs,
    what: &str,
) -> (HdrImage, f64) {
    let (colour, depth) = gpu_march(ctx, field, camera, knobs, None);
    let d = compare(
        field,
        camera,
        &knobs,
        &|_, _| f64::INFINITY,
        &colour,
        &depth,
    );
    assert_within_tolerance(&d, what);
    (colour, d.max_colour)
}

/// A field with view-dependent colour (degree 1 and 2, coefficients of
/// the size of the node's colour, so that the clamp at zero holds in some
/// samples) marches on the GPU as on the CPU, and its image differs from
/// the same field's without them: the coefficients are read.
#[test]
fn gpu_march_matches_the_cpu_reference_with_view_dependent_colour() {
    use inlay_passes::field::sh_extra_coefficients;
    use inlay_passes::rng::Pcg32;
    let ctx = common::gpu();
    let s = scene("plants.toml");
    let plain = small_field(&s, 24, 4);
    let camera = CameraFrame::new(&s.cameras[0], 48, 32);
    let knobs = MarchKnobs {
        samples_per_ray: 256,
        termination: 1e-4,
        skip_empty: true,
    };
    let (base, _) = gpu_march(&ctx, &plain, &camera, knobs, None);
    // The third case is as bright as a field may be: its coefficients pass
    // f16's range, so the device's halves are scaled (`sh_half`).
    for (degree, gain) in [(1, 1.0f32), (2, 1.0), (1, 1.0e5)] {
        let k = sh_extra_coefficients(degree);
        let mut rng = Pcg32::new(degree as u64, 7);
        let mut bright = plain.clone();
        for n in &mut bright.nodes {
            n[..3].iter_mut().for_each(|c| *c *= gain);
        }
        let sh: Vec<[f32; 3]> = (0..plain.nodes.len() * k)
            .map(|i| {
                let c = bright.nodes[i / k];
                std::array::from_fn(|ch| (3.0 * (rng.next_f64() - 0.5)) as f32 * c[ch])
            })
            .collect();
        if gain > 1.0 {
            assert!(inlay_passes::field::sh_half::sh_unscale(&sh) > 1.0);
        }
        let field = bright.clone().with_sh(degree, sh);
        let base = if gain > 1.0 {
            gpu_march(&ctx, &bright, &camera, knobs, None).0
        } else {
            base.clone()
        };
        let (colour, max_colour) = march_matches_cpu(
            &ctx,
            &field,
            &camera,
            knobs,
            &format!("degree {degree}, gain {gain}"),
        );
        let moved = (0..camera.height)
            .flat_map(|y| (0..camera.width).map(move |x| (x, y)))
            .map(|(x, y)| {
                let (a, b) = (colour.at(x, y), base.at(x, y));
                (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0f32, f32::max)
            })
            .fold(0.0f32, f32::max);
        assert!(
            moved as f64 > 0.05 * max_colour,
            "degree {degree}: the view-dependent colour changed the image by only {moved}"
        );
        // Compiled for any field (the default library: the degree read
        // per ray), the same image.
        let uploaded = GpuGridField::upload(&ctx, &field).unwrap();
        let (general, _) = gpu_march_with(
            &ctx,
            &common::test_library(),
            &uploaded,
            &camera,
            knobs,
            None,
        );
        assert_eq!(general.pixels, colour.pixels, "degree {degree}");
    }
    common::assert_no_validation_errors(&ctx);
}

/// llvmpipe stops an invocation's loops after 65535 iterations in all;
/// the view-dependent colour looped 8 + 8·8 times per sample at degree 2,
/// so rays of 2048 samples and more were cut short (colour off by a third
/// of the image's brightest at 4096). It is written out without loops now:
/// a degree-2 field marched at 4096 samples without skipping matches the
/// reference.
#[test]
fn a_view_dependent_field_marches_long_rays_whole() {
    use inlay_passes::field::sh_extra_coefficients;
    use inlay_passes::rng::Pcg32;
    let ctx = common::gpu();
    let s = scene("plants.toml");
    let plain = small_field(&s, 24, 4);
    let camera = CameraFrame::new(&s.cameras[0], 24, 16);
    let k = sh_extra_coefficients(2);
    let mut rng = Pcg32::new(2, 7);
    let sh: Vec<[f32; 3]> = (0..plain.nodes.len() * k)
        .map(|i| {
            let c = plain.nodes[i / k];
            std::array::from_fn(|ch| (3.0 * (rng.next_f64() - 0.5)) as f32 * c[ch])
        })
        .collect();
    let knobs = MarchKnobs {
        samples_per_ray: 4096,
        termination: 1e-4,
        skip_empty: false,
    };
    march_matches_cpu(
        &ctx,
        &plain.with_sh(2, sh),
        &camera,
        knobs,
        "degree 2, 4096 samples",
    );
    common::assert_no_validation_errors(&ctx);
}

/// A view-dependent sample costs the march nine loop iterations on
/// llvmpipe (the loop over its corners is not unrolled), so a march
/// compiled for such fields refuses more than 7280 samples per ray there,
/// naming the knob; compiled for plain fields it takes them.
#[test]
fn a_view_dependent_march_past_the_devices_loop_limit_is_refused() {
    let ctx = common::gpu();
    let knobs = |samples_per_ray| MarchKnobs {
        samples_per_ray,
        ..MarchKnobs::default()
    };
    let general = common::test_library();
    let plain = GpuGridField::upload(&ctx, &small_field(&scene("plants.toml"), 8, 1))
        .unwrap()
        .library(&general);
    assert!(MarchPass::new(&ctx, &general, knobs(7280)).is_ok());
    assert!(MarchPass::new(&ctx, &plain, knobs(32768)).is_ok());
    let long = MarchPass::new(&ctx, &general, knobs(7281));
    if ctx.info().loop_iteration_limit.is_none() {
        assert!(long.is_ok());
        return;
    }
    let e = long.err().expect("refused").to_string();
    for needle in [
        "nerf-march",
        "samples_per_ray` 7281",
        "view-dependent",
        "65535",
    ] {
        assert!(e.contains(needle), "`{needle}` missing: {e}");
    }
}

/// A pass compiled for fields without view-dependent colour refuses one
/// that has it (its colour would be read as the mean).
#[test]
#[should_panic(expected = "compiled for fields without view-dependent colour")]
fn a_pass_for_plain_fields_refuses_view_dependent_colour() {
    let ctx = common::gpu();
    let s = scene("plants.toml");
    let plain = small_field(&s, 8, 1);
    let k = inlay_passes::field::sh_extra_coefficients(1);
    let sh = vec![[0.1, 0.0, 0.0]; plain.nodes.len() * k];
    let lib = GpuGridField::upload(&ctx, &plain)
        .unwrap()
        .library(&common::test_library());
    let field = GpuGridField::upload(&ctx, &plain.clone().with_sh(1, sh)).unwrap();
    let camera = CameraFrame::new(&s.cameras[0], 8, 8);
    gpu_march_with(&ctx, &lib, &field, &camera, MarchKnobs::default(), None);
}

/// A field stored sparsely (only its non-zero bricks, `field::bricks`)
/// marches to the same image, bit for bit, as stored densely: plain and
/// with view-dependent colour of degree 1 and 2, compiled for the field
/// and for any field. The bake leaves most of PLANTS' bricks empty.
#[test]
fn a_sparse_field_marches_as_the_dense_one() {
    use inlay_passes::field::{sh_extra_coefficients, FieldLayout};
    let ctx = common::gpu();
    let s = scene("plants.toml");
    let plain = small_field(&s, 64, 1);
    let camera = CameraFrame::new(&s.cameras[0], 48, 32);
    let knobs = MarchKnobs {
        samples_per_ray: 256,
        termination: 1e-4,
        skip_empty: true,
    };
    for degree in [0, 1, 2] {
        let k = sh_extra_coefficients(degree);
        let sh = (0..plain.nodes.len() * k)
            .map(|i| {
                let c = plain.nodes[i / k];
                let w = ((i % 7) as f32 - 3.0) / 4.0;
                [w * c[0], -w * c[1], 0.5 * w * c[2]]
            })
            .collect();
        let field = plain.clone().with_sh(degree, sh);
        let dense = GpuGridField::upload_as(&ctx, &field, FieldLayout::Dense).unwrap();
        let sparse = GpuGridField::upload_as(&ctx, &field, FieldLayout::Sparse).unwrap();
        assert!(sparse.sparse && !dense.sparse);
        assert!(
            sparse.node_bytes < dense.node_bytes * 2 / 3,
            "degree {degree}: sparse {} bytes, dense {}",
            sparse.node_bytes,
            dense.node_bytes
        );
        let march = |f: &GpuGridField, general: bool| {
            let lib = if general {
                common::test_library()
            } else {
                f.library(&common::test_library())
            };
            gpu_march_with(&ctx, &lib, f, &camera, knobs, None)
        };
        let (want, want_depth) = march(&dense, false);
        for general in [false, true] {
            let (got, got_depth) = march(&sparse, general);
            assert_eq!(
                got.pixels, want.pixels,
                "degree {degree}, general {general}"
            );
            assert_eq!(got_depth.pixels, want_depth.pixels, "degree {degree}");
        }
    }
    common::assert_no_validation_errors(&ctx);
}

/// A pass compiled for dense fields refuses a sparse one (it would read
/// the pool as the grid).
#[test]
#[should_panic(expected = "compiled for dense fields")]
fn a_pass_for_dense_fields_refuses_a_sparse_one() {
    use inlay_passes::field::FieldLayout;
    let ctx = common::gpu();
    let s = scene("plants.toml");
    let plain = small_field(&s, 24, 1);
    let dense = GpuGridField::upload_as(&ctx, &plain, FieldLayout::Dense).unwrap();
    let sparse = GpuGridField::upload_as(&ctx, &plain, FieldLayout::Sparse).unwrap();
    let camera = CameraFrame::new(&s.cameras[0], 8, 8);
    let lib = dense.library(&common::test_library());
    gpu_march_with(&ctx, &lib, &sparse, &camera, MarchKnobs::default(), None);
}

#[test]
fn clipping_removes_the_field_behind_the_object() {
    let ctx = common::gpu();
    let s = scene("cups.toml");
    let field = small_field(&s, 24, 4);
    let camera = CameraFrame::new(&s.cameras[0], 48, 27);
    let knobs = MarchKnobs {
        samples_per_ray: 256,
        ..MarchKnobs::default()
    };
    // The camera is ≈ 2.2 units from the field's front face: 1.0 lies in
    // front of the field, 2.9 inside it.
    let (near, mid) = (1.0f32, 2.9f32);
    let (colour, depth) = gpu_march(&ctx, &field, &camera, knobs, Some((near, mid)));
    let w = camera.width;
    let clip = move |x: u32, _y: u32| -> f64 {
        if 3 * x < w {
            near as f64
        } else if 3 * x < 2 * w {
            mid as f64
        } else {
            f64::INFINITY
        }
    };
    let d = compare(&field, &camera, &knobs, &clip, &colour, &depth);
    assert_within_tolerance(&d, "clipped");
    let (unclipped, _) = gpu_march(&ctx, &field, &camera, knobs, None);
    let mut mid_darker = 0;
    for y in 0..camera.height {
        for x in 0..w {
            let c = colour.at(x, y);
            if 3 * x < w {
                // The object is in front of the field: nothing from behind it.
                assert_eq!(
                    c, [0.0; 4],
                    "pixel ({x}, {y}) received light from behind the object"
                );
                assert_eq!(depth.at(x, y)[0], 0.0);
            } else if 3 * x < 2 * w {
                let u = unclipped.at(x, y);
                assert!(c[3] <= u[3] + 1e-6, "clipping added opacity at ({x}, {y})");
                mid_darker += (c[3] + 1e-3 < u[3]) as u32;
            } else {
                assert_eq!(c, unclipped.at(x, y), "no object, yet ({x}, {y}) changed");
            }
        }
    }
    assert!(
        mid_darker > 10,
        "the mid-depth object clipped only {mid_darker} pixels"
    );
}

/// The field is a resampling of the recipe, so the march of the baked field
/// and the path-traced image of the same camera agree up to the field's
/// resolution: edges are blurred over ~2 voxels and the smooth density puts
/// the visible surface up to a voxel in front of the true one; both images
/// also carry Monte-Carlo noise (32 samples per node, 128 per pixel).
/// Measured on this 48×27 view of CUPS (mean |Δ| over mean radiance, and
/// mean |Δ coverage|): 0.309 / 0.083 with a 24-node field, 0.130 / 0.029
/// with a 48-node field (0.187 / 0.049 and 0.100 / 0.022 before the bake
/// moved surfaces' density inside them and thin shapes' outwards: at 48
/// nodes CUPS' 2 cm plate is a fifth of a voxel thick, and keeping it
/// opaque widens it; at 128 nodes the field came closer to Cycles). The
/// bounds leave ~25 % headroom over the 48-node figures, and the finer
/// field must match better.
#[test]
fn marched_field_matches_the_path_traced_reference() {
    let ctx = common::gpu();
    let s = scene("cups.toml");
    let camera = CameraFrame::new(&s.cameras[0], 48, 27);
    let reference = render_reference(
        s.recipe().unwrap(),
        &s.environment,
        &[],
        &camera,
        &ReferenceOptions {
            samples: 128,
            bounces: 0,
            seed: 7,
            antialias: false,
            sky_behind: false,
        },
        &|_, _| {},
    );
    let knobs = MarchKnobs::default();
    let mut errors = Vec::new();
    for resolution in [24, 48] {
        let field = small_field(&s, resolution, 32);
        let (colour, _) = gpu_march(&ctx, &field, &camera, knobs, None);
        let (mut err, mut mean, mut cover_err) = (0.0, 0.0, 0.0);
        for (i, r) in reference.iter().enumerate() {
            let g = colour.pixels[i];
            for c in 0..3 {
                err += (g[c] - r[c]).abs() as f64;
                mean += r[c] as f64;
            }
            cover_err += (g[3] - r[3]).abs() as f64;
        }
        let relative = err / mean;
        let coverage = cover_err / reference.len() as f64;
        eprintln!(
            "resolution {resolution}: relative error {relative:.4}, coverage error {coverage:.4}"
        );
        errors.push((relative, coverage));
    }
    assert!(
        errors[1].0 < 0.16,
        "48-node field: relative error {:.4}",
        errors[1].0
    );
    assert!(
        errors[1].1 < 0.037,
        "48-node field: coverage error {:.4}",
        errors[1].1
    );
    assert!(
        errors[1].0 < errors[0].0,
        "a finer field must match better: {errors:?}"
    );
}

/// `sky-behind` run on lavapipe over `frame` (a `camera`-sized RGBA
/// image) with what lies `beyond` the field.
fn sky_behind_on_gpu(
    ctx: &Arc<inlay_engine::Context>,
    frame: &[[f32; 4]],
    camera: &CameraFrame,
    beyond: &inlay_passes::sky_behind::Beyond,
) -> Vec<[f32; 4]> {
    use inlay_passes::sky_behind::{SkyBehindPass, SKY_BEHIND_FORMAT};
    let desc = ImageDesc {
        width: camera.width,
        height: camera.height,
        format: SKY_BEHIND_FORMAT,
    };
    let usage = inlay_engine::vk::ImageUsageFlags::SAMPLED
        | inlay_engine::vk::ImageUsageFlags::TRANSFER_DST;
    let input = Arc::new(inlay_engine::Image::new(ctx, "frame", desc, usage).unwrap());
    input.write_rgba32f(frame).unwrap();
    let pass = SkyBehindPass::new(ctx, &common::test_library(), beyond)
        .unwrap()
        .unwrap();
    let readback = Readback::new(ctx, desc).unwrap();
    common::run_frame(ctx, |graph| {
        let c = graph.import_image(&input, "frame", None);
        let out = pass.add(graph, c, camera);
        readback.add_to_graph(graph, out);
    });
    readback.read().unwrap().pixels
}

/// `sky-behind` on lavapipe against its f64 CPU mirror
/// ([`sky_behind_reference`]): a camera looking almost straight up with a
/// wide view, so the image holds the pole and the seam at φ = 0, over a
/// frame whose coverage runs from none to a hair past whole, a sky of
/// random texels with one a hundred times the rest.
#[test]
fn the_sky_behind_the_frame_matches_the_cpu_reference() {
    use inlay_passes::field::Sky;
    use inlay_passes::sky_behind::{sky_behind_reference, Beyond};
    let ctx = common::gpu();
    let (w, h) = (40u32, 30u32);
    let spec = inlay_passes::camera::CameraSpec {
        name: None,
        position: DVec3::ZERO,
        look_at: DVec3::new(0.05, 1.0, 0.02),
        up: DVec3::Z,
        fov_y: 120.0,
    };
    let camera = CameraFrame::new(&spec, w, h);
    let mut rng = inlay_passes::rng::Pcg32::new(11, 4);
    let mut texels: Vec<DVec3> = (0..16 * 8)
        .map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()))
        .collect();
    texels[3] *= 100.0;
    let sky = Sky::new(16, 8, texels).unwrap();
    let frame: Vec<[f32; 4]> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let a = [0.0, 0.25, 0.5, 1.0, 1.0000002][((x + 3 * y) % 5) as usize];
            [0.3 * a, 0.2 * a + 0.01 * x as f32, 0.1, a]
        })
        .collect();
    let beyond = Beyond {
        sky: Some(&sky),
        lights: &[],
        bounds: inlay_passes::geometry::Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
    };
    let gpu = sky_behind_on_gpu(&ctx, &frame, &camera, &beyond);
    let seen: Vec<[f64; 4]> = frame.iter().map(|c| c.map(|v| v as f64)).collect();
    let cpu = sky_behind_reference(&seen, &camera, &beyond);
    let mut behind = 0;
    for (i, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
        let d = camera.pixel_ray(i as u32 % w, i as u32 / w).dir;
        // The f32 direction and atan2 move the bilinear weights by ~1e-5
        // of a texel: the error is that share of the four texels read,
        // beside f32 rounding of the frame's own colour.
        let corners: f64 = sky
            .corners(d)
            .iter()
            .map(|&(k, _)| sky.texels[k].max_element())
            .sum();
        for k in 0..4 {
            let scale = seen[i][k].abs() + corners;
            assert!(
                (g[k] as f64 - c[k]).abs() <= 1e-4 * scale,
                "pixel {i} channel {k}: gpu {} cpu {}",
                g[k],
                c[k]
            );
        }
        assert_eq!(g[3], 1.0, "pixel {i}: coverage after the sky");
        if seen[i][3] < 1.0 {
            behind += 1;
        }
    }
    assert!(
        behind > (w * h / 2) as usize,
        "{behind} pixels show the sky"
    );
}

/// The lights seen past the bounds, drawn by `sky-behind` on lavapipe
/// against its f64 CPU mirror, with and without a sky: from inside a room's
/// box looking up past its top, a bulb above the box (past the bounds:
/// behind the frame) and from outside, looking down through a bulb that
/// hangs between the camera and the box (before the bounds: over it), a
/// second light behind the first, one a tenth of a pixel wide. The disc's
/// edge is ramped over a pixel, so f32 moves an edge pixel's coverage by
/// its ray's rounding over the pixel's angle (about 1e-7 rad over 0.02,
/// 5e-6 of the brightest light's 8000: 0.04), beside f32 rounding of the
/// values themselves.
#[test]
fn the_lights_seen_past_the_bounds_match_the_cpu_reference() {
    use inlay_passes::field::{SeenLight, Sky};
    use inlay_passes::geometry::Aabb;
    use inlay_passes::sky_behind::{sky_behind_reference, Beyond};
    let ctx = common::gpu();
    let (w, h) = (48u32, 36u32);
    let bounds = Aabb::new(DVec3::new(-1.0, -0.1, -1.0), DVec3::new(1.0, 1.4, 1.0));
    let bulb = |c: DVec3, r: f64, e: f64| SeenLight {
        centre: c,
        radius: r,
        radiance: DVec3::new(e, 0.9 * e, 0.8 * e),
        views: 3,
        residual: 0.0,
    };
    let lights = [
        bulb(DVec3::new(0.2, 2.9, 0.3), 0.08, 8000.0),
        bulb(DVec3::new(0.5, 3.5, 0.3), 0.15, 50.0),
        bulb(DVec3::new(-0.3, 2.9, 0.3), 0.004, 3000.0),
    ];
    let cameras = [
        // Inside the box, looking up: every light past the bounds.
        inlay_passes::camera::CameraSpec {
            name: None,
            position: DVec3::new(0.0, 0.5, 0.3),
            look_at: DVec3::new(0.1, 3.0, 0.3),
            up: DVec3::Z,
            fov_y: 40.0,
        },
        // Above the bulbs, looking down through them at the box.
        inlay_passes::camera::CameraSpec {
            name: None,
            position: DVec3::new(0.1, 4.5, 0.3),
            look_at: DVec3::new(0.1, 0.0, 0.3),
            up: DVec3::Z,
            fov_y: 40.0,
        },
    ];
    let mut rng = inlay_passes::rng::Pcg32::new(5, 9);
    let texels: Vec<DVec3> = (0..8 * 4)
        .map(|_| DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()))
        .collect();
    let sky = Sky::new(8, 4, texels).unwrap();
    let frame: Vec<[f32; 4]> = (0..w * h)
        .map(|i| {
            let a = [0.0, 0.25, 0.5, 1.0][((i % w) + 3 * (i / w)) as usize % 4];
            [0.3 * a, 0.2 * a, 0.1 * a, a]
        })
        .collect();
    let seen: Vec<[f64; 4]> = frame.iter().map(|c| c.map(|v| v as f64)).collect();
    let mut lit = [0usize; 2];
    for (k, spec) in cameras.iter().enumerate() {
        let camera = CameraFrame::new(spec, w, h);
        for with_sky in [false, true] {
            let beyond = Beyond {
                sky: with_sky.then_some(&sky),
                lights: &lights,
                bounds,
            };
            let gpu = sky_behind_on_gpu(&ctx, &frame, &camera, &beyond);
            let cpu = sky_behind_reference(&seen, &camera, &beyond);
            for (i, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
                if c[0] > 10.0 {
                    lit[k] += 1;
                }
                for ch in 0..4 {
                    let tolerance = 1e-4 * c[ch].abs() + 0.05;
                    assert!(
                        (g[ch] as f64 - c[ch]).abs() <= tolerance,
                        "camera {k}, sky {with_sky}, pixel {i} channel {ch}: gpu {} cpu {}",
                        g[ch],
                        c[ch]
                    );
                }
            }
        }
    }
    // Both views see the lights: from inside past the bounds, from above
    // over the box.
    assert!(lit[0] > 8 && lit[1] > 8, "{lit:?}");
}
