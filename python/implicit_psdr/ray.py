"""Gradients summed over many views, one Ray task per view.

A *view* is a dict of parameter values applied to the scene before rendering it, usually the
camera's (``{"camera.origin.x": 3.0, "camera.origin.z": 1.5}``); a target is the image that view
should show. ``multi_view_grad`` ships the scene to the cluster once (``ray.put``), runs one task
per view (``grad`` against that view's target) and sums the losses and gradients in view order, so
its result equals ``serial_grad``'s (the same calls in one process) to the last bit.

Each task asks Ray for ``threads_per_task`` CPUs and renders with as many threads, so Ray's
tasks and the renderer's threads do not compete for the same cores. Call ``ray.init()`` first: on
one machine it starts a local Ray with its cores; ``ray.init(address="auto")`` (or the
``RAY_ADDRESS`` environment variable) joins a running cluster, whose nodes need this package
installed.

View ``k`` renders with seed ``seed + 2k`` (its loss pass; the gradient pass takes the next seed),
so the views' noise is independent.
"""

from . import _native

__all__ = ["apply_view", "view_grad", "serial_grad", "multi_view_grad"]


def apply_view(scene, view):
    """A copy of ``scene`` with the parameter values of ``view`` (``{name: value}``) set."""
    scene = scene.copy()
    for name, value in view.items():
        scene.set(name, value)
    return scene


def view_grad(scene, view, target, *, params=(), grids=(), loss="l2", spp=None, seed=0,
              threads=None):
    """``grad`` of one view: ``(loss, {name: float | array})`` of ``scene`` seen with ``view``
    against ``target``."""
    return _native.grad(
        apply_view(scene, view),
        target=target,
        loss=loss,
        params=list(params),
        grids=list(grids),
        spp=spp,
        seed=seed,
        threads=threads,
    )


def _sum(results):
    """The losses and gradients of the views, added in view order."""
    total_loss, total = 0.0, {}
    for loss, gradient in results:
        total_loss += loss
        for name, g in gradient.items():
            total[name] = g if name not in total else total[name] + g
    return total_loss, total


def serial_grad(scene, views, targets, *, params=(), grids=(), loss="l2", spp=None, seed=0,
                threads=None):
    """The sum over views of ``view_grad``, computed one view after the other in this process:
    ``(loss, {name: float | array})``. The reference that ``multi_view_grad`` equals."""
    return _sum(
        view_grad(scene, view, target, params=params, grids=grids, loss=loss, spp=spp,
                  seed=seed + 2 * k, threads=threads)
        for k, (view, target) in enumerate(zip(views, targets, strict=True))
    )


_remote_view_grad = None


def _task():
    """The Ray task of one view (made on first use, so that importing this module needs no Ray)."""
    global _remote_view_grad
    if _remote_view_grad is None:
        import ray

        _remote_view_grad = ray.remote(view_grad)
    return _remote_view_grad


def multi_view_grad(scene, views, targets, *, params=(), grids=(), loss="l2", spp=None, seed=0,
                    threads_per_task=1):
    """The sum over views of the loss and gradient of each view against its target, one Ray task
    per view: ``(loss, {name: float | array})``, equal to ``serial_grad``'s.

    ``scene`` is a ``Scene`` (put into Ray's object store once for all tasks) or an object
    reference to one; ``targets`` are images or object references to them (put them once when the
    same targets serve many calls). ``threads_per_task`` is both the CPUs each task reserves and the
    renderer's threads in it.
    """
    import ray

    if not isinstance(scene, ray.ObjectRef):
        scene = ray.put(scene)
    task = _task().options(num_cpus=threads_per_task)
    futures = [
        task.remote(scene, view, target, params=list(params), grids=list(grids), loss=loss,
                    spp=spp, seed=seed + 2 * k, threads=threads_per_task)
        for k, (view, target) in enumerate(zip(views, targets, strict=True))
    ]
    return _sum(ray.get(futures))
