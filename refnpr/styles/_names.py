"""Parameter names of the styles: deprecated names mapped to current ones, unknown names refused.

Warnings are attributed to the first caller outside refnpr (the user's script, notebook cell or
the ``refnpr`` command), so Python's default filters show them there, wherever inside refnpr the
old name was read.
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

__all__ = ["warn_caller", "warn_deprecated", "renamed_params", "check_known"]

_PACKAGE = str(Path(__file__).resolve().parents[1])  # .../refnpr
_INTERNAL_FILES = ("<string>",)  # dataclass-generated __init__


def _outside_level() -> int:
    """``stacklevel`` (for a ``warnings.warn`` in our caller) of the first frame outside refnpr."""
    frame = sys._getframe(2)  # the caller of warn_caller
    level = 1
    while frame is not None:
        name = frame.f_code.co_filename
        if not (name.startswith(_PACKAGE) or name in _INTERNAL_FILES or "dataclasses" in name):
            return level
        frame = frame.f_back
        level += 1
    return level


def warn_caller(message: str, category: type[Warning] = UserWarning) -> None:
    """A warning attributed to the first caller outside refnpr."""
    warnings.warn(message, category, stacklevel=_outside_level() + 1)


def warn_deprecated(message: str) -> None:
    """A ``DeprecationWarning`` attributed to the first caller outside refnpr."""
    warn_caller(message, DeprecationWarning)


def renamed_params(
    where: str, params: Mapping[str, Any], renamed: Mapping[str, str], *, warn: bool = True
) -> dict[str, Any]:
    """``params`` with deprecated parameter names replaced by the current ones.

    Each old name found gives a ``DeprecationWarning`` naming both (unless ``warn`` is False);
    passing both names is a ``TypeError``. Styles list their old names in ``Style.renamed``
    (applied by :func:`refnpr.styles.register`); nested tables (contours, screens) call this
    where they are parsed.

    Parameters
    ----------
    where : str
        What the parameters belong to, for the message (``"style 'halftone'"``, ``"contours"``).
    params : mapping of str to any
    renamed : mapping of old name -> current name
    """
    out = dict(params)
    for old, new in renamed.items():
        if old not in out:
            continue
        if new in out:
            raise TypeError(
                f"{where}: got both {old!r} (the deprecated name) and {new!r}; pass only {new!r}"
            )
        if warn:
            warn_deprecated(
                f"{where}: parameter {old!r} is deprecated, use {new!r} (one name across styles)"
            )
        out[new] = out.pop(old)
    return out


def check_known(where: str, params: Iterable[str], valid: Iterable[str]) -> None:
    """``TypeError`` naming every unknown parameter and listing the valid ones."""
    valid = sorted(valid)
    unknown = sorted(set(params) - set(valid))
    if unknown:
        raise TypeError(f"{where}: unknown parameter(s) {unknown}; valid parameters: {valid}")
