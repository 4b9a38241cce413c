#!/usr/bin/env python3
"""Writes two generated test scenes (CC0, like the rest of the repository's own assets):

- assets/pbr_extensions/pbr_extensions.gltf: a floor and fifteen spheres, each with one glTF PBR extension
  (KHR_materials_ior, _specular, _clearcoat, _sheen, _anisotropy, _unlit, _emissive_strength,
  _transmission + _volume with absorption, and KHR_texture_transform on a checker texture), one with the
  extensions' textures (clear coat, clear-coat roughness, sheen colour, specular), a thin glass whose
  transmission is textured, one whose texture reads TEXCOORD_1, and two normal-mapped ones (MikkTSpace
  tangents, and the file's own TANGENT), one with COLOR_0 vertex colours whose alpha cuts out its bottom
  cap, a camera and a point light:
  the test scene of the loader's extension mapping (scene/src/gltf_pbr.rs) and of tests/tests/pbr_scene.rs.
- assets/pbr_extensions/checker_floor.gltf: a 400 x 400 floor under a 512 x 512 texture of one-texel
  checks repeated 40 times, seen from 1.7 units up towards the horizon, lit by a directional light: the
  minification case of the texture level of detail (`fovea report ... --texture-lod`).

Run from the repository root:
    python3 scripts/make-pbr-scene.py
"""
import base64
import json
import math
import struct
import zlib


def icosphere(levels):
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
             (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / math.sqrt(sum(x * x for x in v)) for c in v) for v in verts]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        cache = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = [(verts[a][k] + verts[b][k]) / 2 for k in range(3)]
                n = math.sqrt(sum(x * x for x in m))
                verts.append(tuple(x / n for x in m))
                cache[key] = len(verts) - 1
            return cache[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return verts, faces


def checker_png(n=8):
    """An n x n RGBA checker of one-texel squares, 8-bit, as PNG bytes."""
    rows = b""
    for y in range(n):
        rows += b"\0" + b"".join(
            bytes([230, 230, 230, 255] if (x + y) % 2 == 0 else [40, 40, 40, 255]) for x in range(n))
    return png_bytes(n, rows)


def normal_map_png(n=16):
    """An n x n tangent-space normal map of round bumps (RGB = (n + 1) / 2), 8-bit RGBA PNG bytes."""
    rows = b""
    for y in range(n):
        row = b"\0"
        for x in range(n):
            # Height sin(2 pi x / n) sin(2 pi y / n); its normal (-dh/dx, -dh/dy, 1), y up the image.
            a, b = 2 * math.pi * (x + 0.5) / n, 2 * math.pi * (y + 0.5) / n
            dx, dy = 0.6 * math.cos(a) * math.sin(b), -0.6 * math.sin(a) * math.cos(b)
            length = math.sqrt(dx * dx + dy * dy + 1)
            rgb = [round((c / length * 0.5 + 0.5) * 255) for c in (-dx, -dy, 1)]
            row += bytes(rgb + [255])
        rows += row
    return png_bytes(n, rows)


def png_bytes(n, rows):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", n, n, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def main():
    sphere_v, sphere_f = icosphere(3)
    floor_v = [(-6, 0, -4), (6, 0, -4), (6, 0, 4), (-6, 0, 4)]
    floor_uv = [(0, 0), (6, 0), (6, 4), (0, 4)]
    floor_f = [(0, 2, 1), (0, 3, 2)]
    blob = b""
    views, accessors = [], []

    def add(data, count, kind, ctype, target, minmax=None):
        nonlocal blob
        while len(blob) % 4:
            blob += b"\0"
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data), "target": target})
        blob += data
        acc = {"bufferView": len(views) - 1, "componentType": ctype, "count": count, "type": kind}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    def positions(vs):
        lo = [min(v[k] for v in vs) for k in range(3)]
        hi = [max(v[k] for v in vs) for k in range(3)]
        return add(b"".join(struct.pack("<3f", *v) for v in vs), len(vs), "VEC3", 5126, 34962, (lo, hi))

    s_pos = positions(sphere_v)
    s_nrm = add(b"".join(struct.pack("<3f", *v) for v in sphere_v), len(sphere_v), "VEC3", 5126, 34962)
    s_uv = add(b"".join(struct.pack("<2f", 0.5 + math.atan2(v[2], v[0]) / (2 * math.pi), 0.5 - math.asin(v[1]) / math.pi)
                        for v in sphere_v), len(sphere_v), "VEC2", 5126, 34962)
    s_uv1 = add(b"".join(struct.pack("<2f", 1 + math.atan2(v[2], v[0]) / math.pi, 1 - 2 * math.asin(v[1]) / math.pi)
                         for v in sphere_v), len(sphere_v), "VEC2", 5126, 34962)
    # The analytic tangent d p / d u (u grows with atan2(z, x)) and handedness -1: seen from outside the
    # texture is mirrored (u runs to the viewer's left), so the bitangent up the image is -(n x t).
    # (At the poles, where it is undefined, +x.)
    def tangent(v):
        r = math.hypot(v[0], v[2])
        return (-v[2] / r, 0, v[0] / r, -1) if r > 1e-6 else (1, 0, 0, -1)
    s_tan = add(b"".join(struct.pack("<4f", *tangent(v)) for v in sphere_v), len(sphere_v), "VEC4", 5126, 34962)
    s_idx = add(b"".join(struct.pack("<3H", *f) for f in sphere_f), 3 * len(sphere_f), "SCALAR", 5123, 34963)
    f_pos = positions(floor_v)
    f_uv = add(b"".join(struct.pack("<2f", *t) for t in floor_uv), 4, "VEC2", 5126, 34962)
    f_idx = add(b"".join(struct.pack("<3H", *f) for f in floor_f), 6, "SCALAR", 5123, 34963)
    # COLOR_0 as normalised unsigned bytes, RGBA: the colour follows the position, and the alpha is 0
    # below y = -0.6, so that the cut-out opens the sphere's bottom cap.
    def vertex_color(v):
        return tuple(round(255 * (0.5 + 0.5 * c)) for c in v) + ((255 if v[1] > -0.6 else 0),)
    s_col = add(b"".join(struct.pack("<4B", *vertex_color(v)) for v in sphere_v), len(sphere_v), "VEC4", 5121, 34962)
    accessors[s_col]["normalized"] = True

    grey = {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0, "roughnessFactor": 0.5}
    materials = [
        {"name": "floor", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0, "roughnessFactor": 0.8}},
        {"name": "ior", "pbrMetallicRoughness": grey, "extensions": {"KHR_materials_ior": {"ior": 1.33}}},
        {"name": "specular", "pbrMetallicRoughness": grey,
         "extensions": {"KHR_materials_specular": {"specularFactor": 0.6, "specularColorFactor": [1, 0.8, 0.6]}}},
        {"name": "clearcoat", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.05, 0.05, 1], "metallicFactor": 0, "roughnessFactor": 0.6},
         "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1, "clearcoatRoughnessFactor": 0.1}}},
        {"name": "sheen", "pbrMetallicRoughness": {"baseColorFactor": [0.05, 0.05, 0.3, 1], "metallicFactor": 0, "roughnessFactor": 0.9},
         "extensions": {"KHR_materials_sheen": {"sheenColorFactor": [0.9, 0.9, 0.9]}}},
        {"name": "anisotropy", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.8, 0.5, 1], "metallicFactor": 1, "roughnessFactor": 0.4},
         "extensions": {"KHR_materials_anisotropy": {"anisotropyStrength": 0.8}}},
        {"name": "unlit", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.5, 0.1, 1]}, "extensions": {"KHR_materials_unlit": {}}},
        {"name": "emissive_strength", "pbrMetallicRoughness": grey, "emissiveFactor": [1, 0.6, 0.2],
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 5}}},
        {"name": "glass", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                        "KHR_materials_volume": {"thicknessFactor": 1, "attenuationColor": [0.9, 0.95, 1.0], "attenuationDistance": 2},
                        "KHR_materials_ior": {"ior": 1.5}}},
        {"name": "texture_transform", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"scale": [4, 4], "rotation": 0.3}}},
            "metallicFactor": 0, "roughnessFactor": 0.7}},
        {"name": "extension_textures", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.3, 0.1, 1], "metallicFactor": 0, "roughnessFactor": 0.6},
         "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1, "clearcoatRoughnessFactor": 0.5,
                                                    "clearcoatTexture": {"index": 0}, "clearcoatRoughnessTexture": {"index": 0}},
                        "KHR_materials_sheen": {"sheenColorFactor": [1, 1, 1], "sheenColorTexture": {"index": 0}},
                        "KHR_materials_specular": {"specularTexture": {"index": 0}}}},
        {"name": "textured_glass", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0.1},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1, "transmissionTexture": {"index": 0}}}},
        {"name": "texcoord_1", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1},
                                                        "metallicFactor": 0, "roughnessFactor": 0.7}},
        {"name": "normal_map", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.6, 0.4, 1], "metallicFactor": 0, "roughnessFactor": 0.3},
         "normalTexture": {"index": 1}},
        {"name": "normal_map_tangents", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.6, 0.4, 1], "metallicFactor": 0, "roughnessFactor": 0.3},
         "normalTexture": {"index": 1}},
        {"name": "vertex_colors", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicFactor": 0, "roughnessFactor": 0.5},
         "alphaMode": "MASK", "alphaCutoff": 0.5},
    ]
    meshes = [{"name": "floor", "primitives": [{"attributes": {"POSITION": f_pos, "TEXCOORD_0": f_uv}, "indices": f_idx, "material": 0}]}]
    nodes = [{"name": "floor", "mesh": 0}]
    for i, m in enumerate(materials[1:], start=1):
        attributes = {"POSITION": s_pos, "NORMAL": s_nrm, "TEXCOORD_0": s_uv}
        if m["name"] == "texcoord_1":
            attributes["TEXCOORD_1"] = s_uv1
        if m["name"] == "normal_map_tangents":
            attributes["TANGENT"] = s_tan
        if m["name"] == "vertex_colors":
            attributes["COLOR_0"] = s_col
        meshes.append({"name": m["name"], "primitives": [{"attributes": attributes, "indices": s_idx, "material": i}]})
        row, col = divmod(i - 1, 5)
        nodes.append({"name": m["name"], "mesh": i, "translation": [-4.4 + 2.2 * col, 1.0, -1.2 + 2.4 * row],
                      "scale": [0.9, 0.9, 0.9]})
    nodes.append({"name": "camera", "camera": 0, "translation": [0, 5.5, 9.5],
                  "rotation": [-math.sin(0.26), 0, 0, math.cos(0.26)]})
    nodes.append({"name": "light", "translation": [2, 7, 4], "extensions": {"KHR_lights_punctual": {"light": 0}}})
    gltf = {
        "asset": {"version": "2.0", "generator": "fovea scripts/make-pbr-scene.py", "copyright": "CC0 1.0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_anisotropy", "KHR_materials_clearcoat",
                           "KHR_materials_emissive_strength", "KHR_materials_ior", "KHR_materials_sheen",
                           "KHR_materials_specular", "KHR_materials_transmission", "KHR_materials_unlit",
                           "KHR_materials_volume", "KHR_texture_transform"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1, 0.95, 0.9], "intensity": 60}]}},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.75, "aspectRatio": 16 / 9, "znear": 0.1}}],
        "meshes": meshes,
        "materials": materials,
        "textures": [{"source": 0, "sampler": 0}, {"source": 1}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497}],
        "images": [{"uri": "data:image/png;base64," + base64.b64encode(checker_png()).decode()},
                   {"uri": "data:image/png;base64," + base64.b64encode(normal_map_png()).decode()}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    }
    with open("assets/pbr_extensions/pbr_extensions.gltf", "w") as f:
        json.dump(gltf, f, separators=(",", ":"))
        f.write("\n")


def checker_floor():
    size, repeat = 200.0, 40.0
    vs = [(-size, 0, -size), (size, 0, -size), (size, 0, size), (-size, 0, size)]
    uvs = [(0, 0), (repeat, 0), (repeat, repeat), (0, repeat)]
    blob = b"".join(struct.pack("<3f", *v) for v in vs)
    uv_off = len(blob)
    blob += b"".join(struct.pack("<2f", *t) for t in uvs)
    idx_off = len(blob)
    blob += struct.pack("<6H", 0, 2, 1, 0, 3, 2)
    gltf = {
        "asset": {"version": "2.0", "generator": "fovea scripts/make-pbr-scene.py", "copyright": "CC0 1.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 3}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"name": "floor", "mesh": 0},
            {"name": "camera", "camera": 0, "translation": [0, 1.7, 0],
             "rotation": [-math.sin(0.09), 0, 0, math.cos(0.09)]},
            {"name": "sun", "rotation": [-math.sin(0.6), 0, 0, math.cos(0.6)],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 16 / 9, "znear": 0.1}}],
        "meshes": [{"name": "floor", "primitives": [
            {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"name": "checker", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0}, "metallicFactor": 0, "roughnessFactor": 0.9}}],
        "textures": [{"source": 0}],
        "images": [{"uri": "data:image/png;base64," + base64.b64encode(checker_png(512)).decode()}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-size, 0, -size], "max": [size, 0, size]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": uv_off},
            {"buffer": 0, "byteOffset": uv_off, "byteLength": idx_off - uv_off},
            {"buffer": 0, "byteOffset": idx_off, "byteLength": 12},
        ],
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    }
    with open("assets/pbr_extensions/checker_floor.gltf", "w") as f:
        json.dump(gltf, f, separators=(",", ":"))
        f.write("\n")


if __name__ == "__main__":
    main()
    checker_floor()
