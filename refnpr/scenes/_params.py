"""Validation of builder and scene parameters (private): every check raises ``TypeError`` or
``ValueError`` whose message names the parameter, the value received, what was expected and how
to fix it."""

from __future__ import annotations

import math
import numbers

from ..formulas._validate import describe, to_float

__all__ = [
    "MAX_GENERATED_VERTICES",
    "check_grid",
    "check_int",
    "check_real",
    "check_type",
    "check_vec",
    "describe",
    "positives",
]

#: The most vertices a built-in mesh builder makes (about 1.1 GB of float64 positions, normals
#: and uv): its resolution is checked against it before any array is allocated.
MAX_GENERATED_VERTICES = 20_000_000


def check_type(name: str, value, cls, what: str) -> None:
    """``TypeError`` ``"<name>: expected <what>, got <type>"`` unless ``value`` is a ``cls``."""
    if not isinstance(value, cls):
        raise TypeError(f"{name}: expected {what}, got {type(value).__name__}")


def check_int(name: str, value, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """``value`` as an ``int`` in ``[minimum, maximum]`` (bools and floats are rejected)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(
            f"{name}: expected an integer, got {type(value).__name__} {describe(value)}"
        )
    v = int(value)
    if minimum is not None and v < minimum:
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {v}")
    if maximum is not None and v > maximum:
        raise ValueError(f"{name}: expected an integer <= {maximum}, got {v}; use a smaller value")
    return v


def check_real(name: str, value, *, positive: bool = False, nonnegative: bool = False) -> float:
    """``value`` as a finite ``float``; optionally ``> 0`` or ``>= 0`` (an integer beyond the
    float range is not finite)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(
            f"{name}: expected a real number, got {type(value).__name__} {describe(value)}"
        )
    v = to_float(name, value)
    if not math.isfinite(v):
        raise ValueError(f"{name}: expected a finite number, got {v}")
    if positive and v <= 0.0:
        raise ValueError(f"{name}: expected a positive number, got {v}")
    if nonnegative and v < 0.0:
        raise ValueError(f"{name}: expected a number >= 0, got {v}")
    return v


def positives(**values) -> tuple[float, ...]:
    """The keyword arguments' values, each checked by ``check_real(..., positive=True)``."""
    return tuple(check_real(name, v, positive=True) for name, v in values.items())


def check_vec(
    name: str,
    value,
    n: int,
    *,
    broadcast_scalar: bool = False,
    nonnegative: bool = False,
    positive: bool = False,
) -> tuple[float, ...]:
    """``value`` as a tuple of ``n`` finite floats; with ``broadcast_scalar=True`` a single number
    ``x`` stands for ``(x,) * n``."""
    if broadcast_scalar and isinstance(value, numbers.Real) and not isinstance(value, bool):
        value = (value,) * n
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__"):
        hint = " (or a single number)" if broadcast_scalar else ""
        raise TypeError(f"{name}: expected a list of {n} numbers{hint}, got {describe(value)}")
    items = list(value)
    if len(items) != n:
        raise ValueError(f"{name}: expected {n} numbers, got {len(items)}: {describe(value)}")
    return tuple(
        check_real(f"{name}[{i}]", x, nonnegative=nonnegative, positive=positive)
        for i, x in enumerate(items)
    )


def check_grid(vertices: int, counts: dict[str, int], copies: int = 1) -> None:
    """``ValueError`` naming the resolution ``counts`` (``{"n_u": 64, "n_v": 32}``) unless the
    ``vertices`` a builder makes from them (``copies`` grids of that many) are at most
    :data:`MAX_GENERATED_VERTICES`."""
    if vertices * copies > MAX_GENERATED_VERTICES:
        given = ", ".join(f"{k}={v}" for k, v in counts.items())
        raise ValueError(
            f"{', '.join(counts)}: {given} makes about {vertices * copies:,} vertices, more than the "
            f"{MAX_GENERATED_VERTICES:,} a built-in mesh may have; use a smaller resolution"
        )
