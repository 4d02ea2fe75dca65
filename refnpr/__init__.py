"""refnpr: a CPU reference renderer for non-photorealistic shading.

The everyday names are importable from the package itself::

    import refnpr

    scene = refnpr.load_scene("teapot")
    image = refnpr.render(scene, {"name": "toon", "n": 3}, 512, 512, spp=4)
    image.save("teapot.png")

Each is imported on first use, so ``import refnpr`` (and the ``refnpr`` command's start) stays
instant: numba, the kernels and optional dependencies load only when a name that needs them is
used. ``refnpr.render`` is the function :func:`refnpr.render.render` (also when the module
``refnpr.render`` has been imported); the module's other names are imported from it
(``from refnpr.render import RenderContext``).
"""

from __future__ import annotations

import os
import sys
import types
from collections.abc import Callable
from typing import Any

# numba's OpenMP threads (refnpr's kernels are all banded, but a caller's own prange kernels
# run on them) spin after each parallel loop by default and take a core from the banded
# kernels' Python threads that run next (refnpr._jit): 5-20 % slower rasterization on 2 cores
# when they were refnpr's. Wait passively instead; a value already set is kept. Read by libgomp
# when numba first starts its threads, which is after this import.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

__version__ = "0.1.0"

#: The module of each everyday name, imported on first use.
_EXPORTS = {
    # rendering
    "render": "render",
    "RenderContext": "render",
    "Image": "image",
    "render_sequence": "sequence",
    # rasterizer
    "rasterize": "raster",
    "Camera": "raster",
    "GBuffer": "raster",
    "Mesh": "raster",
    # scenes
    "load_scene": "scenes",
    "list_scenes": "scenes",
    "load_mesh": "scenes",
    "Scene": "scenes",
    "SceneObject": "scenes",
    "Light": "scenes",
    "Material": "scenes",
    # styles
    "get_style": "styles",
    "list_styles": "styles",
    "Style": "styles",
    # conformance kit
    "export_kit": "kit",
    "check_kit": "kit",
    # Jupyter (ipywidgets: the optional extra ``notebook``)
    "explore": "explore",
}

__all__ = ["__version__", *_EXPORTS]


def _lazy(package: str, exports: dict[str, str]) -> tuple[Callable, Callable]:
    """The module ``__getattr__`` and ``__dir__`` of ``package``, whose names ``exports``
    (name -> submodule) are imported on first use and then kept as module attributes (this
    package's, and subpackages' such as :mod:`refnpr.coherence`)."""

    def __getattr__(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        import importlib

        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        module = sys.modules[package]
        return sorted(set(vars(module)) | set(module.__all__))

    return __getattr__, __dir__


__getattr__, __dir__ = _lazy(__name__, _EXPORTS)


class _Package(types.ModuleType):
    """The package's module type: a name exported from the submodule of the same name
    (``render``, ``explore``) stays the function when that submodule is imported, which the
    import system would otherwise bind on the package in its place."""

    def __setattr__(self, name: str, value: Any) -> None:
        if (
            _EXPORTS.get(name) == name
            and isinstance(value, types.ModuleType)
            and value.__name__ == f"{__name__}.{name}"
        ):
            value = getattr(value, name)
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
