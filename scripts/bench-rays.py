#!/usr/bin/env python3
"""Ray-traversal throughput of Mitsuba 3 (`llvm_ad_rgb`, which traces with Embree) on a peer-kit scene,
and the ray file that `fovea bench rays --rays FILE` traces, so that both time the very same rays.

Usage (with the peer kit's venv; scripts/bench-rays.sh runs it):
    $PEER_WORK/venv/bin/python scripts/bench-rays.py SCENE RAY_FILE [COUNT] [THREADS] [SET]

SCENE is `small` or `big` (read from $PEER_WORK/scenes); an empty COUNT takes the default. The rays are written as fovea's ray records
(little-endian f32: origin xyz, direction xyz, t_max, kind), from a fixed seed. SET is
- `random` (default): COUNT rays of each kind (default 2**21):
  - closest-hit rays (kind 0, t_max inf): uniform origins in the room (x, y in [-0.99, 0.99], z in
    [-0.99, 2.99]), uniform directions;
  - occlusion rays (kind 1): uniform origins in the room towards uniform points on the ceiling light,
    t_max just short of the light, as a path tracer's shadow rays;
- `paths`: the rays of COUNT three-bounce paths (default 2**18; rounded down to a square number, one
  path per pixel of a square image) from the kit's camera, as a path tracer of the benchmark traces them: per path the camera ray and three bounce rays (closest hit; each bounce
  cosine-distributed about the geometric normal, leaving from the hit point moved 1e-4 along it) and,
  at each of the three vertices, a shadow ray to a uniform point on the light (occlusion). Mitsuba
  finds the hit points. Paths that escape or end stop early.

Times `scene.ray_intersect_preliminary` (closest hit, no surface interaction) and `scene.ray_test` over all
rays of a kind at once, each followed by `dr.eval` and `dr.sync_thread`; one warm-up and three timed passes
(median). Prints one line per kind and a JSON line.
"""
import json
import os
import sys
import time

import numpy as np


def rays(count):
    rng = np.random.default_rng(7)

    def room_points(n):
        return np.stack([rng.uniform(-0.99, 0.99, n), rng.uniform(-0.99, 0.99, n),
                         rng.uniform(-0.99, 2.99, n)], 1)

    origin = room_points(count)
    z = rng.uniform(-1.0, 1.0, count)
    phi = rng.uniform(0.0, 2.0 * np.pi, count)
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    direction = np.stack([r * np.cos(phi), r * np.sin(phi), z], 1)
    closest = np.concatenate([origin, direction, np.full((count, 1), np.inf), np.zeros((count, 1))], 1)

    origin = room_points(count)
    light = np.stack([rng.uniform(-0.25, 0.25, count), np.full(count, 0.995),
                      rng.uniform(-0.2, 0.2, count)], 1)
    to_light = light - origin
    distance = np.linalg.norm(to_light, axis=1)
    occlusion = np.concatenate([origin, to_light / distance[:, None],
                                (distance * (1.0 - 1e-4))[:, None], np.ones((count, 1))], 1)
    return closest.astype(np.float32), occlusion.astype(np.float32)


def path_rays(scene, mi, count):
    """The rays of `count` three-bounce paths from the kit's camera (see the module documentation)."""
    rng = np.random.default_rng(11)
    side = int(np.sqrt(count))
    count = side * side
    eye = np.array([0.0, 0.0, 2.8], np.float32)
    tan_half = np.tan(np.radians(22.5))
    px = (np.arange(count) % side + rng.uniform(0, 1, count)) / side * 2.0 - 1.0
    py = 1.0 - (np.arange(count) // side + rng.uniform(0, 1, count)) / side * 2.0
    d = np.stack([px * tan_half, py * tan_half, -np.ones(count)], 1)
    d /= np.linalg.norm(d, axis=1)[:, None]
    o = np.tile(eye, (count, 1))
    closest, occlusion = [], []
    for bounce in range(4):
        closest.append(np.concatenate([o, d, np.full((len(o), 1), np.inf), np.zeros((len(o), 1))], 1))
        ray = mi.Ray3f(o=mi.Point3f(*(mi.Float(np.ascontiguousarray(o[:, k], np.float32)) for k in range(3))),
                       d=mi.Vector3f(*(mi.Float(np.ascontiguousarray(d[:, k], np.float32)) for k in range(3))))
        si = scene.ray_intersect(ray)
        valid = np.asarray(si.is_valid(), bool)
        p = np.stack([np.asarray(si.p[k]) for k in range(3)], 1)[valid]
        n = np.stack([np.asarray(si.n[k]) for k in range(3)], 1)[valid]
        dv = d[valid]
        n = np.where((np.sum(n * dv, 1) > 0)[:, None], -n, n)
        if bounce == 3 or len(p) == 0:
            break
        o = p + 1e-4 * n
        light = np.stack([rng.uniform(-0.25, 0.25, len(o)), np.full(len(o), 0.995),
                          rng.uniform(-0.2, 0.2, len(o))], 1)
        to_light = light - o
        dist = np.linalg.norm(to_light, axis=1)
        occlusion.append(np.concatenate([o, to_light / dist[:, None], (dist * (1.0 - 1e-4))[:, None],
                                         np.ones((len(o), 1))], 1))
        # Cosine-distributed about n (Malley: a uniform disk point lifted onto the hemisphere).
        r, phi = np.sqrt(rng.uniform(0, 1, len(o))), rng.uniform(0, 2 * np.pi, len(o))
        local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0.0, 1.0 - r * r))], 1)
        helper = np.where((np.abs(n[:, 0]) > 0.5)[:, None], np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]))
        t1 = np.cross(n, helper)
        t1 /= np.linalg.norm(t1, axis=1)[:, None]
        t2 = np.cross(n, t1)
        d = local[:, :1] * t1 + local[:, 1:2] * t2 + local[:, 2:] * n
        d /= np.linalg.norm(d, axis=1)[:, None]
    return np.concatenate(closest).astype(np.float32), np.concatenate(occlusion).astype(np.float32)


def main():
    if len(sys.argv) not in (3, 4, 5, 6):
        sys.exit(__doc__)
    scene_name, ray_file = sys.argv[1], sys.argv[2]
    ray_set = sys.argv[5] if len(sys.argv) > 5 else "random"
    if ray_set not in ("random", "paths"):
        sys.exit(f"unknown ray set {ray_set!r}: random or paths")
    count = int(sys.argv[3]) if len(sys.argv) > 3 and sys.argv[3] else (1 << 21 if ray_set == "random" else 1 << 18)
    threads = int(sys.argv[4]) if len(sys.argv) > 4 else 2

    kit = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "peer")
    sys.path.insert(0, os.environ.get("PEER_KIT", kit))
    import scenes as S
    import drjit as dr
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(threads)
    scene = mi.load_dict(S.scene_dict(scene_name))
    dr.eval()
    dr.sync_thread()

    closest, occlusion = rays(count) if ray_set == "random" else path_rays(scene, mi, count)
    tmp = ray_file + ".tmp"
    np.concatenate([closest, occlusion]).astype("<f4").tofile(tmp)
    os.replace(tmp, ray_file)

    def ray_of(a):
        # Mitsuba has no infinite maxt; its own rays use the largest float.
        maxt = np.where(np.isinf(a[:, 6]), np.finfo(np.float32).max, a[:, 6]).astype(np.float32)
        return mi.Ray3f(o=mi.Point3f(*(mi.Float(np.ascontiguousarray(a[:, k])) for k in range(3))),
                        d=mi.Vector3f(*(mi.Float(np.ascontiguousarray(a[:, k])) for k in range(3, 6))),
                        maxt=mi.Float(maxt), time=mi.Float(0.0), wavelengths=mi.Color0f())

    out = {"scene": scene_name, "set": ray_set, "threads": dr.thread_count()}
    for kind, a in (("closest", closest), ("occlusion", occlusion)):
        count = len(a)
        ray = ray_of(a)
        dr.eval(ray)
        dr.sync_thread()
        times = []
        for _ in range(4):
            start = time.perf_counter()
            if kind == "closest":
                pi = scene.ray_intersect_preliminary(ray, coherent=False)
                dr.eval(pi.t)
                found = pi.is_valid()
            else:
                found = scene.ray_test(ray, coherent=False)
                dr.eval(found)
            dr.sync_thread()
            times.append(time.perf_counter() - start)
        hits = int(np.asarray(dr.count(found)).reshape(-1)[0])
        median = sorted(times[1:])[1]
        out[kind] = {"hits": hits, "median_s": median, "rays_per_second": count / median,
                     "times_s": [round(t, 5) for t in times]}
        print(f"mitsuba {scene_name} {ray_set} {kind}: {hits} of {count} hit, {count / median / 1e6:.2f} M rays/s "
              f"(median {median * 1e3:.1f} ms)")
    print(json.dumps(out))


if __name__ == "__main__":
    main()
