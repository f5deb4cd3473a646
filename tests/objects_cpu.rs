//! glTF loading, scene-file objects and their errors (CPU only).

use std::path::{Path, PathBuf};

use inlay_passes::object::{load_gltf, MaterialOverride};

fn objects_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/objects")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("inlay-objects-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The bundled objects load with their parts, materials and textures.
#[test]
fn bundled_objects_load() {
    let sphere = load_gltf(&objects_dir().join("metal-sphere.gltf")).unwrap();
    assert_eq!(sphere.parts.len(), 1);
    let gold = &sphere.materials[sphere.parts[0].material];
    assert_eq!((gold.metallic, gold.roughness), (1.0, 0.25));
    let (c, r) = sphere.bounding_sphere();
    assert!(c.length() < 1e-6 && (r - 1.0).abs() < 1e-6, "{c} {r}");
    for v in &sphere.vertices {
        // Unit sphere: normals are the positions.
        assert!((v.normal - v.position).length() < 1e-5);
    }

    let cube = load_gltf(&objects_dir().join("checker-cube.gltf")).unwrap();
    assert_eq!(cube.triangles(), 12);
    assert_eq!(cube.textures.len(), 2);
    let m = &cube.materials[cube.parts[0].material];
    assert_eq!(
        (m.base_colour_texture, m.metallic_roughness_texture),
        (Some(0), Some(1))
    );
    // The texture decodes: texel (0, 0) is the light square, (1, 0) the red one.
    assert_eq!(&cube.textures[0].rgba8[..4], &[240, 230, 210, 255]);
    assert_eq!(&cube.textures[0].rgba8[4..8], &[230, 60, 40, 255]);
    // Texture evaluation: sRGB decoded, metallic-roughness from G and B.
    let texel = |x: f64, y: f64| [(x + 0.5) / 8.0, (y + 0.5) / 8.0];
    let light = m.at(texel(0.0, 0.0), &cube.textures);
    let red = m.at(texel(1.0, 0.0), &cube.textures);
    assert!((light.albedo.x - inlay_passes::object::srgb_to_linear(240.0 / 255.0)).abs() < 1e-9);
    assert!(red.albedo.x > 3.0 * red.albedo.y);
    assert!((light.metallic - 1.0).abs() < 1e-9 && (light.roughness - 60.0 / 255.0).abs() < 1e-9);
    assert!(red.metallic < 1e-9 && (red.roughness - 240.0 / 255.0).abs() < 1e-9);

    let toy = load_gltf(&objects_dir().join("toy.glb")).unwrap();
    assert_eq!(toy.parts.len(), 2);
    assert_ne!(toy.parts[0].material, toy.parts[1].material);
    // The cap is a child node: translated up by 0.95 and squashed.
    let b = toy.bounds();
    assert!(b.max.y > 1.2 && b.max.y < 1.5, "{:?}", b);
    // Flat normals were computed for the cap: each of its triangles has
    // three identical normals perpendicular to its edges.
    let cap = toy
        .parts
        .iter()
        .find(|p| toy.materials[p.material].name == "red")
        .unwrap();
    // A triangle away from the (degenerate) pole.
    let mid = (cap.first_index + cap.index_count / 2 / 3 * 3) as usize;
    let tri = &toy.indices[mid..mid + 3];
    let [a, bb, c] = [0, 1, 2].map(|k| toy.vertices[tri[k] as usize]);
    assert_eq!(a.normal, bb.normal);
    assert!(a.normal.dot(bb.position - a.position).abs() < 1e-5);
    assert!(a.normal.dot(c.position - a.position).abs() < 1e-5);
}

/// Overrides replace factors and drop the texture of their channel.
#[test]
fn material_overrides_replace_factors_and_textures() {
    let cube = load_gltf(&objects_dir().join("checker-cube.gltf")).unwrap();
    let m = &cube.materials[0];
    let o = MaterialOverride {
        base_color: Some(glam::DVec3::new(0.2, 0.4, 0.6)),
        roughness: Some(0.5),
        metallic: None,
    };
    let r = o.apply(m);
    assert_eq!(r.base_colour_texture, None);
    assert_eq!(r.metallic_roughness_texture, None);
    assert_eq!((r.roughness, r.metallic), (0.5, 1.0));
    assert!(MaterialOverride {
        roughness: Some(1.5),
        ..Default::default()
    }
    .problem()
    .is_some());
}

fn edited(name: &str, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    let dir = temp_dir(name);
    let src = objects_dir().join("checker-cube.gltf");
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&src).unwrap()).unwrap();
    for f in ["checker-cube.bin", "checker.png", "checker-mr.png"] {
        std::fs::copy(objects_dir().join(f), dir.join(f)).unwrap();
    }
    edit(&mut doc);
    let path = dir.join("edited.gltf");
    std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
    path
}

/// What the engine cannot use is refused with the file and the element.
#[test]
fn unsupported_gltf_is_a_clear_error() {
    type Edit = Box<dyn Fn(&mut serde_json::Value)>;
    let cases: Vec<(&str, Edit, &str, &str)> = vec![
        (
            "draco",
            Box::new(|d| {
                d["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
                d["extensionsUsed"] = serde_json::json!(["KHR_draco_mesh_compression"]);
            }),
            "file",
            "KHR_draco_mesh_compression\": Unsupported extension",
        ),
        (
            "missing-buffer",
            Box::new(|d| d["buffers"][0]["uri"] = "nowhere.bin".into()),
            "buffers",
            "missing",
        ),
        (
            "points",
            Box::new(|d| d["meshes"][0]["primitives"][0]["mode"] = 0.into()),
            "meshes[0].primitives[0]",
            "only triangle lists",
        ),
        (
            "texcoord1",
            Box::new(|d| {
                d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 1.into()
            }),
            "materials[0]",
            "TEXCOORD_1",
        ),
    ];
    for (name, edit, field, words) in cases {
        let path = edited(name, edit);
        let e = load_gltf(&path).expect_err(name);
        let text = e.to_string();
        assert_eq!(e.field, field, "{name}: {text}");
        assert!(text.contains(words), "{name}: {text}");
        assert!(text.contains("edited.gltf"), "{name}: {text}");
    }
    let e = load_gltf(Path::new("/no/such/object.glb")).unwrap_err();
    assert!(e.to_string().contains("/no/such/object.glb"));
    // A corrupt file.
    let dir = temp_dir("corrupt");
    std::fs::write(dir.join("bad.glb"), b"glTF\x02\x00\x00\x00garbage").unwrap();
    assert!(load_gltf(&dir.join("bad.glb")).is_err());
}
