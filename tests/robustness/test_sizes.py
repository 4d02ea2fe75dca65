"""Catalogue, class "sizes": image sizes and sample counts nobody checked, and bad size arguments.

Sizes that would allocate more than the machine has run in child processes under an
address-space limit (``limit_mb``), so a missing check fails fast instead of taking the machine's
memory; bad types and ranges run in-process (they are refused before anything is allocated).
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from .catalogue import Case, Correct, Exits, Raises, cli, parametrize, python

LIMIT_MB = 3000  # address space of a child: enough for a small render, far below any huge one
GB = r"needs about [0-9.]+ GB"


def _size_msg(w: int, h: int, spp: int) -> str:
    return rf"size: {w}x{h} at spp={spp} .*{GB}.* available"


def _render_cli(*args: str):
    def run(tmp: Path) -> subprocess.CompletedProcess:
        return cli("render", *args, "-q", "-o", str(tmp / "out.png"), limit_mb=LIMIT_MB)

    return run


_PRELUDE = (
    "import sys\n"
    "from refnpr.raster import Camera, rasterize\n"
    "from refnpr.render import render\n"
    "from refnpr.scenes import icosphere\n"
    "cam = Camera.look_at(eye=(0, 0, 3), target=(0, 0, 0), up=(0, 1, 0), fov_y=45, near=0.1,"
    " far=100)\n"
)


def _child(call: str):
    """``call`` in a child under the address-space limit; a refusal is printed as ``error:``."""
    code = (
        _PRELUDE + f"try:\n    {call}\nexcept (ValueError, TypeError) as exc:\n"
        "    print(f'error: {exc}', file=sys.stderr)\n    sys.exit(2)\n"
    )

    def run(tmp: Path) -> subprocess.CompletedProcess:
        return python(code, limit_mb=LIMIT_MB)

    return run


def _rasterize(**kw):
    def run(tmp: Path):
        from refnpr.raster import Camera, rasterize
        from refnpr.scenes import icosphere

        cam = Camera.look_at(
            eye=(0, 0, 3), target=(0, 0, 0), up=(0, 1, 0), fov_y=45, near=0.1, far=100
        )
        args = {"width": 32, "height": 24, "spp": 1, **kw}
        return rasterize(icosphere(1), cam, args.pop("width"), args.pop("height"), **args)

    return run


def _render(**kw):
    def run(tmp: Path):
        from refnpr.render import render

        args = {"width": 32, "height": 24, **kw}
        return render("sphere", "toon", **args)

    return run


def _golden(width: int, height: int):
    def run(tmp: Path) -> subprocess.CompletedProcess:
        import numpy as np

        from refnpr.image import write_png_atomic

        suite = tmp / "suite.toml"
        suite.write_text(
            f'[[case]]\nname = "wide"\nscene = "sphere"\nstyle = {{ name = "toon" }}\n'
            f"width = {width}\nheight = {height}\n"
        )
        write_png_atomic(tmp / "wide.png", np.zeros((2, 2, 4), np.uint8))  # a golden to compare
        r = cli("golden", "--check", "--suite", str(suite), limit_mb=LIMIT_MB)
        # golden --check reports a failed case on stdout and exits 1
        return subprocess.CompletedProcess(r.args, r.returncode, r.stdout, r.stdout + r.stderr)

    return run


def _png_written(result: subprocess.CompletedProcess, tmp: Path) -> None:
    assert result.returncode == 0, result.stderr[-500:]
    assert (tmp / "out.png").stat().st_size > 0


def _image_of(w: int, h: int):
    def check(result, tmp: Path) -> None:
        assert result.rgba.shape == (h, w, 4)

    return check


def _c(id, given, run, expect, notes=""):
    return Case(id=id, klass="sizes", given=given, run=run, expect=expect, notes=notes)


CASES = [
    # ---- the CLI ------------------------------------------------------------------------
    _c(
        "cli-size-100000",
        "refnpr render --size 100000x100000 (default spp 4)",
        _render_cli("--size", "100000x100000"),
        Exits(2, _size_msg(100000, 100000, 4) + ".*2\\*\\*31"),
    ),
    _c(
        "cli-size-30000",
        "refnpr render --size 30000x30000 (default spp 4, under a 3 GB address-space limit)",
        _render_cli("--size", "30000x30000"),
        Exits(2, _size_msg(30000, 30000, 4) + r".*Render smaller \(e\.g\. \d+x\d+"),
    ),
    _c(
        "cli-spp-1000000",
        "refnpr render --spp 1000000",
        _render_cli("--spp", "1000000"),
        Exits(2, r"spp: .*at most 65536.*got 1000000"),
    ),
    _c(
        "cli-spp-10000-512",
        "refnpr render --spp 10000 --size 512x512",
        _render_cli("--spp", "10000", "--size", "512x512"),
        Exits(2, _size_msg(512, 512, 10000)),
    ),
    _c(
        "cli-spp-1024-2048",
        "refnpr render --spp 1024 --size 2048x2048 (a 65536 x 65536 sample grid)",
        _render_cli("--spp", "1024", "--size", "2048x2048"),
        Exits(2, _size_msg(2048, 2048, 1024) + ".*2\\*\\*31"),
    ),
    _c(
        "cli-spp-16-4096",
        "refnpr render --spp 16 --size 4096x4096 (under a 3 GB address-space limit)",
        _render_cli("--spp", "16", "--size", "4096x4096"),
        Exits(2, _size_msg(4096, 4096, 16) + ".*RLIMIT_AS"),
    ),
    _c("cli-spp-3", "refnpr render --spp 3", _render_cli("--spp", "3"), Exits(2, r"spp: .*got 3")),
    _c(
        "cli-small-under-limit",
        "refnpr render --size 64x48 --spp 4 under a 3 GB address-space limit (must still work)",
        _render_cli("--size", "64x48", "--spp", "4"),
        Correct(_png_written),
    ),
    _c(
        "golden-width-1000000",
        "a golden suite case of width 1000000 (refnpr golden --check --suite S)",
        _golden(1000000, 192),
        Exits(1, r"FAIL +wide .*" + _size_msg(1000000, 192, 1)),
    ),
    # ---- rasterize / render: sizes -----------------------------------------------------------
    _c(
        "rasterize-size-100000",
        "rasterize(mesh, cam, 100000, 100000)",
        _rasterize(width=100000, height=100000),
        Raises(ValueError, _size_msg(100000, 100000, 1)),
    ),
    _c(
        "rasterize-size-30000-child",
        "rasterize(mesh, cam, 30000, 30000) under a 3 GB address-space limit",
        _child("rasterize(icosphere(1), cam, 30000, 30000)"),
        Exits(2, _size_msg(30000, 30000, 1)),
    ),
    _c(
        "render-size-100000",
        "render('sphere', 'toon', 100000, 100000)",
        _render(width=100000, height=100000),
        Raises(ValueError, _size_msg(100000, 100000, 1)),
    ),
    _c(
        "render-spp-1000000",
        "render('sphere', 'toon', 32, 24, spp=1000000)",
        _render(spp=1000000),
        Raises(ValueError, r"spp: .*at most 65536.*got 1000000"),
    ),
    _c(
        "render-spp-10000-512-child",
        "render(scene, 'toon', 512, 512, spp=10000) under a 3 GB address-space limit",
        _child("render('sphere', 'toon', 512, 512, spp=10000)"),
        Exits(2, _size_msg(512, 512, 10000)),
    ),
    _c(
        "render-size-8000-spp4-child",
        "render('sphere', 'toon', 8000, 6000, spp=4) under a 3 GB address-space limit",
        _child("render('sphere', 'toon', 8000, 6000, spp=4)"),
        Exits(2, _size_msg(8000, 6000, 4)),
    ),
    # ---- bad spp / width / height ------------------------------------------------------------
    _c(
        "rasterize-spp-0",
        "rasterize(..., spp=0)",
        _rasterize(spp=0),
        Raises(ValueError, r"spp: .*got 0"),
    ),
    _c(
        "rasterize-spp-3",
        "rasterize(..., spp=3)",
        _rasterize(spp=3),
        Raises(ValueError, r"spp: .*square.*got 3"),
    ),
    _c(
        "rasterize-spp--4",
        "rasterize(..., spp=-4)",
        _rasterize(spp=-4),
        Raises(ValueError, r"spp: .*got -4"),
    ),
    _c(
        "rasterize-spp-2.5",
        "rasterize(..., spp=2.5)",
        _rasterize(spp=2.5),
        Raises(TypeError, r"spp: .*2\.5"),
    ),
    _c(
        "rasterize-width-0",
        "rasterize(mesh, cam, 0, 24)",
        _rasterize(width=0),
        Raises(ValueError, r"width: .*got 0"),
    ),
    _c(
        "rasterize-width--5",
        "rasterize(mesh, cam, -5, 24)",
        _rasterize(width=-5),
        Raises(ValueError, r"width: .*got -5"),
    ),
    _c(
        "rasterize-width-str",
        "rasterize(mesh, cam, '64', 24)",
        _rasterize(width="64"),
        Raises(TypeError, r"width: .*'64'"),
    ),
    _c(
        "rasterize-height-True",
        "rasterize(mesh, cam, 32, True)",
        _rasterize(height=True),
        Raises(TypeError, r"height: .*True"),
    ),
    _c(
        "render-spp-3",
        "render(..., spp=3)",
        _render(spp=3),
        Raises(ValueError, r"spp: .*square.*got 3"),
    ),
    _c(
        "render-spp-2.5",
        "render(..., spp=2.5)",
        _render(spp=2.5),
        Raises(TypeError, r"spp: .*2\.5"),
    ),
    _c(
        "render-width-0",
        "render(scene, style, 0, 24)",
        _render(width=0),
        Raises(ValueError, r"width: .*got 0"),
    ),
    _c(
        "render-width-str",
        "render(scene, style, '64', 24)",
        _render(width="64"),
        Raises(TypeError, r"width: .*'64'"),
    ),
    _c(
        "render-height-True",
        "render(scene, style, 32, True)",
        _render(height=True),
        Raises(TypeError, r"height: .*True"),
    ),
    _c(
        "render-progress-3",
        "render(..., progress=3)",
        _render(progress=3),
        Raises(TypeError, r"progress: expected a callable.*got int 3"),
    ),
    _c(
        "render-return-gbuffer-str",
        "render(..., return_gbuffer='yes')",
        _render(return_gbuffer="yes"),
        Raises(TypeError, r"return_gbuffer: expected a bool.*'yes'"),
    ),
    _c(
        "render-camera-str",
        "render(..., camera='front')",
        _render(camera="front"),
        Raises(TypeError, r"camera: expected .*Camera.*got str 'front'"),
    ),
    _c(
        "render-spp-65536-4x3",
        "render('sphere', 'toon', 4, 3, spp=65536): the largest spp on a tiny image works",
        _render(width=4, height=3, spp=65536),
        Correct(_image_of(4, 3)),
    ),
]

test_case = parametrize(CASES)
