"""Scene: loading, parameters, grids, pickling, and the errors of bad input."""

import math
import pickle

import numpy as np
import pytest

import implicit_psdr as ip
from conftest import SCENES, write_scene

GRID = "baked_blob.sdf.child"


def test_load_equals_from_dict(small, tmp_path):
    scene, doc = small("sphere_floor")
    loaded = ip.Scene.load(write_scene(doc, tmp_path))
    assert loaded.params() == scene.params()
    assert np.array_equal(ip.render(loaded, seed=3), ip.render(scene, seed=3))
    # numpy values in the dict are their numbers.
    doc["camera"]["origin"] = np.array(doc["camera"]["origin"], dtype=np.float32)
    doc["camera"]["fov_y"] = np.float32(doc["camera"]["fov_y"])
    assert ip.Scene.from_dict(doc).params() == scene.params()
    assert (scene.width, scene.height, scene.spp) == (16, 12, 4)


@pytest.mark.parametrize("name", ["sphere_floor", "csg", "environment", "grid", "blocks"])
def test_params_are_the_cli_listing(small, cli, tmp_path, name):
    scene, doc = small(name)
    listed = {}
    for line in cli("params", write_scene(doc, tmp_path), cwd=tmp_path).splitlines():
        name, rest = line.split(" ", 1)
        if rest.startswith("["):
            listed[name] = tuple(int(n) for n in rest[1 : rest.index("]")].split(","))
        else:
            listed[name] = float(rest)
    params = scene.params()
    assert list(params) == list(listed)
    for k, v in listed.items():
        assert params[k] == pytest.approx(v, rel=1e-6), k


def test_set_changes_the_render_and_checks_the_range(small):
    scene, _ = small("sphere_floor")
    before = ip.render(scene)
    scene.set("ball.radius", 0.7)
    assert scene.params()["ball.radius"] == pytest.approx(0.7)
    assert not np.array_equal(ip.render(scene), before)
    with pytest.raises(ip.SceneError, match=r"^ball\.radius: must be > 0, got -1$"):
        scene.set("ball.radius", -1)
    assert scene.params()["ball.radius"] == pytest.approx(0.7)


def test_unknown_parameter_names_near_matches(small):
    scene, _ = small("sphere_floor")
    with pytest.raises(ip.SceneError, match=r'no parameter "ball\.radiu"; did you mean ball\.radius\? '
                                            r'\(Scene\.params\(\) lists them\)'):
        scene.set("ball.radiu", 1.0)
    with pytest.raises(ip.SceneError, match=r'no parameter "nope"'):
        ip.diff(scene, ["nope"])
    with pytest.raises(ip.SceneError, match=r'no parameter "nope"'):
        ip.grad(scene, adjoint=np.zeros((12, 16, 3)), params=["nope"])


def test_nan_values_are_refused(small):
    scene, doc = small("sphere_floor")
    with pytest.raises(ip.SceneError, match=r"^ball\.radius: must be a finite number, got NaN$"):
        scene.set("ball.radius", math.nan)
    doc["camera"]["fov_y"] = math.nan
    with pytest.raises(ip.SceneError, match=r"^camera\.fov_y: must be a finite number, got NaN$"):
        ip.Scene.from_dict(doc)


def test_malformed_dicts_name_the_field(small):
    _, doc = small("sphere_floor")
    doc["camera"]["colour"] = 1
    with pytest.raises(ip.SceneError, match=r"^camera\.colour: unknown field, expected one of origin"):
        ip.Scene.from_dict(doc)
    _, doc = small("sphere_floor")
    doc["shapes"][0]["sdf"]["radius"] = -1
    with pytest.raises(ip.SceneError, match=r"^shapes\[0\]\.sdf\.radius: must be > 0, got -1"):
        ip.Scene.from_dict(doc)
    _, doc = small("sphere_floor")
    doc["shapes"][0]["sdf"]["center"] = [0, 0, object()]
    with pytest.raises(ip.SceneError, match=r"^shapes\[0\]\.sdf\.center\[2\]: cannot be converted"):
        ip.Scene.from_dict(doc)
    with pytest.raises(ip.SceneError, match=r"^camera: expected an object"):
        ip.Scene.from_dict({"camera": 1})


def test_load_errors_name_the_file(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{"camera": ')
    with pytest.raises(ip.SceneError, match=r"broken\.json: "):
        ip.Scene.load(path)
    with pytest.raises(ip.SceneError, match=r"missing\.json: "):
        ip.Scene.load(tmp_path / "missing.json")


def test_grids_round_trip_and_change_the_surface(small):
    scene, _ = small("grid")
    values = scene.grid(GRID)
    assert values.dtype == np.float32
    assert values.shape == scene.params()[GRID + ".values"] == (27, 32, 27)
    assert np.array_equal(values, np.load(SCENES / "blob.npy"))
    image = ip.render(scene)
    scene.set_grid(GRID + ".values", values)
    assert np.array_equal(ip.render(scene), image)
    scene.set_grid(GRID, values - 0.1)
    assert np.array_equal(scene.grid(GRID), values - np.float32(0.1))
    assert not np.array_equal(ip.render(scene), image)
    # Another resolution of the same box.
    scene.set_grid(GRID, values[::2, ::2, ::2])
    assert scene.params()[GRID + ".values"] == (14, 16, 14)


def test_bad_grids_raise_with_the_message(small):
    scene, _ = small("grid")
    with pytest.raises(ValueError, match=r"expected a 3-d array of shape \(nz, ny, nx\), got shape \(27, 32\)"):
        scene.set_grid(GRID, np.zeros((27, 32)))
    bad = scene.grid(GRID)
    bad[1, 2, 3] = np.nan
    with pytest.raises(ValueError, match=r"must be finite, got NaN at index \[1, 2, 3\]"):
        scene.set_grid(GRID, bad)
    with pytest.raises(ip.SceneError, match=r"grid dimensions must be at least 4"):
        scene.set_grid(GRID, np.zeros((3, 8, 8)))
    with pytest.raises(ip.SceneError, match=r'no grid node "blob" \(grid nodes: baked_blob\.sdf\.child\)'):
        scene.grid("blob")
    with pytest.raises(ip.SceneError, match=r'no grid node "blob"'):
        scene.set_grid("blob", np.zeros((4, 4, 4)))


def test_pickle_keeps_values_and_grids(small):
    scene, _ = small("grid")
    scene.set("ball.radius", 0.55)
    scene.set_grid(GRID, scene.grid(GRID)[::2, ::2, ::2] + 0.05)
    copy = pickle.loads(pickle.dumps(scene))
    assert copy.params() == scene.params()
    assert np.array_equal(copy.grid(GRID), scene.grid(GRID))
    assert np.array_equal(ip.render(copy, seed=2), ip.render(scene, seed=2))


def test_copy_is_independent(small):
    scene, _ = small("sphere_floor")
    other = scene.copy()
    other.set("ball.radius", 0.5)
    assert scene.params()["ball.radius"] == 1.0
