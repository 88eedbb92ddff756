#!/usr/bin/env python3
"""Mitsuba 3's throughput on the many-balls bench scene, for `cargo bench --bench bvh`.

Reads a scene written by `examples/many_balls.rs` (the default scene with its ball replaced by N balls),
builds the same scene in Mitsuba 3 (analytic spheres, the floor slab's top face as a rectangle, the
rectangular light as a one-sided area light, the same camera, tent filter, `direct` with one light and
one BSDF sample), renders it once to compile its kernels, then REPS more times, and prints the median
throughput as `M samples/s: X` (samples = pixels x spp). Variant: MITSUBA_VARIANT, else `llvm_ad_rgb`.

Usage: mitsuba_balls.py SCENE.json [REPS]
"""
import json
import os
import statistics
import sys
import time


def scene_dict(doc, mi):
    cam = doc["camera"]
    T = mi.ScalarTransform4f
    d = {
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 1},
        "sensor": {
            "type": "perspective",
            "fov": cam["fov_y"],
            "fov_axis": "y",
            "to_world": T().look_at(origin=cam["origin"], target=cam["target"], up=cam["up"]),
            "film": {
                "type": "hdrfilm",
                "width": cam["width"],
                "height": cam["height"],
                "rfilter": {"type": "tent"},
            },
            "sampler": {"type": "independent", "sample_count": doc["spp"]},
        },
    }
    for s in doc["shapes"]:
        sdf, albedo = s["sdf"], s["bsdf"]["albedo"]
        bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": albedo}}
        if sdf["type"] == "sphere":
            d[s["name"]] = {"type": "sphere", "center": sdf["center"], "radius": sdf["radius"], "bsdf": bsdf}
        elif sdf["type"] == "box":
            # The slab's top face: all a camera above it sees of it.
            (cx, cy, cz), (hx, hy, hz) = sdf["center"], sdf["half_size"]
            d[s["name"]] = {
                "type": "rectangle",
                "to_world": T().translate([cx, cy + hy, cz]).rotate([1, 0, 0], -90).scale([hx, hz, 1]),
                "bsdf": bsdf,
            }
        else:
            raise SystemExit(f"shape {s['name']}: {sdf['type']} has no Mitsuba counterpart here")
    for e in doc["emitters"]:
        if e["type"] != "rectangle":
            raise SystemExit(f"emitter {e['name']}: {e['type']} has no Mitsuba counterpart here")
        (sx, sy) = e["size"]
        # Mitsuba's rectangle spans [-1, 1]^2 in x, y facing +z; this light faces down (-y).
        d[e["name"]] = {
            "type": "rectangle",
            "to_world": T().translate(e["center"]).rotate([1, 0, 0], 90).scale([sx / 2, sy / 2, 1]),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": e["radiance"]}},
        }
    return d


def main():
    path = sys.argv[1]
    reps = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(os.environ.get("MITSUBA_VARIANT", "llvm_ad_rgb"))
    doc = json.load(open(path))
    scene = mi.load_dict(scene_dict(doc, mi))
    samples = doc["camera"]["width"] * doc["camera"]["height"] * doc["spp"]
    times = []
    for k in range(reps + 1):
        start = time.perf_counter()
        image = mi.render(scene, seed=k)
        dr.eval(image)
        dr.sync_thread()
        if k > 0:
            times.append(time.perf_counter() - start)
    print(f"M samples/s: {samples / statistics.median(times) / 1e6:.3f}")


if __name__ == "__main__":
    main()
