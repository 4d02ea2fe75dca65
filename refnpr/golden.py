"""Golden-image suite: one module both checks and regenerates the ground truth.

The suite ships inside the package, in ``refnpr/suite/`` (:data:`SUITE_DIR`), so an installed
refnpr checks itself and exports the conformance kit from any directory. ``suite.toml`` there
lists cases (scene x style x size). Each image case ``NAME`` is stored beside it as
``NAME.png`` (8-bit sRGB RGBA). G-buffer cases (``kind = "gbuffer"``) store ``NAME.npz`` with
float32 channels, for backends that compare their rasterizer itself. Any other suite file works
the same way (its golden files beside it).

* ``update_suite`` renders every case and writes its files (atomically).
* ``check_suite`` re-renders and compares; a missing golden file is a failure, never a skip. On a
  mismatch it writes ``reference``, ``result`` and ``diff`` images to the failure directory.

Suite format::

    include = ["veryovka.toml"]  # optional: files of more [[case]] tables (same defaults)

    [defaults]              # any case key; the values below are the built-in defaults
    width = 256
    height = 192
    spp = 1
    tolerance = 0.0079      # per-channel difference that counts a pixel as differing (2/255)
    max_frac_over = 0.0005  # fraction of differing pixels allowed
    min_ssim = 0.995
    position_deviation = 1  # kit check: a pixel also passes when a reference pixel within N
                            # pixels (Chebyshev distance) matches it within `tolerance`
    discrete_max_pixels = 0 # gbuffer cases: samples of tri_id / mesh_id allowed to differ

    [[case]]
    name = "teapot-toon"    # file stem: [a-z0-9_-]+
    scene = "teapot"        # built-in scene name, or a .toml, .gltf or .glb path relative to the suite file
    style = { name = "toon", n = 2 }
    spp = 4                 # overrides a default

    [[case]]
    name = "gbuffer-default"
    kind = "gbuffer"
    scene = "default"
    channels = ["depth", "tri_id", "uv", "duv_dx", "duv_dy", "normal"]
    rtol = 1e-5             # gbuffer cases: relative tolerance of float channels

``position_deviation`` and ``discrete_max_pixels`` are the tolerances of ``refnpr kit check``
(the conformance kit carries every tolerance key per case: docs/kit.md); ``refnpr golden
--check`` (refnpr against itself) does not use them. G-buffer float channels pass where
|a - b| <= atol + rtol |b|.
"""

from __future__ import annotations

import os
import re
import stat
import tempfile
from collections.abc import Callable, Iterable, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .compare import ImageMetrics, compare_images, difference_image, load_image
from .image import atomic_file, write_png_atomic
from .raster import rasterize
from .render import render
from .scenes.toml_format import parse_toml_bytes

__all__ = [
    "SUITE_DIR",
    "DEFAULT_SUITE",
    "source_checkout",
    "is_packaged_suite",
    "default_failure_dir",
    "check_writable_suite",
    "GoldenCase",
    "CaseResult",
    "RenderCases",
    "load_suite",
    "update_suite",
    "check_suite",
    "render_case",
    "render_or_error",
]

#: render_cases(cases) -> (index in cases, rendered case, error message or None) for every case,
#: in any order: how check_suite / update_suite get their renders (refnpr.distributed passes one
#: that renders on a Dask cluster; the default renders here, one case after another).
RenderCases = Callable[[Sequence["GoldenCase"]], Iterable[tuple[int, Any, "str | None"]]]

_DEFAULTS: dict[str, Any] = {
    "kind": "image",
    "width": 256,
    "height": 192,
    "spp": 1,
    "tolerance": 2.0 / 255,
    "max_frac_over": 0.0005,
    "min_ssim": 0.995,
    "position_deviation": 1,
    "discrete_max_pixels": 0,
    "rtol": 1e-5,
    "atol": 1e-6,
    "style": None,
    "channels": ["depth", "tri_id", "uv", "duv_dx", "duv_dy", "normal"],
    "texture_size": None,
    "description": "",
}
#: A case name (full match): it names files and kit directories (the kit's own pattern allows
#: dots too; both cap the length at 128).
_NAME = re.compile(r"[a-z0-9][a-z0-9_\-]{0,127}")

#: The golden suite shipped in the package: ``suite.toml``, the ``*.toml`` files it includes, the
#: golden images (``*.png``) and G-buffers (``*.npz``).
SUITE_DIR = Path(__file__).resolve().parent / "suite"
#: The suite ``refnpr golden`` and ``refnpr kit export`` use when no ``--suite`` is given.
DEFAULT_SUITE = SUITE_DIR / "suite.toml"


def source_checkout() -> Path | None:
    """The source tree refnpr runs from (a checkout, installed editable or put on ``sys.path``):
    the directory that holds ``pyproject.toml`` beside the ``refnpr`` package. None for a
    regular install (a wheel in site-packages)."""
    root = Path(__file__).resolve().parent.parent
    return root if (root / "pyproject.toml").is_file() else None


def is_packaged_suite(suite_path: str | Path) -> bool:
    """Whether ``suite_path`` is the suite file shipped in the package (:data:`DEFAULT_SUITE`)."""
    try:
        return Path(suite_path).resolve() == DEFAULT_SUITE
    except (OSError, RuntimeError):  # a symlink loop
        return False


def default_failure_dir(suite_path: str | Path) -> Path:
    """Where :func:`check_suite` writes a failing case's images by default: ``_failures/`` beside
    the suite file, or, for the suite of an installed (not editable) refnpr, a
    ``refnpr-golden-failures-<uid>`` directory of the user in the system temporary directory
    (site-packages is no place for them, and may not be writable).

    Raises
    ------
    ValueError
        That temporary directory exists but is a symbolic link, not a directory, or another
        user's (the shared temporary directory: someone else could redirect the images).
    """
    if not (is_packaged_suite(suite_path) and source_checkout() is None):
        return Path(suite_path).parent / "_failures"
    uid = os.getuid() if hasattr(os, "getuid") else None
    out = Path(tempfile.gettempdir()) / f"refnpr-golden-failures-{uid if uid is not None else 0}"
    try:
        st = os.lstat(out)
    except FileNotFoundError:
        out.mkdir(mode=0o700)
        return out
    if (
        stat.S_ISLNK(st.st_mode)
        or not stat.S_ISDIR(st.st_mode)
        or (uid is not None and st.st_uid != uid)
    ):
        raise ValueError(
            f"{str(out)!r} is not a directory of yours (a symbolic link, a file or another "
            "user's); remove it, or give check_suite a failure_dir"
        )
    return out


def check_writable_suite(suite_path: str | Path) -> None:
    """A ValueError if ``suite_path`` is the suite of an installed (not editable) refnpr: its
    golden files are part of the package, and :func:`update_suite` must not rewrite them."""
    if is_packaged_suite(suite_path) and source_checkout() is None:
        raise ValueError(
            f"suite: {str(suite_path)!r} is the golden suite installed with refnpr; updating it "
            "would overwrite the package's reference images. Regenerate them in a refnpr "
            "checkout (pip install -e .), or copy the directory "
            f"{str(SUITE_DIR)!r} and pass --suite COPY/suite.toml"
        )


@dataclass(frozen=True)
class GoldenCase:
    name: str
    scene: str
    params: dict[str, Any] = field(default_factory=dict)

    def __getattr__(self, key: str) -> Any:
        if key == "params" or key.startswith("__"):  # unpickling asks before params is set
            raise AttributeError(key)
        try:
            return self.params[key]
        except KeyError:
            raise AttributeError(key) from None


@dataclass(frozen=True)
class CaseResult:
    name: str
    passed: bool
    message: str
    metrics: ImageMetrics | None = None


def load_suite(path: str | Path) -> list[GoldenCase]:
    """Parse ``suite.toml`` into cases (clear ValueError naming the file and key on errors)."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(
            f"suite: {str(path)!r} is a directory; give the suite file in it, such as "
            f"{str(path / 'suite.toml')!r}"
        )
    if not path.is_file():
        raise ValueError(
            f"suite: {str(path)!r} does not exist (looked for {str(path.absolute())!r}); "
            "give an existing suite file (TOML), or leave --suite out to use the suite "
            "installed with refnpr"
        )
    data = _read_toml(path)
    unknown = set(data) - {"defaults", "case", "include"}
    if unknown:
        raise ValueError(
            f"{path}: unknown top-level keys {sorted(unknown)}; use include, [defaults], [[case]]"
        )
    raw_cases = list(data.get("case", []))
    includes = data.get("include", [])
    if not isinstance(includes, list) or not all(isinstance(i, str) for i in includes):
        raise ValueError(f"{path}: include must be a list of file names, got {includes!r}")
    for inc in includes:
        inc_path = path.parent / inc
        if not inc_path.is_file():
            raise ValueError(
                f"{path}: include {inc!r} does not exist (paths are relative to the suite)"
            )
        inc_data = _read_toml(inc_path)
        if set(inc_data) - {"case"}:
            raise ValueError(f"{inc_path}: an included file holds only [[case]] tables")
        raw_cases += list(inc_data.get("case", []))
    _check_keys(data.get("defaults", {}), f"{path}: [defaults]")
    defaults = {**_DEFAULTS, **data.get("defaults", {})}
    cases, seen = [], set()
    for i, raw in enumerate(raw_cases):
        raw = dict(raw)
        name = raw.pop("name", None)
        scene = raw.pop("scene", None)
        if not isinstance(name, str) or not _NAME.fullmatch(name):
            raise ValueError(
                f"{path}: case #{i + 1}: 'name' must match [a-z0-9][a-z0-9_-]* (at most 128 characters), got {name!r}"
            )
        if name in seen:
            raise ValueError(f"{path}: case {name!r} is listed twice")
        seen.add(name)
        if not isinstance(scene, str):
            raise ValueError(
                f"{path}: case {name!r}: 'scene' (a built-in name, or a .toml, .gltf or .glb path) is required"
            )
        _check_keys(raw, f"{path}: case {name!r}:")
        params = {**defaults, **raw}
        _check_case(path, name, params)
        if params["kind"] not in ("image", "gbuffer"):
            raise ValueError(
                f"{path}: case {name!r}: kind must be 'image' or 'gbuffer', got {params['kind']!r}"
            )
        if scene.lower().endswith((".toml", ".gltf", ".glb")):
            scene = str((path.parent / scene).resolve())
        cases.append(GoldenCase(name, scene, params))
    if not cases:
        raise ValueError(f"{path}: the suite has no [[case]] entries")
    return cases


def scene_case(
    name: str,
    scene: str | Path,
    *,
    style: Any = None,
    width: int = 256,
    height: int = 192,
    spp: int = 1,
) -> GoldenCase:
    """An image case of the user's own scene, with the suite's defaults (tolerance, threshold,
    SSIM, position deviation): what ``refnpr kit export DIR --scene FILE`` exports.

    Parameters
    ----------
    name : str
        The case name, ``[a-z0-9][a-z0-9_-]*``.
    scene : str or path
        A built-in scene name or a scene file (.toml, .gltf, .glb).
    style : str, dict or None
        As in a suite file (None: the scene's own style).
    width, height, spp : int
        Image size and samples per pixel.

    Raises
    ------
    ValueError
        A bad name, size or spp, naming it; the scene and style are checked when exported.
    """
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise ValueError(
            f"name: expected a case name matching [a-z0-9][a-z0-9_-]* (at most 128 characters), got {name!r}"
        )
    params = {**_DEFAULTS, "style": style, "width": width, "height": height, "spp": spp}
    _check_case(Path(str(scene)), name, params)
    scene = str(scene)
    if scene.lower().endswith((".toml", ".gltf", ".glb")):
        scene = str(Path(scene).resolve())
    return GoldenCase(name, scene, params)


def _check_keys(table: dict[str, Any], where: str) -> None:
    for key in table:
        if key not in _DEFAULTS:
            raise ValueError(f"{where} unknown key {key!r}; valid keys: {sorted(_DEFAULTS)}")


def _read_toml(path: Path) -> dict[str, Any]:
    """A suite file parsed; a ValueError naming the file (and the line) on any failure."""
    return parse_toml_bytes(path.read_bytes(), str(path), what="suite files (TOML)")


def _check_case(path: Path, name: str, params: dict[str, Any]) -> None:
    """Types and ranges of a case's numbers (a NaN tolerance would pass any image)."""

    def fail(key: str, expected: str) -> None:
        raise ValueError(f"{path}: case {name!r}: {key}: expected {expected}, got {params[key]!r}")

    for key in ("width", "height", "spp"):
        v = params[key]
        if isinstance(v, bool) or not isinstance(v, int) or v < 1:
            fail(key, "a positive integer")
    for key, hi in (("position_deviation", 16), ("discrete_max_pixels", 2**31 - 1)):
        v = params[key]
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= hi:
            fail(key, f"an integer in [0, {hi}]")
    for key, (lo, hi) in {
        "tolerance": (0.0, 1.0),
        "max_frac_over": (0.0, 1.0),
        "min_ssim": (-1.0, 1.0),
        "rtol": (0.0, 1.0),
        "atol": (0.0, float("inf")),
    }.items():
        v = params[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not lo <= v <= hi:
            fail(key, f"a number in [{lo}, {hi}]")
    ch = params["channels"]
    if not isinstance(ch, list) or not ch or not all(isinstance(c, str) for c in ch):
        fail("channels", "a non-empty list of channel names")


def render_case(case: GoldenCase) -> np.ndarray | dict[str, np.ndarray]:
    """Render one case: (H, W, 4) uint8 sRGB for images, dict of float32 channels for G-buffers."""
    if case.kind == "gbuffer":
        from .scenes import load_scene

        scene = load_scene(case.scene)
        extra = {"texture_size": tuple(case.texture_size)} if case.texture_size else {}
        gb = rasterize(
            scene, scene.camera, case.width, case.height, case.channels, case.spp, **extra
        )
        return {k: np.asarray(gb[k]) for k in gb}
    return render(case.scene, case.style, case.width, case.height, case.spp).to_srgb8()


def render_or_error(case: GoldenCase) -> tuple[Any, str | None]:
    """``(render_case(case), None)``, or ``(None, "render failed: ...")`` when the case's
    scene or style is invalid (ValueError, TypeError, OSError): one broken case must not hide
    the rest of a check."""
    try:
        return render_case(case), None
    except (ValueError, TypeError, OSError) as exc:
        return None, f"render failed: {exc}"


def _render(case: GoldenCase, catch: bool) -> tuple[Any, str | None]:
    """One case's render, and with ``catch`` a render error as check_suite words it."""
    return render_or_error(case) if catch else (render_case(case), None)


@contextmanager
def _renders(render_cases: RenderCases | None, cases: list[GoldenCase], catch: bool):
    """The renders of ``cases`` (here, one after another, without ``render_cases``), closed when
    the block ends: a generator of renders elsewhere cancels what is left (errors, Ctrl-C)."""
    if render_cases is None:
        renders = ((i, *_render(case, catch)) for i, case in enumerate(cases))
    else:
        renders = iter(render_cases(cases))
    try:
        yield renders
    finally:
        close = getattr(renders, "close", None)
        if close is not None:
            close()


def _files(root: Path, case: GoldenCase) -> Path:
    return root / (f"{case.name}.npz" if case.kind == "gbuffer" else f"{case.name}.png")


def update_suite(
    suite_path: str | Path,
    *,
    only: list[str] | None = None,
    log=print,
    render_cases: RenderCases | None = None,
) -> list[Path]:
    """Render every case (or those named in ``only``) and write the golden files.

    ``render_cases`` (see :data:`RenderCases`) renders the cases elsewhere (a Dask cluster:
    :func:`refnpr.distributed.update_suite`); each file is written as its render arrives.
    Returns the files in suite order.

    Raises
    ------
    ValueError
        The suite cannot be read, an unknown name in ``only``, or ``suite_path`` is the suite of
        an installed (not editable) refnpr, whose golden files are part of the package.
    """
    suite_path = Path(suite_path)
    root = suite_path.parent
    check_writable_suite(suite_path)
    cases = _select(load_suite(suite_path), only)
    written: dict[int, Path] = {}
    with _renders(render_cases, cases, catch=False) as renders:
        for i, result, _ in renders:
            case = cases[i]
            target = _files(root, case)
            if case.kind == "gbuffer":
                with atomic_file(target, suffix=".npz") as tmp:
                    np.savez_compressed(tmp, **result)
            else:
                write_png_atomic(target, result)
            written[i] = target
            log(f"wrote {target}")
    return [written[i] for i in sorted(written)]


def _select(cases: list[GoldenCase], only: list[str] | None) -> list[GoldenCase]:
    if not only:
        return cases
    names = {c.name for c in cases}
    unknown = [n for n in only if n not in names]
    if unknown:
        raise ValueError(f"only: unknown case names {unknown}; the suite has {sorted(names)}")
    return [c for c in cases if c.name in only]


def _load_golden_npz(target: Path) -> dict[str, np.ndarray]:
    """The channels of a G-buffer golden file (ValueError naming it if it is not a valid .npz)."""
    try:
        with np.load(target, allow_pickle=False) as ref:
            if not hasattr(ref, "files"):
                raise ValueError("a single array, not an .npz archive of channels")
            return {k: ref[k] for k in ref.files}
    except Exception as exc:  # noqa: BLE001 -- zipfile, pickle and numpy raise many types
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise ValueError(
            f"cannot read golden file {str(target)!r} ({first}); expected an .npz archive "
            "of float32/int32 channels: run `refnpr golden --update` to rewrite it"
        ) from None


def _check_gbuffer(case: GoldenCase, target: Path, got: dict[str, np.ndarray]) -> CaseResult:
    try:
        ref = _load_golden_npz(target)
    except ValueError as exc:
        return CaseResult(case.name, False, str(exc))
    if set(ref) != set(got):
        return CaseResult(
            case.name, False, f"channels differ: golden {sorted(ref)}, got {sorted(got)}"
        )
    worst = []
    for k in sorted(ref):
        a, b = ref[k], got[k]
        if a.shape != b.shape:
            return CaseResult(case.name, False, f"{k}: shape {b.shape} != golden {a.shape}")
        if a.dtype.kind in "iu":
            bad = float(np.mean(a != b))
            if bad > case.max_frac_over:
                worst.append(f"{k}: {bad:.4%} of samples differ")
        else:
            finite = np.isfinite(a) & np.isfinite(b)
            if np.any(np.isfinite(a) != np.isfinite(b)):
                worst.append(f"{k}: finite/inf pattern differs")
            close = np.isclose(b[finite], a[finite], rtol=case.rtol, atol=case.atol)
            bad = float(np.mean(~close)) if close.size else 0.0
            if bad > case.max_frac_over:
                worst.append(f"{k}: {bad:.4%} of samples beyond rtol={case.rtol}")
    if worst:
        return CaseResult(case.name, False, "; ".join(worst))
    return CaseResult(case.name, True, "ok")


def check_suite(
    suite_path: str | Path,
    *,
    only: list[str] | None = None,
    failure_dir: str | Path | None = None,
    render_cases: RenderCases | None = None,
) -> list[CaseResult]:
    """Re-render every case and compare with its golden file. Missing golden files fail.

    A failing image case's ``reference``, ``result`` and ``diff`` PNGs go to
    ``failure_dir / NAME/`` (default: :func:`default_failure_dir`; no ``diff`` when the sizes
    differ); those of an earlier failure are removed when the case passes, and that directory
    with them if nothing else is in it.

    ``render_cases`` (see :data:`RenderCases`) renders the cases elsewhere (a Dask cluster:
    :func:`refnpr.distributed.check_suite`); the comparison, the messages and the failure
    images are the same. Results are in suite order.
    """
    suite_path = Path(suite_path)
    root = suite_path.parent
    if failure_dir is not None:
        fail_root = Path(failure_dir)
    else:
        fail_root = default_failure_dir(suite_path)
    cases = _select(load_suite(suite_path), only)
    results: dict[int, CaseResult] = {}
    present = []
    for i, case in enumerate(cases):
        target = _files(root, case)
        if not target.exists():
            results[i] = CaseResult(
                case.name, False, f"missing golden file {target}; run `refnpr golden --update`"
            )
        else:
            present.append(i)
    with _renders(render_cases, [cases[i] for i in present], catch=True) as renders:
        for j, got, error in renders:
            i = present[j]
            case = cases[i]
            if error is not None:
                results[i] = CaseResult(case.name, False, error)
            else:
                results[i] = _check_case_render(case, _files(root, case), got, fail_root)
    return [results[i] for i in sorted(results)]


#: The images :func:`check_suite` writes into a failing case's directory ``failure_dir / NAME``
_FAILURE_IMAGES = ("reference.png", "result.png", "diff.png")


def _write_failure_images(
    d: Path, ref: np.ndarray, got: np.ndarray, diff: np.ndarray | None
) -> None:
    """Write a failing case's ``reference``, ``result`` and, where the sizes agree, ``diff``
    PNGs into ``d``; without a ``diff``, the one of an earlier failure is removed (it is stale)."""
    write_png_atomic(d / "reference.png", np.rint(ref * 255).astype(np.uint8))
    write_png_atomic(d / "result.png", got)
    if diff is not None:
        write_png_atomic(d / "diff.png", diff)
    else:
        (d / "diff.png").unlink(missing_ok=True)


def _remove_failure_images(d: Path) -> None:
    """Remove the images of an earlier failure of a case (it now passes, or has no images to
    show), and its directory ``d`` if that leaves it empty (other files stay, with it)."""
    if d.is_symlink() or not d.is_dir():
        return
    for name in _FAILURE_IMAGES:
        (d / name).unlink(missing_ok=True)
    with suppress(OSError):  # not empty: something else is kept there
        d.rmdir()


def _check_case_render(case: GoldenCase, target: Path, got: Any, fail_root: Path) -> CaseResult:
    """Compare one case's render with its golden file (writing failure images)."""
    if case.kind == "gbuffer":
        return _check_gbuffer(case, target, got)
    d = fail_root / case.name
    try:
        ref = load_image(target, what="golden file")
    except ValueError as exc:  # a corrupt golden file fails its case, not the suite
        _remove_failure_images(d)  # those of an earlier failure would be stale
        return CaseResult(case.name, False, f"{exc}; run `refnpr golden --update` to rewrite it")
    cand = got.astype(np.float64) / 255.0
    m = compare_images(ref, cand, name=case.name, tolerance=case.tolerance)
    if m.status == "size":
        _write_failure_images(d, ref, got, None)
        gh, gw = ref.shape[:2]
        why = (
            f"size: golden file {str(target)!r} is {gw}x{gh} but the case renders "
            f"{case.width}x{case.height}; if the suite's size changed on purpose, "
            f"run `refnpr golden --update`; images written to {d}"
        )
        return CaseResult(case.name, False, why, m)
    ok = m.passes(max_frac_over=case.max_frac_over, min_ssim=case.min_ssim)
    if ok:
        _remove_failure_images(d)
    else:
        diff = difference_image(ref, cand) if m.status == "ok" else None
        _write_failure_images(d, ref, got, diff)
    msg = (
        f"{m.status}: max_abs={m.max_abs:.4f} rmse={m.rmse:.5f} "
        f"frac>tol={m.frac_over:.5f} (allowed {case.max_frac_over}) "
        + ("ssim=n/a (image too small)" if np.isnan(m.ssim) else f"ssim={m.ssim:.4f}")
    )
    if not ok:
        msg += f"; images written to {fail_root / case.name}"
    return CaseResult(case.name, ok, msg, m)
