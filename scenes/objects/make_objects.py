#!/usr/bin/env python3
"""Writes the bundled glTF objects (standard library only; made here,
licensed with the project). Run from anywhere: python3 make_objects.py

- metal-sphere.gltf  glossy gold sphere, one buffer embedded as base64
- checker-cube.gltf  textured cube: .bin buffer, base-colour checker PNG and
                     metallic-roughness PNG beside it
- toy.glb            binary glTF: a node hierarchy (stem + rotated, scaled
                     cap as a child), two materials, the cap without normals
                     (the loader computes flat ones)
- monkey.glb         a Suzanne-like head (muzzle, brow, eye sockets, ears) as
                     one closed star-shaped mesh of 3968 triangles, smooth
                     normals: concave where ears and muzzle meet the head, so
                     it self-shadows as the paper's monkey does
"""
import base64, json, math, os, struct, zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def png(path, w, h, pixel):
    rows = b"".join(b"\x00" + bytes(c for x in range(w) for c in pixel(x, y)) for y in range(h))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
    data += chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b"")
    open(path, "wb").write(data)


class Builder:
    """Accumulates one buffer with views and accessors."""

    def __init__(self):
        self.data = bytearray()
        self.views, self.accessors = [], []

    def add(self, values, fmt, comps, target, kind, with_bounds=False):
        while len(self.data) % 4:
            self.data.append(0)
        offset = len(self.data)
        flat = [c for v in values for c in (v if isinstance(v, (list, tuple)) else [v])]
        self.data += struct.pack("<%d%s" % (len(flat), fmt), *flat)
        self.views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(self.data) - offset, "target": target})
        acc = {"bufferView": len(self.views) - 1, "componentType": 5126 if fmt == "f" else 5125,
               "count": len(values), "type": kind}
        if with_bounds:
            acc["min"] = [min(v[i] for v in values) for i in range(comps)]
            acc["max"] = [max(v[i] for v in values) for i in range(comps)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def primitive(self, pos, nrm, uv, idx, material):
        attrs = {"POSITION": self.add(pos, "f", 3, 34962, "VEC3", True)}
        if nrm is not None:
            attrs["NORMAL"] = self.add(nrm, "f", 3, 34962, "VEC3")
        if uv is not None:
            attrs["TEXCOORD_0"] = self.add(uv, "f", 2, 34962, "VEC2")
        return {"attributes": attrs, "indices": self.add(idx, "I", 1, 34963, "SCALAR"), "material": material}


def sphere(radius=1.0, rings=16, segments=32, hemisphere=False):
    pos, nrm, uv, idx = [], [], [], []
    top = rings // 2 if hemisphere else rings
    for r in range(top + 1):
        theta = math.pi * r / rings
        for s in range(segments + 1):
            phi = 2 * math.pi * s / segments
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            pos.append(tuple(radius * c for c in n)); nrm.append(n); uv.append((s / segments, r / rings))
    for r in range(top):
        for s in range(segments):
            a, b = r * (segments + 1) + s, (r + 1) * (segments + 1) + s
            idx += [a, b, a + 1, a + 1, b, b + 1]
    return pos, nrm, uv, idx


def cylinder(radius, height, segments=24):
    pos, nrm, uv, idx = [], [], [], []
    for y in (0.0, height):
        for s in range(segments + 1):
            phi = 2 * math.pi * s / segments
            n = (math.cos(phi), 0.0, -math.sin(phi))
            pos.append((radius * n[0], y, radius * n[2])); nrm.append(n); uv.append((s / segments, y / height))
    for s in range(segments):
        a, b = s, segments + 1 + s
        idx += [a, a + 1, b, a + 1, b + 1, b]
    return pos, nrm, uv, idx


def cube():
    pos, nrm, uv, idx = [], [], [], []
    faces = [((1, 0, 0), (0, 0, -1), (0, 1, 0)), ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
             ((0, 1, 0), (1, 0, 0), (0, 0, -1)), ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
             ((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 0, -1), (-1, 0, 0), (0, 1, 0))]
    for n, u, v in faces:
        base = len(pos)
        for (a, b) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            pos.append(tuple(0.5 * (n[i] + a * u[i] + b * v[i]) for i in range(3)))
            nrm.append(n); uv.append(((a + 1) / 2, (1 - b) / 2))
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, uv, idx


def monkey_radius(n):
    """The head's radius along unit direction n (+Y up, +Z the face)."""
    def unit(v):
        l = math.sqrt(sum(c * c for c in v))
        return tuple(c / l for c in v)

    def bump(height, sharpness, axis):
        a = unit(axis)
        return height * math.exp(sharpness * (sum(x * y for x, y in zip(n, a)) - 1.0))

    r = 1.0
    r += bump(0.38, 10.0, (0.0, -0.45, 1.0))      # muzzle
    r += bump(0.12, 25.0, (0.0, 0.4, 1.0))        # brow
    for side in (-1.0, 1.0):
        r += bump(0.6, 45.0, (side, 0.2, -0.1))   # ears
        r -= bump(0.14, 70.0, (side * 0.38, 0.22, 1.0))  # eye sockets
    return r


def monkey(rings=32, segments=64):
    """A closed star-shaped mesh: the unit sphere's grid pushed out to
    monkey_radius, with normals averaged over the faces around each point
    (seam and pole copies share theirs)."""
    pos, idx = [], []
    for r in range(rings + 1):
        theta = math.pi * r / rings
        for s in range(segments + 1):
            phi = 2 * math.pi * s / segments
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            k = monkey_radius(n)
            pos.append(tuple(k * c for c in n))
    for r in range(rings):
        for s in range(segments):
            a, b = r * (segments + 1) + s, (r + 1) * (segments + 1) + s
            if r > 0:
                idx += [a, b, a + 1]
            if r < rings - 1:
                idx += [a + 1, b, b + 1]
    acc = {}
    key = lambda p: tuple(round(c, 9) for c in p)
    for t in range(0, len(idx), 3):
        p0, p1, p2 = (pos[i] for i in idx[t:t + 3])
        e1 = [p1[i] - p0[i] for i in range(3)]
        e2 = [p2[i] - p0[i] for i in range(3)]
        fn = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
        for i in idx[t:t + 3]:
            a = acc.setdefault(key(pos[i]), [0.0, 0.0, 0.0])
            for c in range(3):
                a[c] += fn[c]
    nrm = []
    for p in pos:
        a = acc[key(p)]
        l = math.sqrt(sum(c * c for c in a))
        nrm.append(tuple(c / l for c in a))
    return pos, nrm, None, idx


def write_glb(path, doc, data):
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    data = bytes(data) + b"\x00" * (-len(data) % 4)
    glb = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(data))
    glb += struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(data), 0x004E4942) + data
    open(path, "wb").write(glb)


def gltf_doc(b, meshes, nodes, materials, extra=None):
    doc = {"asset": {"version": "2.0", "generator": "inlay scenes/objects/make_objects.py"},
           "scene": 0, "scenes": [{"nodes": [0]}], "nodes": nodes, "meshes": meshes,
           "materials": materials, "accessors": b.accessors, "bufferViews": b.views,
           "buffers": [{"byteLength": len(b.data)}]}
    doc.update(extra or {})
    return doc


# Glossy gold sphere, buffer embedded.
b = Builder()
prim = b.primitive(*sphere(), material=0)
doc = gltf_doc(b, [{"name": "sphere", "primitives": [prim]}], [{"name": "sphere", "mesh": 0}],
               [{"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.78, 0.34, 1.0],
                                                          "metallicFactor": 1.0, "roughnessFactor": 0.25}}])
doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(bytes(b.data)).decode()
json.dump(doc, open(os.path.join(HERE, "metal-sphere.gltf"), "w"), indent=1)

# Textured cube: external buffer and PNGs.
b = Builder()
prim = b.primitive(*cube(), material=0)
doc = gltf_doc(b, [{"name": "cube", "primitives": [prim]}], [{"name": "cube", "mesh": 0}],
               [{"name": "checker", "pbrMetallicRoughness": {
                   "baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 1},
                   "metallicFactor": 1.0, "roughnessFactor": 1.0}}],
               {"textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
                "images": [{"uri": "checker.png"}, {"uri": "checker-mr.png"}],
                "samplers": [{"magFilter": 9729, "minFilter": 9729}]})
doc["buffers"][0]["uri"] = "checker-cube.bin"
open(os.path.join(HERE, "checker-cube.bin"), "wb").write(bytes(b.data))
json.dump(doc, open(os.path.join(HERE, "checker-cube.gltf"), "w"), indent=1)
png(os.path.join(HERE, "checker.png"), 8, 8,
    lambda x, y: (230, 60, 40, 255) if (x + y) % 2 else (240, 230, 210, 255))
# Roughness (G) and metallic (B): rough dielectric and glossy metal squares.
png(os.path.join(HERE, "checker-mr.png"), 8, 8,
    lambda x, y: (0, 240, 0, 255) if (x + y) % 2 else (0, 60, 255, 255))

# Binary toy: stem with a child cap, two materials, cap without normals.
b = Builder()
stem = b.primitive(*cylinder(0.25, 1.0), material=0)
cpos, _, _, cidx = sphere(0.6, rings=12, segments=24, hemisphere=True)
cap = b.primitive(cpos, None, None, cidx, material=1)
nodes = [{"name": "stem", "mesh": 0, "children": [1], "scale": [1.0, 1.0, 1.0]},
         {"name": "cap", "mesh": 1, "translation": [0.0, 0.95, 0.0],
          "rotation": [0.0, 0.0, math.sin(math.radians(10)), math.cos(math.radians(10))],
          "scale": [1.0, 0.7, 1.0]}]
doc = gltf_doc(b, [{"name": "stem", "primitives": [stem]}, {"name": "cap", "primitives": [cap]}], nodes,
               [{"name": "plastic", "pbrMetallicRoughness": {"baseColorFactor": [0.85, 0.82, 0.7, 1.0],
                                                             "metallicFactor": 0.0, "roughnessFactor": 0.7}},
                {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.08, 0.05, 1.0],
                                                         "metallicFactor": 0.0, "roughnessFactor": 0.35}}])
data = bytes(b.data)
js = json.dumps(doc).encode()
js += b" " * (-len(js) % 4)
data += b"\x00" * (-len(data) % 4)
glb = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(data))
glb += struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(data), 0x004E4942) + data
open(os.path.join(HERE, "toy.glb"), "wb").write(glb)

# Suzanne-like head, clay grey, binary glTF.
b = Builder()
prim = b.primitive(*monkey(), material=0)
doc = gltf_doc(b, [{"name": "monkey", "primitives": [prim]}], [{"name": "monkey", "mesh": 0}],
               [{"name": "clay", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.66, 0.6, 1.0],
                                                          "metallicFactor": 0.0, "roughnessFactor": 0.7}}])
write_glb(os.path.join(HERE, "monkey.glb"), doc, b.data)
print("wrote metal-sphere.gltf, checker-cube.gltf (+ .bin, 2 PNGs), toy.glb, monkey.glb")
