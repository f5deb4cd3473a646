//! `object-edge-aa` on lavapipe against its f64 CPU mirror
//! ([`edge_aa_reference`]) on an HDR image with two objects, one partly
//! in front of the other, and values from 1e-4 to 1e4.

mod common;

use std::sync::Arc;

use inlay_engine::{vk, Image, ImageDesc, Readback};
use inlay_passes::composite::COMPOSITE_FORMAT;
use inlay_passes::edge_aa::{edge_aa_reference, EdgeAaKnobs, EdgeAaPass};
use inlay_passes::gbuffer::DISTANCE_ID_FORMAT;

const W: u32 = 40;
const H: u32 = 28;

/// The test frame: a field gradient, a bright disc (object 0) and a dim
/// square (object 1) overlapping it, with a speckle pattern on both.
fn frame() -> (Vec<[f64; 4]>, Vec<f64>) {
    let mut colour = Vec::new();
    let mut object = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let (fx, fy) = (x as f64, y as f64);
            let speckle = 1.0 + 0.3 * ((x * 7 + y * 13) % 5) as f64;
            let disc = (fx - 14.3).powi(2) + (fy - 12.7).powi(2) < 81.0;
            let square = (18.5..33.5).contains(&fx) && (9.5..24.5).contains(&fy);
            let (c, id) = if square {
                ([0.02 * speckle, 0.03, 0.01, 1.0], 1.0)
            } else if disc {
                ([40.0 * speckle, 25.0, 1e4 * (x % 2) as f64, 1.0], 0.0)
            } else {
                let g = 1e-4 + 0.5 * fx / W as f64 + 0.3 * fy / H as f64;
                ([g, g * 0.8, g * 0.6, 0.7], -1.0)
            };
            colour.push(c);
            object.push(id);
        }
    }
    (colour, object)
}

fn image(ctx: &Arc<inlay_engine::Context>, name: &str, format: vk::Format) -> Arc<Image> {
    let desc = ImageDesc {
        width: W,
        height: H,
        format,
    };
    // TRANSFER_SRC: with a region, the pass copies the frame first.
    let usage = vk::ImageUsageFlags::SAMPLED
        | vk::ImageUsageFlags::TRANSFER_DST
        | vk::ImageUsageFlags::TRANSFER_SRC;
    Arc::new(Image::new(ctx, name, desc, usage).unwrap())
}

#[test]
fn edge_aa_gpu_matches_cpu() {
    let ctx = common::gpu();
    let lib = common::test_library();
    let knobs = EdgeAaKnobs::default();
    let pass = EdgeAaPass::new(&ctx, &lib, knobs).unwrap();
    let (colour, object) = frame();
    let colour_img = image(&ctx, "colour", COMPOSITE_FORMAT);
    let texels: Vec<[f32; 4]> = colour.iter().map(|c| c.map(|v| v as f32)).collect();
    colour_img.write_rgba32f(&texels).unwrap();
    let ids = image(&ctx, "distance-id", DISTANCE_ID_FORMAT);
    let id_bytes: Vec<u8> = object
        .iter()
        .flat_map(|&id| [1.0f32, id as f32])
        .flat_map(f32::to_le_bytes)
        .collect();
    ids.write_texels(&id_bytes).unwrap();
    let readback = Readback::new(
        &ctx,
        ImageDesc {
            width: W,
            height: H,
            format: COMPOSITE_FORMAT,
        },
    )
    .unwrap();
    // The whole image, and the objects' region widened by a pixel (the
    // disc reaches 4..24 × 3..22, the square 19..34 × 10..25): the rest is
    // copied, and the image must be the same.
    let regions = [None, Some([3, 2, 35, 26])];
    let gpu: Vec<Vec<[f32; 4]>> = regions
        .iter()
        .map(|&region| {
            common::run_frame(&ctx, |graph| {
                let c = graph.import_image(&colour_img, "colour", None);
                let d = graph.import_image(&ids, "distance-id", None);
                let out = pass.add(graph, c, d, region);
                readback.add_to_graph(graph, out);
            });
            readback.read().unwrap().pixels
        })
        .collect();
    assert_eq!(
        gpu[0], gpu[1],
        "the region's image differs from the whole image's"
    );
    let gpu = &gpu[0];
    // The CPU mirror on the f32 inputs the GPU saw.
    let seen: Vec<[f64; 4]> = texels.iter().map(|c| c.map(|v| v as f64)).collect();
    let cpu = edge_aa_reference(&seen, &object, W as usize, H as usize, &knobs);
    let mut changed = 0;
    for (i, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
        if c != &seen[i] {
            changed += 1;
        }
        for k in 0..4 {
            // f32 sums of eight neighbours and a blend weight from a
            // difference of lumas over their range: a few ulp of the
            // largest value involved.
            let scale = c[k].abs().max(seen[i][k].abs()).max(1e-3);
            assert!(
                (g[k] as f64 - c[k]).abs() <= 2e-5 * scale,
                "pixel {i} ({}, {}) channel {k}: gpu {} cpu {}",
                i as u32 % W,
                i as u32 / W,
                g[k],
                c[k]
            );
        }
    }
    assert!(changed > 40, "only {changed} outline pixels blended");
}
