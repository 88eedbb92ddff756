"""Many views as Ray tasks: the summed gradient equals the serial sum over views."""

import numpy as np
import pytest

import implicit_psdr as ip

ray = pytest.importorskip("ray")
from implicit_psdr.ray import multi_view_grad, serial_grad  # noqa: E402


@pytest.fixture(scope="module")
def local_ray():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


def views():
    """Four cameras on a circle around the ball."""
    out = []
    for k in range(4):
        a = 2 * np.pi * k / 4
        out.append({"camera.origin.x": 5 * np.sin(a), "camera.origin.z": 5 * np.cos(a)})
    return out


def test_ray_gradient_is_the_serial_sum(small, local_ray):
    scene, _ = small("grid", width=12, height=10)
    truth = scene.copy()
    truth.set("ball.radius", 0.5)
    targets = [ip.render(ip.ray.apply_view(truth, v), spp=8) for v in views()]
    kw = dict(params=["ball.radius", "ball.center.x"], grids=["baked_blob.sdf.child"], seed=3)
    loss, g = multi_view_grad(scene, views(), targets, **kw)
    serial_loss, serial = serial_grad(scene, views(), targets, **kw)
    assert loss == serial_loss > 0
    assert list(g) == list(serial)
    for name in serial:
        assert np.array_equal(g[name], serial[name]), name
    assert g["ball.radius"] != 0
    # Each view contributes: the sum is not one view's gradient.
    one_loss, _ = serial_grad(scene, views()[:1], targets[:1], **kw)
    assert one_loss < loss
