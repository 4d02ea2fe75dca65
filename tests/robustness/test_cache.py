"""Catalogue, class "cache": numba's on-disk cache where nothing is writable.

numba caches a kernel in ``__pycache__`` beside its source, else in ``NUMBA_CACHE_DIR``, else in
a user-wide directory under ``HOME``; where none is writable it used to raise "cannot cache
function ...: no locator available" at import. Each case runs a copy of the package in a child
process whose ``__pycache__`` directories are plain files (nothing, not even root, can create a
directory there) and whose ``HOME``/``XDG_CACHE_HOME``/``NUMBA_CACHE_DIR`` lie under a file.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from .catalogue import ROOT, Case, Correct, parametrize

UNWRITABLE = "/dev/null/refnpr-cache"  # a path below a file: cannot be created by anyone


def unwritable_copy(tmp: Path) -> Path:
    """A copy of the package whose ``__pycache__`` directories cannot be created."""
    dest = tmp / "pkg"
    shutil.copytree(ROOT / "refnpr", dest / "refnpr", ignore=shutil.ignore_patterns("__pycache__"))
    for d in [dest / "refnpr", *(p for p in (dest / "refnpr").rglob("*") if p.is_dir())]:
        (d / "__pycache__").write_text("")
    return dest


def child_env(pkg: Path, tmpdir: Path, **extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_CACHE", "XDG_"))}
    env.update(
        PYTHONPATH=str(pkg),
        HOME=UNWRITABLE,
        XDG_CACHE_HOME=UNWRITABLE,
        TMPDIR=str(tmpdir),
        PYTHONDONTWRITEBYTECODE="1",
        **extra,
    )
    return env


def run_in_copy(tmp: Path, args: list[str], **extra: str) -> subprocess.CompletedProcess:
    pkg = tmp / "pkg" if (tmp / "pkg").exists() else unwritable_copy(tmp)
    tmpdir = tmp / "t"
    tmpdir.mkdir(exist_ok=True)
    return subprocess.run(
        [sys.executable, *args],
        capture_output=True,
        text=True,
        timeout=300,
        env=child_env(pkg, tmpdir, **extra),
        cwd=tmp,
    )


#: ``refnpr render`` of the style with the fewest kernels to compile (the cache's behaviour is
#: the same for every kernel; the default scene's halftone and contours take 4 s more)
RENDER = ["-m", "refnpr.cli", "render", "--scene", "sphere", "--style", "smooth", "--spp", "1"]


def _render(tmp: Path, **extra: str) -> subprocess.CompletedProcess:
    return run_in_copy(
        tmp,
        [*RENDER, "--size", "32x24", "-q", "-o", str(tmp / "o.png")],
        **extra,
    )


def _ok(result: subprocess.CompletedProcess, tmp: Path) -> None:
    assert result.returncode == 0, result.stderr[-600:]
    assert "Traceback" not in result.stderr, result.stderr[-600:]
    assert "pkg/refnpr" in result.stdout, result.stdout  # the copy, not the checkout, ran


def _import_all(tmp: Path) -> subprocess.CompletedProcess:
    code = (
        "import refnpr, refnpr.raster, refnpr.styles, refnpr.texture, refnpr.render\n"
        "print(refnpr.__file__)"
    )
    return run_in_copy(tmp, ["-c", code])


def _render_ok(tmp: Path) -> subprocess.CompletedProcess:
    r = _render(tmp)
    return subprocess.CompletedProcess(
        r.args, r.returncode, r.stdout + str(tmp / "pkg/refnpr"), r.stderr
    )


def _rendered(result: subprocess.CompletedProcess, tmp: Path) -> None:
    _ok(result, tmp)
    assert (tmp / "o.png").stat().st_size > 0


def _render_twice(tmp: Path) -> subprocess.CompletedProcess:
    first = _render(tmp)
    if first.returncode:
        return first
    second = _render(tmp)
    return subprocess.CompletedProcess(
        second.args, second.returncode, second.stdout + str(tmp / "pkg/refnpr"), second.stderr
    )


def _cached_in_tmp(result: subprocess.CompletedProcess, tmp: Path) -> None:
    _rendered(result, tmp)
    index = list((tmp / "t").rglob("*.nbi"))
    assert index, "no numba index files under TMPDIR: the fallback cache was not used"
    assert "warn" not in result.stderr.lower(), result.stderr  # a writable fallback is silent


def _cache_dir_unwritable(tmp: Path) -> subprocess.CompletedProcess:
    code = (
        "import refnpr, refnpr.raster, refnpr.styles, refnpr.texture\n"
        "from refnpr.render import render\n"
        "render('sphere', 'toon', 16, 12)\n"
        "print(refnpr.__file__)"
    )
    return run_in_copy(tmp, ["-c", code], NUMBA_CACHE_DIR=UNWRITABLE)


def _c(id, given, run, expect, notes=""):
    return Case(id=id, klass="cache", given=given, run=run, expect=expect, notes=notes)


CASES = [
    _c(
        "import-no-locator",
        "import refnpr.raster/styles/texture with no writable __pycache__, HOME or cache dir",
        _import_all,
        Correct(_ok),
    ),
    _c(
        "render-no-locator",
        "refnpr render with no writable __pycache__, HOME or XDG cache",
        _render_ok,
        Correct(_rendered),
    ),
    _c(
        "render-no-locator-caches-in-tmp",
        "the same twice: the second run loads the kernels from a cache under TMPDIR",
        _render_twice,
        Correct(_cached_in_tmp),
    ),
    _c(
        "numba-cache-dir-unwritable",
        "NUMBA_CACHE_DIR unwritable, no writable __pycache__ or HOME: render in Python",
        _cache_dir_unwritable,
        Correct(_ok),
    ),
]


test_case = parametrize(CASES)


def test_no_writable_fallback_compiles_without_cache_and_warns_once(tmp_path):
    # the fallback directory exists but others may write to it: numba's pickles are not trusted
    bad = tmp_path / "t" / f"refnpr-numba-{os.getuid()}"
    bad.mkdir(parents=True)
    bad.chmod(0o777)
    r = _render(tmp_path)
    assert r.returncode == 0, r.stderr[-600:]
    warnings = [ln for ln in r.stderr.splitlines() if "no writable numba cache directory" in ln]
    assert len(warnings) == 1, r.stderr
    assert not list(bad.rglob("*.nbi"))


def test_read_only_install_and_home(tmp_path):
    """The package and HOME on a read-only bind mount (root with mount namespaces only)."""
    if shutil.which("unshare") is None or os.geteuid() != 0:
        pytest.skip("needs root and unshare for a read-only bind mount")
    probe = subprocess.run(["unshare", "-m", "true"], capture_output=True)
    if probe.returncode:
        pytest.skip("no mount namespaces here")
    ro = tmp_path / "ro"
    shutil.copytree(ROOT / "refnpr", ro / "refnpr", ignore=shutil.ignore_patterns("__pycache__"))
    (ro / "home").mkdir()
    (tmp_path / "t").mkdir()
    env = {**child_env(ro, tmp_path / "t"), "HOME": str(ro / "home")}
    env.pop("XDG_CACHE_HOME")
    script = (
        f"mount --bind {ro} {ro} && mount -o remount,bind,ro {ro} && "
        f"{sys.executable} {' '.join(RENDER)} --size 32x24 -q -o {tmp_path / 'o.png'}"
    )
    r = subprocess.run(
        ["unshare", "-m", "sh", "-c", script],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr[-600:]
    assert (tmp_path / "o.png").stat().st_size > 0
    assert list((tmp_path / "t").rglob("*.nbi")), r.stderr  # cached in the fallback directory
