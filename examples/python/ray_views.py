"""Many views on Ray: fit the ball of scenes/sphere_floor.json to target images from eight cameras,
each step's gradient summed over the views by one Ray task per view.

    pip install ray
    python examples/python/ray_views.py             # the optimisation, on the local cores
    python examples/python/ray_views.py --measure   # time one gradient: serial against Ray

ray.init() starts Ray on this machine's cores. On a Ray cluster (this package installed on every
node), the same script joins it with RAY_ADDRESS=auto (or an address) in the environment, or
--address auto: each view then runs wherever Ray has a free CPU.
"""
import argparse
import math
import time

import numpy as np
import ray

import implicit_psdr as ip
from implicit_psdr.ray import apply_view, multi_view_grad, serial_grad

parser = argparse.ArgumentParser()
parser.add_argument("--address", help="a Ray cluster to join (default: RAY_ADDRESS, else local)")
parser.add_argument("--views", type=int, default=8)
parser.add_argument("--spp", type=int, default=16)
parser.add_argument("--steps", type=int, default=12)
parser.add_argument("--measure", action="store_true", help="time serial against Ray, then stop")
parser.add_argument("--rounds", type=int, default=5, help="rounds of --measure")
args = parser.parse_args()
ray.init(address=args.address)

# Eight cameras on a circle 5 units from the ball, 3 units up, all looking at it.
views = [
    {"camera.origin.x": 5 * math.sin(2 * math.pi * k / args.views), "camera.origin.y": 3.0,
     "camera.origin.z": 5 * math.cos(2 * math.pi * k / args.views)}
    for k in range(args.views)
]
scene = ip.Scene.load("scenes/sphere_floor.json")
targets = [ip.render(apply_view(scene, v), spp=64, seed=100 + k) for k, v in enumerate(views)]
targets = [ray.put(t) for t in targets]  # shipped once, used by every step
params = ["ball.radius", "ball.center.x", "ball.center.z"]

if args.measure:
    kw = dict(params=params, spp=args.spp)
    multi_view_grad(scene, views, targets, **kw)  # warm up the workers
    plain = [ray.get(t) for t in targets]
    runs = {
        "serial, 1 thread": lambda: serial_grad(scene, views, plain, threads=1, **kw),
        "serial, all cores (rayon)": lambda: serial_grad(scene, views, plain, **kw),
        "Ray, 1 task per view, 1 thread each": lambda: multi_view_grad(scene, views, targets, **kw),
    }
    # Rounds of the three, alternating, so that a busy moment of a shared machine hits them alike.
    times = {label: [] for label in runs}
    for _ in range(args.rounds):
        for label, run in runs.items():
            start = time.perf_counter()
            run()
            times[label].append(time.perf_counter() - start)
    ray_time = np.median(times["Ray, 1 task per view, 1 thread each"])
    for label, t in times.items():
        print(f"{label}: median {np.median(t):.2f} s over {args.rounds} rounds "
              f"({np.median(t) / ray_time:.2f}x Ray's)")
    raise SystemExit

# Start from a smaller ball off to the side; plain gradient descent with a fixed step.
for name, value in [("ball.radius", 0.75), ("ball.center.x", 0.3), ("ball.center.z", -0.2)]:
    scene.set(name, value)
for step in range(args.steps):
    loss, g = multi_view_grad(scene, views, targets, params=params, spp=args.spp, seed=2 * step)
    for name in params:
        scene.set(name, scene.params()[name] - 0.6 * g[name])
    values = ", ".join(f"{n} {scene.params()[n]:+.3f}" for n in params)
    print(f"step {step}: loss {loss:.3e}; {values}")
