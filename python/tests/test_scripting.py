"""Scripting as from the command line: fd, bake, write_exr and Scene.save give the command-line
tool's numbers and files, bit for bit; errors speak Python (the argument's name, the package's
exception name); a grid must be floats, as in a .npy file."""

import json

import numpy as np
import pytest

import implicit_psdr as ip
from conftest import write_scene

GRID = "baked_blob.sdf.child"


def test_fd_is_the_cli_exr(small, cli, tmp_path):
    scene, doc = small("sphere_floor")
    params = ["ball.radius", "light.center.x"]
    d = ip.fd(scene, params, seed=3)
    cli("fd", write_scene(doc, tmp_path), "--seed", 3, "--param", params[0], "--param", params[1],
        cwd=tmp_path)
    ip.write_exr(tmp_path / "mine.exr", d)
    assert_same_exr(tmp_path / "mine.exr", tmp_path / "fd.exr")
    # One name is a list of one.
    assert np.array_equal(ip.fd(scene, "ball.radius", seed=3)["d.ball.radius"], d["d.ball.radius"])
    with pytest.raises(ValueError, match="h: must be a finite number > 0, got -1"):
        ip.fd(scene, "ball.radius", h=-1)


def assert_same_exr(a, b):
    """Same channels, in the same order, with the same values."""
    ca, cb = ip.read_exr(a), ip.read_exr(b)
    assert list(ca) == list(cb)
    for name in ca:
        assert np.array_equal(ca[name], cb[name]), name


def test_write_exr_of_diff_is_the_cli_exr(small, cli, tmp_path):
    scene, doc = small("sphere_floor")
    d = ip.diff(scene, "ball.radius", terms=True)
    assert list(d)[:2] == ["image", "d.ball.radius"]
    cli("diff", write_scene(doc, tmp_path), "--param", "ball.radius", "--terms", cwd=tmp_path)
    ip.write_exr(tmp_path / "new" / "mine.exr", d)
    assert_same_exr(tmp_path / "new" / "mine.exr", tmp_path / "diff.exr")
    # One channel per 2-d array, by its name.
    ip.write_exr(tmp_path / "one.exr", {"Z": d["image"][..., 0]})
    assert list(ip.read_exr(tmp_path / "one.exr")) == ["Z"]
    with pytest.raises(ValueError, match=r"channels\['x'\]: expected shape"):
        ip.write_exr(tmp_path / "bad.exr", {"x": np.zeros((2, 3, 4), np.float32)})
    with pytest.raises(ValueError, match="one non-empty size"):
        ip.write_exr(tmp_path / "bad.exr", {"a": np.zeros((2, 3)), "b": np.zeros((3, 2))})
    assert not (tmp_path / "bad.exr").exists()


def test_bake_is_the_cli_grid(small, cli, tmp_path):
    scene, doc = small("sphere_floor")
    values, node = ip.bake(scene, "ball", 8)
    stdout = cli("bake", write_scene(doc, tmp_path), "--shape", "ball", "--res", 8, "--out",
                 "ball.npy", cwd=tmp_path)
    assert values.dtype == np.float32
    assert np.array_equal(values, np.load(tmp_path / "ball.npy"))
    printed = json.loads(stdout.splitlines()[-1])
    assert node == {k: v for k, v in printed.items() if k != "file"}
    with pytest.raises(ip.SceneError, match="shape: no shape named"):
        ip.bake(scene, "bal", 8)
    with pytest.raises(ValueError, match="res: must be >= 4, got 2"):
        ip.bake(scene, "ball", 2)


def test_save_writes_a_scene_file_with_its_grids(small, cli, tmp_path):
    scene, _ = small("grid")
    scene.set("ball.radius", 0.7)
    grid = scene.grid(GRID)
    scene.set_grid(GRID, grid + np.float32(0.05))
    path = tmp_path / "out" / "fitted.json"
    scene.save(path)
    assert (tmp_path / "out" / f"fitted.{GRID}.npy").is_file()
    again = ip.Scene.load(path)
    assert again.params()["ball.radius"] == np.float32(0.7)
    assert np.array_equal(again.grid(GRID), scene.grid(GRID))
    image = ip.render(scene)
    assert np.array_equal(ip.render(again), image)
    cli("render", path, "--out", "r.exr", "--png", "r.png", cwd=tmp_path)
    exr = ip.read_exr(tmp_path / "r.exr")
    assert np.array_equal(np.stack([exr[c] for c in "RGB"], axis=-1), image)
    # to_dict: the file's structure with the current values.
    d = scene.to_dict()
    assert d["shapes"] == json.loads(path.read_text())["shapes"] or GRID
    ball = next(s for s in d["shapes"] if s["name"] == "ball")
    assert ball["sdf"]["radius"] == pytest.approx(0.7)
    with pytest.raises(ip.SceneError, match="must end in .json"):
        scene.save(tmp_path / "fitted.txt")


def test_errors_speak_python(small):
    scene, _ = small("sphere_floor")
    for call, match in [
        (lambda: ip.render(scene, spp=-1), "spp: must be >= 1, got -1"),
        (lambda: ip.render(scene, seed=-1), r"seed: must be in \[0, 2\*\*64\), got -1"),
        (lambda: ip.render(scene, threads=-2), "threads: must be >= 1, got -2"),
        (lambda: ip.diff(scene, "ball.radius", spp_primary=-1), "spp_primary: must be a finite number >= 0"),
        (lambda: ip.grad(scene, adjoint=np.ones((12, 16, 3)), params="ball.radius",
                         spp_secondary=float("nan")),
         "spp_secondary: must be a finite number >= 0, got NaN"),
        (lambda: ip.grad(scene, adjoint=np.ones((12, 16, 3)), params="ball.radius", spp=-3),
         "spp: must be >= 1, got -3"),
    ]:
        with pytest.raises(ValueError, match=match):
            call()
    with pytest.raises(TypeError, match="params: expected a name or a list of names"):
        ip.diff(scene, 3)
    # Boundary budgets may be fractional: a quarter of a sample per pixel is still a secondary term.
    quarter = ip.diff(scene, "ball.radius", terms=True, spp_secondary=0.25)
    assert "d_secondary.ball.radius" in quarter
    assert np.isfinite(quarter["d.ball.radius"]).all()
    # A single name is a list of one.
    one = ip.diff(scene, "ball.radius")
    assert np.array_equal(one["d.ball.radius"], ip.diff(scene, ["ball.radius"])["d.ball.radius"])
    _, g = ip.grad(scene, adjoint=np.ones((12, 16, 3), np.float32), params="ball.radius")
    assert list(g) == ["ball.radius"]
    assert repr(ip.SceneError) == "<class 'implicit_psdr.SceneError'>"
    assert issubclass(ip.SceneError, ValueError)


def test_grids_must_be_floats_as_in_a_file(small):
    scene, _ = small("grid")
    grid = scene.grid(GRID)
    for dtype in [np.int32, np.int64, np.bool_]:
        with pytest.raises(ValueError, match=f"expected an array of floats.*got dtype"):
            scene.set_grid(GRID, grid.astype(dtype))
    assert np.array_equal(scene.grid(GRID), grid)
    scene.set_grid(GRID, grid.astype(np.float64))
    assert np.array_equal(scene.grid(GRID), grid)


def test_a_light_that_lights_nothing_warns(small):
    _, doc = small("sphere_floor")
    doc["emitters"] = [dict(doc["emitters"][0], normal=[0, 1, 0])]
    with pytest.warns(RuntimeWarning, match='emitter "light" lights nothing the camera sees'):
        scene = ip.Scene.from_dict(doc)
    assert ip.render(scene).max() == 0


def test_optimize_warns_about_a_shape_outside_every_view(small, tmp_path):
    _, doc = small("sphere_floor")
    far = dict(doc["shapes"][0], name="behind")
    far["sdf"] = dict(far["sdf"], center=[0, 1, 20])
    doc["shapes"].append(far)
    path = write_scene(doc, tmp_path)
    front = {"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45}
    config = {"scene": path.name, "target": {"scene": path.name}, "views": [front, front],
              "optimize": {"params": ["ball.radius"]}, "iterations": 1, "spp": 1,
              "target_spp": 1}
    with pytest.warns(RuntimeWarning, match='shape "behind" lies outside every view'):
        ip.optimize(config, base_dir=tmp_path)
