"""The PyTorch adapter: loss.backward() through a render gives grad's gradient."""

import numpy as np
import pytest

import implicit_psdr as ip

torch = pytest.importorskip("torch")
import implicit_psdr.torch as ipt  # noqa: E402

GRID = "baked_blob.sdf.child"


def test_backward_is_grad_with_grad_output_as_adjoint(small):
    scene, _ = small("grid", width=12, height=10)
    target = torch.from_numpy(ip.render(scene, spp=16, seed=9)) * 0.9
    radius = torch.tensor(0.55, requires_grad=True)
    values = torch.tensor(scene.grid(GRID), requires_grad=True)
    image = ipt.render(scene, {"ball.radius": radius}, {GRID: values}, seed=4)
    assert image.shape == (10, 12, 3) and image.dtype == torch.float32
    loss = ((image - target) ** 2).mean()
    loss.backward()

    moved = scene.copy()
    moved.set("ball.radius", 0.55)
    assert np.array_equal(image.detach().numpy(), ip.render(moved, seed=4))
    adjoint = (2 * (image - target) / image.numel()).detach().numpy()
    _, g = ip.grad(moved, adjoint=adjoint, params=["ball.radius"], grids=[GRID], seed=5)
    # torch forms grad_output with its own rounding: equal to a few ulps of the largest entry.
    assert radius.grad.item() == pytest.approx(g["ball.radius"], rel=1e-5)
    scale = np.abs(g[GRID]).max()
    assert scale > 0
    assert np.allclose(values.grad.numpy(), g[GRID], rtol=0, atol=1e-5 * scale)
    assert radius.grad.item() != 0
    assert scene.params()["ball.radius"] == pytest.approx(0.6)


def test_gradient_steps_lower_the_loss(small):
    # The ball is too large: the gradient says so, and steps against it lower the loss.
    scene, _ = small("sphere_floor", width=24, height=18, spp=16)
    truth = scene.copy()
    truth.set("ball.radius", 0.8)
    target = torch.from_numpy(ip.render(truth, spp=64))
    radius = torch.tensor(1.0, requires_grad=True)
    losses = []
    for step in range(3):
        image = ipt.render(scene, {"ball.radius": radius}, seed=2 * step)
        loss = ((image - target) ** 2).mean()
        loss.backward()
        losses.append(loss.item())
        assert radius.grad.item() > 0, step
        with torch.no_grad():
            radius -= 0.08
            radius.grad.zero_()
    assert losses[0] > losses[1] > losses[2]
