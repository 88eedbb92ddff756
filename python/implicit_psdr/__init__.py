"""Physically based rendering of implicit surfaces, with complete derivatives of the image.

The same calls as the ``implicit-psdr`` command-line tool, with its defaults (the scene's ``spp``,
seed 0, the differentiable pixel normalisation, the default boundary budgets):

- ``Scene.load(path)`` / ``Scene.from_dict(d)``; ``scene.params()``, ``scene.set(name, value)``,
  ``scene.set_grid(node, array)``, ``scene.grid(node)``;
- ``render(scene, spp=, seed=)``: the image, a float32 array (height, width, 3);
- ``diff(scene, params=[...], ...)``: the image and its derivatives in forward mode, a dict named as
  the ``diff`` command's EXR channels (``"image"``, ``"d.P"``, ...);
- ``grad(scene, target=..., params=[...], grids=[...])`` or ``grad(scene, adjoint=...)``: a loss and
  its gradient in reverse mode, ``(loss, {name: float | array})``;
- ``optimize(config, out=None, base_dir=None)``: the run of an ``OPT.json`` (a path or a dict), as the
  ``optimize`` command; returns the rows of its ``progress.csv``, one dict per iteration, and writes
  the command's files in ``out`` if given;
- ``read_exr(path)``: the channels of an EXR the tool wrote;
- ``extract_mesh(scene, shape, res=128)``: a shape's surface as ``(vertices, faces)`` arrays, the
  mesh the ``mesh`` command writes.

Arrays are numpy float32: images (height, width, 3) with row 0 at the top, grids (nz, ny, nx).
Errors in the scene or the request raise ``SceneError`` (a ``ValueError``) with the tool's one-line
message; malformed arrays raise ``ValueError``. ``implicit_psdr.torch`` wraps a render as a
``torch.autograd.Function``; ``implicit_psdr.ray`` sums gradients over many views as Ray tasks.
"""

from ._native import (
    Scene,
    SceneError,
    diff,
    extract_mesh,
    grad,
    optimize,
    read_exr,
    render,
)

__all__ = [
    "Scene",
    "SceneError",
    "diff",
    "extract_mesh",
    "grad",
    "optimize",
    "read_exr",
    "render",
]
