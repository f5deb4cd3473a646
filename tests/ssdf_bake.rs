//! The SSDF bake on meshes the size users bring: a 100k-triangle mesh
//! against the f64 CPU mirror (the bake's kernels once ended early on
//! lavapipe there, silently: llvmpipe stops all of an invocation's loops
//! after 65535 iterations in all), the batch's candidate edges against
//! their mirror, a mesh whose outline outgrows the bake's lists refused
//! by name, and far nodes blended from a coarser lattice of the grid.

mod common;

use std::sync::Arc;

use glam::{DVec3, Vec3};
use inlay_passes::object::{Material, MeshPart, MeshVertex, ObjectMesh};
use inlay_passes::rng::Pcg32;
use inlay_passes::shaders::embedded_library;
use inlay_passes::ssdf::bake::{edge_candidates, morton_order, node_sites};
use inlay_passes::ssdf::coarse::NodePlan;
use inlay_passes::ssdf::{bake_reference, object_scene, SilhouetteMesh, SsdfBaker, SsdfKnobs};

/// A mesh from positions and triangles (flat normals unused by the bake).
fn mesh(name: &str, positions: Vec<Vec3>, indices: Vec<u32>) -> Arc<ObjectMesh> {
    let vertices = positions
        .into_iter()
        .map(|position| MeshVertex {
            position,
            normal: Vec3::Y,
            uv: [0.0; 2],
        })
        .collect();
    Arc::new(ObjectMesh {
        name: name.into(),
        vertices,
        parts: vec![MeshPart {
            first_index: 0,
            index_count: indices.len() as u32,
            material: 0,
        }],
        indices,
        materials: vec![Material::default()],
        textures: Vec::new(),
    })
}

/// A closed sphere of `rings` × `segments` quads, its radius bumped by
/// 25 % in a 5 × 4 pattern so that it folds: seen from around it, the
/// bumps hide parts of each other's contours (inner contours, and the
/// outline passing behind a bump). 2 · rings · segments triangles less
/// the poles' degenerate ones.
fn bumpy_sphere(rings: u32, segments: u32) -> Arc<ObjectMesh> {
    let mut positions = Vec::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let r = 1.0 + 0.25 * (5.0 * phi).sin() * (4.0 * theta).sin();
            positions.push(
                r * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                ),
            );
        }
    }
    let at = |i: u32, j: u32| i * segments + j % segments;
    let mut indices = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            indices.extend([a, c, b, b, c, d]);
        }
    }
    mesh("bumpy sphere", positions, indices)
}

/// Points around a mesh of bounding radius about 1.25, from just off its
/// surface to twice its size away.
fn points_around(count: usize, seed: u64) -> Vec<DVec3> {
    let mut rng = Pcg32::new(seed, 3);
    (0..count)
        .map(|_| {
            let d = loop {
                let v = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0 - 1.0;
                if (0.01..=1.0).contains(&v.length_squared()) {
                    break v.normalize();
                }
            };
            d * (1.3 + 1.4 * rng.next_f64())
        })
        .collect()
}

/// On a 100k-triangle mesh (some 2 500 silhouette edges and 10 000
/// pieces' rays from each point) the kernels agree with the f64 mirror as
/// on the bundled meshes (`shadow_gpu.rs`): to f32 rounding except where
/// f32 decides a grazing ray or a silhouette test otherwise (1 % allowed).
/// Before the bake's work was bounded per invocation, the kernel that
/// found a point's outline stopped after about two thirds of the edges on
/// such a mesh and left most of its outline out.
#[test]
fn a_fine_mesh_bakes_as_its_cpu_mirror() {
    let ctx = common::gpu();
    let baker = SsdfBaker::new(&ctx, &embedded_library()).unwrap();
    let mesh = bumpy_sphere(224, 224);
    assert!(mesh.triangles() > 99_000, "{}", mesh.triangles());
    let scene = object_scene(&mesh);
    let points = points_around(40, 7);
    let gpu = baker
        .run(&ctx, &mesh, &scene, &points, 16, &|_, _| {})
        .unwrap()
        .0;
    let cpu = bake_reference(&mesh, &scene, &points, 16);
    let off = gpu
        .iter()
        .zip(&cpu)
        .filter(|(g, c)| (**g as f64 - **c).abs() > 1e-4)
        .count();
    assert!(off * 100 <= cpu.len(), "{off} of {} differ", cpu.len());
    // Hits and misses both, and outlines of some size.
    assert!(cpu.iter().any(|v| *v < -0.1) && cpu.iter().any(|v| *v > 0.5));
    common::assert_no_validation_errors(&ctx);
}

/// The candidates kernel keeps exactly the edges its mirror keeps, and
/// those hold every edge on the silhouette from any point of the box; a
/// small box far from the mesh keeps few of them.
#[test]
fn batch_candidates_hold_every_silhouette_edge() {
    let ctx = common::gpu();
    let baker = SsdfBaker::new(&ctx, &embedded_library()).unwrap();
    let mesh = common::bundled_object("monkey.glb");
    let sil = SilhouetteMesh::new(&mesh);
    let (c, r) = mesh.bounding_sphere();
    let mut rng = Pcg32::new(2, 9);
    for (k, (offset, size)) in [(1.2, 0.15), (1.5, 0.05), (0.9, 0.3), (2.0, 0.6)]
        .into_iter()
        .enumerate()
    {
        let centre = c + DVec3::new(offset, 0.3 * k as f64, -0.5 * offset) * r;
        let half = DVec3::splat(size * r);
        let (lo, hi) = (centre - half, centre + half);
        let cpu = edge_candidates(&sil, lo, hi);
        assert_eq!(
            baker.candidates(&ctx, &mesh, lo, hi).unwrap(),
            cpu,
            "box {k}"
        );
        for _ in 0..64 {
            let t = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let x = lo + (hi - lo) * t;
            for (i, e) in sil.edges.iter().enumerate() {
                if e.is_silhouette(x) {
                    assert!(
                        cpu.binary_search(&(i as u32)).is_ok(),
                        "box {k}: edge {i} at {x}"
                    );
                }
            }
        }
        if k == 1 {
            assert!(
                cpu.len() * 4 < sil.edges.len(),
                "{} of {}",
                cpu.len(),
                sil.edges.len()
            );
        }
    }
    common::assert_no_validation_errors(&ctx);
}

/// A batch is a compact block: along the Morton curve through a grid of
/// 8³ to 64³ nodes, every 32 consecutive nodes span 4 × 4 × 2 nodes.
#[test]
fn morton_batches_are_blocks() {
    for n in [8, 16, 32, 64] {
        let points: Vec<DVec3> = (0..n * n * n)
            .map(|i| DVec3::new((i % n) as f64, ((i / n) % n) as f64, (i / (n * n)) as f64))
            .collect();
        let order = morton_order(&points);
        for batch in order.chunks(32) {
            let (lo, hi) = batch.iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), &i| (lo.min(points[i]), hi.max(points[i])),
            );
            assert_eq!(hi - lo, DVec3::new(3.0, 3.0, 1.0), "{n}³");
        }
    }
}

/// 6 000 separate small triangles in a plane, seen from off it: every
/// edge is on the outline, 18 000 arcs, more than a node's list holds.
/// The bake is refused, naming the mesh, instead of measuring S to part
/// of the outline: before any GPU work when a corner of the grid sees it
/// (`SsdfBaker::bake`), and when the batch is read back otherwise
/// (`SsdfBaker::run` from a point of the caller's).
#[test]
fn an_outline_too_large_for_the_bake_is_refused() {
    let ctx = common::gpu();
    let baker = SsdfBaker::new(&ctx, &embedded_library()).unwrap();
    let (mut positions, mut indices) = (Vec::new(), Vec::new());
    for i in 0..6000u32 {
        let o = Vec3::new((i % 80) as f32, (i / 80) as f32, 0.0) * 0.02 - Vec3::new(0.8, 0.75, 0.0);
        positions.extend([
            o,
            o + Vec3::new(0.01, 0.0, 0.0),
            o + Vec3::new(0.0, 0.01, 0.0),
        ]);
        indices.extend([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let mesh = mesh("confetti", positions, indices);
    let scene = object_scene(&mesh);
    let e = baker
        .run(
            &ctx,
            &mesh,
            &scene,
            &[DVec3::new(0.0, 0.0, 3.0)],
            8,
            &|_, _| {},
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("confetti") && e.contains("outline arcs"), "{e}");
    let knobs = SsdfKnobs {
        grid: 2,
        directions: 8,
        components: 1,
        coarse_angle: 0.0,
    };
    let e = baker
        .bake(&ctx, &mesh, &knobs, &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("confetti") && e.contains("outline arcs") && e.contains("corner"),
        "{e}"
    );
    common::assert_no_validation_errors(&ctx);
}

/// A closed box of 2 × 0.2 × 2, flat enough that a small grid has nodes
/// far above and below it.
fn slab() -> Arc<ObjectMesh> {
    let positions = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -0.1 } else { 0.1 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            )
        })
        .collect();
    let indices = vec![
        0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1, 2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4,
        1, 5, 7, 1, 7, 3,
    ];
    mesh("slab", positions, indices)
}

/// With a coarse angle, the nodes the plan bakes come out of the GPU bake
/// as they do with every node baked, and the rest are the trilinear
/// blends of those: the bake and the plan agree on which is which, and
/// the blends stay near the exact values: mean |ΔS| 0.0093 rad at the
/// largest angle (0.5) and this coarse map (8²), bound at 0.02; a row
/// left unfilled reads about 1 rad. (`coarse.rs`'s test bounds the
/// blends' error at the default angle on the monkey.)
#[test]
fn blended_nodes_blend_the_baked_ones() {
    let ctx = common::gpu();
    let baker = SsdfBaker::new(&ctx, &embedded_library()).unwrap();
    let slab = slab();
    let knobs = |coarse_angle| SsdfKnobs {
        grid: 12,
        directions: 8,
        components: 1,
        coarse_angle,
    };
    let every = baker.bake(&ctx, &slab, &knobs(0.0), &|_, _| {}).unwrap();
    let some = baker.bake(&ctx, &slab, &knobs(0.5), &|_, _| {}).unwrap();
    assert_eq!(every.blended, 0);
    let scene = object_scene(&slab);
    let inside: Vec<bool> = node_sites(&scene, &every.grid)
        .iter()
        .map(|s| s.1)
        .collect();
    let plan = NodePlan::new(&scene, &every.grid, &inside, 0.5);
    assert!(plan.blended.len() > 100, "{}", plan.blended.len());
    assert_eq!(some.blended, plan.blended.len());
    let texels = 64;
    let row = |v: &[f32], i: usize| v[i * texels..(i + 1) * texels].to_vec();
    let baked: Vec<f32> = plan
        .baked
        .iter()
        .flat_map(|&i| row(&every.values, i))
        .collect();
    let filled = plan.fill(&every.grid, &baked, texels);
    for i in 0..every.grid.count() {
        assert_eq!(row(&some.values, i), row(&filled, i), "node {i}");
    }
    let off: f64 = plan
        .blended
        .iter()
        .flat_map(|b| {
            row(&some.values, b.node)
                .into_iter()
                .zip(row(&every.values, b.node))
        })
        .map(|(a, b)| (a - b).abs() as f64)
        .sum::<f64>()
        / (plan.blended.len() * texels) as f64;
    eprintln!("mean |ΔS| at the blended nodes against their bake: {off:.5} rad");
    assert!(off < 0.02, "{off}");
    common::assert_no_validation_errors(&ctx);
}
