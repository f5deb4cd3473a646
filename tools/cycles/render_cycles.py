"""Independent ground truth for inlay: a scene file rendered by Blender Cycles.

Run by hand (never in CI) with Debian's Blender 3.4:

    blender -b --factory-startup --python tools/cycles/render_cycles.py -- \
        scenes/dog.toml --out docs/cycles/dog [--what cameras,probes,training] \
        [--width 320 --height 180 --samples 512 --seeds 1,2 --threads 0] \
        [--object-diffuse burley|lambert]

The scene file is translated, not re-modelled: every recipe primitive
becomes a mesh (planes as large quads, spheres and cylinders finely
tessellated and smooth-shaded (media flat: see build_recipe), boxes as cubes turned by their `rotation`,
quads as the thin box behind their face, whose one outward face alone
carries the emission), Lambertian surfaces a pure Diffuse BSDF (Cycles'
Diffuse BSDF at roughness 0 is Lambert, so the recipe's surfaces are
modelled exactly; the Principled BSDF's Burley diffuse would not be; a
`checker` albedo is built from math nodes on the world position, the
same cubes as inlay's), emitters an Emission shader whose strength 1 makes
the colour the emitted radiance (both sides; the recipe's spheres are
closed, so only the outside is seen), media a Volume Scatter plus Volume
Absorption pair whose extinction is the recipe's density and whose
single-scattering albedo is the recipe's albedo, the environment (SG lobes
or an equirect EXR) an equirect world texture, cameras perspective cameras
with the scene's vertical field of view, and each glTF object imported by
Blender's glTF importer (a Principled BSDF: metallic-roughness, F0 = 0.04
for dielectrics, α = roughness²; its diffuse part is Burley's, not
Lambert's) and posed as the scene poses it, with the scene's material
override applied. `--object-diffuse lambert` swaps the Principled
diffuse for glTF's own Lambertian one (the specular kept) and tags the
object images `-lambert`: the two renders measure how much of inlay's
object error is the material model (docs/fidelity.md, seventeenth pass).

Coordinates: inlay is +Y up, Blender +Z up; a point (x, y, z) of inlay is
(x, −z, y) in Blender, as Blender's glTF importer maps it.

Outputs (linear OpenEXR, float32, RGB; pixel filter a 1-pixel box, i.e. the
mean over each pixel's area; no clamping, no denoising):
- cameras: `<camera>-<objects|bare>-<direct|full>-s<seed>.exr` for every
  camera; `direct` is direct light only (max bounces 0), `full` has the
  scene's [bake] bounces of indirect light (what inlay's fields hold).
- probes: `probe-<object>-s<seed>.exr`, the full-bounce incident radiance
  at each object's centre with the objects removed, as an equirect map in
  inlay's convention (2n × n, +Y up, u = atan2(z, x)/2π, v = θ/π).
- training: `training/` with `transforms.json` (nerfstudio/instant-ngp
  convention, OpenGL camera axes, inlay's world axes, an `aabb` that holds
  the recipe's bounds and every surface that crosses them, which Cycles
  draws whole)
  and one linear HDR EXR per view (half floats), full bounces, no objects.
  `--only-views 8,24 --seeds 2 --out DIR` renders those views again with
  another seed: the PSNR between the two renders of a view bounds what any
  field can score against it (docs/benchmarks.md, "The Cycles sets' own
  noise").
- depth: `training/depth/depth-NNN.png` for the training cameras, Cycles'
  Z pass (the distance along the camera's viewing direction) at each
  pixel's centre (one sample, a pixel filter 0.01 wide) as 16-bit integers
  in thousandths of the scene's units (0 where the ray meets nothing
  within 65.535), and `training/depth/transforms.json`: the training set's
  own (rendered first: `--what training`), its frames' images one folder
  up, each frame's `depth_file_path` and the file's
  `depth_unit_scale_factor` added. The photographs alone stay
  `training/transforms.json`.
- alpha: `training/alpha/view-NNN.exr`, the training views (rendered
  first: `--what training`) with alpha, as a synthetic set of the Blender
  convention is made: the share of each pixel's area whose rays meet the
  scene (`--alpha-samples` a pixel, the film transparent, no bounces) as
  alpha, and the photograph less the environment seen through the rest
  (the environment's mean over the pixel, rendered alone with the same
  samples, times 1 − alpha) as its premultiplied colour;
  `training/alpha/transforms.json` names them. What the photographs
  record of the scene is untouched; only the environment seen past it
  leaves.
- `render.json`: Blender's version, the command, samples, seeds and the
  wall time of each image.
"""

import json
import math
import os
import sys
import time
import tomllib

import bpy
import numpy as np
from mathutils import Matrix, Vector

# Blender 3.4's glTF importer still uses `np.bool`, which NumPy 1.24 (Debian
# bookworm's) removed; the alias is the builtin.
if "bool" not in np.__dict__:
    np.bool = bool


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    import argparse

    p = argparse.ArgumentParser(prog="render_cycles.py")
    p.add_argument("scene")
    p.add_argument("--out", required=True)
    p.add_argument("--what", default="cameras,probes")
    p.add_argument("--width", type=int, default=320)
    p.add_argument("--height", type=int, default=180)
    p.add_argument("--samples", type=int, default=512)
    p.add_argument("--probe-samples", type=int, default=1024)
    p.add_argument("--sensor-samples", type=int, default=4096)
    p.add_argument("--probe-resolution", type=int, default=64, help="n: the probe is 2n x n")
    p.add_argument("--seeds", default="1,2")
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--cameras", default="", help="only these cameras (comma-separated names)")
    p.add_argument("--modes", default="bare,objects", help="bare and/or objects")
    p.add_argument("--light", default="direct,full", help="direct and/or full")
    p.add_argument("--views", type=int, default=32, help="training views")
    p.add_argument("--view-size", type=int, default=96)
    p.add_argument("--view-samples", type=int, default=256)
    p.add_argument("--alpha-samples", type=int, default=1024, help="samples a pixel of --what alpha's two passes")
    p.add_argument(
        "--only-views",
        default="",
        help="only these training views (comma-separated indices), e.g. the held-out ones again with "
        "another seed (--seeds 2) into another --out, to read the views' own noise",
    )
    p.add_argument(
        "--object-diffuse",
        default="burley",
        choices=["burley", "lambert"],
        help="the objects' diffuse: the importer's Principled BSDF (Burley) or glTF's own Lambert",
    )
    return p.parse_args(argv)


# inlay (x, y, z), +Y up  ->  Blender (x, -z, y), +Z up.
C = Matrix(((1, 0, 0, 0), (0, 0, -1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))


# inlay's scene::QUAD_THICKNESS: a quad is a thin box behind its face.
QUAD_THICKNESS = 0.01


def to_b(v):
    return Vector((v[0], -v[2], v[1]))


def vec3(v, default=None):
    if v is None:
        return default
    return [float(x) for x in v]


# ---------------------------------------------------------------- materials


def checker_colour(nt, albedo, checker):
    """A colour socket with inlay's world-space 3D checkerboard: the cube
    of edge `size` holding x has checker["albedo"] when
    floor(x/s) + floor(y/s) + floor(z/s) is odd (inlay axes), else `albedo`."""
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    nt.links.new(geo.outputs["Position"], sep.inputs[0])
    size = float(checker["size"])

    def op(name, a, b=None):
        n = nt.nodes.new("ShaderNodeMath")
        n.operation = name
        for i, v in enumerate((a, b)):
            if v is None:
                continue
            if isinstance(v, (int, float)):
                n.inputs[i].default_value = float(v)
            else:
                nt.links.new(v, n.inputs[i])
        return n.outputs[0]

    # inlay (x, y, z) = Blender (x, z, -y).
    cells = [
        op("FLOOR", op("DIVIDE", sep.outputs["X"], size)),
        op("FLOOR", op("DIVIDE", sep.outputs["Z"], size)),
        op("FLOOR", op("DIVIDE", op("MULTIPLY", sep.outputs["Y"], -1.0), size)),
    ]
    total = op("ADD", op("ADD", cells[0], cells[1]), cells[2])
    odd = op("SUBTRACT", total, op("MULTIPLY", op("FLOOR", op("MULTIPLY", total, 0.5)), 2.0))
    mix = nt.nodes.new("ShaderNodeMixRGB")
    mix.blend_type = "MIX"
    nt.links.new(odd, mix.inputs["Fac"])
    mix.inputs["Color1"].default_value = (*albedo, 1.0)
    mix.inputs["Color2"].default_value = (*[float(c) for c in checker["albedo"]], 1.0)
    return mix.outputs["Color"]


def diffuse_material(name, albedo, checker=None):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (*albedo, 1.0)
    if checker is not None:
        nt.links.new(checker_colour(nt, albedo, checker), d.inputs["Color"])
    d.inputs["Roughness"].default_value = 0.0
    nt.links.new(d.outputs["BSDF"], out.inputs["Surface"])
    return m


def emitter_material(name, albedo, emission):
    m = diffuse_material(name, albedo)
    nt = m.node_tree
    out = next(n for n in nt.nodes if n.type == "OUTPUT_MATERIAL")
    d = next(n for n in nt.nodes if n.type == "BSDF_DIFFUSE")
    e = nt.nodes.new("ShaderNodeEmission")
    e.inputs["Color"].default_value = (*emission, 1.0)
    e.inputs["Strength"].default_value = 1.0
    add = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(d.outputs["BSDF"], add.inputs[0])
    nt.links.new(e.outputs["Emission"], add.inputs[1])
    nt.links.new(add.outputs["Shader"], out.inputs["Surface"])
    return m


def medium_material(name, albedo, density):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    # Cycles: scattering coefficient colour·density, absorption (1 − colour)·density.
    s = nt.nodes.new("ShaderNodeVolumeScatter")
    s.inputs["Color"].default_value = (*albedo, 1.0)
    s.inputs["Density"].default_value = density
    s.inputs["Anisotropy"].default_value = 0.0
    a = nt.nodes.new("ShaderNodeVolumeAbsorption")
    a.inputs["Color"].default_value = (*albedo, 1.0)
    a.inputs["Density"].default_value = density
    add = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(s.outputs["Volume"], add.inputs[0])
    nt.links.new(a.outputs["Volume"], add.inputs[1])
    nt.links.new(add.outputs["Shader"], out.inputs["Volume"])
    # Constant density: sampled analytically, not ray-marched in steps.
    m.cycles.homogeneous_volume = True
    return m


# ---------------------------------------------------------------- geometry


def link(obj, collection):
    collection.objects.link(obj)
    return obj


def mesh_object(name, verts, faces, smooth, collection):
    me = bpy.data.meshes.new(name)
    me.from_pydata([tuple(v) for v in verts], [], faces)
    me.update()
    for p in me.polygons:
        p.use_smooth = smooth
    return link(bpy.data.objects.new(name, me), collection)


def sphere_mesh(centre, radius, segments=192, rings=96):
    """A watertight UV sphere (one vertex at each pole), faces counter-
    clockwise seen from outside: a closed volume's faces must face out for
    Cycles to know its inside."""
    point = lambda th, ph: to_b([centre[i] + radius * d for i, d in enumerate((math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph)))])
    verts = [point(0.0, 0.0)]
    for r in range(1, rings):
        th = math.pi * r / rings
        verts += [point(th, 2 * math.pi * s / segments) for s in range(segments)]
    south = len(verts)
    verts.append(point(math.pi, 0.0))
    ring = lambda r, s: 1 + (r - 1) * segments + s % segments
    faces = [(0, ring(1, s + 1), ring(1, s)) for s in range(segments)]
    for r in range(1, rings - 1):
        for s in range(segments):
            faces.append((ring(r, s), ring(r, s + 1), ring(r + 1, s + 1), ring(r + 1, s)))
    faces += [(south, ring(rings - 1, s), ring(rings - 1, s + 1)) for s in range(segments)]
    return verts, faces


def basis(axis):
    a = np.array(axis, float)
    a /= np.linalg.norm(a)
    t = np.array([1.0, 0, 0]) if abs(a[0]) < 0.9 else np.array([0, 0, 1.0])
    u = np.cross(a, t)
    u /= np.linalg.norm(u)
    return a, u, np.cross(a, u)


def cylinder_mesh(centre, axis, radius, height, watertight, segments=192):
    """The side (smooth-shaded for a surface) and the two caps. For a surface the caps are
    flat, with vertices of their own, so smoothing does not bend the side's
    normals into them; for a medium's boundary the caps share the side's
    rim vertices: Cycles tracks a volume's inside only across a watertight
    mesh (with separate rims it rendered CUPS' glass with black caps)."""
    a, u, w = basis(axis)
    c = np.array(centre, float)
    ring = [radius * (u * math.cos(2 * math.pi * s / segments) + w * math.sin(2 * math.pi * s / segments)) for s in range(segments)]
    verts, side = [], []
    for end in (-0.5, 0.5):
        verts += [to_b(c + a * end * height + r) for r in ring]
    for s in range(segments):
        s1 = (s + 1) % segments
        side.append((s, s1, segments + s1, segments + s))
    caps_v, caps = [], []
    for end, rim, flip in ((-0.5, 0, True), (0.5, segments, False)):
        if watertight:
            centre_index = len(verts) + len(caps_v)
            caps_v.append(to_b(c + a * end * height))
            ring_index = [rim + s for s in range(segments)]
        else:
            base = 2 * segments + len(caps_v)
            caps_v += [to_b(c + a * end * height)] + [to_b(c + a * end * height + r) for r in ring]
            centre_index = base
            ring_index = [base + 1 + s for s in range(segments)]
        for s in range(segments):
            tri = (centre_index, ring_index[s], ring_index[(s + 1) % segments])
            caps.append(tri[::-1] if flip else tri)
    return verts + caps_v, side, caps


def box_mesh(centre, size, rotation=None):
    c = np.array(centre, float)
    h = 0.5 * np.array(size, float)
    R = np.eye(3) if rotation is None else rotation
    corners = []
    for z in (-1, 1):
        for y in (-1, 1):
            for x in (-1, 1):
                corners.append(to_b(c + R @ (h * np.array([x, y, z]))))
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return corners, faces


def rotation_matrix(degrees):
    """World from box axes for a scene's `rotation` (degrees; extrinsic X,
    then Y, then Z, in inlay axes), as inlay's rotation_matrix."""
    rx, ry, rz = (math.radians(a) for a in degrees)

    def rot(axis, a):
        c, s = math.cos(a), math.sin(a)
        i, j = [k for k in range(3) if k != axis]
        R = np.eye(3)
        R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
        return R

    return rot(2, rz) @ rot(1, ry) @ rot(0, rx)


def quad_frame(p):
    """A quad's box (centre, size, rotation) and its face: the same frame
    as inlay's (height along `up` made perpendicular to the normal)."""
    n = np.array(p["normal"], float)
    n /= np.linalg.norm(n)
    if "up" in p:
        up = np.array(p["up"], float)
        up /= np.linalg.norm(up)
    else:
        up = np.array([0.0, 0.0, -1.0]) if abs(n[1]) > 0.9 else np.array([0.0, 1.0, 0.0])
    v = up - n * up.dot(n)
    v /= np.linalg.norm(v)
    u = np.cross(v, n)
    t = float(p.get("thickness", QUAD_THICKNESS))
    centre = np.array(p["center"], float) - n * 0.5 * t
    return centre, [float(p["width"]), float(p["height"]), t], np.stack([u, v, n], axis=1)


def plane_mesh(point, normal, extent=1e3):
    n, u, w = basis(normal)
    p = np.array(point, float)
    verts = [to_b(p + extent * (su * u + sw * w)) for su, sw in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return verts, [(0, 1, 2, 3)]


def build_recipe(recipe, collection):
    """Adds the recipe's primitives to `collection`; returns the surfaces and
    media (not lights, not endless planes), whose extents can reach past
    the recipe's bounds."""
    solids = []
    for i, p in enumerate(recipe.get("primitives", [])):
        name = p.get("name", f"primitive-{i}")
        t = p["type"]
        albedo = vec3(p.get("albedo"), [0.5, 0.5, 0.5])
        emission = vec3(p.get("emission"), [0.0, 0.0, 0.0])
        density = p.get("density")
        # A medium's boundary has no surface to shade, and smooth shading
        # changes what Cycles renders through it: with smooth normals on
        # CUPS' glass (a watertight cylinder, whose rim vertices average the
        # caps' normals into the side's) light crossing its top cap came
        # out up to 2.6 times darker than the glass's transmittance allows,
        # and its shadow on the table up to 1.8 times too dark. Flat, Cycles
        # and inlay's path tracer agree within Monte-Carlo noise there.
        smooth = t in ("sphere", "cylinder") and density is None
        flat = []
        if t == "sphere":
            v, f = sphere_mesh(p["center"], p["radius"])
        elif t == "cylinder":
            v, f, flat = cylinder_mesh(p["center"], p["axis"], p["radius"], p["height"], density is not None)
        elif t == "box":
            R = rotation_matrix(p["rotation"]) if "rotation" in p else None
            v, f = box_mesh(p["center"], p["size"], R)
        elif t == "quad":
            v, f = box_mesh(*quad_frame(p))
        elif t == "plane":
            v, f = plane_mesh(p["point"], p["normal"])
        else:
            raise SystemExit(f"{name}: primitive type `{t}` is not translated")
        obj = mesh_object(name, v, f + flat, smooth, collection)
        for poly in obj.data.polygons[len(f) :]:
            poly.use_smooth = False
        if density is not None:
            mat = medium_material(name, albedo, float(density))
        elif max(emission) > 0 and t == "quad":
            # One-sided: only the box's +z face (the quad's face) emits;
            # emission inside the closed box never leaves it.
            obj.data.materials.append(diffuse_material(name + "-back", albedo))
            mat = emitter_material(name, albedo, emission)
            obj.data.polygons[1].material_index = 1
        elif max(emission) > 0:
            mat = emitter_material(name, albedo, emission)
        else:
            mat = diffuse_material(name, albedo, p.get("checker"))
        obj.data.materials.append(mat)
        if max(emission) <= 0 and t != "plane":
            solids.append(obj)
    return solids


def bounds_holding(bounds, solids):
    """The recipe's bounds widened to hold every solid that crosses them:
    a field in the recipe's bounds holds only the part inside (as inlay's
    `Recipe::crossing_bounds` says), but Cycles draws the whole primitive,
    so a training set's `aabb` must hold all of what its photographs show.
    Solids wholly outside stay outside."""
    lo, hi = np.array(bounds["min"], float), np.array(bounds["max"], float)
    out_lo, out_hi = lo.copy(), hi.copy()
    for obj in solids:
        v = np.array([obj.matrix_world @ x.co for x in obj.data.vertices], float)
        # Blender's axes to inlay's: the inverse of `to_b`.
        v = np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1)
        e_lo, e_hi = v.min(axis=0), v.max(axis=0)
        if np.all(e_lo < hi) and np.all(e_hi > lo):
            out_lo, out_hi = np.minimum(out_lo, e_lo), np.maximum(out_hi, e_hi)
    return [[round(float(x), 6) for x in out_lo], [round(float(x), 6) for x in out_hi]]


# ---------------------------------------------------------------- environment


def eval_lobes(lobes, scale, d):
    """Σ μ exp(λ(d·p − 1)) over lobes, d: (..., 3) unit directions (inlay axes)."""
    out = np.zeros(d.shape[:-1] + (3,))
    for lobe in lobes:
        p = np.array(lobe["direction"], float)
        p /= np.linalg.norm(p)
        lam = float(lobe["sharpness"])
        mu = np.array(lobe["amplitude"], float)
        out += np.exp(lam * (d @ p - 1.0))[..., None] * mu
    return out * scale


def load_equirect_exr(path):
    """An equirect EXR (inlay's convention) as an (h, w, 3) array, via Blender."""
    img = bpy.data.images.load(path)
    w, h = img.size
    px = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[::-1, :, :3]
    return px


def world_from_environment(scene_dir, env, width=2048):
    """The world shader: inlay's environment as a Blender equirect texture.
    Blender's equirect column u looks along azimuth atan2(Y, X) = 2π(0.5 − u)
    (Blender axes), row top = +Z; inlay's column u looks along atan2(z, x) =
    2πu. A direction of azimuth φ in inlay has Blender azimuth −φ, so
    Blender's u = 0.5 + inlay's u: the same image rolled by half its width."""
    h = width // 2
    scale = float(env.get("scale", 1.0)) if env else 1.0
    if env is None or (not env.get("lobes") and not env.get("equirect")):
        pixels = np.zeros((h, width, 3))
    elif env.get("lobes"):
        v = (np.arange(h) + 0.5) / h
        u = (np.arange(width) + 0.5) / width
        th = math.pi * v[:, None]
        ph = 2 * math.pi * (u[None, :] - 0.5)  # inlay azimuth of Blender column u
        d = np.stack(
            [np.sin(th) * np.cos(ph), np.cos(th) * np.ones_like(ph), np.sin(th) * np.sin(ph)], axis=-1
        )
        pixels = eval_lobes(env["lobes"], scale, d)
    else:
        src = load_equirect_exr(os.path.join(scene_dir, env["equirect"])) * scale
        pixels = np.roll(src, src.shape[1] // 2, axis=1)
        h, width = pixels.shape[:2]
    img = bpy.data.images.new("environment", width, h, float_buffer=True, alpha=False)
    rgba = np.concatenate([pixels, np.ones((h, width, 1))], axis=-1)[::-1]
    img.pixels.foreach_set(rgba.astype(np.float32).ravel())
    world = bpy.data.worlds.new("environment")
    world.use_nodes = True
    nt = world.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputWorld")
    bg = nt.nodes.new("ShaderNodeBackground")
    tex = nt.nodes.new("ShaderNodeTexEnvironment")
    tex.image = img
    tex.interpolation = "Linear"
    nt.links.new(tex.outputs["Color"], bg.inputs["Color"])
    nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
    world.cycles.sampling_method = "MANUAL"
    world.cycles.sample_map_resolution = 1024
    return world


# ---------------------------------------------------------------- objects


def pose_matrix(o):
    """The scene's object-to-world transform in inlay axes (translation ·
    extrinsic X, Y, Z rotation · scale), as inlay's ObjectPose::matrix."""
    pos = vec3(o.get("position"), [0.0, 0.0, 0.0])
    rot = [math.radians(a) for a in vec3(o.get("rotation"), [0.0, 0.0, 0.0])]
    s = o.get("scale", 1.0)
    s = [float(s)] * 3 if not isinstance(s, list) else [float(x) for x in s]
    R = (
        Matrix.Rotation(rot[2], 4, "Z")
        @ Matrix.Rotation(rot[1], 4, "Y")
        @ Matrix.Rotation(rot[0], 4, "X")
    )
    S = Matrix.Diagonal((*s, 1.0))
    return Matrix.Translation(pos) @ R @ S


def import_object(scene_dir, o, collection, lambert=False):
    before = set(bpy.data.objects)
    bpy.ops.import_scene.gltf(filepath=os.path.join(scene_dir, o["file"]))
    new = [ob for ob in bpy.data.objects if ob not in before]
    root = bpy.data.objects.new(o.get("name", os.path.splitext(os.path.basename(o["file"]))[0]), None)
    collection.objects.link(root)
    for ob in new:
        for c in ob.users_collection:
            c.objects.unlink(ob)
        collection.objects.link(ob)
        if ob.parent is None:
            ob.parent = root
    # The importer already maps glTF's axes to Blender's (C); the pose acts in inlay's.
    root.matrix_world = C @ pose_matrix(o) @ C.inverted()
    override = o.get("material", {})
    swapped = set()
    for ob in new:
        if ob.type != "MESH":
            continue
        for slot in ob.material_slots:
            m = slot.material
            if m is None or not m.use_nodes:
                continue
            for n in m.node_tree.nodes:
                if n.type != "BSDF_PRINCIPLED":
                    continue
                for key, socket in (("base_color", "Base Color"), ("roughness", "Roughness"), ("metallic", "Metallic")):
                    if key not in override:
                        continue
                    inp = n.inputs[socket]
                    for lk in list(inp.links):
                        m.node_tree.links.remove(lk)
                    v = override[key]
                    inp.default_value = (*[float(x) for x in v], 1.0) if key == "base_color" else float(v)
                # inlay clamps roughness to at least 0.1.
                r = n.inputs["Roughness"]
                if not r.links:
                    r.default_value = max(r.default_value, 0.1)
            if lambert and m.name not in swapped:
                swapped.add(m.name)
                for n in [n for n in m.node_tree.nodes if n.type == "BSDF_PRINCIPLED"]:
                    lambert_diffuse(m.node_tree, n)
    return root, new


def lambert_diffuse(nt, p):
    """Swap the Principled BSDF `p`'s Burley diffuse for glTF's own
    Lambertian one, keeping its specular: the material becomes
    mix(metallic; P₀ + Lambert(base), P₁) where P₀ is `p` with a black base
    colour and metallic 0 (its white F0 = 0.04 specular alone: in Cycles 3.x
    the Principled diffuse is added to the specular, not weighted by it) and
    P₁ is `p` with metallic 1 (no diffuse at all). Both ends are exactly
    glTF's f = (1 − metallic)·albedo/π + specular, inlay's model; between
    them the blend is linear in metallic, as glTF's is."""
    out_links = [lk for lk in nt.links if lk.from_node == p]
    metal = nt.nodes.new("ShaderNodeBsdfPrincipled")
    for inp in p.inputs:
        if inp.name not in metal.inputs or not hasattr(inp, "default_value"):
            continue
        metal.inputs[inp.name].default_value = inp.default_value
        for lk in inp.links:
            nt.links.new(lk.from_socket, metal.inputs[inp.name])
    metal.distribution = p.distribution
    for lk in list(metal.inputs["Metallic"].links):
        nt.links.remove(lk)
    metal.inputs["Metallic"].default_value = 1.0
    lam = nt.nodes.new("ShaderNodeBsdfDiffuse")
    lam.inputs["Roughness"].default_value = 0.0
    base = p.inputs["Base Color"]
    lam.inputs["Color"].default_value = base.default_value
    for lk in list(base.links):
        nt.links.new(lk.from_socket, lam.inputs["Color"])
        nt.links.remove(lk)
    base.default_value = (0.0, 0.0, 0.0, 1.0)
    mix = nt.nodes.new("ShaderNodeMixShader")
    fac = p.inputs["Metallic"]
    mix.inputs["Fac"].default_value = fac.default_value
    for lk in list(fac.links):
        nt.links.new(lk.from_socket, mix.inputs["Fac"])
        nt.links.remove(lk)
    fac.default_value = 0.0
    add = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(p.outputs["BSDF"], add.inputs[0])
    nt.links.new(lam.outputs["BSDF"], add.inputs[1])
    nt.links.new(add.outputs["Shader"], mix.inputs[1])
    nt.links.new(metal.outputs["BSDF"], mix.inputs[2])
    for lk in out_links:
        to = lk.to_socket
        nt.links.remove(lk)
        nt.links.new(mix.outputs["Shader"], to)


def object_centre(objs):
    """The centre of the world-space bounding box of `objs`' vertices, in
    inlay axes (where inlay traces the object's probe)."""
    bpy.context.view_layer.update()
    lo = np.full(3, np.inf)
    hi = -lo
    for ob in objs:
        if ob.type != "MESH":
            continue
        mw = ob.matrix_world
        for v in ob.data.vertices:
            p = mw @ v.co
            q = np.array([p.x, p.z, -p.y])
            lo = np.minimum(lo, q)
            hi = np.maximum(hi, q)
    return 0.5 * (lo + hi)


# ---------------------------------------------------------------- cameras and rendering


def look_at_matrix(position, look_at, up):
    pos, tgt, upv = to_b(position), to_b(look_at), to_b(up)
    f = (tgt - pos).normalized()
    x = f.cross(upv).normalized()
    y = x.cross(f)
    m = Matrix(((x[0], y[0], -f[0], pos[0]), (x[1], y[1], -f[1], pos[1]), (x[2], y[2], -f[2], pos[2]), (0, 0, 0, 1)))
    return m


def add_camera(name, position, look_at, up, fov_y_deg):
    cam = bpy.data.cameras.new(name)
    cam.sensor_fit = "VERTICAL"
    cam.angle_y = math.radians(fov_y_deg)
    cam.clip_start = 1e-3
    cam.clip_end = 1e4
    ob = bpy.data.objects.new(name, cam)
    bpy.context.scene.collection.objects.link(ob)
    ob.matrix_world = look_at_matrix(position, look_at, up)
    return ob


def setup_render(args):
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    cy = sc.cycles
    cy.device = "CPU"
    cy.use_denoising = False
    cy.use_adaptive_sampling = False
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.blur_glossy = 0.0
    cy.caustics_reflective = True
    cy.caustics_refractive = True
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.film_exposure = 1.0
    sc.render.film_transparent = False
    sc.view_settings.view_transform = "Standard"
    sc.view_settings.look = "None"
    sc.view_settings.exposure = 0.0
    sc.view_settings.gamma = 1.0
    sc.render.image_settings.file_format = "OPEN_EXR"
    sc.render.image_settings.color_mode = "RGB"
    sc.render.image_settings.color_depth = "32"
    sc.render.image_settings.exr_codec = "ZIP"
    sc.render.resolution_percentage = 100
    if args.threads > 0:
        sc.render.threads_mode = "FIXED"
        sc.render.threads = args.threads


def set_bounces(bounces):
    cy = bpy.context.scene.cycles
    cy.max_bounces = bounces
    cy.diffuse_bounces = bounces
    cy.glossy_bounces = bounces
    cy.transmission_bounces = bounces
    cy.volume_bounces = bounces
    cy.transparent_max_bounces = 64


def render_to(path, log):
    sc = bpy.context.scene
    tmp = path + ".partial.exr"
    sc.render.filepath = tmp
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    os.replace(tmp, path)
    dt = time.time() - t0
    log.append({"file": os.path.basename(path), "seconds": round(dt, 1), "samples": sc.cycles.samples, "seed": sc.cycles.seed})
    print(f"wrote {path} in {dt:.1f} s", flush=True)


def write_probe(path, centre, n, samples, seed, log):
    """An equirect panorama at `centre` in inlay's convention. Cycles'
    equirect camera with rotation (90°, 0, −90°) renders the world's
    equirect mapping (column u looks along Blender azimuth 2π(0.5 − u));
    turned a further 180° about +Z, column u looks along Blender azimuth
    −2πu, which is inlay azimuth 2πu: inlay's map, with no resampling."""
    sc = bpy.context.scene
    cam = bpy.data.cameras.new("probe")
    cam.type = "PANO"
    try:
        cam.panorama_type = "EQUIRECTANGULAR"
    except AttributeError:
        cam.cycles.panorama_type = "EQUIRECTANGULAR"
    ob = bpy.data.objects.new("probe", cam)
    sc.collection.objects.link(ob)
    ob.location = to_b(centre)
    ob.rotation_euler = (math.radians(90), 0.0, math.radians(90))
    sc.camera = ob
    sc.render.resolution_x, sc.render.resolution_y = 2 * n, n
    sc.cycles.samples = samples
    sc.cycles.seed = seed
    render_to(path, log)
    bpy.data.objects.remove(ob)


AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}


def measure_irradiance(centre, samples, seed, log):
    """Irradiance at `centre` from each axis' hemisphere, with next-event
    estimation (a camera ray into a panorama only finds a 0.3° bulb by
    chance): a 1 mm white Lambertian square at `centre` facing the axis,
    seen head-on by an orthographic camera and by nothing else (invisible
    to every other ray), shows radiance E/π. Returns {axis: [r, g, b]}.
    (Images are read back from EXRs that the render wrote: Blender's
    Image.save applies the view transform, sRGB, even to float images.)"""
    sc = bpy.context.scene
    size = 1e-3
    white = diffuse_material("sensor", [1.0, 1.0, 1.0])
    out = {}
    for name, n in AXES.items():
        nb = to_b(n)
        # One face of a tiny square, built facing +Z in Blender axes, then turned.
        h = 0.5 * size
        me = bpy.data.meshes.new("sensor")
        me.from_pydata([(-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0)], [], [(0, 1, 2, 3)])
        me.update()
        patch = bpy.data.objects.new("sensor", me)
        sc.collection.objects.link(patch)
        patch.data.materials.append(white)
        rot = Vector((0, 0, 1)).rotation_difference(nb).to_matrix().to_4x4()
        patch.matrix_world = Matrix.Translation(to_b(centre)) @ rot
        for attr in ("visible_diffuse", "visible_glossy", "visible_transmission", "visible_volume_scatter", "visible_shadow"):
            setattr(patch, attr, False)
        cam = bpy.data.cameras.new("sensor-camera")
        cam.type = "ORTHO"
        cam.ortho_scale = 0.5 * size
        cam.clip_start = 1e-5
        cam.clip_end = 1.0
        cob = bpy.data.objects.new("sensor-camera", cam)
        sc.collection.objects.link(cob)
        cob.matrix_world = Matrix.Translation(to_b(centre) + nb * 0.01) @ rot
        sc.camera = cob
        sc.render.resolution_x = sc.render.resolution_y = 4
        sc.cycles.samples = samples
        sc.cycles.seed = seed
        tmp = os.path.join(bpy.app.tempdir or "/tmp", f"sensor-{os.getpid()}.exr")
        sc.render.filepath = tmp
        bpy.ops.render.render(write_still=True)
        img = bpy.data.images.load(tmp)
        px = np.array(img.pixels[:], dtype=np.float64).reshape(-1, 4)[:, :3]
        bpy.data.images.remove(img)
        os.remove(tmp)
        out[name] = [float(x) for x in math.pi * px.mean(axis=0)]
        bpy.data.objects.remove(cob)
        bpy.data.objects.remove(patch)
    return out


def png16_grey(path, values):
    """A 16-bit greyscale PNG of `values` (rows top first, integers), written
    by hand (zlib and struct: Blender's image saving would apply its colour
    management)."""
    import struct
    import zlib

    h, w = values.shape

    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + values[y].astype(">u2").tobytes() for y in range(h))
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path + ".partial", "wb") as fh:
        fh.write(png)
    os.replace(path + ".partial", path)


def render_pixels(name):
    """Renders the current camera into a temporary RGBA EXR and returns its
    pixels as an (h, w, 4) array, top row first."""
    sc = bpy.context.scene
    tmp = os.path.join(bpy.app.tempdir, f"{name}.exr")
    sc.render.filepath = tmp
    bpy.ops.render.render(write_still=True)
    px = read_exr(tmp)
    os.remove(tmp)
    return px


def read_exr(path):
    """An EXR's pixels as an (h, w, 4) float64 array, top row first, as
    stored (no colour transform)."""
    img = bpy.data.images.load(path)
    img.colorspace_settings.name = "Non-Color"
    w, h = img.size
    px = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[::-1]
    bpy.data.images.remove(img)
    return px


def write_exr_rgba(path, px):
    """Writes (h, w, 4) linear RGBA, top row first, as a half-float RGBA EXR
    (the scene's EXR settings), through a partial file."""
    sc = bpy.context.scene
    h, w, _ = px.shape
    img = bpy.data.images.new("alpha-out", w, h, alpha=True, float_buffer=True)
    img.colorspace_settings.name = "Non-Color"
    img.pixels = px[::-1].astype(np.float32).ravel()
    tmp = path + ".partial.exr"
    img.save_render(tmp, scene=sc)
    bpy.data.images.remove(img)
    back = read_exr(tmp)
    # Half floats keep 11 bits: anything further off is a colour transform.
    err = np.abs(back - px).max() / max(1e-6, np.abs(px).max())
    if err > 2e-3:
        raise SystemExit(f"{path}: the EXR written reads back {err:.2e} off (relative): a colour transform?")
    os.replace(tmp, path)


def render_depth(path, log):
    """Renders the current camera's Z pass through the compositor into a
    float EXR, reads it back and writes it as `png16_grey` in thousandths
    of the scene's units."""
    sc = bpy.context.scene
    sc.use_nodes = True
    tree = sc.node_tree
    tree.nodes.clear()
    layers = tree.nodes.new("CompositorNodeRLayers")
    out = tree.nodes.new("CompositorNodeOutputFile")
    tmp_dir = path + ".partial-dir"
    out.base_path = tmp_dir
    out.format.file_format = "OPEN_EXR"
    out.format.color_depth = "32"
    out.format.color_mode = "RGB"
    out.file_slots[0].path = "z"
    tree.links.new(layers.outputs["Depth"], out.inputs[0])
    t0 = time.time()
    bpy.ops.render.render(write_still=False)
    written = [f for f in os.listdir(tmp_dir) if f.startswith("z") and f.endswith(".exr")]
    px = read_exr(os.path.join(tmp_dir, written[0]))[..., 0]
    for f in written:
        os.remove(os.path.join(tmp_dir, f))
    os.rmdir(tmp_dir)
    codes = np.round(px * 1000.0)
    codes[~np.isfinite(codes) | (codes < 1) | (codes > 65535)] = 0
    png16_grey(path, codes.astype(np.uint16))
    dt = time.time() - t0
    log.append({"file": os.path.basename(path), "seconds": round(dt, 1), "samples": sc.cycles.samples, "seed": sc.cycles.seed})
    print(f"wrote {path} in {dt:.1f} s", flush=True)


def training_views(scene_spec, count):
    """Cameras on the upper hemisphere around the field, looking at its
    centre: a Fibonacci spiral from 10° to 70° of elevation; over the
    scene's `[capture] azimuth = [from, to]` (degrees from +x towards +z,
    where a photographer can stand) when it names one, a Fibonacci lattice
    of the same golden angle over that arc, as `inlay render-views` does."""
    b = scene_spec["recipe"]["bounds"]
    lo, hi = np.array(b["min"], float), np.array(b["max"], float)
    centre = 0.5 * (lo + hi)
    radius = 1.6 * np.linalg.norm(hi - lo)
    arc = scene_spec.get("capture", {}).get("azimuth")
    golden = math.pi * (3 - math.sqrt(5))
    views = []
    for k in range(count):
        el = math.radians(10 + 60 * (k + 0.5) / count)
        if arc is None or arc[1] - arc[0] >= 360:
            az = k * golden
        else:
            turn = math.fmod(k * golden / (2 * math.pi), 1.0)
            az = math.radians(arc[0] + turn * (arc[1] - arc[0]))
        d = np.array([math.cos(el) * math.cos(az), math.sin(el), math.cos(el) * math.sin(az)])
        views.append((centre + radius * d, centre))
    return views


def write_json(path, value):
    """Writes `value` as JSON through a partial file: an interrupted run
    leaves the earlier file as it was."""
    with open(path + ".partial", "w") as fh:
        json.dump(value, fh, indent=1)
    os.replace(path + ".partial", path)


def training_set_variant(spec, args, name, prefix):
    """For a folder `name` beside the training set (rendered first: `--what
    training`): its path, the set's transforms (to be written there), and
    each of the set's views as (k, frame), its camera (`prefix`-NNN) placed
    as the view's and made the scene's."""
    tdir = os.path.join(args.out, "training")
    sub = os.path.join(tdir, name)
    os.makedirs(sub, exist_ok=True)
    with open(os.path.join(tdir, "transforms.json")) as fh:
        transforms = json.load(fh)
    by_file = {f["file_path"]: f for f in transforms["frames"]}
    fov = math.radians(40.0)

    def views():
        for k, (pos, tgt) in enumerate(training_views(spec, args.views)):
            frame = by_file.get(f"view-{k:03d}.exr")
            if frame is None:
                continue
            cam = add_camera(f"{prefix}-{k:03d}", pos, tgt, [0, 1, 0], math.degrees(fov))
            bpy.context.scene.camera = cam
            yield k, frame

    return sub, transforms, views()


def main():
    args = parse_args()
    scene_path = os.path.abspath(args.scene)
    scene_dir = os.path.dirname(scene_path)
    with open(scene_path, "rb") as f:
        spec = tomllib.load(f)
    if "recipe" not in spec:
        raise SystemExit(f"{args.scene}: only recipe scenes can be rendered by Cycles")
    os.makedirs(args.out, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    setup_render(args)
    sc = bpy.context.scene
    field = bpy.data.collections.new("field")
    sc.collection.children.link(field)
    solids = build_recipe(spec["recipe"], field)
    sc.world = world_from_environment(scene_dir, spec.get("environment"))
    objects = bpy.data.collections.new("objects")
    sc.collection.children.link(objects)
    placed = []
    for o in spec.get("objects", []):
        root, parts = import_object(scene_dir, o, objects, args.object_diffuse == "lambert")
        # The scene's name, not Blender's (which adds .001 when a glTF
        # node of the same name came first).
        placed.append((o.get("name", os.path.splitext(os.path.basename(o["file"]))[0]), parts))
    bounces = int(spec.get("bake", {}).get("bounces", 1))
    seeds = [int(s) for s in args.seeds.split(",") if s]
    what = set(args.what.split(","))
    log = []

    def show_objects(on):
        objects.hide_render = not on

    if "cameras" in what:
        # Camera images in half floats (11-bit mantissa, well under their
        # Monte-Carlo noise); probes and sensors stay float32.
        sc.render.image_settings.color_depth = "16"
        sc.render.resolution_x, sc.render.resolution_y = args.width, args.height
        sc.cycles.samples = args.samples
        for i, c in enumerate(spec.get("cameras", [])):
            name = c.get("name", str(i))
            if args.cameras and name not in args.cameras.split(","):
                continue
            cam = add_camera(name, c["position"], c["look_at"], c.get("up", [0, 1, 0]), c.get("fov_y", 50.0))
            sc.camera = cam
            for mode in args.modes.split(","):
                if mode == "objects" and not placed:
                    continue
                show_objects(mode == "objects")
                for light in args.light.split(","):
                    set_bounces(0 if light == "direct" else bounces)
                    for s in seeds:
                        sc.cycles.seed = s
                        tag = "-lambert" if mode == "objects" and args.object_diffuse == "lambert" else ""
                        render_to(os.path.join(args.out, f"{name}-{mode}-{light}{tag}-s{s}.exr"), log)

    if "probes" in what:
        sc.render.image_settings.color_depth = "32"
        show_objects(False)
        set_bounces(bounces)
        for name, parts in placed:
            centre = object_centre(parts)
            for s in seeds:
                write_probe(
                    os.path.join(args.out, f"probe-{name}-s{s}.exr"),
                    centre,
                    args.probe_resolution,
                    args.probe_samples,
                    s,
                    log,
                )
            log[-1]["centre"] = [float(x) for x in centre]
            sensors = {}
            for s in seeds:
                sensors[f"s{s}"] = measure_irradiance(centre, args.sensor_samples, s, log)
            path = os.path.join(args.out, f"irradiance-{name}.json")
            write_json(path, {"centre": [float(x) for x in centre], "irradiance": sensors})
            print(f"wrote {path}", flush=True)

    if "training" in what:
        sc.render.image_settings.color_depth = "16"
        show_objects(False)
        set_bounces(bounces)
        tdir = os.path.join(args.out, "training")
        os.makedirs(tdir, exist_ok=True)
        n = args.view_size
        sc.render.resolution_x = sc.render.resolution_y = n
        sc.cycles.samples = args.view_samples
        sc.cycles.seed = seeds[0]
        fov = math.radians(40.0)
        frames = []
        only = {int(v) for v in args.only_views.split(",") if v}
        for k, (pos, tgt) in enumerate(training_views(spec, args.views)):
            if only and k not in only:
                continue
            cam = add_camera(f"view-{k:03d}", pos, tgt, [0, 1, 0], math.degrees(fov))
            sc.camera = cam
            fname = f"view-{k:03d}.exr"
            render_to(os.path.join(tdir, fname), log)
            # camera-to-world in inlay axes, OpenGL camera (looks along −z, +y up).
            m = C.inverted() @ cam.matrix_world
            frames.append({"file_path": fname, "transform_matrix": [list(r) for r in m]})
        f = 0.5 * n / math.tan(0.5 * fov)
        transforms = {
            "camera_model": "PINHOLE",
            "fl_x": f,
            "fl_y": f,
            "cx": n / 2,
            "cy": n / 2,
            "w": n,
            "h": n,
            "aabb": bounds_holding(spec["recipe"]["bounds"], solids),
            "frames": frames,
        }
        write_json(os.path.join(tdir, "transforms.json"), transforms)

    if "depth" in what:
        show_objects(False)
        set_bounces(0)
        bpy.context.view_layer.use_pass_z = True
        n = args.view_size
        sc.render.resolution_x = sc.render.resolution_y = n
        # One sample at each pixel's centre: the depth along its centre ray.
        sc.cycles.samples = 1
        sc.cycles.filter_width = 0.01
        ddir, transforms, views = training_set_variant(spec, args, "depth", "depth")
        for k, frame in views:
            name = f"depth-{k:03d}.png"
            render_depth(os.path.join(ddir, name), log)
            frame["file_path"] = "../" + frame["file_path"]
            frame["depth_file_path"] = name
        transforms["depth_unit_scale_factor"] = 0.001
        write_json(os.path.join(ddir, "transforms.json"), transforms)

    if "alpha" in what:
        show_objects(False)
        set_bounces(0)
        sc.use_nodes = False
        bpy.context.view_layer.use_pass_z = False
        n = args.view_size
        sc.render.resolution_x = sc.render.resolution_y = n
        sc.render.image_settings.color_mode = "RGBA"
        sc.render.image_settings.color_depth = "16"
        sc.cycles.samples = args.alpha_samples
        sc.cycles.seed = seeds[0]
        sc.cycles.filter_width = 1.0
        adir, transforms, views = training_set_variant(spec, args, "alpha", "alpha")
        for k, frame in views:
            fname = frame["file_path"]
            # The share of the pixel whose rays meet the scene.
            t0 = time.time()
            sc.render.film_transparent = True
            alpha = np.clip(render_pixels(f"alpha-{k:03d}")[..., 3], 0.0, 1.0)
            # The environment alone, its mean over each pixel: seen through
            # the share the scene leaves (a held-out scene would not do:
            # Cycles holds out surfaces, not media, and a medium the lights
            # still reach would scatter into the environment's picture).
            sc.render.film_transparent = False
            field.hide_render = True
            world = render_pixels(f"environment-{k:03d}")[..., :3]
            field.hide_render = False
            full = read_exr(os.path.join(args.out, "training", fname))[..., :3]
            rgb = np.maximum(full - (1.0 - alpha[..., None]) * world, 0.0)
            rgb[alpha <= 0.0] = 0.0
            write_exr_rgba(os.path.join(adir, fname), np.concatenate([rgb, alpha[..., None]], axis=2))
            log.append({"file": f"alpha/{fname}", "seconds": round(time.time() - t0, 1), "samples": sc.cycles.samples, "seed": sc.cycles.seed})
            print(f"wrote {os.path.join(adir, fname)}: alpha {alpha.mean():.3f} on average", flush=True)
        sc.render.film_transparent = False
        sc.render.image_settings.color_mode = "RGB"
        write_json(os.path.join(adir, "transforms.json"), transforms)

    command = "blender -b --factory-startup --python tools/cycles/render_cycles.py -- " + " ".join(
        sys.argv[sys.argv.index("--") + 1 :]
    )
    # Each image keeps the command that made it: a directory's images come
    # from several runs (the last one's command is the file's "command").
    for e in log:
        e.setdefault("command", command)
    meta = {
        "blender": bpy.app.version_string,
        "scene": os.path.relpath(scene_path),
        "command": command,
        "bounces": bounces,
        "images": log,
    }
    meta_path = os.path.join(args.out, "render.json")
    old = {}
    if os.path.exists(meta_path):
        with open(meta_path) as fh:
            old = json.load(fh)
    merged = {e["file"]: e for e in old.get("images", [])}
    merged.update({e["file"]: e for e in log})
    meta["images"] = sorted(merged.values(), key=lambda e: e["file"])
    write_json(meta_path, meta)


if __name__ == "__main__":
    main()
