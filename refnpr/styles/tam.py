"""The ``tam`` style (RPTAM baseline of the TAMISS paper) at its documented import path.

The implementation lives with the rest of the paper's pipeline in :mod:`refnpr.styles.tamiss.tam`.
"""

from __future__ import annotations

from .tamiss.tam import TamStyle

__all__ = ["TamStyle"]
