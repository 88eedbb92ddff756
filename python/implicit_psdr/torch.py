"""PyTorch adapter: a render as a differentiable function of scene parameters and grid values.

``render(scene, params={"ball.radius": r}, grids={"blob": g})`` returns the image as a float32
tensor (height, width, 3). Its forward pass renders the scene with the tensors' values; its
backward pass calls ``implicit_psdr.grad`` with ``grad_output`` as the pixel adjoint ``dL/dI``, so
``loss.backward()`` gives every tensor its gradient (the complete derivative: interior, silhouette
and shadow terms). The backward pass uses the samples of ``seed + 1``, independent of the forward
image, as the ``grad`` command does for a loss (an L2 loss estimated with the image's own samples
would be biased by their covariance).

Scene parameters are scalars (0-d tensors, or tensors of one element); grids are tensors of shape
(nz, ny, nx). The rendering runs on the CPU; tensors on another device are copied, and the image
and the gradients come back on the device (and in the dtype) of the tensors they belong to.
"""

import numpy as np
import torch

from . import _native

__all__ = ["RenderFunction", "render"]


class RenderFunction(torch.autograd.Function):
    """The image of ``scene`` with the named parameters and grids set to ``values``.

    ``RenderFunction.apply(scene, names, nodes, options, *values)``: ``names`` and ``nodes`` list the
    parameters and grid nodes that ``values`` (tensors, parameters first) set; ``options`` holds
    ``spp``, ``seed`` and ``threads``. Prefer :func:`render`.
    """

    @staticmethod
    def forward(ctx, scene, names, nodes, options, *values):
        scene = scene.copy()
        for name, value in zip(names, values[: len(names)]):
            scene.set(name, float(value.detach().reshape(()).cpu()))
        for node, value in zip(nodes, values[len(names) :]):
            scene.set_grid(node, value.detach().cpu().numpy().astype(np.float32))
        image = _native.render(
            scene, spp=options["spp"], seed=options["seed"], threads=options["threads"]
        )
        ctx.scene, ctx.names, ctx.nodes, ctx.options = scene, names, nodes, options
        ctx.like = [(v.dtype, v.device, v.shape) for v in values]
        device = values[0].device if values else torch.device("cpu")
        return torch.from_numpy(image).to(device)

    @staticmethod
    def backward(ctx, grad_output):
        wanted = ctx.needs_input_grad[4:]
        names = [n for n, w in zip(ctx.names, wanted) if w]
        nodes = [n for n, w in zip(ctx.nodes, wanted[len(ctx.names) :]) if w]
        gradients = {}
        if names or nodes:
            options = ctx.options
            adjoint = grad_output.detach().cpu().numpy().astype(np.float32)
            _, gradients = _native.grad(
                ctx.scene,
                adjoint=adjoint,
                params=names,
                grids=nodes,
                spp=options["spp"],
                seed=options["seed"] + 1,
                threads=options["threads"],
            )
        out = []
        for key, (dtype, device, shape) in zip(ctx.names + ctx.nodes, ctx.like):
            g = gradients.get(key)
            out.append(
                None
                if g is None
                else torch.as_tensor(np.asarray(g), dtype=dtype, device=device).reshape(shape)
            )
        return (None, None, None, None, *out)


def render(scene, params=None, grids=None, *, spp=None, seed=0, threads=None):
    """The image of ``scene`` as a float32 tensor (height, width, 3), differentiable with respect to
    the tensors in ``params`` (``{name: scalar tensor}``, names as ``scene.params()`` lists them)
    and ``grids`` (``{node: tensor (nz, ny, nx)}``). ``spp`` (default: the scene's), ``seed``
    (default 0) and ``threads`` are those of ``implicit_psdr.render``; the backward pass uses the
    same ``spp`` and the seed ``seed + 1``. ``scene`` itself is not changed.
    """
    params = dict(params or {})
    grids = dict(grids or {})
    options = {"spp": spp, "seed": seed, "threads": threads}
    values = [torch.as_tensor(v) for v in params.values()]
    values += [torch.as_tensor(v) for v in grids.values()]
    return RenderFunction.apply(scene, list(params), list(grids), options, *values)
