"""render and diff: the command-line tool's images and EXR channels, bit for bit."""

import numpy as np
import pytest

import implicit_psdr as ip
from conftest import write_scene

GRID = "baked_blob.sdf.child"


def test_render_is_the_cli_image(small, cli, tmp_path):
    scene, doc = small("csg")
    image = ip.render(scene, seed=5)
    assert image.shape == (12, 16, 3) and image.dtype == np.float32
    assert image.mean() > 0
    cli("render", write_scene(doc, tmp_path), "--seed", 5, "--out", "r.exr", "--png", "r.png",
        cwd=tmp_path)
    exr = ip.read_exr(tmp_path / "r.exr")
    assert np.array_equal(np.stack([exr[c] for c in "RGB"], axis=-1), image)


def test_render_defaults_and_threads(small):
    scene, _ = small("sphere_floor")
    image = ip.render(scene)
    assert np.array_equal(image, ip.render(scene, spp=4, seed=0))
    assert np.array_equal(image, ip.render(scene, threads=1))
    assert not np.array_equal(image, ip.render(scene, seed=1))
    with pytest.raises(ValueError, match="spp: must be >= 1, got 0"):
        ip.render(scene, spp=0)
    with pytest.raises(ValueError, match="threads: must be >= 1, got 0"):
        ip.render(scene, threads=0)


def exr_images(path):
    """The EXR's channels grouped as (height, width, 3) images, named as diff's dict."""
    channels = ip.read_exr(path)
    images = {}
    for name in channels:
        if name.endswith(".R") or name == "R":
            stem = name[:-2] if name != "R" else None
            key = stem or "image"
            prefix = f"{stem}." if stem else ""
            images[key] = np.stack([channels[prefix + c] for c in "RGB"], axis=-1)
    return images


def test_diff_is_the_cli_exr(small, cli, tmp_path):
    scene, doc = small("sphere_floor", spp=8)
    params = ["ball.radius", "light.center.x"]
    d = ip.diff(scene, params, seed=7, terms=True)
    args = ["diff", write_scene(doc, tmp_path), "--seed", 7, "--terms"]
    for p in params:
        args += ["--param", p]
    cli(*args, cwd=tmp_path)
    expected = exr_images(tmp_path / "diff.exr")
    assert list(d) == list(dict.fromkeys(["image"] + [k for k in d if k != "image"]))
    assert set(d) == set(expected)
    assert {"d.ball.radius", "d_interior.ball.radius", "d_primary.ball.radius",
            "d_secondary.ball.radius"} <= set(d)
    for k in expected:
        assert np.array_equal(d[k], expected[k]), k
    assert np.array_equal(d["image"], ip.render(scene, seed=7))
    for p in params:
        terms = sum(d[f"{t}.{p}"] for t in ("d_interior", "d_primary", "d_secondary"))
        assert np.allclose(terms, d[f"d.{p}"], atol=1e-5)


def test_diff_grid_direction_is_the_cli_exr(small, cli, tmp_path):
    scene, doc = small("grid", width=12, height=10)
    u = np.random.default_rng(1).standard_normal(scene.grid(GRID).shape).astype(np.float32)
    np.save(tmp_path / "u.npy", u)
    d = ip.diff(scene, ["ball.radius"], grid_directions={GRID: u}, spp_secondary=0)
    assert list(d) == ["image", "d.ball.radius", f"d.{GRID}.values"]
    cli("diff", write_scene(doc, tmp_path), "--param", "ball.radius", "--grid-direction",
        f"{GRID}=u.npy", "--spp-secondary", 0, cwd=tmp_path)
    expected = exr_images(tmp_path / "diff.exr")
    assert set(d) == set(expected)
    for k in expected:
        assert np.array_equal(d[k], expected[k]), k
    assert np.abs(d[f"d.{GRID}.values"]).sum() > 0


def test_diff_bad_requests(small):
    scene, _ = small("grid")
    with pytest.raises(ValueError, match="nothing to differentiate"):
        ip.diff(scene)
    with pytest.raises(ip.SceneError, match=r'grid_directions\["baked_blob.sdf.child"\]: shape \[4, 4, 4\], but grid'):
        ip.diff(scene, grid_directions={GRID: np.zeros((4, 4, 4))})
    with pytest.raises(ip.SceneError, match=r'grid_directions: no grid node "nope"'):
        ip.diff(scene, grid_directions={"nope": np.zeros((4, 4, 4))})
    with pytest.raises(ValueError, match=r"normalization: "):
        ip.diff(scene, ["ball.radius"], normalization="sometimes")
    with pytest.raises(ValueError, match=r"velocity_field: unknown velocity field"):
        ip.diff(scene, ["ball.radius"], velocity_field="sideways")
    u = np.zeros(scene.grid(GRID).shape)
    u[0, 0, 0] = np.inf
    with pytest.raises(ValueError, match=r"must be finite, got inf at index \[0, 0, 0\]"):
        ip.diff(scene, grid_directions={GRID: u})
    scene, doc = small("sphere_floor")
    doc["camera"]["filter"] = "box"
    with pytest.raises(ip.SceneError, match=r"^camera\.filter: .*box filter"):
        ip.diff(ip.Scene.from_dict(doc), ["ball.radius"])


def test_diff_velocity_field(small, cli, tmp_path):
    """`velocity_field` is `--velocity-field`: `auto` keeps the ball's normal field, `carried` moves it
    rigidly (another estimate of the same derivative), bit for bit as the tool."""
    scene, doc = small("sphere_floor")
    d = {f: ip.diff(scene, ["ball.center.x"], velocity_field=f)["d.ball.center.x"]
         for f in ("auto", "normal", "carried")}
    assert np.array_equal(d["auto"], d["normal"])
    assert not np.array_equal(d["auto"], d["carried"])
    cli("diff", write_scene(doc, tmp_path), "--param", "ball.center.x", "--velocity-field", "carried",
        "--out", "d.exr", "--png", "d.png", cwd=tmp_path)
    exr = ip.read_exr(tmp_path / "d.exr")
    cli_d = np.stack([exr[f"d.ball.center.x.{c}"] for c in "RGB"], axis=-1)
    assert np.array_equal(cli_d, d["carried"])
