"""Kernels take records, not argument lists: no numba-compiled function of refnpr has more
than eight parameters, counting everything numba compiles (a banded kernel's ``lo, hi`` too)."""

from __future__ import annotations

import ast
from pathlib import Path

import refnpr

ROOT = Path(refnpr.__file__).resolve().parent
MAX_PARAMS = 8
#: Decorators that compile the function they decorate.
_COMPILERS = ("njit", "banded", "jit", "vectorize", "guvectorize")


def _compiled(node: ast.FunctionDef) -> bool:
    for deco in node.decorator_list:
        target = deco.func if isinstance(deco, ast.Call) else deco
        name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
        if name in _COMPILERS:
            return True
    return False


def _count(node: ast.FunctionDef) -> int:
    a = node.args
    return len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + bool(a.vararg) + bool(a.kwarg)


def compiled_functions(root: Path) -> list[tuple[str, int, int]]:
    """(file:function, line, parameter count) of every compiled function under ``root``."""
    out = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and _compiled(node):
                rel = path.relative_to(root.parent)
                out.append((f"{rel}:{node.name}", node.lineno, _count(node)))
    return out


def test_the_checker_sees_the_kernels():
    names = {name for name, _, _ in compiled_functions(ROOT)}
    assert "refnpr/styles/xtoon/_kernels.py:shade_xtoon" in names
    assert "refnpr/device/sampling.py:trilinear" in names


def test_no_compiled_function_takes_more_than_eight_parameters():
    wide = [f"{n} (line {line}): {k}" for n, line, k in compiled_functions(ROOT) if k > MAX_PARAMS]
    assert wide == [], "group these parameters into records:\n" + "\n".join(wide)
