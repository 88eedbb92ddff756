"""grad: against forward mode (the dot-product test), against the command-line tool, and its errors."""

import json

import numpy as np
import pytest

import implicit_psdr as ip
from conftest import write_scene

GRID = "baked_blob.sdf.child"


def dot(a, b):
    return float(np.sum(a.astype(np.float64) * b.astype(np.float64)))


def test_adjoint_gradient_is_the_contraction_of_diff(small):
    # sum_j A_j dI_j/dP from forward mode equals reverse mode's dP for the same samples (seed).
    scene, _ = small("sphere_floor", spp=8)
    params = ["ball.radius", "ball.center.x", "light.center.x", "ball.albedo.g"]
    adjoint = np.random.default_rng(2).standard_normal((12, 16, 3)).astype(np.float32)
    d = ip.diff(scene, params, seed=3)
    loss, g = ip.grad(scene, adjoint=adjoint, params=params, seed=3)
    assert loss is None and list(g) == params
    for p in params:
        expected = dot(adjoint, d[f"d.{p}"])
        assert abs(expected) > 1e-3, p
        assert g[p] == pytest.approx(expected, rel=1e-4, abs=1e-6), p


def test_grid_gradient_is_the_contraction_of_a_direction(small):
    scene, _ = small("grid", width=12, height=10)
    rng = np.random.default_rng(4)
    adjoint = rng.standard_normal((10, 12, 3)).astype(np.float32)
    u = rng.standard_normal(scene.grid(GRID).shape).astype(np.float32)
    d = ip.diff(scene, grid_directions={GRID: u}, seed=1)
    _, g = ip.grad(scene, adjoint=adjoint, grids=[GRID + ".values"], seed=1)
    assert g[GRID].shape == u.shape and g[GRID].dtype == np.float32
    forward = dot(adjoint, d[f"d.{GRID}.values"])
    assert abs(forward) > 1e-3
    assert dot(u, g[GRID]) == pytest.approx(forward, rel=1e-3)


def test_loss_gradient_is_the_cli_json(small, cli, tmp_path):
    scene, doc = small("grid", width=12, height=10)
    target_scene = scene.copy()
    target_scene.set("ball.radius", 0.5)
    target = ip.render(target_scene, spp=16)
    path = write_scene(doc, tmp_path)
    # The target as the tool reads it: through an EXR written by the tool itself.
    target_doc = dict(doc, spp=16)
    target_doc["shapes"] = [dict(s) for s in doc["shapes"]]
    target_doc["shapes"][1] = dict(doc["shapes"][1], sdf=dict(doc["shapes"][1]["sdf"], radius=0.5))
    (tmp_path / "t.json").write_text(json.dumps(target_doc))
    cli("render", "t.json", "--out", "t.exr", "--png", "t.png", cwd=tmp_path)
    exr = ip.read_exr(tmp_path / "t.exr")
    assert np.array_equal(np.stack([exr[c] for c in "RGB"], axis=-1), target)

    params = ["ball.radius", "key.center.y"]
    loss, g = ip.grad(scene, target=target, params=params, grids=[GRID], seed=2)
    cli("grad", path, "--target", "t.exr", "--param", params[0], "--param", params[1], "--grid",
        GRID, "--seed", 2, "--out", "g.json", cwd=tmp_path)
    expected = json.loads((tmp_path / "g.json").read_text())
    assert loss == expected["loss"] > 0
    assert [g[p] for p in params] == [expected["params"][p] for p in params]
    assert np.array_equal(g[GRID], np.load(tmp_path / expected["grids"][GRID]))
    assert g["ball.radius"] != 0


def test_l1_loss_and_its_gradient(small):
    scene, _ = small("sphere_floor")
    target = np.zeros((12, 16, 3), np.float32)
    image = ip.render(scene)
    loss, g = ip.grad(scene, target=target, loss="l1", params=["ball.albedo.r"])
    assert loss == pytest.approx(float(np.abs(image.astype(np.float64)).mean()), rel=1e-6)
    assert g["ball.albedo.r"] > 0


def test_bad_gradient_requests(small):
    scene, _ = small("sphere_floor")
    image = np.zeros((12, 16, 3), np.float32)
    with pytest.raises(ValueError, match="exactly one of target"):
        ip.grad(scene, params=["ball.radius"])
    with pytest.raises(ValueError, match="exactly one of target"):
        ip.grad(scene, target=image, adjoint=image, params=["ball.radius"])
    with pytest.raises(ValueError, match="nothing to differentiate"):
        ip.grad(scene, target=image)
    with pytest.raises(ValueError, match=r"adjoint: expected shape \(12, 16, 3\) .* got \(16, 12, 3\)"):
        ip.grad(scene, adjoint=np.zeros((16, 12, 3)), params=["ball.radius"])
    bad = image.copy()
    bad[2, 3, 1] = np.nan
    with pytest.raises(ValueError, match=r"target: must be finite, got NaN at index \[2, 3, 1\]"):
        ip.grad(scene, target=bad, params=["ball.radius"])
    with pytest.raises(ValueError, match=r'loss: unknown loss "l3"'):
        ip.grad(scene, target=image, loss="l3", params=["ball.radius"])
    with pytest.raises(ip.SceneError, match=r'^params: parameter "ball.radius" is given twice$'):
        ip.grad(scene, target=image, params=["ball.radius", "ball.radius"])
    with pytest.raises(ip.SceneError, match=r'no grid node "blob" \(the scene has no grid\)'):
        ip.grad(scene, target=image, grids=["blob"])
