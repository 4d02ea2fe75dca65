"""``refnpr kit export``: write every input of the golden cases as a conformance kit (the
layout and every key: ``docs/kit.md``).

Each case is built in a temporary directory beside its target and renamed into place, so a case
directory is never partial; ``index.json`` is written last (atomically), with the provenance of
the export and the content hashes of every case (refnpr.kit.provenance, refnpr.kit.content).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..golden import DEFAULT_SUITE, GoldenCase, load_suite
from ..image import atomic_file, read_image_file
from ..raster import rasterize
from . import KIT_FORMAT, KIT_VERSION
from ._json import jsonable, write_json
from .camera import camera_entry, sample_positions
from .content import (
    GROUPS,
    case_files,
    case_hashes,
    digest,
    is_digest,
    list_files,
    read_bytes,
    read_json,
)
from .derived import channel_derived, generic_derived
from .exr import write_exr
from .provenance import provenance
from .scene_export import kit_meshes, lights_entry, objects_entry
from .schema import SCHEMA_FILES, schema_path
from .styles import export_style, style_name
from .tolerance import tolerance_entry

__all__ = ["export_kit", "export_case", "DEFAULT_SUITE"]

RESOLVE = {
    "filter": "box",
    "composite": "per sample: premultiplied over the background, then the n x n box mean, "
    "then unpremultiply (rgb / alpha where alpha > 0)",
}


def _check_dir(directory: str | os.PathLike) -> Path:
    if not isinstance(directory, (str, os.PathLike)):
        raise TypeError(f"dir: expected a directory path, got {type(directory).__name__}")
    d = Path(directory)
    if d.exists() and not d.is_dir():
        raise ValueError(
            f"dir: {str(directory)!r} exists and is not a directory; give a new or existing "
            "directory for the kit"
        )
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"dir: cannot create {str(directory)!r}: {exc.strerror}") from None
    if not os.access(d, os.W_OK):
        raise ValueError(f"dir: {str(directory)!r} is not writable")
    return d


def _select(cases: list[GoldenCase], only: list[str] | None) -> list[GoldenCase]:
    if only is None:
        return cases
    if isinstance(only, str) or not all(isinstance(n, str) for n in only):
        raise TypeError(f"only: expected a list of case names, got {only!r}")
    names = [c.name for c in cases]
    unknown = [n for n in only if n not in names]
    if unknown:
        import difflib

        hints = {n: difflib.get_close_matches(n, names, n=3) for n in unknown}
        hint = "; ".join(f"{n!r}: did you mean {h}?" for n, h in hints.items() if h)
        raise ValueError(
            f"only: unknown case names {unknown} (the suite has {len(names)} cases; list them "
            f"with `refnpr golden --check`){'; ' + hint if hint else ''}"
        )
    return [c for c in cases if c.name in set(only)]


def _style_of(case: GoldenCase, scene: Any) -> Any:
    from ..render import DEFAULT_STYLE
    from ..styles import style_from_spec

    spec = (
        case.style if case.style is not None else (getattr(scene, "style", None) or DEFAULT_STYLE)
    )
    return style_from_spec(spec)


def raster_options(options: dict[str, Any], channels: list[str]) -> dict[str, Any]:
    """The rasterize keyword arguments as JSON, with rasterize's own defaults filled in for the
    channels that depend on them (``line_period`` and ``dyadic_coord`` for ``dyadic_scale``;
    ``texture_size`` as ``[W, H]``)."""
    import inspect

    defaults = {
        k: p.default
        for k, p in inspect.signature(rasterize).parameters.items()
        if p.default is not inspect.Parameter.empty
    }
    out = dict(options)
    out.setdefault("cull_backfaces", defaults["cull_backfaces"])
    out.setdefault("dtype", defaults["dtype"])
    if "dyadic_scale" in channels:
        for key in ("line_period", "dyadic_coord"):
            out.setdefault(key, defaults[key])
    size = out.get("texture_size")
    if isinstance(size, (int, np.integer)):
        out["texture_size"] = [int(size), int(size)]
    return jsonable(out, where="raster_options")


def _base(case: GoldenCase, scene: Any) -> dict[str, Any]:
    return {
        "name": case.name,
        "description": case.description,
        "kind": case.kind,
        "width": case.width,
        "height": case.height,
        "spp": case.spp,
        "sample_positions": sample_positions(case.spp),
        "camera": camera_entry(scene.camera, case.width, case.height),
        "background": [float(c) for c in scene.background],
        "ambient": [float(c) for c in scene.ambient],
        "lights": lights_entry(scene),
    }


def _export_image(
    case: GoldenCase, scene: Any, tmp: Path, golden_root: Path | None
) -> dict[str, Any]:
    from ..render import render

    style = _style_of(case, scene)
    sx = export_style(style, scene, tmp, width=case.width, height=case.height, spp=case.spp)
    data = _base(case, scene)
    data["resolve"] = dict(RESOLVE)
    data["objects"] = objects_entry(scene, tmp, sx.vertex_attributes)
    if sx.frames:
        data["frames"] = sx.frames
    data["style"] = {"name": style_name(style), "params": sx.params}
    channels = sorted(style.requires(scene))
    data["channels"] = channels
    data["raster_options"] = raster_options(style.raster_options(scene), channels)
    data["textures"] = sx.textures
    image = render(scene, style, case.width, case.height, case.spp)
    srgb8 = image.to_srgb8()
    golden = golden_root / f"{case.name}.png" if golden_root is not None else None
    if golden is not None and golden.is_file():
        shutil.copyfile(golden, tmp / "expected.png")
        matches = bool(np.array_equal(read_image_file(golden, what="golden file"), srgb8))
    else:
        from ..image import write_png_atomic

        write_png_atomic(tmp / "expected.png", srgb8)
        matches = True
    write_exr(tmp / "expected.exr", image.rgba)
    data["expected"] = {
        "png": "expected.png",
        "linear": "expected.exr",
        "png_from_golden": golden is not None and golden.is_file(),
        "linear_matches_png": matches,
    }
    data["tolerance"] = tolerance_entry(case)
    data["derived"] = {**generic_derived(), **channel_derived(channels), **sx.derived}
    return data


def _export_gbuffer(
    case: GoldenCase, scene: Any, tmp: Path, golden_root: Path | None
) -> dict[str, Any]:
    data = _base(case, scene)
    data["resolve"] = None
    data["objects"] = objects_entry(scene, tmp)
    data["style"] = None
    data["channels"] = None  # set below from the exported arrays
    opts = {"texture_size": tuple(case.texture_size)} if case.texture_size else {}
    data["textures"] = {}
    # the ground truth of the kit's own inputs: refnpr rasterizing the float32 kit meshes
    # (the golden <name>.npz beside the suite file was rasterized from the float64 originals;
    # "golden_frac_over" says how far apart the two are, measured with the case's rtol/atol)
    gb = rasterize(
        kit_meshes(scene), scene.camera, case.width, case.height, case.channels, case.spp, **opts
    )
    arrays = {k: np.asarray(gb[k]) for k in gb}
    golden = golden_root / f"{case.name}.npz" if golden_root is not None else None
    matches, golden_frac = None, None
    if golden is not None and golden.is_file():
        with np.load(golden, allow_pickle=False) as z:
            ref = {k: z[k] for k in z.files}
        matches = set(ref) == set(arrays) and all(
            np.array_equal(ref[k], arrays[k], equal_nan=arrays[k].dtype.kind == "f") for k in arrays
        )
        if set(ref) == set(arrays):
            golden_frac = {k: _frac_off(arrays[k], ref[k], case) for k in sorted(arrays)}
    entries = {}
    for ch, arr in sorted(arrays.items()):
        rel = f"expected/{ch}.npy"
        with atomic_file(tmp / rel, suffix=".npy") as t:
            np.save(t, arr, allow_pickle=False)
        entries[ch] = {"file": rel, "dtype": str(arr.dtype), "shape": list(arr.shape)}
    data["channels"] = sorted(arrays)
    data["raster_options"] = raster_options(opts, sorted(arrays))
    data["expected"] = {
        "channels": entries,
        "format": "npy",
        "geometry": "kit",
        "matches_golden": matches,
        "golden_frac_over": golden_frac,
    }
    data["tolerance"] = tolerance_entry(case)
    data["derived"] = {**generic_derived(), **channel_derived(sorted(arrays))}
    return data


def _frac_off(got: np.ndarray, ref: np.ndarray, case: GoldenCase) -> float:
    """Fraction of elements of ``got`` outside the case's rtol/atol of ``ref`` (integer
    channels: elements that differ); 1.0 for a shape mismatch."""
    if got.shape != ref.shape:
        return 1.0
    if got.dtype.kind in "iu":
        return float(np.mean(got != ref))
    fin = np.isfinite(ref) & np.isfinite(got)
    bad = ~np.isclose(got, ref, rtol=case.rtol, atol=case.atol) & fin
    bad |= np.isfinite(ref) != np.isfinite(got)
    return float(np.mean(bad))


def export_case(case: GoldenCase, directory: Path, golden_root: Path | None) -> Path:
    """Export one case into ``directory / case.name`` (replacing it whole); its expected image is
    the golden file of that name in ``golden_root`` where there is one, else refnpr's render
    (``golden_root`` None: always the render, as for a case of the user's own scene).

    Returns
    -------
    Path
        The case's ``case.json``.
    """
    from ..scenes import load_scene

    scene = load_scene(case.scene)
    target = directory / case.name
    tmp = Path(tempfile.mkdtemp(prefix=f".{case.name}.", dir=directory))
    try:
        if case.kind == "gbuffer":
            data = _export_gbuffer(case, scene, tmp, golden_root)
        else:
            data = _export_image(case, scene, tmp, golden_root)
        write_json(tmp / "case.json", data)
        os.chmod(tmp, 0o755)
        old = None
        if target.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{case.name}.old.", dir=directory))
            os.replace(target, old / "case")
        os.replace(tmp, target)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return target / "case.json"


def export_kit(
    dir: str | os.PathLike,
    suite: str | os.PathLike | None = None,
    only: list[str] | None = None,
    *,
    cases: list[GoldenCase] | None = None,
    log: Callable[[str], None] | None = None,
) -> list[Path]:
    """Export the golden suite (or the cases in ``only``, or the given ``cases``) as a
    conformance kit in ``dir``.

    Parameters
    ----------
    dir : path
        The kit directory (created; an existing kit is updated case by case).
    suite : path, optional
        The suite file (default: the suite installed with refnpr,
        :data:`refnpr.golden.DEFAULT_SUITE`); golden files are read beside it.
    only : list of str, optional
        Case names to export (all when None).
    cases : list of GoldenCase, optional
        Cases of the user's own scenes (:func:`refnpr.golden.scene_case`) to export instead of
        the suite's: same schema, tolerances and derived texts, the expected image rendered by
        refnpr (there is no golden file); added to the kit's other cases.
    log : callable(str), optional
        Called with one line per case written.

    Returns
    -------
    list of Path
        The ``case.json`` files written, in suite order.

    Raises
    ------
    ValueError
        ``dir`` is a file or cannot be created; the suite cannot be read; an unknown case name.
    """
    if cases is not None and (suite is not None or only is not None):
        raise ValueError("cases: give either cases of your own or a suite (and only), not both")
    user = cases is not None
    suite_path = Path(suite) if suite is not None else DEFAULT_SUITE
    cases = list(cases) if user else _select(load_suite(suite_path), only)
    directory = _check_dir(dir)
    for name in SCHEMA_FILES:
        with atomic_file(directory / name, suffix=".json") as tmp:
            shutil.copyfile(schema_path(name), tmp)
    written = []
    for case in cases:
        try:
            written.append(export_case(case, directory, None if user else suite_path.parent))
        except (ValueError, TypeError) as exc:  # name the case in the message
            raise type(exc)(f"case {case.name!r}: {exc}") from exc
        if log is not None:
            log(f"wrote {written[-1]}")
    _write_index(directory, provenance(None if user else suite_path), {c.name for c in cases})
    return written


def _earlier(directory: Path) -> tuple[dict[str, Any] | None, dict[str, Any]]:
    """The provenance of the kit's previous index.json and its entries by case name (nothing
    when there is none or it cannot be read: the cases it described then read as unknown)."""
    try:
        old = read_json(directory / "index.json", what="index.json")
    except ValueError:
        return None, {}
    if not isinstance(old, dict) or not isinstance(old.get("cases"), list):
        return None, {}
    entries = {
        e["name"]: e for e in old["cases"] if isinstance(e, dict) and isinstance(e.get("name"), str)
    }
    prov = old.get("provenance")
    return (prov if isinstance(prov, dict) else None), entries


def _carried(entry: Any, case_dir: Path, what: str) -> tuple[dict, dict] | None:
    """The hashes and file digests an earlier index.json records for a case this export did not
    write, when the entry is intact: the same file names, the same case.json (hashing the rest
    of every earlier case again on each export would cost the whole kit's size)."""
    if not isinstance(entry, dict):
        return None
    hashes, files = entry.get("hashes"), entry.get("files")
    if not (
        isinstance(hashes, dict)
        and sorted(hashes) == sorted(GROUPS)
        and all(is_digest(v) for v in hashes.values())
        and isinstance(files, dict)
        and all(is_digest(v) for v in files.values())
    ):
        return None
    if list(files) != list(list_files(case_dir, what=what)):
        return None
    if files.get("case.json") != digest(read_bytes(case_dir / "case.json", what=what)):
        return None
    return hashes, files


def _write_index(directory: Path, prov: dict[str, Any], exported: set[str]) -> None:
    """index.json listing every case directory of the kit (those exported earlier too), with
    ``prov`` and each case's content hashes. A case exported earlier, not now, keeps the
    provenance it had (``null``: unknown) in its entry when that differs from ``prov``, and
    its hashes when its earlier entry is intact (:func:`_carried`)."""
    old_prov, old_entries = _earlier(directory)
    entries = []
    for case_json in sorted(directory.glob("*/case.json")):
        case_dir = case_json.parent
        if case_dir.name.startswith("."):
            continue
        what = f"case {case_dir.name!r}"
        data = read_json(case_json, what=what)
        name = data["name"]
        kept = None if name in exported else _carried(old_entries.get(name), case_dir, what)
        if kept is None:
            files = case_files(case_dir, what=what)
            kept = case_hashes(data, files), files
        style = data.get("style")
        entry = {
            "name": name,
            "kind": data["kind"],
            "style": style["name"] if style else None,
            "case": f"{case_dir.name}/case.json",
            "hashes": kept[0],
            "files": kept[1],
        }
        if name not in exported:
            before = old_entries.get(name, {}).get("provenance", old_prov)
            if before != prov:
                entry["provenance"] = before if isinstance(before, dict) else None
        entries.append(entry)
    index = {
        "format": KIT_FORMAT,
        "version": KIT_VERSION,
        "refnpr": __version__,
        "provenance": prov,
        "hashes": {"algorithm": "sha256", "groups": list(GROUPS)},
        "schema": "case.schema.json",
        "cases": entries,
    }
    write_json(directory / "index.json", index)
