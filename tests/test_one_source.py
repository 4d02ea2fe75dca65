"""The code that renders is the code that is tested: editing the body of a formula's device
function (``f.scalar``) changes the images of the styles that use it.

The package is copied once to a temporary directory. For each formula below, the last
``return`` of ``f.scalar``'s body is scaled by 0.5 in the copy, a child process renders a style
that uses the formula from the copy, and the file is restored. The copy's numba cache is shared
by the renders: the kernels that call into the edited file are compiled again from its source
(their cache entries are keyed on the files they call into), the others are loaded. The image
must differ from the same render with the package as it is; the unedited copy must give the same
bytes (the check is not vacuous).
"""

from __future__ import annotations

import importlib
import inspect
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import refnpr
from refnpr.render import render

PACKAGE = Path(refnpr.__file__).resolve().parent

#: (formula module, public name, scene, style table): a style whose images use the formula.
CASES = [
    ("refnpr.formulas.xtoon", "detail_depth", "xtoon_teapot", {"name": "xtoon"}),
    (
        "refnpr.formulas.xtoon",
        "detail_orientation",
        "xtoon_teapot",
        {"name": "xtoon", "detail": "orientation", "texture": "silhouette_fade"},
    ),
    ("refnpr.formulas.threshold", "multiscale_line", "veryovka_plane", {"name": "threshold"}),
    ("refnpr.formulas.threshold", "step_n", "veryovka_plane", {"name": "threshold", "n": 3}),
    ("refnpr.formulas.tamiss", "darkness", "tamiss_teapot", {"name": "tam"}),
    ("refnpr.formulas.tamiss", "cubic", "tamiss_teapot", {"name": "tamiss"}),
    ("refnpr.formulas.halftone", "smooth_threshold", "halftone_teapot", {"name": "halftone"}),
    (
        "refnpr.formulas.halftone",
        "binary_threshold",
        "halftone_teapot",
        {"name": "halftone", "threshold": "binary"},
    ),
]
SIZE = (64, 48)

_CHILD = """
import json, sys
import numpy as np
from refnpr.render import render
spec = json.loads(sys.argv[1])
img = render(spec["scene"], spec["style"], spec["w"], spec["h"], 1)
np.save(sys.argv[2], img.rgba)
"""


def _edited(source: str) -> str:
    """``source`` (a function's) with its last ``return X`` made ``return 0.5 * (X)``."""
    lines = source.splitlines()
    for i in range(len(lines) - 1, -1, -1):
        m = re.match(r"(\s*)return (.+?)(\s*#.*)?$", lines[i])
        if m:
            lines[i] = f"{m.group(1)}return 0.5 * ({m.group(2)}){m.group(3) or ''}"
            return "\n".join(lines) + "\n"
    raise AssertionError("no return statement to edit")


def _render_copy(root: Path, scene: str, style: dict, tmp: Path) -> np.ndarray:
    out = tmp / "rgba.npy"
    spec = json.dumps({"scene": scene, "style": style, "w": SIZE[0], "h": SIZE[1]})
    env = {
        **os.environ,
        "PYTHONPATH": str(root),
        "NUMBA_CACHE_DIR": str(root / "numba"),
        "PYTHONDONTWRITEBYTECODE": "1",  # no .pyc keyed on whole seconds of a file edited twice
    }
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, spec, str(out)],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return np.load(out)


@pytest.fixture(scope="module")
def copy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The package copied (``<root>/refnpr``) with its numba cache at ``<root>/numba``."""
    root = tmp_path_factory.mktemp("one_source") / "src"
    shutil.copytree(PACKAGE, root / "refnpr", ignore=shutil.ignore_patterns("__pycache__"))
    return root


@pytest.mark.slow
@pytest.mark.parametrize("module, name, scene, style", CASES, ids=[c[1] for c in CASES])
def test_editing_a_formula_changes_the_images_that_use_it(
    module, name, scene, style, copy, tmp_path
):
    scalar = getattr(importlib.import_module(module), name).scalar
    py = scalar.py_func
    source = textwrap.dedent(inspect.getsource(py))
    path = Path(inspect.getsourcefile(py))
    target = copy / "refnpr" / path.relative_to(PACKAGE)
    text = target.read_text(encoding="utf-8")
    assert text.count(source) == 1, f"{name}.scalar's source not found once in {target}"
    target.write_text(text.replace(source, _edited(source)), encoding="utf-8")
    try:
        got = _render_copy(copy, scene, style, tmp_path)
    finally:
        target.write_text(text, encoding="utf-8")
    want = render(scene, style, SIZE[0], SIZE[1], 1).rgba
    changed = np.mean(np.any(got != want, axis=-1))
    assert changed > 0.05, f"editing {name}.scalar changed {changed:.1%} of the pixels"


@pytest.mark.slow
def test_an_unedited_copy_renders_the_same_bytes(copy, tmp_path):
    module, name, scene, style = CASES[0]
    want = render(scene, style, SIZE[0], SIZE[1], 1).rgba
    got = _render_copy(copy, scene, style, tmp_path)
    assert np.array_equal(got.view(np.uint32), want.view(np.uint32))
