"""The GLSL backend reads only the kit: ``python -m refnpr_glsl`` runs with refnpr unimportable.

The backend runs in a subprocess whose ``-c`` wrapper installs a meta-path finder that raises
``ImportError`` for ``refnpr`` and every ``refnpr.*`` module *before* anything else is imported
(so neither the editable install nor the repository on ``sys.path`` can provide it), then runs
the ``refnpr_glsl`` module as ``__main__``. A control run proves the blocker blocks. The kit
(exported here with refnpr, in this process) holds an image case with contours, a lake-mode case
with a ramp texture and the G-buffer case; the renders must pass ``refnpr kit check``.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from refnpr.golden import DEFAULT_SUITE

pytest.importorskip("moderngl")  # the extra "glsl"; CI installs it

REPO = Path(__file__).resolve().parents[2]
SUITE = DEFAULT_SUITE

#: Installed first in the child: refnpr and refnpr.* cannot be imported at all.
BLOCKER = """
import sys
class _NoRefnpr:
    def find_spec(self, name, path=None, target=None):
        if name == "refnpr" or name.startswith("refnpr."):
            raise ImportError(f"refnpr is blocked: the GLSL backend must not import {name!r}")
        return None
sys.meta_path.insert(0, _NoRefnpr())
for _m in [m for m in sys.modules if m == "refnpr" or m.startswith("refnpr.")]:
    del sys.modules[_m]
"""

RUN_BACKEND = (
    BLOCKER
    + """
import runpy
sys.argv = ["refnpr_glsl", *sys.argv[1:]]
runpy.run_module("refnpr_glsl", run_name="__main__", alter_sys=True)
"""
)

VARIANT = """
[defaults]
width = 64
height = 48
spp = 4

[[case]]
name = "iso-toon-contours"
scene = "teapot"
style = { name = "toon", n = 2, contours = { width = 1.5, crease_angle = 60.0 } }

[[case]]
name = "iso-lake"
scene = "sphere"
style = { name = "toon", mode = "lake", n = 3 }
spp = 1
"""


@pytest.fixture(scope="module")
def small_kit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from refnpr.kit import export_kit

    d = tmp_path_factory.mktemp("iso_kit")
    suite = tmp_path_factory.mktemp("iso_suite") / "suite.toml"
    suite.write_text(VARIANT)
    export_kit(d, suite=suite)
    export_kit(d, suite=SUITE, only=["gbuffer-default"])
    return d


def test_blocker_blocks() -> None:
    proc = subprocess.run(
        [sys.executable, "-c", BLOCKER + "\nimport refnpr\n"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode != 0
    assert "refnpr is blocked" in proc.stderr


def test_backend_runs_without_refnpr(small_kit: Path, tmp_path: Path) -> None:
    out = tmp_path / "renders"
    proc = subprocess.run(
        [sys.executable, "-c", RUN_BACKEND, str(small_kit), str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-4000:]
    report = json.loads((out / "backend.json").read_text())
    assert {k: v["status"] for k, v in report["cases"].items()} == {
        "iso-toon-contours": "rendered",
        "iso-lake": "rendered",
        "gbuffer-default": "rendered",
    }
    from refnpr.kit.check import check_kit

    results = check_kit(small_kit, out)
    assert [r.name for r in results if not r.passed] == [], [r.message for r in results]
