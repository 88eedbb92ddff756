"""extract_mesh: a shape's surface as numpy arrays, the same mesh as the ``mesh`` command."""

import struct

import numpy as np
import pytest

import implicit_psdr as ip
from conftest import write_scene


def read_ply(path):
    """Vertices (n, 3) and faces (m, 3) of a binary PLY as the ``mesh`` command writes it."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    count = {line.split()[1]: int(line.split()[2]) for line in header if line.startswith("element")}
    n, m = count["vertex"], count["face"]
    rows = np.frombuffer(data, dtype="<f4", count=6 * n, offset=end).reshape(n, 6)
    faces = []
    at = end + 24 * n
    for _ in range(m):
        assert data[at] == 3
        faces.append(struct.unpack_from("<3i", data, at + 1))
        at += 13
    return rows[:, :3], np.array(faces, dtype=np.int32)


def test_extract_mesh_is_the_command_s_mesh(small, cli, tmp_path):
    scene, doc = small("csg")
    vertices, faces = ip.extract_mesh(scene, "ring", res=24)
    assert vertices.dtype == np.float32 and vertices.shape[1] == 3
    assert faces.dtype == np.int32 and faces.shape[1] == 3
    assert faces.min() >= 0 and faces.max() < len(vertices)
    path = write_scene(doc, tmp_path)
    cli("mesh", path, "--shape", "ring", "--res", "24", "--out", tmp_path / "ring.ply", cwd=tmp_path)
    ply_vertices, ply_faces = read_ply(tmp_path / "ring.ply")
    assert np.array_equal(ply_vertices, vertices)
    assert np.array_equal(ply_faces, faces)


def test_bad_requests_raise(small):
    scene, _ = small("blocks")
    with pytest.raises(ip.SceneError, match="unbounded"):
        ip.extract_mesh(scene, "floor")
    with pytest.raises(ip.SceneError):
        ip.extract_mesh(scene, "nothing")
    with pytest.raises(ValueError, match="res"):
        ip.extract_mesh(scene, "can", res=2)


def cube_mesh(lo, hi):
    """The box [lo, hi] as 12 triangles facing outwards."""
    lo, hi = np.asarray(lo, dtype=np.float32), np.asarray(hi, dtype=np.float32)
    v = np.array([[hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]]
                  for i in range(8)], dtype=np.float32)
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    faces = np.array([t for q in quads for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])])
    return v, faces


def test_mesh_to_grid_is_a_box_s_signed_distance():
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([1.0, 2.0, 1.5])
    v, f = cube_mesh(lo, hi)
    values, bmin, bmax = ip.mesh_to_grid(v, f, res=20, bbox=((-0.5, -0.5, -0.5), (1.5, 2.5, 2.0)))
    assert values.shape == (20, 20, 20) and values.dtype == np.float32
    np.testing.assert_allclose(bmin, [-0.5, -0.5, -0.5])
    np.testing.assert_allclose(bmax, [1.5, 2.5, 2.0])
    # The box's signed distance in closed form at every sample ([z, y, x] order).
    axes = [np.linspace(bmin[k], bmax[k], 20) for k in range(3)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    p = np.stack([x, y, z], axis=-1)
    q = np.abs(p - (lo + hi) / 2) - (hi - lo) / 2
    want = np.linalg.norm(np.maximum(q, 0), axis=-1) + np.minimum(q.max(axis=-1), 0)
    np.testing.assert_allclose(values, want, atol=1e-5)


def test_mesh_to_grid_default_box_is_a_padded_cube_and_bad_meshes_raise():
    v, f = cube_mesh([0, 0, 0], [1, 2, 1])
    values, bmin, bmax = ip.mesh_to_grid(v, f.astype(np.int32), res=8)
    assert values.shape == (8, 8, 8)
    np.testing.assert_allclose(bmax - bmin, [2.4, 2.4, 2.4], rtol=1e-6)
    np.testing.assert_allclose((bmin + bmax) / 2, [0.5, 1.0, 0.5], atol=1e-6)
    with pytest.raises(ValueError, match="out of range"):
        ip.mesh_to_grid(v, f + 8, res=8)
    bad = v.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="not finite"):
        ip.mesh_to_grid(bad, f, res=8)
    with pytest.raises(ValueError, match="no faces"):
        ip.mesh_to_grid(v, np.zeros((0, 3), dtype=np.int64), res=8)
