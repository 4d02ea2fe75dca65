"""Fixtures shared by the conformance-kit tests (exporter, checker, GLSL backend).

``kit_dir``: the whole golden suite exported once per test run into a pytest temporary
directory (``refnpr kit export``), shared by the pytest-xdist workers of the run (the first
worker to ask exports it under a lock; the kit is only read). Cases are exported one by one so
that one failing style exporter does not take every kit test down: the failures are in
``kit_export_errors`` (a test in test_export.py asserts there are none) and those cases are
absent from the kit.

``REFNPR_TEST_KIT_DIR=/path`` reuses a kit exported earlier (a development shortcut on a busy
machine: the tests then test that kit, not the current code; CI never sets it).
"""

from __future__ import annotations

import fcntl
import json
import os
from pathlib import Path

import numpy as np
import pytest

from refnpr.golden import DEFAULT_SUITE

REPO = Path(__file__).resolve().parents[2]
SUITE = DEFAULT_SUITE


def export_cases(directory: Path, names: list[str] | None = None) -> dict[str, str]:
    """Export the suite's cases (or ``names``) one by one into ``directory``; case -> error."""
    from refnpr.golden import load_suite
    from refnpr.kit import export_kit

    errors: dict[str, str] = {}
    for case in load_suite(SUITE):
        if names is not None and case.name not in names:
            continue
        try:
            export_kit(directory, suite=SUITE, only=[case.name])
        except Exception as exc:  # noqa: BLE001 -- recorded and asserted by a test
            errors[case.name] = f"{type(exc).__name__}: {exc}"
    return errors


def read_exr(path: Path) -> np.ndarray:
    """A kit EXR with OpenEXR alone: (H, W) float32 for a ``Y`` file, else (H, W, C) in R, G, B,
    A order; the channel naming of docs/kit.md is asserted."""
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    assert sorted(ch) in (["Y"], ["G", "R"], ["B", "G", "R"], ["A", "B", "G", "R"]), sorted(ch)
    if "Y" in ch:
        return ch["Y"]
    return np.stack([ch[n] for n in "RGBA" if n in ch], axis=-1)


@pytest.fixture(scope="session")
def _kit_export(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, str]]:
    given = os.environ.get("REFNPR_TEST_KIT_DIR")
    if given:
        d = Path(given)
        if not (d / "index.json").is_file():
            raise RuntimeError(f"REFNPR_TEST_KIT_DIR={given!r} holds no index.json")
        return d, {}
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the run's directory, above each worker's own
    d, done = base / "kit-suite", base / "kit-suite.errors.json"
    with open(base / "kit-suite.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if not done.is_file():
            d.mkdir(exist_ok=True)
            done.write_text(json.dumps(export_cases(d)))
    return d, json.loads(done.read_text())


@pytest.fixture(scope="session")
def kit_dir(_kit_export: tuple[Path, dict[str, str]]) -> Path:
    """An exported kit of the whole golden suite (made once per session)."""
    return _kit_export[0]


@pytest.fixture(scope="session")
def kit_export_errors(_kit_export: tuple[Path, dict[str, str]]) -> dict[str, str]:
    """Cases whose export raised (name -> error), absent from ``kit_dir``."""
    return _kit_export[1]


@pytest.fixture(scope="session")
def kit_cases(kit_dir: Path) -> dict[str, dict]:
    """name -> parsed case.json of every case in ``kit_dir``."""
    index = json.loads((kit_dir / "index.json").read_text())
    return {c["name"]: json.loads((kit_dir / c["case"]).read_text()) for c in index["cases"]}


@pytest.fixture(scope="module")
def gl():
    """A headless OpenGL 4.5 core context of the GLSL backend (EGL; llvmpipe on this machine)."""
    from refnpr_glsl.context import GL

    g = GL()
    yield g
    g.release()
