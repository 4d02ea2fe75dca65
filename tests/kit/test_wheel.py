"""The installed kit: a wheel built from this checkout, installed into a fresh virtual
environment, runs ``refnpr golden --check`` and ``refnpr kit export`` from a directory outside
any checkout, with the golden suite the wheel carries.

The wheel is built offline (``pip wheel --no-deps --no-build-isolation`` with this interpreter's
setuptools) from a copy of the sources, so nothing is written into the checkout. The fresh
environment gets the wheel alone (``--no-deps``); its dependencies (numpy, numba, ...) are the
test environment's, put on its path by a ``.pth`` file written after the install. That file only
adds directories: the ``.pth`` files in them, among them an editable install's finder that maps
``refnpr`` to this checkout, are not run, and the environment's own site-packages comes first, so
the test asserts that ``refnpr`` is imported from the new environment.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import site
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
CASE = "sphere-toon3"  # a small case: toon at 256 x 192, spp 1

pytestmark = pytest.mark.slow


def _run(cmd: list[str], cwd: Path, env: dict[str, str], timeout: float = 240):
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def _build_wheel(tmp: Path) -> Path:
    src = tmp / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        if (REPO / name).is_file():  # LICENSE: the build puts it in the wheel's metadata
            shutil.copy2(REPO / name, src / name)
    shutil.copytree(
        REPO / "refnpr",
        src / "refnpr",
        ignore=shutil.ignore_patterns("__pycache__", "_failures", "*.nbi", "*.nbc"),
    )
    dist = tmp / "dist"
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index"]
        + ["-q", "-w", str(dist), str(src)],
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert proc.returncode == 0, (
        "building the wheel offline failed (the test extra needs setuptools>=77):\n"
        + proc.stdout[-1500:]
        + proc.stderr[-1500:]
    )
    (wheel,) = dist.glob("refnpr-*.whl")
    return wheel


def _fresh_env(tmp: Path, wheel: Path) -> tuple[Path, dict[str, str]]:
    venv = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps"]
        + ["--no-index", "-q", str(wheel)],
        capture_output=True,
        text=True,
        timeout=240,
    )
    assert proc.returncode == 0, proc.stdout[-1500:] + proc.stderr[-1500:]
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    deps = [p for p in site.getsitepackages() if Path(p).is_dir()]
    Path(purelib, "_test_dependencies.pth").write_text("\n".join(deps) + "\n")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PYTHONNOUSERSITE"] = "1"
    return venv, env


def test_wheel_runs_golden_check_and_kit_export_outside_a_checkout(tmp_path):
    wheel = _build_wheel(tmp_path)
    size_mb = wheel.stat().st_size / 1e6
    stated = re.search(r"wheel\s+is\s+about\s+([\d.]+)\s+MB", (REPO / "README.md").read_text())
    assert stated, "README.md states the wheel size as 'wheel is about N MB'"
    assert abs(size_mb - float(stated.group(1))) <= 0.25 * float(stated.group(1)), size_mb

    venv, env = _fresh_env(tmp_path, wheel)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    assert REPO not in elsewhere.parents and not (elsewhere / "pyproject.toml").exists()

    # the wheel's refnpr, with the wheel's suite; the checkout is not importable
    probe = _run(
        [
            str(venv / "bin" / "python"),
            "-c",
            "import json, refnpr, refnpr.golden as g; print(json.dumps([refnpr.__file__, "
            "str(g.DEFAULT_SUITE), g.source_checkout() is None]))",
        ],
        elsewhere,
        env,
    )
    assert probe.returncode == 0, probe.stderr[-1500:]
    module, suite, installed = json.loads(probe.stdout)
    assert Path(module).is_relative_to(venv), module
    assert Path(suite).is_relative_to(venv) and Path(suite).is_file(), suite
    assert installed, "the wheel's refnpr believes it runs from a checkout"

    refnpr = str(venv / "bin" / "refnpr")
    check = _run([refnpr, "golden", "--check", "--only", CASE], elsewhere, env)
    assert check.returncode == 0, check.stdout[-1500:] + check.stderr[-1500:]
    assert check.stdout.startswith(f"PASS {CASE}") and "1 passed, 0 failed" in check.stdout

    export = _run([refnpr, "kit", "export", "kit", "--only", CASE], elsewhere, env)
    assert export.returncode == 0, export.stdout[-1500:] + export.stderr[-1500:]
    first = export.stdout.splitlines()[0]
    assert first.startswith("refnpr 0.1.0, git unknown"), first
    assert suite in first and "the suite installed with refnpr" in first, first
    index = json.loads((elsewhere / "kit" / "index.json").read_text())
    prov = index["provenance"]
    assert prov["refnpr"] == index["refnpr"] and prov["git_commit"] is None
    assert prov["suite"]["packaged"] is True and prov["suite"]["path"] == "refnpr/suite/suite.toml"
    assert [c["name"] for c in index["cases"]] == [CASE]
    png = elsewhere / "kit" / CASE / "expected.png"
    assert png.read_bytes() == (REPO / "refnpr" / "suite" / f"{CASE}.png").read_bytes()

    # the installed golden files are the package's: --update refuses to rewrite them
    update = _run([refnpr, "golden", "--update", "--only", CASE], elsewhere, env)
    assert update.returncode == 2, update.stdout + update.stderr
    assert "installed with refnpr" in update.stderr and "--suite" in update.stderr
    assert "Traceback" not in update.stderr
    assert sorted(p.name for p in elsewhere.iterdir()) == ["kit"]
