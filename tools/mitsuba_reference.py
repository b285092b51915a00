#!/usr/bin/env python3
"""An independent check of hybrid-rt's reference path tracer: the same scenes rendered by
Mitsuba 3 with the glTF 2.0 Appendix B material written here as a Mitsuba BSDF plugin.

    python3 tools/mitsuba_reference.py scenes        # write the test scenes (standard library only)
    python3 tools/mitsuba_reference.py check-bsdf    # the plugin's sample() against eval()/pdf()
    python3 tools/mitsuba_reference.py render [NAME ...] [--spp N] [--size WxH]
    python3 tools/mitsuba_reference.py render nvpro_cornell_box   # a scene of ../shared/scenes

`scenes` writes tests/mitsuba/<name>/scene.gltf (buffers inline as data URIs, textures as PNG
beside it). `render` reads those glTF files with the small glTF reader below (the subset the
scenes use: node TRS or matrices, triangle meshes with POSITION/NORMAL/TEXCOORD_0 (interleaved
or not), metallic-roughness materials with a nearest-filtered baseColorTexture, alphaMode BLEND
(a `mask` BSDF of opacity alpha, rendered with `volpath`, whose shadow rays cross it as
hybrid-rt's do), emission with KHR_materials_emissive_strength (double-sided only on a closed
mesh), KHR_lights_punctual point lights, one perspective camera; anything else is refused with
a message), builds the same scene in Mitsuba (world-space
meshes written as PLY, an area emitter per emissive mesh, a point emitter per point light,
the camera by look-at from its node, a box pixel filter) and renders it twice with
different seeds at the same size and spp: tests/mitsuba/<name>/mitsuba-a.exr and
mitsuba-b.exr, linear RGB; the difference between the two is Mitsuba's own noise floor. A
scene of ../shared/scenes (SHARED_SCENES) is read where it lies, never copied: only its
renders and mitsuba.json go to tests/mitsuba/<name>/.
tests/mitsuba.rs renders `hybrid-rt reference` on the same glTF file at the same size and
spp and compares. A third render at 16 times the spp (mitsuba-converged.exr) gives the mean
luminance with little noise of its own. mitsuba.json beside them records the settings, the
Mitsuba version and the render times.

Needs: pip install mitsuba numpy; the llvm_ad_rgb variant needs libLLVM >= 17 (Debian 12:
apt-get install libllvm19; the script finds /usr/lib/x86_64-linux-gnu/libLLVM.so.19.1, or set
DRJIT_LIBLLVM_PATH). `--variant scalar_rgb` needs no LLVM but is far slower.

Light units as hybrid-rt reads them: emission is radiance (W/sr/m^2), a point light's
intensity is W/sr. Lights are chosen for next-event estimation in proportion to their power,
as hybrid-rt does (src/world/lights.rs), through Mitsuba's `sampling_weight`: only variance
depends on it, but the comparison of noise levels is fairer with the same choice.
"""

import argparse
import base64
import json
import math
import os
import struct
import sys
import time
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT_DIR = os.path.join(ROOT, "tests", "mitsuba")
SCENES = ["diffuse_box", "glossy_blocks", "textured"]
DEFAULT_SIZE = (64, 64)
DEFAULT_SPP = 512
# Scenes nobody here wrote, read where CI has them (../shared/scenes beside the checkout; never
# copied into the project): name -> (path under ../shared/scenes, size, spp). The nvpro Cornell
# box's camera is 4:3; its light is a closed box under the ceiling whose top face lights a
# narrow gap, where light bounces many times: a noisy mean, hence the spp.
SHARED_SCENES = {"nvpro_cornell_box": ("nvpro-cornell-box/cornellBox.gltf", (64, 48), 8192)}
SHARED_DIR = os.path.join(os.path.dirname(ROOT), "shared", "scenes")
# The converged render (for the mean luminance) takes this many times the spp, seed 2.
CONVERGED_FACTOR = 16
SEEDS = (0, 1)

# ---- The test scenes (standard library only) ----------------------------------------------------
#
# One closed room for all three: inside x in [-1, 1], y in [0, 2], z in [-1, 3], every wall
# facing in, lit by a 0.6 x 0.6 m quad just under the ceiling. The camera stands inside near
# the front wall looking down -Z, so every ray stays in the room (no environment) and light
# bounces until Russian roulette ends the path: the closed box is where an energy difference
# of the material model adds up bounce after bounce.

WHITE = [0.725, 0.71, 0.68]
RED = [0.63, 0.065, 0.05]
GREEN = [0.14, 0.45, 0.091]


def sub(a, b): return [x - y for x, y in zip(a, b)]
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def dot(a, b): return sum(x * y for x, y in zip(a, b))


def normalize(a):
    n = math.sqrt(dot(a, a))
    return [x / n for x in a]


def quad(corner, u, v, uv_scale=1.0):
    """Quad corner, corner + u, corner + u + v, corner + v; faces u x v (counter-clockwise)."""
    n = normalize(cross(u, v))
    p = [corner, [c + d for c, d in zip(corner, u)], [c + d + e for c, d, e in zip(corner, u, v)],
         [c + e for c, e in zip(corner, v)]]
    # glTF UVs: (0, 0) is the image's top-left; v runs down the image, against the quad's v.
    uv = [[0, uv_scale], [uv_scale, uv_scale], [uv_scale, 0], [0, 0]]
    return {"pos": p, "nrm": [n] * 4, "uv": uv, "idx": [0, 1, 2, 0, 2, 3]}


def merge(*meshes):
    out = {"pos": [], "nrm": [], "uv": [], "idx": []}
    for m in meshes:
        base = len(out["pos"])
        for k in ("pos", "nrm", "uv"):
            out[k] += m[k]
        out["idx"] += [i + base for i in m["idx"]]
    return out


def box(sx, sy, sz):
    """Axis-aligned box centred on the origin, faces outward, 4 vertices per face (flat)."""
    x, y, z = sx / 2, sy / 2, sz / 2
    return merge(
        quad([-x, -y, z], [2 * x, 0, 0], [0, 2 * y, 0]),    # +z
        quad([x, -y, -z], [-2 * x, 0, 0], [0, 2 * y, 0]),   # -z
        quad([x, -y, z], [0, 0, -2 * z], [0, 2 * y, 0]),    # +x
        quad([-x, -y, -z], [0, 0, 2 * z], [0, 2 * y, 0]),   # -x
        quad([-x, y, z], [2 * x, 0, 0], [0, 0, -2 * z]),    # +y
        quad([-x, -y, -z], [2 * x, 0, 0], [0, 0, 2 * z]),   # -y
    )


def png(width, height, rows):
    """8-bit RGB PNG from rows of [r, g, b, ...] bytes."""
    raw = b"".join(b"\x00" + bytes(r) for r in rows)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def checker_png():
    """8 x 8 cells of two colours, and one odd cell (top-left, red) so orientation shows."""
    rows = []
    for y in range(8):
        row = []
        for x in range(8):
            c = [230, 228, 220] if (x + y) % 2 == 0 else [70, 90, 130]
            if x == 0 and y == 0:
                c = [200, 40, 30]
            row += c
        rows.append(row)
    return png(8, 8, rows)


def stripes_png():
    """4 x 1 vertical stripes: yellow, white, teal, white."""
    row = [220, 180, 40, 240, 240, 240, 30, 150, 140, 240, 240, 240]
    return png(4, 1, [row])


class Gltf:
    def __init__(self):
        self.doc = {"asset": {"version": "2.0", "generator": "hybrid-rt tools/mitsuba_reference.py"},
                    "scene": 0, "scenes": [{"nodes": []}], "nodes": [], "meshes": [], "materials": [],
                    "accessors": [], "bufferViews": [], "buffers": []}
        self.bin = bytearray()

    def accessor(self, values, comps, ctype, target):
        while len(self.bin) % 4:
            self.bin.append(0)
        offset = len(self.bin)
        flat = [c for v in values for c in (v if isinstance(v, list) else [v])]
        fmt = {5126: "f", 5125: "I"}[ctype]
        self.bin += struct.pack("<%d%s" % (len(flat), fmt), *flat)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": offset, "byteLength": len(self.bin) - offset,
                                        "target": target})
        acc = {"bufferView": len(self.doc["bufferViews"]) - 1, "componentType": ctype, "count": len(values),
               "type": {1: "SCALAR", 2: "VEC2", 3: "VEC3"}[comps]}
        if comps == 3 and target == 34962:
            acc["min"] = [min(v[i] for v in values) for i in range(3)]
            acc["max"] = [max(v[i] for v in values) for i in range(3)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def material(self, name, base, metallic, roughness, texture=None, emissive=None):
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": base + [1.0], "metallicFactor": metallic,
                                                    "roughnessFactor": roughness}}
        if texture is not None:
            m["pbrMetallicRoughness"]["baseColorTexture"] = {"index": texture}
        if emissive is not None:
            m["emissiveFactor"] = [1.0, 1.0, 1.0]
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": emissive}}
            self.doc.setdefault("extensionsUsed", []).append("KHR_materials_emissive_strength")
        self.doc["materials"].append(m)
        return len(self.doc["materials"]) - 1

    def texture(self, uri):
        # Nearest filtering without mipmaps: both renderers read exactly one texel.
        self.doc.setdefault("samplers", [{"magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497}])
        self.doc.setdefault("images", []).append({"uri": uri})
        self.doc.setdefault("textures", []).append({"source": len(self.doc["images"]) - 1, "sampler": 0})
        return len(self.doc["textures"]) - 1

    def mesh(self, name, geo, material, translation=None, rotation_y=None):
        prim = {"attributes": {"POSITION": self.accessor(geo["pos"], 3, 5126, 34962),
                               "NORMAL": self.accessor(geo["nrm"], 3, 5126, 34962),
                               "TEXCOORD_0": self.accessor(geo["uv"], 2, 5126, 34962)},
                "indices": self.accessor(geo["idx"], 1, 5125, 34963), "material": material}
        self.doc["meshes"].append({"name": name, "primitives": [prim]})
        node = {"name": name, "mesh": len(self.doc["meshes"]) - 1}
        if translation:
            node["translation"] = translation
        if rotation_y:
            node["rotation"] = [0.0, math.sin(rotation_y / 2), 0.0, math.cos(rotation_y / 2)]
        self.node(node)

    def node(self, node):
        self.doc["nodes"].append(node)
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)

    def point_light(self, name, position, color, intensity):
        ext = self.doc.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {"lights": []})
        ext["lights"].append({"name": name, "type": "point", "color": color, "intensity": intensity})
        self.doc.setdefault("extensionsUsed", []).append("KHR_lights_punctual")
        self.node({"name": name, "translation": position,
                   "extensions": {"KHR_lights_punctual": {"light": len(ext["lights"]) - 1}}})

    def write(self, path):
        self.doc["buffers"] = [{"byteLength": len(self.bin),
                                "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.bin)).decode()}]
        if "extensionsUsed" in self.doc:
            self.doc["extensionsUsed"] = sorted(set(self.doc["extensionsUsed"]))
        with open(path, "w") as f:
            json.dump(self.doc, f, indent=1)
            f.write("\n")


def room(g, floor_texture=None):
    white = g.material("white", WHITE, 0.0, 1.0)
    floor = g.material("floor", [1.0, 1.0, 1.0] if floor_texture is not None else WHITE, 0.0, 1.0, floor_texture)
    red = g.material("red", RED, 0.0, 1.0)
    green = g.material("green", GREEN, 0.0, 1.0)
    light = g.material("light", [0.78, 0.78, 0.78], 0.0, 1.0, emissive=12.0)
    floor_uv = 4.0 if floor_texture is not None else 1.0
    g.mesh("floor", quad([-1, 0, 3], [2, 0, 0], [0, 0, -4], floor_uv), floor)
    g.mesh("ceiling", quad([-1, 2, -1], [2, 0, 0], [0, 0, 4]), white)
    g.mesh("back_wall", quad([-1, 0, -1], [2, 0, 0], [0, 2, 0]), white)
    g.mesh("front_wall", quad([1, 0, 3], [-2, 0, 0], [0, 2, 0]), white)
    g.mesh("left_wall", quad([-1, 0, 3], [0, 0, -4], [0, 2, 0]), red)
    g.mesh("right_wall", quad([1, 0, -1], [0, 0, 4], [0, 2, 0]), green)
    g.mesh("ceiling_light", quad([-0.3, 1.99, -0.3], [0.6, 0, 0], [0, 0, 0.6]), light)
    g.doc["cameras"] = [{"name": "inside", "type": "perspective",
                         "perspective": {"yfov": 0.8, "aspectRatio": 1.0, "znear": 0.05, "zfar": 20.0}}]
    g.node({"name": "inside", "translation": [0.0, 1.0, 2.8], "camera": 0})


def make_scene(name):
    g = Gltf()
    folder = os.path.join(OUT_DIR, name)
    os.makedirs(folder, exist_ok=True)
    if name == "diffuse_box":
        room(g)
        white = g.material("block", WHITE, 0.0, 1.0)
        g.mesh("tall_block", box(0.6, 1.2, 0.6), white, [-0.35, 0.6, -0.3], 0.3)
        g.mesh("short_block", box(0.6, 0.6, 0.6), white, [0.4, 0.3, 0.4], -0.3)
    elif name == "glossy_blocks":
        room(g)
        gold = g.material("gold_metal", [1.0, 0.78, 0.34], 1.0, 0.3)
        blue = g.material("glossy_blue_dielectric", [0.2, 0.3, 0.6], 0.0, 0.3)
        steel = g.material("rough_steel", [0.6, 0.6, 0.62], 1.0, 0.6)
        g.mesh("gold_block", box(0.6, 1.2, 0.6), gold, [-0.35, 0.6, -0.3], 0.3)
        g.mesh("blue_block", box(0.6, 0.6, 0.6), blue, [0.4, 0.3, 0.4], -0.3)
        g.mesh("steel_block", box(0.4, 0.3, 0.4), steel, [-0.45, 0.15, 0.7], 0.5)
        g.point_light("point_light", [0.6, 1.6, 1.6], [1.0, 0.9, 0.8], 1.5)
    elif name == "textured":
        with open(os.path.join(folder, "checker.png"), "wb") as f:
            f.write(checker_png())
        with open(os.path.join(folder, "stripes.png"), "wb") as f:
            f.write(stripes_png())
        room(g, floor_texture=g.texture("checker.png"))
        stripes = g.material("stripes", [1.0, 1.0, 1.0], 0.0, 0.5, g.texture("stripes.png"))
        g.mesh("striped_block", box(0.6, 1.2, 0.6), stripes, [-0.35, 0.6, -0.3], 0.3)
    else:
        sys.exit(f"unknown scene {name} (known: {', '.join(SCENES)})")
    path = os.path.join(folder, "scene.gltf")
    g.write(path)
    print(f"wrote {os.path.relpath(path, ROOT)}")


# ---- Reading glTF back (for Mitsuba) ---------------------------------------------------------------

def fail(path, why):
    sys.exit(f"{path}: {why}")


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def node_matrix(node):
    if "matrix" in node:
        m = node["matrix"]
        return [[m[c * 4 + r] for c in range(4)] for r in range(4)]
    t = node.get("translation", [0, 0, 0])
    x, y, z, w = node.get("rotation", [0, 0, 0, 1])
    s = node.get("scale", [1, 1, 1])
    r = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    return [[r[i][0] * s[0], r[i][1] * s[1], r[i][2] * s[2], t[i]] for i in range(3)] + [[0, 0, 0, 1]]


def srgb_to_linear(c):
    # shaders-glsl/common/color.glsl, applied to 8-bit texels as the GPU reads them.
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def closed_mesh(pos, idx):
    """Whether every edge of the triangles (vertices welded by position) has two triangles."""
    import numpy as np
    _, weld = np.unique(np.round(pos, 6), axis=0, return_inverse=True)
    tri = weld.reshape(-1)[idx.reshape(-1, 3)]
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))


def read_gltf(path):
    """The scene as plain data: meshes in world space with their materials, point lights,
    the camera (position, forward, up, yfov)."""
    import numpy as np
    with open(path) as f:
        doc = json.load(f)
    folder = os.path.dirname(path)
    for ext in doc.get("extensionsRequired", []):
        fail(path, f"extension {ext} is not supported by this reader")
    buffers = []
    for b in doc["buffers"]:
        uri = b["uri"]
        if uri.startswith("data:"):
            buffers.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            with open(os.path.join(folder, uri), "rb") as f:
                buffers.append(f.read())

    def accessor(i):
        a = doc["accessors"][i]
        view = doc["bufferViews"][a["bufferView"]]
        dtype = {5126: np.float32, 5125: np.uint32, 5123: np.uint16}.get(a["componentType"])
        if dtype is None:
            fail(path, f"accessor {i}: component type {a['componentType']} not supported")
        comps = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[a["type"]]
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        size = np.dtype(dtype).itemsize
        stride = view.get("byteStride") or comps * size
        if stride % size:
            fail(path, f"accessor {i}: byteStride {stride} is not a multiple of the component size")
        # An interleaved view: every stride/size-th run of comps components.
        step = stride // size
        words = np.frombuffer(buffers[view["buffer"]], dtype=dtype, count=(a["count"] - 1) * step + comps,
                              offset=start)
        data = np.lib.stride_tricks.as_strided(words, (a["count"], comps), (stride, size)).copy()
        return data if comps > 1 else data[:, 0]

    textures = {}

    def texture(info):
        if info.get("texCoord", 0) != 0 or "extensions" in info:
            fail(path, "only TEXCOORD_0 without texture transforms is supported")
        t = doc["textures"][info["index"]]
        sampler = doc["samplers"][t["sampler"]] if "sampler" in t else {}
        if sampler.get("magFilter") != 9728 or sampler.get("minFilter") != 9728:
            fail(path, "textures must use NEAREST filtering (9728) for an exact comparison")
        if sampler.get("wrapS", 10497) != 10497 or sampler.get("wrapT", 10497) != 10497:
            fail(path, "only REPEAT wrapping is supported")
        key = t["source"]
        if key not in textures:
            import mitsuba as mi
            img = np.array(mi.Bitmap(os.path.join(folder, doc["images"][key]["uri"])))
            if img.dtype != np.uint8 or img.ndim != 3 or img.shape[2] < 3:
                fail(path, f"image {key}: expected 8-bit RGB(A)")
            lin = np.vectorize(srgb_to_linear)(img[:, :, :3].astype(np.float64) / 255.0)
            textures[key] = lin.astype(np.float32)
        return textures[key]

    materials = []
    for m in doc.get("materials", []):
        pbr = m.get("pbrMetallicRoughness", {})
        for unsupported in ("normalTexture", "occlusionTexture", "emissiveTexture"):
            if unsupported in m:
                fail(path, f"material {m.get('name')}: {unsupported} not supported")
        if "metallicRoughnessTexture" in pbr or m.get("alphaMode", "OPAQUE") == "MASK":
            fail(path, f"material {m.get('name')}: metallicRoughnessTexture and alphaMode MASK are not supported")
        strength = m.get("extensions", {}).get("KHR_materials_emissive_strength", {}).get("emissiveStrength", 1.0)
        emission = [e * strength for e in m.get("emissiveFactor", [0, 0, 0])]
        blend = m.get("alphaMode", "OPAQUE") == "BLEND"
        if any(emission) and blend:
            fail(path, f"material {m.get('name')}: blended emitters are not supported")
        materials.append({
            "name": m.get("name", ""),
            "base": pbr.get("baseColorFactor", [1, 1, 1, 1])[:3],
            # alphaMode BLEND: the share of each point the surface covers (hybrid-rt passes the
            # rest straight through, paths and shadow rays alike).
            "alpha": pbr.get("baseColorFactor", [1, 1, 1, 1])[3] if blend else 1.0,
            "double_sided": bool(m.get("doubleSided")),
            "texture": texture(pbr["baseColorTexture"]) if "baseColorTexture" in pbr else None,
            "metallic": pbr.get("metallicFactor", 1.0),
            "roughness": pbr.get("roughnessFactor", 1.0),
            "emission": emission,
        })

    meshes, lights, camera = [], [], None
    lights_def = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])

    def walk(i, parent):
        nonlocal camera
        node = doc["nodes"][i]
        m = mat_mul(parent, node_matrix(node))
        if "mesh" in node:
            for prim in doc["meshes"][node["mesh"]]["primitives"]:
                if prim.get("mode", 4) != 4 or "targets" in prim:
                    fail(path, "only plain triangle lists are supported")
                pos = accessor(prim["attributes"]["POSITION"]).astype(np.float64)
                nrm = accessor(prim["attributes"]["NORMAL"]).astype(np.float64)
                uv = accessor(prim["attributes"]["TEXCOORD_0"])
                idx = accessor(prim["indices"]).astype(np.uint32)
                lin = np.array([row[:3] for row in m[:3]])
                world = pos @ lin.T + np.array([row[3] for row in m[:3]])
                nrm_w = nrm @ np.linalg.inv(lin)
                nrm_w /= np.linalg.norm(nrm_w, axis=1, keepdims=True)
                material = materials[prim["material"]]
                # Mitsuba's area emitters are one-sided. A double-sided emitter is the same only
                # where its mesh is closed: its back faces face its inside, which no light leaves.
                if any(material["emission"]) and material["double_sided"] and not closed_mesh(pos, idx):
                    fail(path, f"material {material['name']}: a double-sided emitter on an open mesh is not supported")
                meshes.append({"name": node.get("name", f"node{i}"), "pos": world, "nrm": nrm_w, "uv": uv,
                               "idx": idx, "material": material})
        light = node.get("extensions", {}).get("KHR_lights_punctual")
        if light is not None:
            ld = lights_def[light["light"]]
            if ld["type"] != "point" or "range" in ld:
                fail(path, f"light {ld.get('name')}: only point lights without range are supported")
            lights.append({"position": [m[0][3], m[1][3], m[2][3]],
                           "intensity": [c * ld.get("intensity", 1.0) for c in ld.get("color", [1, 1, 1])]})
        if "camera" in node:
            if camera is not None:
                fail(path, "more than one camera")
            cam = doc["cameras"][node["camera"]]
            if cam["type"] != "perspective":
                fail(path, "only perspective cameras are supported")
            eye = [m[0][3], m[1][3], m[2][3]]
            forward = [-m[r][2] for r in range(3)]
            up = [m[r][1] for r in range(3)]
            camera = {"eye": eye, "forward": forward, "up": up, "yfov": cam["perspective"]["yfov"],
                      "aspect": cam["perspective"].get("aspectRatio")}
        for c in node.get("children", []):
            walk(c, m)

    identity = [[1 if r == c else 0 for c in range(4)] for r in range(4)]
    for i in doc["scenes"][doc.get("scene", 0)]["nodes"]:
        walk(i, identity)
    if camera is None:
        fail(path, "the scene has no camera")
    return meshes, lights, camera


# ---- The glTF 2.0 Appendix B material as a Mitsuba BSDF ---------------------------------------------

def register_bsdf():
    """Registers the plugin `gltf_pbr`. Parameters: base_color (texture), metallic, roughness.

    eval() is Appendix B written out: specular_brdf = V D (GGX D, height-correlated Smith V,
    alpha = roughness^2), diffuse_brdf = baseColor / pi, metal_brdf = conductor_fresnel(
    baseColor, specular_brdf), dielectric_brdf = fresnel_mix(ior 1.5, diffuse_brdf,
    specular_brdf) with F = 0.04 + 0.96 (1 - |v.h|)^5, material = mix(dielectric_brdf,
    metal_brdf, metallic). Both sides shade alike (the side a ray arrives from is the front), as
    in hybrid-rt. sample() picks the GGX layer (Mitsuba's visible-normal sampler) or the cosine
    hemisphere with a probability set by the Fresnel weights at the view; pdf() is that mixture.
    """
    import drjit as dr
    import mitsuba as mi

    # hybrid-rt clamps alpha here (a perfect mirror has no finite GGX density); the scenes stay
    # far above it.
    min_alpha = 1e-3

    class GltfPbr(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            base = props["base_color"]
            # A constant colour arrives as a colour, a bitmap as a texture.
            self.base = base if isinstance(base, mi.Texture) else mi.load_dict({"type": "rgb", "value": list(base)})
            self.metallic = float(props["metallic"])
            self.roughness = float(props["roughness"])
            self.alpha = max(self.roughness * self.roughness, min_alpha)
            sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            self.m_components = [mi.BSDFFlags.GlossyReflection | sides, mi.BSDFFlags.DiffuseReflection | sides]
            self.m_flags = self.m_components[0] | self.m_components[1]

        def _frame(self, si, wo):
            # Two-sided: mirror both directions to the side the view is on.
            flip = mi.Frame3f.cos_theta(si.wi) < 0
            wi = mi.Vector3f(si.wi.x, si.wi.y, dr.abs(si.wi.z))
            wo = mi.Vector3f(wo.x, wo.y, dr.select(flip, -wo.z, wo.z))
            return wi, wo

        def _eval(self, si, wi, wo, active):
            c = self.base.eval(si, active)
            cos_i, cos_o = wi.z, wo.z
            valid = active & (cos_i > 0) & (cos_o > 0)
            h = dr.normalize(wi + wo)
            vh = dr.abs(dr.dot(wi, h))
            nh = h.z
            a2 = self.alpha * self.alpha
            d = a2 / (dr.pi * dr.square(nh * nh * (a2 - 1) + 1))
            v = 0.5 / (cos_o * dr.sqrt(cos_i * cos_i * (1 - a2) + a2) + cos_i * dr.sqrt(cos_o * cos_o * (1 - a2) + a2))
            specular_brdf = v * d
            diffuse_brdf = c * dr.inv_pi
            k = dr.power(1 - vh, 5)
            metal_brdf = specular_brdf * (c + (1 - c) * k)
            fresnel = 0.04 + 0.96 * k
            dielectric_brdf = dr.lerp(diffuse_brdf, specular_brdf, fresnel)
            f = dr.lerp(dielectric_brdf, metal_brdf, self.metallic)
            return dr.select(valid, f * cos_o, 0.0), c

        def _spec_probability(self, c, cos_i):
            # Only variance depends on it: the view's Fresnel for the GGX layer against what
            # it leaves the diffuse layer (0 for a metal).
            f0 = dr.lerp(mi.Color3f(0.04), c, self.metallic)
            f = f0 + (1 - f0) * dr.power(1 - dr.clip(cos_i, 0, 1), 5)
            s = mi.luminance(f)
            d = mi.luminance((1 - f) * c * (1 - self.metallic))
            return dr.select(s + d > 0, s / (s + d), 0.5)

        def _pdf(self, wi, wo, p_spec):
            distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, self.alpha, True)
            h = dr.normalize(wi + wo)
            spec = distr.pdf(wi, h) / (4 * dr.abs(dr.dot(wo, h)))
            diff = mi.warp.square_to_cosine_hemisphere_pdf(wo)
            valid = (wi.z > 0) & (wo.z > 0)
            return dr.select(valid, p_spec * spec + (1 - p_spec) * diff, 0.0)

        def eval(self, ctx, si, wo, active=True):
            wi, wo = self._frame(si, wo)
            value, _ = self._eval(si, wi, wo, active)
            return value

        def pdf(self, ctx, si, wo, active=True):
            wi, wo = self._frame(si, wo)
            c = self.base.eval(si, active)
            return self._pdf(wi, wo, self._spec_probability(c, wi.z))

        def eval_pdf(self, ctx, si, wo, active=True):
            wi, wo = self._frame(si, wo)
            value, c = self._eval(si, wi, wo, active)
            return value, self._pdf(wi, wo, self._spec_probability(c, wi.z))

        def sample(self, ctx, si, sample1, sample2, active=True):
            flip = mi.Frame3f.cos_theta(si.wi) < 0
            wi = mi.Vector3f(si.wi.x, si.wi.y, dr.abs(si.wi.z))
            c = self.base.eval(si, active)
            p_spec = self._spec_probability(c, wi.z)
            use_spec = sample1 < p_spec
            distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, self.alpha, True)
            m, _ = distr.sample(wi, sample2)
            wo = dr.select(use_spec, mi.reflect(wi, m), mi.warp.square_to_cosine_hemisphere(sample2))
            value, _ = self._eval(si, wi, wo, active)
            pdf = self._pdf(wi, wo, p_spec)
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.Vector3f(wo.x, wo.y, dr.select(flip, -wo.z, wo.z))
            bs.pdf = pdf
            bs.eta = 1.0
            bs.sampled_type = dr.select(use_spec, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                        mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
            bs.sampled_component = dr.select(use_spec, mi.UInt32(0), mi.UInt32(1))
            ok = active & (pdf > 0) & (wo.z > 0)
            return bs, dr.select(ok, value / dr.select(ok, pdf, 1.0), 0.0)

        def traverse(self, callback):
            callback.put("base_color", self.base, mi.ParamFlags.NonDifferentiable)

        def to_string(self):
            return f"GltfPbr[metallic={self.metallic}, roughness={self.roughness}]"

    mi.register_bsdf("gltf_pbr", lambda props: GltfPbr(props))


# ---- Mitsuba --------------------------------------------------------------------------------------

def luminance(c):
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]


def set_variant(variant):
    if variant.startswith("llvm") and "DRJIT_LIBLLVM_PATH" not in os.environ:
        for p in ("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
                  "/usr/lib/x86_64-linux-gnu/libLLVM-18.so", "/usr/lib/x86_64-linux-gnu/libLLVM-17.so"):
            if os.path.exists(p):
                os.environ["DRJIT_LIBLLVM_PATH"] = p
                break
    import mitsuba as mi
    mi.set_variant(variant)
    register_bsdf()
    return mi


def integrator(meshes):
    """`path`, or where a blended surface lets light through, `volpath`: its shadow rays cross
    a `mask` BSDF's uncovered share (scaled by it), as hybrid-rt's do; `path`'s would stop."""
    return "volpath" if any(m["material"]["alpha"] < 1.0 for m in meshes) else "path"


def mitsuba_scene(mi, path, size, tmp):
    import numpy as np
    meshes, lights, camera = read_gltf(path)
    kind = integrator(meshes)
    width, height = size
    if camera["aspect"] is not None and abs(camera["aspect"] - width / height) > 1e-6:
        fail(path, f"the camera's aspect ratio {camera['aspect']} differs from {width}x{height}")
    eye = camera["eye"]
    target = [e + f for e, f in zip(eye, camera["forward"])]
    scene = {
        "type": "scene",
        # hybrid-rt's reference: one light sample and one BSDF sample per vertex, power-heuristic
        # MIS, Russian roulette from the fourth vertex; paths end only by roulette.
        "integrator": {"type": kind, "max_depth": -1, "rr_depth": 4},
        "sensor": {
            "type": "perspective", "fov_axis": "y", "fov": math.degrees(camera["yfov"]),
            "near_clip": 0.05, "far_clip": 1e4,
            "to_world": mi.ScalarTransform4f().look_at(origin=eye, target=target, up=camera["up"]),
            "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
                     "pixel_format": "rgb", "component_format": "float32"},
            "sampler": {"type": "independent"},
        },
    }
    for i, m in enumerate(meshes):
        mat = m["material"]
        mesh = mi.Mesh(m["name"], len(m["pos"]), len(m["idx"]) // 3, has_vertex_normals=True,
                       has_vertex_texcoords=True)
        p = mi.traverse(mesh)
        p["vertex_positions"] = mi.Float(m["pos"].astype(np.float32).ravel())
        p["vertex_normals"] = mi.Float(m["nrm"].astype(np.float32).ravel())
        p["vertex_texcoords"] = mi.Float(np.asarray(m["uv"], dtype=np.float32).ravel())
        p["faces"] = mi.UInt32(m["idx"])
        p.update()
        ply = os.path.join(tmp, f"mesh{i}.ply")
        mesh.write_ply(ply)
        if mat["texture"] is not None:
            texels = mat["texture"] * np.array(mat["base"], dtype=np.float32)
            base = {"type": "bitmap", "bitmap": mi.Bitmap(texels), "raw": True, "filter_type": "nearest",
                    "wrap_mode": "repeat"}
        else:
            base = {"type": "rgb", "value": mat["base"]}
        bsdf = {"type": "gltf_pbr", "base_color": base, "metallic": mat["metallic"], "roughness": mat["roughness"]}
        if mat["alpha"] < 1.0:
            bsdf = {"type": "mask", "opacity": {"type": "rgb", "value": [mat["alpha"]] * 3}, "bsdf": bsdf}
        entry = {"type": "ply", "filename": ply, "face_normals": True, "bsdf": bsdf}
        if any(mat["emission"]):
            tri = m["pos"][m["idx"].reshape(-1, 3)]
            area = float(0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum())
            entry["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": mat["emission"]},
                                "sampling_weight": math.pi * luminance(mat["emission"]) * area}
        scene[f"mesh{i}"] = entry
    for i, light in enumerate(lights):
        scene[f"light{i}"] = {"type": "point", "position": light["position"],
                              "intensity": {"type": "rgb", "value": light["intensity"]},
                              "sampling_weight": 4 * math.pi * luminance(light["intensity"])}
    return mi.load_dict(scene), kind


def render(args):
    import tempfile
    import numpy as np
    mi = set_variant(args.variant)
    for name in args.names or SCENES:
        folder = os.path.join(OUT_DIR, name)
        size, spp = DEFAULT_SIZE, DEFAULT_SPP
        if name in SHARED_SCENES:
            rel, size, spp = SHARED_SCENES[name]
            path = os.path.join(SHARED_DIR, rel)
            scene_name = f"../shared/scenes/{rel}"
            os.makedirs(folder, exist_ok=True)
        else:
            path = os.path.join(folder, "scene.gltf")
            scene_name = f"tests/mitsuba/{name}/scene.gltf"
        if not os.path.exists(path):
            sys.exit(f"{path}: missing; run `python3 tools/mitsuba_reference.py scenes` first"
                     if name not in SHARED_SCENES else f"{path}: missing (../shared/scenes beside the checkout)")
        width, height = (int(v) for v in args.size.lower().split("x")) if args.size else size
        spp = args.spp or spp
        record = {"scene": scene_name, "size": [width, height], "spp": spp,
                  "mitsuba": mi.__version__, "variant": args.variant,
                  "renders": []}
        with tempfile.TemporaryDirectory() as tmp:
            scene, kind = mitsuba_scene(mi, path, (width, height), tmp)
            record["integrator"] = f"{kind} (max_depth -1, rr_depth 4)"
            runs = [(SEEDS[0], "a", spp), (SEEDS[1], "b", spp), (2, "converged", CONVERGED_FACTOR * spp)]
            for seed, label, spp in runs:
                start = time.time()
                img = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float32)[:, :, :3]
                seconds = time.time() - start
                out = os.path.join(folder, f"mitsuba-{label}.exr")
                mi.Bitmap(img, mi.Bitmap.PixelFormat.RGB).write(out)
                mean = float(luminance([img[:, :, c].mean() for c in range(3)]))
                record["renders"].append({"file": f"mitsuba-{label}.exr", "seed": seed, "spp": spp,
                                          "seconds": round(seconds, 1), "mean_luminance": mean})
                print(f"{name}: wrote {os.path.relpath(out, ROOT)} (seed {seed}, {spp} spp, {width}x{height}, "
                      f"{seconds:.1f} s, mean luminance {mean:.5f})", flush=True)
        with open(os.path.join(folder, "mitsuba.json"), "w") as f:
            json.dump(record, f, indent=1)
            f.write("\n")


# ---- The plugin's own check --------------------------------------------------------------------------

def channels(x):
    """An RGB Dr.Jit array as a numpy array of shape (3, n)."""
    import numpy as np
    a = np.array(x)
    return a if a.shape[0] == 3 else a.T


def check_bsdf(args):
    """For each material and view angle: the mean of sample()'s weights (the sampled
    directional albedo) against midpoint quadrature of eval() over the hemisphere; every
    sample's weight against eval()/pdf() at its direction; the quadrature of pdf() against the
    share of samples that stayed above the horizon."""
    import drjit as dr
    import numpy as np
    mi = set_variant(args.variant)
    n = args.samples
    rng = np.random.default_rng(7)
    # (base colour, metallic, roughness)
    materials = [([1.0, 1.0, 1.0], 0.0, 1.0), ([0.2, 0.3, 0.6], 0.0, 0.3), ([1.0, 0.78, 0.34], 1.0, 0.3),
                 ([0.6, 0.6, 0.62], 1.0, 0.6), ([0.9, 0.5, 0.2], 0.5, 0.5), ([1.0, 1.0, 1.0], 0.0, 0.3)]
    failures = 0
    for base, metallic, roughness in materials:
        bsdf = mi.load_dict({"type": "gltf_pbr", "base_color": {"type": "rgb", "value": base},
                             "metallic": metallic, "roughness": roughness})
        for mu in (0.95, 0.5, 0.15):
            wi = mi.Vector3f(math.sqrt(1 - mu * mu), 0.0, mu)
            si = dr.zeros(mi.SurfaceInteraction3f, n)
            si.wi = wi
            ctx = mi.BSDFContext()
            bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n)), mi.Point2f(rng.random(n), rng.random(n)))
            wo = bs.wo
            value, pdf = bsdf.eval_pdf(ctx, si, wo)
            w, value, pdf = channels(weight), channels(value), np.array(pdf)
            kept = (pdf > 0) & (np.array(wo.z) > 0)
            ratio = np.where(kept, value / np.where(kept, pdf, 1.0), 0.0)
            consistent = bool(np.abs(w - ratio).max() <= 1e-4 * max(1.0, np.abs(ratio).max()))
            sampled = w.mean(axis=1)
            se = w.std(axis=1) / math.sqrt(n)
            lost = 1.0 - float(kept.mean())
            # Quadrature: z = t^2 (nodes where grazing lobes live), 600 x 1200 midpoints.
            nt, nphi = 600, 1200
            t = (np.arange(nt) + 0.5) / nt
            phi = 2 * np.pi * (np.arange(nphi) + 0.5) / nphi
            T, P = np.meshgrid(t, phi, indexing="ij")
            z = (T * T).ravel()
            r = np.sqrt(1 - z * z)
            dirs = mi.Vector3f(r * np.cos(P.ravel()), r * np.sin(P.ravel()), z)
            sq = dr.zeros(mi.SurfaceInteraction3f, nt * nphi)
            sq.wi = wi
            qv, qp = bsdf.eval_pdf(ctx, sq, dirs)
            jac = (2 * T.ravel()) * (2 * np.pi / (nt * nphi))
            quad = (channels(qv) * jac).sum(axis=1)
            pdf_integral = float((np.array(qp) * jac).sum())
            tol = 4 * se + 0.003 * quad + 1e-4
            ok = consistent and np.all(np.abs(sampled - quad) <= tol) and abs(pdf_integral + lost - 1) < 0.01
            failures += not ok
            print(f"{'ok  ' if ok else 'FAIL'} base {base} metallic {metallic} roughness {roughness} mu {mu}: "
                  f"sampled albedo {np.round(sampled, 4)} +- {np.round(se, 4)}, quadrature {np.round(quad, 4)}; "
                  f"pdf integral {pdf_integral:.4f} + lost {lost:.4f}; weight = eval/pdf: {consistent}")
    if failures:
        sys.exit(f"{failures} check(s) failed")
    print("the plugin's sample(), eval() and pdf() agree")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub_ = ap.add_subparsers(dest="command", required=True)
    sub_.add_parser("scenes", help="write tests/mitsuba/*/scene.gltf")
    c = sub_.add_parser("check-bsdf", help="check the plugin's sampling against its eval and pdf")
    c.add_argument("--samples", type=int, default=1 << 20)
    c.add_argument("--variant", default="llvm_ad_rgb")
    r = sub_.add_parser("render", help="render the scenes with Mitsuba (two seeds each)")
    r.add_argument("names", nargs="*", help=f"scenes (default: all of {', '.join(SCENES)}; also "
                   f"{', '.join(SHARED_SCENES)} from ../shared/scenes)")
    r.add_argument("--spp", type=int, help=f"default {DEFAULT_SPP}, or the shared scene's")
    r.add_argument("--size", help="WxH; default %dx%d, or the shared scene's" % DEFAULT_SIZE)
    r.add_argument("--variant", default="llvm_ad_rgb")
    args = ap.parse_args()
    if args.command == "scenes":
        for name in SCENES:
            make_scene(name)
    elif args.command == "check-bsdf":
        check_bsdf(args)
    else:
        render(args)


if __name__ == "__main__":
    main()
