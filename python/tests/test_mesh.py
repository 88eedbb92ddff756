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
