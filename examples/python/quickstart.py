"""Render, differentiate and take gradient steps: python examples/python/quickstart.py"""
import implicit_psdr as ip

scene = ip.Scene.load("scenes/sphere_floor.json")
target = ip.render(scene, spp=64)                      # (64, 64, 3) float32, the ball of radius 1
d = ip.diff(scene, ["ball.radius"], spp=16)            # {"image": ..., "d.ball.radius": ...}
print("sum of dI/d radius:", d["d.ball.radius"].sum())

scene.set("ball.radius", 0.8)                          # start from a smaller ball
for step in range(8):
    loss, g = ip.grad(scene, target=target, params=["ball.radius"], spp=16, seed=2 * step)
    radius = scene.params()["ball.radius"] - 2.0 * g["ball.radius"]
    scene.set("ball.radius", radius)
    print(f"step {step}: loss {loss:.3e}, radius {radius:.4f}")
