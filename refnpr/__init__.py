"""refnpr: a CPU reference renderer for non-photorealistic shading."""

from __future__ import annotations

from typing import Any

__version__ = "0.1.0"

__all__ = ["__version__", "explore"]


def __getattr__(name: str) -> Any:
    """``refnpr.explore`` on first use, so that ``import refnpr`` never imports ipywidgets
    (the optional extra ``notebook``) nor the renderer."""
    if name == "explore":
        from .explore import explore

        globals()["explore"] = explore  # the function, not the submodule import just bound
        return explore
    raise AttributeError(f"module 'refnpr' has no attribute {name!r}")
