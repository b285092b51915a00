#!/usr/bin/env python3
"""Writes assets/default/: hybrid-rt's built-in Cornell-box scene (glTF 2.0, metres, +Y up).

Run from anywhere: python3 tools/make_default_scene.py
Only the standard library is used and the output is the same bytes on every run, so the generated
files are committed and a regeneration shows up in a diff only when this script changes.
After writing, the script re-reads its own output and checks it (see check()).
"""
import json
import math
import struct
import zlib
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "assets" / "default"
GLTF, BIN = "cornell.gltf", "cornell.bin"
FLOAT, U16 = 5126, 5123
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963

# Cornell-box reflectances (the classic measured wall colours), linear RGB.
WHITE = [0.725, 0.71, 0.68]
RED = [0.63, 0.065, 0.05]
GREEN = [0.14, 0.45, 0.091]


# ---------------------------------------------------------------- small maths

def sub(a, b): return [x - y for x, y in zip(a, b)]
def dot(a, b): return sum(x * y for x, y in zip(a, b))
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def scale(a, s): return [x * s for x in a]
def normalize(a): return scale(a, 1.0 / math.sqrt(dot(a, a)))


def f32(x):
    """x as float32, written with the fewest digits that read back to the same float32.

    Keeps the JSON readable, and min/max then match the .bin data exactly (validators compare).
    """
    packed = struct.pack("<f", x)
    for digits in range(1, 10):
        s = float(f"{struct.unpack('<f', packed)[0]:.{digits}g}")
        if struct.pack("<f", s) == packed:
            return s + 0.0  # turns -0.0 into 0.0
    raise AssertionError(x)


def yaw(deg):
    """Quaternion (x, y, z, w) for a rotation of deg degrees about +Y."""
    h = math.radians(deg) / 2
    return [0.0, math.sin(h), 0.0, math.cos(h)]


def look_rotation(eye, target, up=(0.0, 1.0, 0.0)):
    """Quaternion turning local -Z (where glTF cameras and spot lights point) from eye to target."""
    z = normalize(sub(eye, target))
    x = normalize(cross(up, z))
    y = cross(z, x)
    m = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
    t = m[0][0] + m[1][1] + m[2][2]
    if t > 0:
        s = 2 * math.sqrt(t + 1)
        q = [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, s / 4]
    else:
        i = max(range(3), key=lambda k: m[k][k])
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2 * math.sqrt(1 + m[i][i] - m[j][j] - m[k][k])
        q = [0.0] * 4
        q[i], q[j], q[k], q[3] = s / 4, (m[j][i] + m[i][j]) / s, (m[k][i] + m[i][k]) / s, (m[k][j] - m[j][k]) / s
    return normalize(q)


# ---------------------------------------------------------------- geometry
# A mesh is (positions, normals, uvs, indices); front faces are counter-clockwise seen from the
# side the normals point to.

def quad(c, u, v):
    """Quad centred at c spanning c±u±v (half extents); faces u×v. UV (0,0) is at the c-u+v corner."""
    n = normalize(cross(u, v))
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    pos = [[c[i] + a * u[i] + b * v[i] for i in range(3)] for a, b in corners]
    uv = [[(a + 1) / 2, (1 - b) / 2] for a, b in corners]  # glTF UV v runs downwards
    return pos, [n] * 4, uv, [0, 1, 2, 0, 2, 3]


def merge(*meshes):
    out = ([], [], [], [])
    for p, n, t, idx in meshes:
        base = len(out[0])
        out[0].extend(p), out[1].extend(n), out[2].extend(t)
        out[3].extend(base + i for i in idx)
    return out


def box(sx, sy, sz):
    """Closed box centred at the origin, one quad per face (so normals and UVs are per face)."""
    hx, hy, hz = sx / 2, sy / 2, sz / 2
    X, Y, Z = [hx, 0, 0], [0, hy, 0], [0, 0, hz]
    return merge(quad(X, scale(Z, -1), Y), quad(scale(X, -1), Z, Y),
                 quad(Y, X, scale(Z, -1)), quad(scale(Y, -1), X, Z),
                 quad(Z, X, Y), quad(scale(Z, -1), scale(X, -1), Y))


def sphere(r, segments=32, rings=16):
    """UV sphere centred at the origin; the seam column is duplicated so U runs 0..1."""
    pos, nrm, uv, idx = [], [], [], []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segments + 1):
            ph = 2 * math.pi * j / segments
            n = [math.sin(th) * math.cos(ph), math.cos(th), -math.sin(th) * math.sin(ph)]
            pos.append(scale(n, r)), nrm.append(n), uv.append([j / segments, i / rings])
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
            if i != rings - 1:  # the triangles touching a pole would be degenerate there
                idx += [a, b, b + 1]
            if i != 0:
                idx += [a, b + 1, a + 1]
    return pos, nrm, uv, idx


# ---------------------------------------------------------------- textures

def png(width, height, rows, colour_type):
    """8-bit PNG, colour_type 2 = RGB or 6 = RGBA; every row uses filter 0, which is enough here."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    raw = b"".join(b"\0" + row for row in rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def floor_checker():
    # Near-white sRGB values (about 0.96 and 0.73 linear) multiply the white wall factor, so the
    # floor's mean albedo stays close to the other white surfaces while the 25 cm checker shows
    # texture filtering and detail in the denoised output.
    light, dark = bytes([250, 250, 250]), bytes([222, 222, 222])
    return png(256, 256, [b"".join(light if (x // 32 + y // 32) % 2 == 0 else dark for x in range(256))
                          for y in range(256)], 2)


def mask_holes():
    # A 4x4 grid of round holes: alpha is strictly 0 or 255 so the MASK cutoff is unambiguous.
    # The holes keep the opaque RGB so bilinear filtering does not darken their edges.
    def texel(x, y):
        dx, dy = x % 32 - 15.5, y % 32 - 15.5
        return bytes([235, 222, 190, 0 if dx * dx + dy * dy < 11.0 ** 2 else 255])
    return png(128, 128, [b"".join(texel(x, y) for x in range(128)) for y in range(128)], 6)


# ---------------------------------------------------------------- glTF writer

class Builder:
    def __init__(self):
        self.bin = bytearray()
        self.doc = {
            "asset": {"version": "2.0", "generator": "hybrid-rt tools/make_default_scene.py"},
            "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
            "scene": 0, "scenes": [], "nodes": [], "meshes": [], "materials": [], "textures": [],
            "images": [], "samplers": [], "cameras": [], "animations": [], "accessors": [],
            "bufferViews": [], "buffers": [],
            "extensions": {"KHR_lights_punctual": {"lights": []}},
        }

    def add(self, kind, item):
        self.doc[kind].append(item)
        return len(self.doc[kind]) - 1

    def accessor(self, values, kind, target=None, bounds=False):
        """One bufferView per accessor, so no byteStride is needed and every offset is 4-aligned."""
        flat = [x for v in values for x in (v if isinstance(v, (list, tuple)) else [v])]
        data = struct.pack(f"<{len(flat)}H", *flat) if kind == "SCALAR_U16" else struct.pack(f"<{len(flat)}f", *flat)
        self.bin += b"\0" * (-len(self.bin) % 4)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            view["target"] = target
        self.bin += data
        acc = {"bufferView": self.add("bufferViews", view), "componentType": U16 if kind == "SCALAR_U16" else FLOAT,
               "count": len(values), "type": "SCALAR" if kind == "SCALAR_U16" else kind}
        if bounds:
            cols = list(zip(*[v if isinstance(v, (list, tuple)) else [v] for v in values]))
            acc["min"], acc["max"] = [f32(min(c)) for c in cols], [f32(max(c)) for c in cols]
        return self.add("accessors", acc)

    def mesh(self, name, geometry, material):
        pos, nrm, uv, idx = geometry
        attrs = {"POSITION": self.accessor(pos, "VEC3", ARRAY_BUFFER, bounds=True),
                 "NORMAL": self.accessor(nrm, "VEC3", ARRAY_BUFFER),
                 "TEXCOORD_0": self.accessor(uv, "VEC2", ARRAY_BUFFER)}
        prim = {"attributes": attrs, "indices": self.accessor(idx, "SCALAR_U16", ELEMENT_ARRAY_BUFFER),
                "material": material, "mode": 4}
        return self.add("meshes", {"name": name, "primitives": [prim]})

    def material(self, name, base, metallic, roughness, **extra):
        pbr = {"baseColorFactor": [*base, 1.0], "metallicFactor": metallic, "roughnessFactor": roughness}
        if "texture" in extra:
            pbr["baseColorTexture"] = {"index": extra.pop("texture"), "texCoord": 0}
        return self.add("materials", {"name": name, "pbrMetallicRoughness": pbr, **extra})

    def texture(self, name, data):
        (OUT / name).write_bytes(data)
        image = self.add("images", {"name": name[:-4], "uri": name, "mimeType": "image/png"})
        return self.add("textures", {"name": name[:-4], "source": image, "sampler": 0})

    def node(self, name, t=None, r=None, s=None, **extra):
        node = {"name": name}
        for key, value in (("translation", t), ("rotation", r), ("scale", s)):
            if value is not None:
                node[key] = [f32(x) for x in value]
        return self.add("nodes", {**node, **{k: v for k, v in extra.items() if v is not None}})


def build():
    g = Builder()
    # Trilinear and repeat: the checker is viewed at grazing angles, where mip-mapping matters.
    g.add("samplers", {"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497})
    floor_tex = g.texture("floor_checker.png", floor_checker())
    mask_tex = g.texture("mask_holes.png", mask_holes())

    m_white = g.material("white_wall", WHITE, 0.0, 1.0)
    m_floor = g.material("floor_checker", WHITE, 0.0, 1.0, texture=floor_tex)
    m_red = g.material("red_wall", RED, 0.0, 1.0)
    m_green = g.material("green_wall", GREEN, 0.0, 1.0)
    # The classic box's light (radiance ~17, 0.13 x 0.105 m in a 0.55 m room) scaled to this 2 m
    # room would cover ~0.18 m^2; 0.5 x 0.4 m at the same radiance keeps the classic exposure.
    m_light = g.material("ceiling_light", [0.78] * 3, 0.0, 1.0, emissiveFactor=[1.0, 1.0, 1.0],
                         extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 17.0}})
    m_mirror = g.material("mirror", [0.95] * 3, 1.0, 0.0)
    m_gold = g.material("gold", [1.0, 0.78, 0.34], 1.0, 0.25)
    m_tall = g.material("tall_box_white", WHITE, 0.0, 0.9)
    m_cube = g.material("cube_blue_grey", [0.2, 0.3, 0.6], 0.0, 0.5)
    m_mask = g.material("mask_screen", [1.0, 1.0, 1.0], 0.0, 0.8, texture=mask_tex,
                        alphaMode="MASK", alphaCutoff=0.5, doubleSided=True)
    m_ball = g.material("orange_plastic", [0.9, 0.35, 0.1], 0.0, 0.6)

    x, y, z = [1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]
    nz = scale(z, -1)
    roots = []

    def place(name, mesh, **trs):
        n = g.node(name, mesh=mesh, **trs)
        roots.append(n)
        return n

    # Walls are in world coordinates with identity nodes; each faces into the room.
    place("floor", g.mesh("floor", quad([0, 0, 0], x, nz), m_floor))
    place("ceiling", g.mesh("ceiling", quad([0, 2, 0], x, z), m_white))
    place("back_wall", g.mesh("back_wall", quad([0, 1, -1], x, y), m_white))
    place("left_wall", g.mesh("left_wall", quad([-1, 1, 0], nz, y), m_red))
    place("right_wall", g.mesh("right_wall", quad([1, 1, 0], z, y), m_green))
    # 2 cm below the ceiling so the emitter never shares a plane with it.
    place("ceiling_light", g.mesh("ceiling_light", quad([0, 0, 0], scale(x, 0.25), scale(z, 0.2)), m_light),
          t=[0, 1.98, 0])

    # A spot of 4 cd lights its pool on the tall box about 1.4x as strongly as the ceiling light's
    # direct light on the floor: visible, but the area light still sets the look.
    lights = g.doc["extensions"]["KHR_lights_punctual"]["lights"]
    lights.append({
        "name": "spot_light", "type": "spot", "color": [1.0, 0.9, 0.75], "intensity": 4.0, "range": 6.0,
        "spot": {"innerConeAngle": 0.35, "outerConeAngle": 0.5}, "extras": {"radius": 0.05}})
    spot = len(lights) - 1
    spot_pos = [-0.85, 1.85, 0.85]
    place("spot_light", None, t=spot_pos, r=look_rotation(spot_pos, [-0.3, 0.4, -0.1]),
          extensions={"KHR_lights_punctual": {"light": spot}})

    # Local quads; the nodes place them. The mirror stands 5 cm above the floor, turned 20 degrees
    # toward the room centre, its nearest corner 6 cm in front of the back wall.
    place("mirror", g.mesh("mirror", quad([0, 0, 0], scale(x, 0.4), scale(y, 0.6)), m_mirror),
          t=[0.45, 0.65, -0.8], r=yaw(-20))
    place("gold_sphere", g.mesh("gold_sphere", sphere(0.3), m_gold), t=[0.45, 0.3, 0.35])
    place("tall_box", g.mesh("tall_box", box(0.6, 1.2, 0.6), m_tall), t=[-0.35, 0.6, -0.35], r=yaw(17))
    cube = g.mesh("cube", box(0.3, 0.3, 0.3), m_cube)
    cube_a = g.node("cube_a", mesh=cube, t=[0.35, 0.15, -0.45], r=yaw(25))
    cube_b = g.node("cube_b", mesh=cube, t=[-0.8, 0.09, 0.26], r=yaw(-30), s=[1.2, 0.6, 1.2])
    roots.append(g.node("cubes", t=[0.05, 0, 0.05], r=yaw(10), children=[cube_a, cube_b]))
    place("mask_screen", g.mesh("mask_screen", quad([0, 0.3, 0], scale(x, 0.3), scale(y, 0.3)), m_mask),
          t=[-0.3, 0, 0.12], r=yaw(10))

    # The ball starts where the animation starts, so a loader that ignores animation sees frame 0.
    ball = place("moving_ball", g.mesh("moving_ball", sphere(0.12), m_ball), t=[-0.5, 0.5, 0.8])
    keys = g.accessor([0.0, 2.0, 4.0], "SCALAR", bounds=True)
    path = g.accessor([[-0.5, 0.5, 0.8], [0.5, 0.5, 0.8], [-0.5, 0.5, 0.8]], "VEC3")
    # One turn about Y in quarter steps: slerp between neighbours takes the intended way, and the
    # last key (w = -1) is the same rotation as the first, so the loop has no jump.
    spin_keys = g.accessor([0.0, 1.0, 2.0, 3.0, 4.0], "SCALAR", bounds=True)
    spin = g.accessor([yaw(90 * k) for k in range(5)], "VEC4")
    g.add("animations", {"name": "moving_ball_sweep", "samplers": [
        {"input": keys, "output": path, "interpolation": "LINEAR"},
        {"input": spin_keys, "output": spin, "interpolation": "LINEAR"}], "channels": [
        {"sampler": 0, "target": {"node": ball, "path": "translation"}},
        {"sampler": 1, "target": {"node": ball, "path": "rotation"}}]})

    cam = g.add("cameras", {"name": "front", "type": "perspective", "perspective": {
        "yfov": 0.69, "znear": 0.05, "zfar": 20.0, "aspectRatio": 1.0}})
    place("front", None, t=[0, 1, 3.4], camera=cam)
    cam = g.add("cameras", {"name": "corner", "type": "perspective", "perspective": {
        "yfov": 0.8, "znear": 0.05, "zfar": 20.0, "aspectRatio": 1.0}})
    corner = [-0.7, 1.5, 2.6]
    place("corner", None, t=corner, r=look_rotation(corner, [0, 1, 0]), camera=cam)

    g.add("scenes", {"name": "cornell", "nodes": roots})
    g.bin += b"\0" * (-len(g.bin) % 4)
    g.add("buffers", {"uri": BIN, "byteLength": len(g.bin)})
    (OUT / BIN).write_bytes(bytes(g.bin))
    (OUT / GLTF).write_text(json.dumps(g.doc, indent=1) + "\n")


# ---------------------------------------------------------------- self-check

def check():
    """Re-reads the output: alignment, accessor bounds, index ranges, winding vs normals, room fit."""
    doc = json.loads((OUT / GLTF).read_text())
    blob = (OUT / BIN).read_bytes()
    assert doc["buffers"][0]["byteLength"] == len(blob)

    def read(i):
        a = doc["accessors"][i]
        v = doc["bufferViews"][a["bufferView"]]
        size, fmt = (2, "H") if a["componentType"] == U16 else (4, "f")
        n = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[a["type"]]
        off = v["byteOffset"] + a.get("byteOffset", 0)
        assert off % size == 0 and off + a["count"] * n * size <= v["byteOffset"] + v["byteLength"] <= len(blob)
        flat = struct.unpack_from(f"<{a['count'] * n}{fmt}", blob, off)
        rows = [list(flat[k:k + n]) for k in range(0, len(flat), n)]
        if "min" in a:
            cols = list(zip(*rows))
            assert a["min"] == [f32(min(c)) for c in cols] and a["max"] == [f32(max(c)) for c in cols], i
        return rows if n > 1 else flat

    for i in range(len(doc["accessors"])):
        read(i)
    for m in doc["meshes"]:
        for p in m["primitives"]:
            at = p["attributes"]
            assert set(at) == {"POSITION", "NORMAL", "TEXCOORD_0"} and "min" in doc["accessors"][at["POSITION"]]
            pos, nrm, idx = read(at["POSITION"]), read(at["NORMAL"]), read(p["indices"])
            assert len(nrm) == len(pos) == len(read(at["TEXCOORD_0"])) and max(idx) < len(pos)
            for t in range(0, len(idx), 3):
                tri = idx[t:t + 3]
                gn = cross(sub(pos[tri[1]], pos[tri[0]]), sub(pos[tri[2]], pos[tri[0]]))
                assert dot(gn, gn) > 1e-12, (m["name"], t)
                assert all(dot(gn, nrm[k]) > 0 for k in tri), (m["name"], t)

    def matrix(node):  # rows of T * R * S, 3x4
        qx, qy, qz, qw = node.get("rotation", [0, 0, 0, 1])
        r = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
             [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
             [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
        s, t = node.get("scale", [1, 1, 1]), node.get("translation", [0, 0, 0])
        return [[r[i][j] * s[j] for j in range(3)] + [t[i]] for i in range(3)]

    def mul(a, b):
        return [[sum(a[i][k] * b[k][j] for k in range(3)) + (a[i][3] if j == 3 else 0) for j in range(4)]
                for i in range(3)]

    report = []

    def walk(i, parent):
        node = doc["nodes"][i]
        world = mul(parent, matrix(node))
        if "mesh" in node:
            pos = read(doc["meshes"][node["mesh"]]["primitives"][0]["attributes"]["POSITION"])
            ws = [[dot(world[r][:3], p) + world[r][3] for r in range(3)] for p in pos]
            lo, hi = [min(c) for c in zip(*ws)], [max(c) for c in zip(*ws)]
            room_lo, room_hi = [-1, 0, -1], [1, 2, 1]
            assert all(room_lo[k] - 1e-5 <= lo[k] and hi[k] <= room_hi[k] + 1e-5 for k in range(3)), node["name"]
            report.append(f"  {node['name']:<14} world bounds {[round(v, 3) + 0.0 for v in lo]} .. {[round(v, 3) + 0.0 for v in hi]}")
        for c in node.get("children", []):
            walk(c, world)

    for i in doc["scenes"][0]["nodes"]:
        walk(i, [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]])
    return report


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    build()
    report = check()
    for name in ("cornell.gltf", "cornell.bin", "floor_checker.png", "mask_holes.png"):
        print(f"wrote {OUT / name} ({(OUT / name).stat().st_size} bytes)")
    print("check passed; mesh nodes inside the room:")
    print("\n".join(report))


if __name__ == "__main__":
    main()
