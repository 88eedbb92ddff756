"""Physically based rendering of implicit surfaces, with complete derivatives of the image.

The same calls as the ``implicit-psdr`` command-line tool, with its defaults (the scene's ``spp``,
seed 0, the differentiable pixel normalisation, the default boundary budgets):

- ``Scene.load(path)`` / ``Scene.from_dict(d)``; ``scene.params()``, ``scene.set(name, value)``,
  ``scene.set_grid(node, array)``, ``scene.grid(node)``; ``scene.to_dict()`` and ``scene.save(path)``
  (the scene file with the current values, grids written beside it);
- ``render(scene, spp=, seed=)``: the image, a float32 array (height, width, 3);
- ``diff(scene, params=[...], ...)``: the image and its derivatives in forward mode, a dict named as
  the ``diff`` command's EXR channels (``"image"``, ``"d.P"``, ...);
- ``grad(scene, target=..., params=[...], grids=[...])`` or ``grad(scene, adjoint=...)``: a loss and
  its gradient in reverse mode, ``(loss, {name: float | array})``;
- ``optimize(config, out=None, base_dir=None)``: the run of an ``OPT.json`` (a path or a dict), as the
  ``optimize`` command; returns the rows of its ``progress.csv``, one dict per iteration, and writes
  the command's files in ``out`` if given;
- ``fd(scene, params, h=)``: central finite differences, named as ``diff``'s;
- ``bake(scene, shape, res)``: a shape's SDF sampled into a grid, ``(values, grid node)``;
- ``extract_mesh(scene, shape, res=128)``: a shape's surface as ``(vertices, faces)`` arrays, the
  mesh the ``mesh`` command writes;
- ``mesh_to_grid(vertices, faces, res=64, bbox=None)``: a triangle mesh's signed distance on a
  ``res``³ lattice, ``(values, bbox_min, bbox_max)``, as ``bake --mesh`` computes it;
- ``read_exr(path)``: the channels of an EXR the tool wrote; ``write_exr(path, channels)`` writes
  them (``write_exr(path, diff(...))`` writes ``diff``'s channels).

Names (``params``, ``grids``) are one string or a list. ``implicit-psdr`` on the command line is
this package's console script (``implicit_psdr.cli``), the same tool as the Rust binary.

Arrays are numpy float32: images (height, width, 3) with row 0 at the top, grids (nz, ny, nx).
Errors in the scene or the request raise ``SceneError`` (a ``ValueError``) with the tool's one-line
message; malformed arguments raise ``ValueError`` naming the argument (``spp: must be >= 1, got
-1``), arrays of integers included. ``implicit_psdr.torch`` wraps a render as a
``torch.autograd.Function``; ``implicit_psdr.ray`` sums gradients over many views as Ray tasks.
"""

from ._native import (
    Scene,
    SceneError,
    bake,
    diff,
    extract_mesh,
    mesh_to_grid,
    fd,
    grad,
    optimize,
    read_exr,
    render,
    write_exr,
)

__all__ = [
    "Scene",
    "SceneError",
    "bake",
    "diff",
    "extract_mesh",
    "mesh_to_grid",
    "fd",
    "grad",
    "optimize",
    "read_exr",
    "render",
    "write_exr",
]
