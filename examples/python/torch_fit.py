"""A training loop with PyTorch: fit the ball's radius and colour to a target image with Adam.

    pip install torch
    python examples/python/torch_fit.py

The render is a differentiable function of the tensors (implicit_psdr.torch.render); the loss is
any torch expression of the image; loss.backward() runs the renderer's reverse mode.
"""
import torch

import implicit_psdr as ip
import implicit_psdr.torch as ipt

scene = ip.Scene.load("scenes/sphere_floor.json")
target = torch.from_numpy(ip.render(scene, spp=64))      # radius 1, albedo 0.8

radius = torch.tensor(0.7, requires_grad=True)
albedo = torch.tensor([0.4, 0.8, 0.8], requires_grad=True)
optimizer = torch.optim.Adam([radius, albedo], lr=0.04)
for step in range(30):
    optimizer.zero_grad()
    image = ipt.render(
        scene,
        {"ball.radius": radius, "ball.albedo.r": albedo[0], "ball.albedo.g": albedo[1],
         "ball.albedo.b": albedo[2]},
        spp=16,
        seed=2 * step,
    )
    loss = torch.nn.functional.mse_loss(image, target)
    loss.backward()
    optimizer.step()
    with torch.no_grad():
        albedo.clamp_(0.0, 1.0)
    if step % 5 == 4:
        print(f"step {step}: loss {loss.item():.3e}, radius {radius.item():.3f}, "
              f"albedo {[round(a, 3) for a in albedo.tolist()]}")
