"""``refnpr kit check``: compare a backend's renders with an exported conformance kit.

For every case of ``KIT_DIR/index.json`` the checker reads the case's ``case.json`` (its
``expected`` files and its own ``tolerance``) and the backend's output in ``RENDERS_DIR``: image
cases ``<name>.png`` (8-bit sRGB RGBA) and optionally ``<name>.exr`` (float32 linear
straight-alpha RGBA); G-buffer cases ``<name>/<channel>.npy`` for every channel of ``expected``.

An image case passes when the fraction of pixels failing the two-sided position-tolerant compare
(:func:`position_tolerant_mismatch`) is at most ``tolerance.max_frac_over`` and the mean SSIM of
luminance at least ``tolerance.min_ssim`` (not judged in an image under 3 px that differs, whose
SSIM cannot be computed); a G-buffer case when every channel is within
``rtol``/``atol`` (discrete channels: exact but ``max_pixels``). docs/kit.md ("How ``refnpr kit
check`` decides") states every rule and reported metric.

A kit is untrusted input. Case names match :data:`CASE_NAME`; every path a kit gives is relative,
without ``..``, and resolves (symbolic links followed) inside the kit; renders are read only
inside the renders directory; only regular files are read, each size-capped; image and array
sizes are read from the PNG / OpenEXR / ``.npy`` header and checked against the case before any
pixel is decoded; JSON is size- and depth-limited; tolerances lie in documented ranges
(:mod:`refnpr.kit.tolerance`); :mod:`refnpr.kit.limits` holds the other limits. A malformed
case fails alone with status ``"kit"`` and a message naming the file and key; only a kit whose
``index.json`` cannot be read, or whose case names are invalid or repeated, is refused whole.
Per-case verdicts: :mod:`refnpr.kit.verdict`.
"""

from __future__ import annotations

import difflib
import math
import os
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from .._reading import inside, printable, read_regular
from . import KIT_FORMAT, KIT_VERSION, limits
from ._json import load_json, write_json
from .tolerance import validate_tolerance
from .verdict import (
    CaseCheck,
    CaseError,
    KitCase,
    Visual,
    check_gbuffer,
    check_image,
    composite_over_black,
    failing_as,
    position_tolerant_mismatch,
    render_exists,
)

__all__ = [
    "CASE_NAME",
    "valid_case_name",
    "MISSING_POLICIES",
    "CaseCheck",
    "Visual",
    "case_style",
    "check_kit",
    "composite_over_black",
    "format_table",
    "position_tolerant_mismatch",
    "run",
    "summarize",
]

#: A case name (``re.fullmatch``; also never containing ``..``): 1-128 characters of lower-case
#: ASCII letters, digits, ``.``, ``_`` and ``-``, starting with a letter or digit. It names the
#: case's render files, so it is one safe path component on every file system.
CASE_NAME = re.compile(r"[a-z0-9][a-z0-9._-]{0,127}")
#: ``--missing``: what a case without a render does to the exit status.
MISSING_POLICIES = ("fail", "skip")

_STYLE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")


def valid_case_name(name: Any) -> bool:
    """Whether ``name`` is a case name a kit may give: :data:`CASE_NAME`, without ``..`` (it
    names the case's render files)."""
    return isinstance(name, str) and CASE_NAME.fullmatch(name) is not None and ".." not in name


def _q(value: Any, limit: int = 100) -> str:
    """``repr(value)`` (control characters escaped), shortened to ``limit`` characters."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


# -- reading the kit ---------------------------------------------------------------------------


@dataclass(frozen=True)
class _Entry:
    """One entry of index.json: its position, a valid unique name, and the raw rest."""

    index: int
    name: str
    raw: dict[str, Any]


def _dir(path: str | os.PathLike, what: str) -> Path:
    p = Path(path)
    if not p.is_dir():
        why = "it is a file" if p.exists() else "it does not exist"
        raise ValueError(f"{what}: {_q(str(p))} is not a directory ({why})")
    return p.resolve(strict=True)


def _read_index(kit_root: Path, kit_dir: Path) -> list[_Entry]:
    """The cases of index.json; ValueError (the whole kit refused) when the file is not a kit
    index or a case name is invalid or repeated (names choose the render files)."""
    shown = _q(str(kit_dir / "index.json"))
    if not os.path.lexists(kit_root / "index.json"):
        raise ValueError(
            f"kit_dir: {_q(str(kit_dir))} has no index.json; export a kit with "
            "`refnpr kit export DIR`"
        )
    try:
        path = inside(kit_root, "index.json", what="index.json", root_name="the kit")
        data = load_json(
            read_regular(path, what=shown, max_bytes=limits.MAX_JSON_BYTES),
            what=shown,
            max_depth=limits.MAX_JSON_DEPTH,
        )
    except ValueError as exc:
        raise ValueError(f"kit_dir: {exc}") from None
    if not isinstance(data, dict) or data.get("format") != KIT_FORMAT:
        raise ValueError(f'{shown}: expected {{"format": "{KIT_FORMAT}", ...}}')
    version = data.get("version")
    if type(version) is not int or version != KIT_VERSION:
        raise ValueError(
            f"{shown}: kit format version {_q(version)}; this refnpr reads version {KIT_VERSION}"
        )
    cases = data.get("cases")
    if not isinstance(cases, list) or not cases:
        raise ValueError(f"{shown}: 'cases' must be a non-empty list, got {_q(cases)}")
    problems, entries, seen = [], [], {}
    for i, c in enumerate(cases):
        name = c.get("name") if isinstance(c, dict) else None
        if not isinstance(c, dict):
            problems.append(f"cases[{i}] is {_q(c, 40)}, not an object")
        elif not valid_case_name(name):
            problems.append(f"cases[{i}].name {_q(name, 60)} is not a valid case name")
        elif name in seen:
            problems.append(
                f"cases[{i}].name {name!r} repeats cases[{seen[name]}]; names must be unique"
            )
        else:
            seen[name] = i
            entries.append(_Entry(i, name, c))
    if problems:
        more = f" (and {len(problems) - 8} more)" if len(problems) > 8 else ""
        raise ValueError(
            f"{shown}: {'; '.join(problems[:8])}{more}. A case name matches "
            f"{CASE_NAME.pattern!r} without '..' (it names the render files)"
        )
    return entries


def _int_field(data: dict[str, Any], key: str, lo: int, hi: int, default: Any = None) -> int:
    v = data.get(key, default)
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        got = "nothing (the key is missing)" if key not in data else _q(v)
        raise ValueError(f"{key}: expected an integer in [{lo}, {hi}], got {got}")
    return v


def case_style(data: dict[str, Any]) -> str | None:
    """The style of a parsed case.json: ``style.name``, or ``"gbuffer"`` for a G-buffer case
    (whose ``style`` is null); None when neither is there (or the name is not a plain word)."""
    style = data.get("style")
    name = style.get("name") if isinstance(style, dict) else None
    if isinstance(name, str) and _STYLE_NAME.fullmatch(name):
        return name
    if style is None and data.get("kind") == "gbuffer":
        return "gbuffer"
    return None


def _case_rel(entry: _Entry) -> Any:
    return entry.raw.get("case", f"{entry.name}/case.json")


def _load_case(kit_root: Path, entry: _Entry) -> KitCase:
    """case.json of ``entry``, read and checked (not its tolerance or expected files)."""
    rel = _case_rel(entry)
    with failing_as("kit", f"index.json, case {entry.name!r}: "):
        path = inside(kit_root, rel, what="case", root_name="the kit")
        rel = path.relative_to(kit_root).as_posix()
        data = load_json(
            read_regular(path, what=f"kit file {rel!r}", max_bytes=limits.MAX_JSON_BYTES),
            what=f"kit file {rel!r}",
            max_depth=limits.MAX_JSON_DEPTH,
        )
    where = f"kit file {rel!r}: "
    if not isinstance(data, dict):
        raise CaseError("kit", f"{where}expected a JSON object, got {type(data).__name__}")
    if "name" in data and data["name"] != entry.name:
        raise CaseError(
            "kit", f"{where}name: {_q(data['name'])} differs from the name in index.json"
        )
    kind = data.get("kind", entry.raw.get("kind", "image"))
    if kind not in ("image", "gbuffer"):
        raise CaseError("kit", f"{where}kind: expected 'image' or 'gbuffer', got {_q(kind)}")
    with failing_as("kit", where):
        width = _int_field(data, "width", 1, limits.MAX_IMAGE_SIDE)
        height = _int_field(data, "height", 1, limits.MAX_IMAGE_SIDE)
        spp = _int_field(data, "spp", 1, limits.MAX_SPP, default=1)
    if width * height > limits.MAX_IMAGE_PIXELS:
        raise CaseError(
            "kit",
            f"{where}width x height: {width} x {height} = {width * height} pixels, more than "
            f"the {limits.MAX_IMAGE_PIXELS} allowed",
        )
    if math.isqrt(spp) ** 2 != spp:
        raise CaseError("kit", f"{where}spp: expected a square number n * n, got {spp}")
    style = case_style({**data, "kind": kind})
    return KitCase(path, rel, data, kind, width, height, spp, style)


def _index_kind(entry: _Entry) -> str:
    kind = entry.raw.get("kind")
    return kind if kind in ("image", "gbuffer") else "?"


# -- the whole kit -----------------------------------------------------------------------------


def _names_list(value: Any, what: str) -> list[str] | None:
    if value is None:
        return None
    if isinstance(value, str) or not all(isinstance(n, str) for n in value):
        raise TypeError(f"{what}: expected a list of names, got {_q(value)}")
    return list(value)


def _unknown(what: str, unknown: list[str], known: list[str], noun: str) -> ValueError:
    """The error for names the kit lacks: each with its close matches, then all the kit has."""
    parts = []
    for n in unknown:
        near = difflib.get_close_matches(n, known, n=3)
        parts.append(_q(n, 60) + (f" (did you mean {', '.join(near)}?)" if near else ""))
    return ValueError(
        f"{what}: unknown {noun} {', '.join(parts)}; the kit has {len(known)} {noun}: "
        f"{', '.join(known)}"
    )


def _peek_style(kit_root: Path, entry: _Entry) -> str | None:
    """The style of an entry for ``styles=`` (its case.json's; index.json's when case.json
    cannot be read, which the check then reports)."""
    try:
        return _load_case(kit_root, entry).style
    except CaseError:
        style = entry.raw.get("style")
        if isinstance(style, str) and _STYLE_NAME.fullmatch(style):
            return style
        return "gbuffer" if entry.raw.get("kind") == "gbuffer" else None


def _select(
    entries: list[_Entry], kit_root: Path, only: list[str] | None, styles: list[str] | None
) -> list[_Entry]:
    """The entries in ``only`` and of ``styles`` (each checked against the whole kit)."""
    selected = entries
    if only is not None:
        names = [e.name for e in entries]
        unknown = [n for n in dict.fromkeys(only) if n not in set(names)]
        if unknown:
            raise _unknown("only", unknown, names, "case names")
        selected = [e for e in selected if e.name in set(only)]
    if styles is not None:
        found = {e.name: _peek_style(kit_root, e) for e in entries}
        present = sorted({s for s in found.values() if s is not None})
        unknown = [s for s in dict.fromkeys(styles) if s not in present]
        if unknown:
            raise _unknown("styles", unknown, present, "styles")
        selected = [e for e in selected if found[e.name] in set(styles)]
    if not selected:
        raise ValueError("only, styles: no case of the kit is both in --only and of --styles")
    return selected


def _check_one(entry: _Entry, kit_root: Path, renders_root: Path) -> tuple[CaseCheck, Visual]:
    """One case's verdict; every failure of the kit or the render is its message."""
    vis = Visual()
    kind, style, tol = _index_kind(entry), None, {}
    try:
        case = _load_case(kit_root, entry)
        kind, style = case.kind, case.style
        with failing_as("kit", f"kit file {case.rel!r}: "):
            tol = validate_tolerance(case.data.get("tolerance"), case.kind)
        check = check_image if case.kind == "image" else check_gbuffer
        r = check(case, entry.name, tol, kit_root, renders_root, vis)
    except CaseError as exc:
        r = CaseCheck(entry.name, kind, False, exc.status, exc.message, tolerance=tol)
    except MemoryError:
        r = CaseCheck(entry.name, kind, False, "kit", "out of memory while checking the case")
        vis = Visual()
    except Exception as exc:  # noqa: BLE001 -- one case never aborts the check of the others
        r = CaseCheck(
            entry.name,
            kind,
            False,
            "kit",
            f"unexpected {type(exc).__name__} while checking the case (a refnpr bug; please "
            f"report it): {_q(str(exc), 200)}",
            tolerance=tol,
        )
    if style is not None:
        r = replace(r, style=style)
    return r, vis


def _has_render(entry: _Entry, kit_root: Path, renders_root: Path) -> bool:
    """Whether the case's render exists (True when case.json cannot say: the check reports)."""
    try:
        return render_exists(renders_root, _load_case(kit_root, entry), entry.name)
    except CaseError:
        return True


def _stream(
    entries: list[_Entry], kit_root: Path, renders_root: Path
) -> Iterator[tuple[CaseCheck, Visual]]:
    """(verdict, visual) per case: the cases with a render in index order, then those without
    (checked last, so that no case's arrays wait in memory); one case's arrays at a time."""
    later = []
    for entry in entries:
        if not _has_render(entry, kit_root, renders_root):
            later.append(entry)
            continue
        r, vis = _check_one(entry, kit_root, renders_root)
        if r.status == "missing":  # removed meanwhile
            later.append(entry)
            continue
        yield r, vis
        del vis
    for entry in later:
        yield _check_one(entry, kit_root, renders_root)


def _overlap(a: Path, b: Path) -> bool:
    return a == b or a.is_relative_to(b) or b.is_relative_to(a)


def check_kit(
    kit_dir: str | os.PathLike,
    renders_dir: str | os.PathLike,
    *,
    report_dir: str | os.PathLike | None = None,
    json_path: str | os.PathLike | None = None,
    only: Iterable[str] | None = None,
    styles: Iterable[str] | None = None,
    missing: str = "fail",
) -> list[CaseCheck]:
    """Compare a backend's renders with the cases of an exported kit.

    Parameters
    ----------
    kit_dir : str or path
        An exported kit (``refnpr kit export``): ``index.json`` and ``<case>/case.json``.
        Untrusted: see the module docstring for what is refused.
    renders_dir : str or path
        The backend's output: ``<case>.png`` (optionally ``<case>.exr``) per image case,
        ``<case>/<channel>.npy`` per G-buffer case.
    report_dir : str or path, optional
        Writes the HTML report there (:func:`refnpr.kit.report.write_report`), case by case as
        they are checked. It may not be, lie in or hold the kit or the renders directory.
    json_path : str or path, optional
        Writes ``{"kit", "renders", "selection": {only, styles}, "summary": {cases, passed,
        failed, missing, missing_policy}, "cases": [...]}``, each case as
        :meth:`CaseCheck.to_json`. It may not lie inside the kit.
    only : list of str, optional
        Check only these cases (names of index.json).
    styles : list of str, optional
        Check only the cases of these styles (:func:`case_style`: ``style.name`` of
        case.json, ``"gbuffer"`` for G-buffer cases). With ``only``: the cases in both.
    missing : {"fail", "skip"}
        What a case without a render counts as (:func:`summarize`, the exit status of
        :func:`run`); either way it is listed apart, after the compared cases, with status
        ``"missing"`` and ``passed`` False.

    Returns
    -------
    list of CaseCheck
        One per selected case: the compared cases in ``index.json`` order, then the cases
        without a render. A case whose render is unreadable or of the wrong size fails with the
        reason; so does a case whose kit files are broken.

    Raises
    ------
    ValueError
        ``kit_dir`` is not a kit (no or invalid ``index.json``, or case names that are invalid
        or repeated); ``renders_dir`` is not a directory; ``report_dir`` is a file or overlaps
        the kit or the renders; ``json_path`` is a directory or inside the kit; ``only`` or
        ``styles`` name something the kit lacks, or select nothing; ``missing`` is neither
        ``"fail"`` nor ``"skip"``.
    TypeError
        ``only`` or ``styles`` is not a list of strings.
    """
    if missing not in MISSING_POLICIES:
        raise ValueError(f"missing: expected 'fail' or 'skip', got {_q(missing)}")
    only, styles = _names_list(only, "only"), _names_list(styles, "styles")
    kit_root = _dir(kit_dir, "kit_dir")
    entries = _read_index(kit_root, Path(kit_dir))
    renders_root = _dir(renders_dir, "renders_dir")
    if report_dir is not None:
        rp = Path(report_dir)
        if rp.exists() and not rp.is_dir():
            raise ValueError(f"report_dir: {_q(str(rp))} is a file; expected a directory")
        for root, what in ((kit_root, "the kit"), (renders_root, "the renders directory")):
            if _overlap(rp.resolve(), root):
                raise ValueError(
                    f"report_dir: {_q(str(rp))} overlaps {what} ({_q(str(root))}); write the "
                    "report to a directory of its own"
                )
    if json_path is not None:
        jp = Path(json_path)
        if jp.is_dir():
            raise ValueError(
                f"json_path: {_q(str(jp))} is a directory; give a file name such as "
                f"{_q(str(jp / 'check.json'))}"
            )
        if jp.resolve().is_relative_to(kit_root):
            raise ValueError(f"json_path: {_q(str(jp))} lies inside the kit; write it elsewhere")
    selected = _select(entries, kit_root, only, styles)
    cases = _stream(selected, kit_root, renders_root)
    if report_dir is not None:
        from .report import write_report

        results = write_report(
            Path(report_dir), cases, kit_dir=Path(kit_dir), renders_dir=Path(renders_dir)
        )
    else:
        results = [r for r, _ in cases]
    if json_path is not None:
        doc = {
            "kit": str(kit_dir),
            "renders": str(renders_dir),
            "selection": {"only": only, "styles": styles},
            "summary": summarize(results, missing=missing),
            "cases": [r.to_json() for r in results],
        }
        write_json(json_path, doc)
    return results


def summarize(results: list[CaseCheck], *, missing: str = "fail") -> dict[str, Any]:
    """Counts of a check: ``cases``, ``passed``, ``failed`` (compared or broken cases that did
    not pass, not counting the missing ones), ``missing`` (no render) and ``missing_policy``."""
    n_missing = sum(r.status == "missing" for r in results)
    passed = sum(r.passed for r in results)
    return {
        "cases": len(results),
        "passed": passed,
        "failed": len(results) - passed - n_missing,
        "missing": n_missing,
        "missing_policy": missing,
    }


def _summary_line(s: dict[str, Any]) -> str:
    line = f"{s['cases']} cases: {s['passed']} passed, {s['failed']} failed"
    if s["missing"]:
        how = "skipped" if s["missing_policy"] == "skip" else "failing; --missing skip skips them"
        line += f", {s['missing']} missing ({how})"
    return line


def format_table(
    results: list[CaseCheck], *, missing: str = "fail", failures_only: bool = False
) -> str:
    """Plain-text table: one line per compared case and the reason under each failure, then
    the cases without a render, then the summary line (:func:`summarize`, of every case).
    Every field is printable (control characters escaped). ``failures_only`` (``-q``): the
    lines of passing cases are left out."""
    lines = [
        f"{'case':44s} {'kind':7s} {'result':6s} {'status':10s} {'max_abs':>8s} {'rmse':>8s} "
        f"{'frac>thr':>9s} {'pos.frac':>9s} {'ssim':>7s}"
    ]
    absent = []
    for r in results:
        if r.status == "missing":
            absent.append(r)
            continue
        m = r.metrics
        nums = " ".join(
            f"{m[k]:{w}.{p}f}"
            if k in m and not math.isnan(m[k])
            else f"{'-' if k not in m else 'n/a':>{w}s}"  # n/a: an SSIM under 3 px
            for k, w, p in (
                ("max_abs", 8, 4),
                ("rmse", 8, 5),
                ("frac_over", 9, 5),
                ("frac_over_position", 9, 5),
                ("ssim", 7, 4),
            )
        )
        if failures_only and r.passed:
            continue
        if r.kind == "gbuffer" and r.status == "ok":
            nums = f"{'':8s} {'':8s} {'':9s} {m.get('frac_bad', 0.0):9.5f} {'':7s}"
        verdict = "PASS" if r.passed else "FAIL"
        lines.append(
            f"{printable(r.name):44s} {printable(r.kind):7s} {verdict:6s} "
            f"{printable(r.status):10s} {nums}"
        )
        if not r.passed:
            lines.append(f"    {printable(r.message)}")
    if absent:
        how = "skipped" if missing == "skip" else "each fails"
        lines.append(f"missing: {len(absent)} case(s) without a render ({how}):")
        lines += [f"    {printable(r.name):44s} {printable(r.message)}" for r in absent]
    lines.append(_summary_line(summarize(results, missing=missing)))
    return "\n".join(lines)


#: Most file names listed in the note on renders without a case.
_EXTRA_LISTED = 20


def run(args: Any) -> int:
    """The ``refnpr kit check`` command: print the table, write the report/JSON, exit status.

    ``args`` has ``kit_dir``, ``renders_dir``, ``report`` (directory or None), ``json`` (file
    or None) and optionally ``only``, ``styles`` (lists or None) and ``missing`` (``"fail"``,
    the default, or ``"skip"``). Returns 0 when every selected case passes (with ``--missing
    skip``: every case that has a render), 1 otherwise.
    """
    policy = getattr(args, "missing", None) or "fail"
    results = check_kit(
        args.kit_dir,
        args.renders_dir,
        report_dir=getattr(args, "report", None),
        json_path=getattr(args, "json", None),
        only=getattr(args, "only", None),
        styles=getattr(args, "styles", None),
        missing=policy,
    )
    quiet = bool(getattr(args, "quiet", False))
    print(format_table(results, missing=policy, failures_only=quiet))
    kit_root = Path(args.kit_dir).resolve()
    names = {e.name for e in _read_index(kit_root, Path(args.kit_dir))}
    extra = sorted(
        e.name
        for e in os.scandir(args.renders_dir)
        if e.name.endswith(".png") and e.name[: -len(".png")] not in names
    )
    if extra and not quiet:
        shown = ", ".join(printable(n) for n in extra[:_EXTRA_LISTED])
        more = f" and {len(extra) - _EXTRA_LISTED} more" if len(extra) > _EXTRA_LISTED else ""
        print(
            f"note: {len(extra)} render(s) without a case in the kit, not compared: {shown}{more}"
        )
    if getattr(args, "report", None) is not None:
        print(f"report: {printable(Path(args.report) / 'index.html')}")
    s = summarize(results, missing=policy)
    return 0 if s["failed"] == 0 and (s["missing"] == 0 or policy == "skip") else 1
