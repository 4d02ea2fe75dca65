"""refnpr: a CPU reference renderer for non-photorealistic shading."""

from __future__ import annotations

import os
from typing import Any

# numba's OpenMP threads (refnpr's kernels are all banded, but a caller's own prange kernels
# run on them) spin after each parallel loop by default and take a core from the banded
# kernels' Python threads that run next (refnpr._jit): 5-20 % slower rasterization on 2 cores
# when they were refnpr's. Wait passively instead; a value already set is kept. Read by libgomp
# when numba first starts its threads, which is after this import.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

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
