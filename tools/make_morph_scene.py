#!/usr/bin/env python3
"""Writes assets/morph/morph_wave.gltf: a small glTF 2.0 scene with a morphing mesh.

A 24 x 24 grid (the "flag") in front of a back wall, with two morph targets (POSITION and NORMAL
deltas): a bump towards the camera and a travelling ripple. The mesh's default weights are
(0, 0); one animation drives the weights with LINEAR keys over 2 s. A camera and a directional
light complete it, so `hybrid-rt render assets/morph/morph_wave.gltf` shows the deformation.

Run from anywhere: python3 tools/make_morph_scene.py
Only the standard library is used; the buffer is embedded as a data URI and the output is the same
bytes on every run.
"""
import base64
import json
import math
import struct
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "assets" / "morph" / "morph_wave.gltf"
FLOAT, U16 = 5126, 5123
N = 24
HALF = 1.0


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def normalize(v):
    length = math.sqrt(sum(c * c for c in v))
    return [c / length for c in v]


def surface(x, y, bump, ripple):
    """Height of the grid at (x, y) for the two weights."""
    return bump * 0.5 * math.exp(-(x * x + y * y) * 3.0) + ripple * 0.15 * math.sin(x * 6.0)


def normal(x, y, bump, ripple, h=1e-3):
    dx = (surface(x + h, y, bump, ripple) - surface(x - h, y, bump, ripple)) / (2 * h)
    dy = (surface(x, y + h, bump, ripple) - surface(x, y - h, bump, ripple)) / (2 * h)
    return normalize([-dx, -dy, 1.0])


def main():
    positions, normals, bump_d, bump_n, ripple_d, ripple_n = [], [], [], [], [], []
    for j in range(N + 1):
        for i in range(N + 1):
            x, y = (i / N * 2 - 1) * HALF, (j / N * 2 - 1) * HALF
            positions.append([x, y, 0.0])
            base = [0.0, 0.0, 1.0]
            normals.append(base)
            bump_d.append([0.0, 0.0, surface(x, y, 1, 0)])
            bump_n.append([a - b for a, b in zip(normal(x, y, 1, 0), base)])
            ripple_d.append([0.0, 0.0, surface(x, y, 0, 1)])
            ripple_n.append([a - b for a, b in zip(normal(x, y, 0, 1), base)])
    indices = []
    for j in range(N):
        for i in range(N):
            a, b = j * (N + 1) + i, (j + 1) * (N + 1) + i
            indices += [a, a + 1, b + 1, a, b + 1, b]
    wall = [[-4.0, -3.0, -2.0], [4.0, -3.0, -2.0], [4.0, 3.0, -2.0], [-4.0, 3.0, -2.0]]
    wall_n = [[0.0, 0.0, 1.0]] * 4
    wall_i = [0, 1, 2, 0, 2, 3]
    times = [0.0, 0.5, 1.0, 1.5, 2.0]
    weights = [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0]

    blob = bytearray()
    views, accessors = [], []

    def add(values, fmt, ty, count, component=FLOAT, minmax=False):
        while len(blob) % 4:
            blob.append(0)
        offset = len(blob)
        for v in values:
            blob.extend(struct.pack(fmt, *(v if isinstance(v, list) else [v])))
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(blob) - offset})
        acc = {"bufferView": len(views) - 1, "componentType": component, "count": count, "type": ty}
        if minmax:
            acc["min"] = [f32(min(v[k] for v in values)) for k in range(3)]
            acc["max"] = [f32(max(v[k] for v in values)) for k in range(3)]
        accessors.append(acc)
        return len(accessors) - 1

    count = len(positions)
    pos = add(positions, "<3f", "VEC3", count, minmax=True)
    nor = add(normals, "<3f", "VEC3", count)
    idx = add(indices, "<H", "SCALAR", len(indices), U16)
    t0p = add(bump_d, "<3f", "VEC3", count, minmax=True)
    t0n = add(bump_n, "<3f", "VEC3", count)
    t1p = add(ripple_d, "<3f", "VEC3", count, minmax=True)
    t1n = add(ripple_n, "<3f", "VEC3", count)
    wpos = add(wall, "<3f", "VEC3", 4, minmax=True)
    wnor = add(wall_n, "<3f", "VEC3", 4)
    widx = add(wall_i, "<H", "SCALAR", 6, U16)
    key_t = add(times, "<f", "SCALAR", len(times))
    accessors[key_t]["min"], accessors[key_t]["max"] = [times[0]], [times[-1]]
    key_w = add(weights, "<f", "SCALAR", len(weights))

    gltf = {
        "asset": {"version": "2.0", "generator": "hybrid-rt tools/make_morph_scene.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"name": "flag", "mesh": 0, "translation": [0.0, 0.0, 0.0]},
            {"name": "wall", "mesh": 1},
            {"name": "camera", "camera": 0, "translation": [0.0, 0.0, 4.0]},
            {"name": "sun", "rotation": [-0.3826834, 0.0, 0.0, 0.9238795],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
        ],
        "meshes": [
            {"name": "flag", "weights": [0.0, 0.0], "primitives": [{
                "attributes": {"POSITION": pos, "NORMAL": nor}, "indices": idx, "material": 0,
                "targets": [{"POSITION": t0p, "NORMAL": t0n}, {"POSITION": t1p, "NORMAL": t1n}],
            }]},
            {"name": "wall", "primitives": [{
                "attributes": {"POSITION": wpos, "NORMAL": wnor}, "indices": widx, "material": 1}]},
        ],
        "materials": [
            {"name": "orange", "pbrMetallicRoughness": {
                "baseColorFactor": [0.9, 0.4, 0.1, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.6},
             "doubleSided": True},
            {"name": "white", "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 1.0}},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 50.0}}],
        "animations": [{"name": "wave", "samplers": [{"input": key_t, "output": key_w, "interpolation": "LINEAR"}],
                        "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "color": [1.0, 1.0, 1.0], "intensity": 3.0}]}},
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(gltf, indent=1) + "\n")
    print(f"wrote {OUT} ({count} vertices, {len(indices) // 3} triangles, 2 morph targets)")


if __name__ == "__main__":
    main()
