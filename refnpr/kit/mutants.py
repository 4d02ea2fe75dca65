"""``refnpr kit mutants``: is the kit sensitive to the bugs GPU ports make?

For every case of an exported kit, refnpr renders the case itself (the **control**: it must
pass) and once under each port bug of :data:`refnpr.kit.port_bugs.BUGS` (sample positions off
by half a pixel, v flipped, sRGB applied twice or never, quad derivatives, LOD bias +-1, light
negated, normals not renormalized, premultiplied colour, unsnapped vertices, ...), writes the
renders as a backend would and judges them with the kit's own check
(:func:`refnpr.kit.check.check_kit`). The result is a case x bug matrix: per bug, which cases
catch it (their check fails) and which do not.

Verdicts per case and bug:

``caught``
    The mutant render fails the case's check.
``missed``
    The mutant render differs from refnpr's correct render but passes the check.
``no_effect``
    The mutant render equals the correct render, or differs from it by at most one 8-bit level
    anywhere (:data:`NO_EFFECT_LEVELS`: float rounding; G-buffer cases: bit for bit): the bug
    cannot show in this case (opaque samples hide premultiplied colour; a flat room has unit
    normals anyway; X-Toon renormalizes its normals itself).
``n/a``
    The bug cannot occur in this case's style (no textures: no LOD bias; no derivatives).
``error``
    Rendering the mutant failed (the message says why), or refnpr's own render of the case
    fails its check (then no verdict on the case means anything).

The **target**: every bug is caught by at least one case of every style it changes (a style
whose cases show the bug: verdicts ``caught`` or ``missed``).
"""

from __future__ import annotations

import difflib
import inspect
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from .._reading import inside, read_regular, short_repr
from . import limits
from ._json import load_json
from .check import CASE_NAME, valid_case_name
from .mutant_render import CaseRenderer
from .port_bugs import BUGS, NotApplicable

__all__ = [
    "MutantCase",
    "MutantReport",
    "VERDICTS",
    "NO_EFFECT_LEVELS",
    "run_mutants",
    "format_text",
    "format_markdown",
    "run",
]

#: The verdicts of a (case, bug) pair (see the module docstring).
VERDICTS = ("caught", "missed", "no_effect", "n/a", "error")


@dataclass
class MutantCase:
    """One case of the matrix.

    Attributes
    ----------
    name, style, kind : str
        The case, its style (``"gbuffer"`` for G-buffer cases) and ``"image"``/``"gbuffer"``.
    control : str
        ``"pass"`` when refnpr's own render passes the case's check, else ``"fail"`` or
        ``"error"``; ``control_message`` says why.
    results : dict of str to dict
        Per bug ``{"verdict": one of VERDICTS, "message": str, "metrics": {...}}`` (metrics:
        the check's numbers when it compared the render).
    seconds : float
        Time spent rendering the case and its mutants.
    """

    name: str
    style: str
    kind: str
    control: str = "error"
    control_message: str = ""
    results: dict[str, dict[str, Any]] = field(default_factory=dict)
    seconds: float = 0.0


@dataclass
class MutantReport:
    """The case x bug matrix of a kit (see the module docstring).

    Attributes
    ----------
    kit : str
        The kit directory.
    bugs : list of str
        The bugs rendered, in :data:`BUGS` order.
    cases : list of MutantCase
        In ``index.json`` order.
    seconds : float
        Wall time of the whole run.
    """

    kit: str
    bugs: list[str]
    cases: list[MutantCase]
    seconds: float = 0.0

    def summary(self) -> dict[str, dict[str, dict[str, int]]]:
        """style -> bug -> counts of each verdict (``caught``, ``missed``, ...) and ``shown``
        (caught + missed: the cases where the bug changes the render)."""
        out: dict[str, dict[str, dict[str, int]]] = {}
        for c in self.cases:
            per = out.setdefault(c.style, {})
            for bug in self.bugs:
                counts = per.setdefault(bug, {v: 0 for v in VERDICTS} | {"shown": 0})
                verdict = c.results.get(bug, {}).get("verdict", "error")
                counts[verdict] += 1
                counts["shown"] += verdict in ("caught", "missed")
        return out

    def uncaught(self) -> list[tuple[str, str]]:
        """(bug, style) pairs where the bug changes some case of the style but no case of the
        style catches it: where the target is not met."""
        return [
            (bug, style)
            for style, per in self.summary().items()
            for bug, n in per.items()
            if n["shown"] and not n["caught"]
        ]

    @property
    def controls_pass(self) -> bool:
        return all(c.control == "pass" for c in self.cases)

    def to_json(self) -> dict[str, Any]:
        """The matrix as JSON data."""
        from .mutant_render import FINE_SAMPLES

        return {
            "kit": self.kit,
            "refnpr": __version__,
            "seconds": round(self.seconds, 3),
            "bugs": [
                {
                    "name": b,
                    "stage": BUGS[b].stage,
                    "port": BUGS[b].port,
                    "emulation": BUGS[b].emulation,
                }
                for b in self.bugs
            ],  # fmt: skip
            "fine_samples": FINE_SAMPLES,
            "summary": self.summary(),
            "target": {
                "met": not self.uncaught() and self.controls_pass,
                "controls_pass": self.controls_pass,
                "uncaught": [{"bug": b, "style": s} for b, s in self.uncaught()],
            },
            "cases": [
                {
                    "name": c.name,
                    "style": c.style,
                    "kind": c.kind,
                    "control": c.control,
                    "control_message": c.control_message,
                    "seconds": round(c.seconds, 3),
                    "results": c.results,
                }
                for c in self.cases
            ],
        }


# -- reading the kit ----------------------------------------------------------------------------


def _read_json(kit_dir: Path, rel: str) -> Any:
    """The kit's JSON file ``rel``, read as ``kit check`` reads it (the kit is untrusted): a
    path inside the kit, a regular file (a FIFO would block, a link to ``/dev/zero`` never end)
    of at most :data:`~refnpr.kit.limits.MAX_JSON_BYTES`, JSON nested at most
    :data:`~refnpr.kit.limits.MAX_JSON_DEPTH` deep."""
    what = f"kit file {rel!r}"
    try:
        kit_root = kit_dir.resolve(strict=True)
    except (OSError, RuntimeError) as exc:  # the directory went away, a symbolic link loop
        raise ValueError(f"{what}: the kit {str(kit_dir)!r} cannot be read ({exc})") from None
    path = inside(kit_root, rel, what=what, root_name="the kit")
    data = read_regular(path, what=what, max_bytes=limits.MAX_JSON_BYTES)
    return load_json(data, what=what, max_depth=limits.MAX_JSON_DEPTH)


def _kit_entries(kit_dir: Path) -> list[dict[str, Any]]:
    """The cases of ``kit_dir/index.json``: ``[{"name", "kind", "style"}]`` (names checked)."""
    if not kit_dir.is_dir():
        why = "it is a file" if kit_dir.exists() else "it does not exist"
        raise ValueError(
            f"kit_dir: {str(kit_dir)!r} is not a directory ({why}); export a kit with "
            "`refnpr kit export DIR`"
        )
    try:
        index = _read_json(kit_dir, "index.json")
    except ValueError as exc:
        raise ValueError(f"kit_dir: {exc}") from None
    cases = index.get("cases") if isinstance(index, dict) else None
    if not isinstance(cases, list) or not cases:
        raise ValueError(
            f"kit_dir: {str(kit_dir / 'index.json')!r} lists no cases; expected "
            '{"cases": [{"name": ..., "kind": ..., "style": ...}, ...]} (refnpr kit export)'
        )
    out, seen = [], set()
    for i, c in enumerate(cases):
        name = c.get("name") if isinstance(c, dict) else None
        if not valid_case_name(name):
            raise ValueError(
                f"kit_dir: index.json cases[{i}].name: expected a name matching "
                f"{CASE_NAME.pattern} without '..', got {short_repr(name)}"
            )
        if name in seen:
            raise ValueError(f"kit_dir: index.json lists the case {name!r} twice")
        seen.add(name)
        kind = c.get("kind", "image")
        style = c.get("style") if kind == "image" else None
        out.append({"name": name, "kind": kind, "style": style if style else "gbuffer"})
    return out


def _select(items: list[str], wanted: Sequence[str] | None, what: str, listing: str) -> list[str]:
    if wanted is None:
        return items
    if isinstance(wanted, str) or not all(isinstance(w, str) for w in wanted):
        raise TypeError(f"{what}: expected a list of names, got {wanted!r}")
    unknown = [w for w in wanted if w not in items]
    if unknown:
        hints = []
        for u in unknown:
            close = difflib.get_close_matches(u, items, n=3)
            if close:
                hints.append(f"{u!r}: did you mean {close}?")
        raise ValueError(
            f"{what}: unknown name(s) {unknown}; {listing}"
            + ("; " + "; ".join(hints) if hints else "")
        )
    return [i for i in items if i in set(wanted)]


# -- rendering and judging ----------------------------------------------------------------------


def _write(render: Any, root: Path, name: str) -> None:
    """A render as a backend writes it: ``<name>.png`` or ``<name>/<channel>.npy``."""
    from ..image import write_png_atomic

    root.mkdir(parents=True, exist_ok=True)
    if isinstance(render, dict):
        d = root / name
        d.mkdir(exist_ok=True)
        for ch, arr in render.items():
            np.save(d / f"{ch}.npy", arr, allow_pickle=False)
    else:
        write_png_atomic(root / f"{name}.png", render)


#: 8-bit levels an image mutant may differ from the correct render and still count as
#: ``no_effect``: one level is float rounding (a float32 GPU differs from refnpr's float64 by
#: that much), not a bug any tolerance could be asked to see.
NO_EFFECT_LEVELS = 1


def _no_effect(render: Any, correct: Any) -> str | None:
    """Why ``render`` counts as the correct render (see :data:`NO_EFFECT_LEVELS`), or None."""
    if isinstance(render, dict):
        same = render.keys() == correct.keys() and all(
            np.array_equal(render[k], correct[k], equal_nan=render[k].dtype.kind == "f")
            for k in render
        )
        return "the render equals refnpr's correct render" if same else None
    diff = int(np.abs(render.astype(np.int16) - correct.astype(np.int16)).max())
    if diff == 0:
        return "the render equals refnpr's correct render"
    if diff <= NO_EFFECT_LEVELS:
        return f"the render is within {diff} 8-bit level of refnpr's correct render (rounding)"
    return None


def _check(kit_dir: Path, renders: Path, names: list[str]) -> dict[str, Any]:
    """The kit's verdicts on ``names`` (the cases rendered into ``renders``)."""
    from .check import check_kit

    kwargs: dict[str, Any] = {}
    if "only" in inspect.signature(check_kit).parameters:
        kwargs["only"] = names
    wanted = set(names)
    return {r.name: r for r in check_kit(kit_dir, renders, **kwargs) if r.name in wanted}


def _numbers(metrics: dict[str, Any]) -> dict[str, float]:
    keep = ("frac_over_position", "ssim", "max_abs", "frac_bad")
    return {k: float(metrics[k]) for k in keep if k in metrics and metrics[k] is not None}


def _lod_bias(case_json: dict[str, Any]) -> float | None:
    style = case_json.get("style")
    params = style.get("params") if isinstance(style, dict) else None
    v = params.get("lod_bias") if isinstance(params, dict) else None
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def run_mutants(
    kit_dir: str | Path,
    *,
    only: Sequence[str] | None = None,
    bugs: Sequence[str] | None = None,
    suite: str | Path | None = None,
    log: Callable[[str], None] | None = None,
) -> MutantReport:
    """Render the kit's cases with refnpr under each port bug and check every render.

    Parameters
    ----------
    kit_dir : str or path
        An exported kit (``refnpr kit export``).
    only : list of str, optional
        Case names (default: every case of the kit).
    bugs : list of str, optional
        Bug names of :data:`refnpr.kit.port_bugs.BUGS` (default: all).
    suite : str or path, optional
        The suite the kit was exported from (default :data:`refnpr.golden.DEFAULT_SUITE`):
        refnpr renders each kit case from the suite case of the same name.
    log : callable(str), optional
        Called with one progress line per case.

    Returns
    -------
    MutantReport

    Raises
    ------
    ValueError
        ``kit_dir`` is not a kit, an unknown case or bug name, an unreadable suite.
    """
    from ..golden import DEFAULT_SUITE, load_suite

    t_start = time.perf_counter()
    kit_dir = Path(kit_dir)
    entries = _kit_entries(kit_dir)
    names = _select([e["name"] for e in entries], only, "only", f"the kit has {len(entries)} cases")
    bug_names = _select(list(BUGS), bugs, "bugs", f"the bugs are {list(BUGS)}")
    suite_cases = {c.name: c for c in load_suite(DEFAULT_SUITE if suite is None else suite)}
    say = log or (lambda line: None)
    cases: list[MutantCase] = []
    with tempfile.TemporaryDirectory(prefix="refnpr-mutants-") as tmp:
        root = Path(tmp)
        rendered: dict[str, list[str]] = {}  # renders dir -> cases written there
        selected = [e for e in entries if e["name"] in set(names)]
        for i, e in enumerate(selected):
            mc = MutantCase(e["name"], e["style"], e["kind"])
            cases.append(mc)
            t0 = time.perf_counter()
            _render_case(kit_dir, e, suite_cases, bug_names, mc, root, rendered)
            mc.seconds = time.perf_counter() - t0
            changed = sum(r["verdict"] == "pending" for r in mc.results.values())
            say(f"[{i + 1}/{len(selected)}] {mc.name} ({mc.style}): {changed} mutant render(s) "
                f"to check, {mc.seconds:.1f} s")  # fmt: skip
        by_name = {c.name: c for c in cases}
        for key, written in rendered.items():
            try:
                verdicts, why = _check(kit_dir, root / key, written), None
            except (ValueError, TypeError, OSError) as exc:  # the kit refuses the renders
                verdicts, why = {}, f"the check raised: {exc}"
            for name in written:
                _judge(by_name[name], key, verdicts.get(name), why)
    for c in cases:
        if c.control != "pass":
            for r in c.results.values():
                if r["verdict"] in ("caught", "missed"):
                    r["verdict"] = "error"
                    r["message"] = f"refnpr's own render fails this case: {c.control_message}"
    return MutantReport(str(kit_dir), bug_names, cases, time.perf_counter() - t_start)


def _render_case(
    kit_dir: Path,
    entry: dict[str, Any],
    suite_cases: dict[str, Any],
    bug_names: list[str],
    mc: MutantCase,
    root: Path,
    rendered: dict[str, list[str]],
) -> None:
    """Render one case (control and mutants) into ``root/<key>/``; verdicts still pending."""

    def fail_all(why: str) -> None:
        mc.control, mc.control_message = "error", why
        for bug in bug_names:
            mc.results[bug] = {"verdict": "error", "message": why, "metrics": {}}

    case = suite_cases.get(mc.name)
    if case is None:
        return fail_all(
            f"the suite has no case {mc.name!r}: export the kit from the suite refnpr renders "
            "(refnpr kit export), or give that suite"
        )
    try:
        case_json = _read_json(kit_dir, f"{mc.name}/case.json")
        if not isinstance(case_json, dict):
            raise ValueError(f"case {mc.name!r}: case.json is not a JSON object")
        size = tuple(case_json.get(k) for k in ("width", "height", "spp"))
        if size != (case.width, case.height, case.spp):
            raise ValueError(
                f"case {mc.name!r}: the kit's width, height, spp {size} differ from the suite's "
                f"{(case.width, case.height, case.spp)}: the kit comes from another suite"
            )
        renderer = CaseRenderer(case, lod_bias=_lod_bias(case_json))
        correct = renderer.correct()
    except (ValueError, TypeError, OSError, MemoryError) as exc:  # a MemoryError may say nothing
        return fail_all(f"cannot render the case: {str(exc) or type(exc).__name__}")
    _write(correct, root / "control", mc.name)
    rendered.setdefault("control", []).append(mc.name)
    for bug in bug_names:
        try:
            render = renderer.mutant(bug)
        except NotApplicable as exc:
            mc.results[bug] = {"verdict": "n/a", "message": str(exc), "metrics": {}}
            continue
        except (ValueError, TypeError, OSError, MemoryError) as exc:
            mc.results[bug] = {
                "verdict": "error",
                "message": f"render failed: {exc}",
                "metrics": {},
            }
            continue
        same = _no_effect(render, correct)
        if same is not None:
            mc.results[bug] = {"verdict": "no_effect", "message": same, "metrics": {}}
            continue
        _write(render, root / bug, mc.name)
        rendered.setdefault(bug, []).append(mc.name)
        mc.results[bug] = {"verdict": "pending", "message": "", "metrics": {}}


def _judge(mc: MutantCase, key: str, check: Any, why: str | None = None) -> None:
    """Fold the kit's verdict on one render of ``mc`` (``key``: "control" or a bug) into it
    (``why``: the reason there is none)."""
    if check is None:
        verdict, metrics = None, {}
        message = why or "the check returned no verdict for the case"
    else:
        metrics = _numbers(check.metrics)
        verdict = check.passed
        message = f"{check.status}: {check.message}"
    if key == "control":
        mc.control = "error" if verdict is None else ("pass" if verdict else "fail")
        mc.control_message = message
        return
    if verdict is None:
        mc.results[key] = {"verdict": "error", "message": message, "metrics": metrics}
    else:
        name = "missed" if verdict else "caught"
        mc.results[key] = {"verdict": name, "message": message, "metrics": metrics}


# -- output -------------------------------------------------------------------------------------

_CELL = {"caught": "FAIL", "missed": "pass", "no_effect": "=", "n/a": "-", "error": "err"}


def _styles(report: MutantReport) -> list[str]:
    seen: list[str] = []
    for c in report.cases:
        if c.style not in seen:
            seen.append(c.style)
    return seen


def _summary_cell(n: dict[str, int]) -> str:
    if n["shown"]:
        cell = f"{n['caught']}/{n['shown']}"
        return cell + ("!" if not n["caught"] else "")
    if n["error"]:
        return "err"
    return "=" if n["no_effect"] else "-"


def format_text(report: MutantReport) -> str:
    """Plain text: per style, each bug caught by N of the M cases it changes; then where the
    target is not met."""
    summary = report.summary()
    lines = []
    for style in _styles(report):
        cases = sum(c.style == style for c in report.cases)
        lines.append(f"{style} ({cases} case{'s' if cases != 1 else ''})")
        for bug in report.bugs:
            n = summary[style][bug]
            if n["shown"]:
                text = f"caught by {n['caught']} of the {n['shown']} case(s) it changes"
                if not n["caught"]:
                    text += "  <- NOT CAUGHT"
            elif n["error"]:
                text = f"{n['error']} error(s)"
            elif n["no_effect"]:
                text = "no effect on any case"
            else:
                text = "n/a"
            extra = [f"{n[k]} {k}" for k in ("no_effect", "n/a", "error") if n[k] and n["shown"]]
            lines.append(f"  {bug:22s} {text}" + (f" ({', '.join(extra)})" if extra else ""))
    bad = [c for c in report.cases if c.control != "pass"]
    for c in bad:
        lines.append(f"control {c.control}: {c.name}: {c.control_message}")
    uncaught = report.uncaught()
    lines.append(
        f"{len(report.cases)} cases x {len(report.bugs)} bugs in {report.seconds:.0f} s; "
        + ("target met" if not uncaught and not bad else
           f"target NOT met: {len(uncaught)} (bug, style) pair(s) uncaught, "
           f"{len(bad)} control(s) failing")
    )  # fmt: skip
    return "\n".join(lines)


def _md_row(cells: list[str]) -> str:
    return "| " + " | ".join(cells) + " |"


def format_markdown(report: MutantReport) -> str:
    """Markdown: the bugs and their emulation, the per-style summary (caught N of the M cases a
    bug changes) and the full case x bug matrix."""
    summary = report.summary()
    out = ["### Bugs", "", _md_row(["bug", "stage", "what the port does", "how refnpr renders it"])]
    out.append(_md_row(["---"] * 4))
    for b in report.bugs:
        bug = BUGS[b]
        out.append(_md_row([f"`{b}`", bug.stage, bug.port, bug.emulation]))
    out += [
        "",
        "### Caught, per style",
        "",
        "Each cell: the cases of the style that catch the bug / the cases whose render the bug "
        "changes (`!`: none catches it; `=`: the bug changes no case of the style; `-`: it "
        "cannot occur in the style).",
        "",
    ]
    out.append(_md_row(["style", "cases", *[f"`{b}`" for b in report.bugs]]))
    out.append(_md_row(["---"] * (len(report.bugs) + 2)))
    for style in _styles(report):
        cases = str(sum(c.style == style for c in report.cases))
        cells = [_summary_cell(summary[style][b]) for b in report.bugs]
        out.append(_md_row([style, cases, *cells]))
    out += [
        "",
        "### Every case",
        "",
        "`FAIL`: the case catches the bug; `pass`: the bug changes the render but the case "
        "passes; `=`: no effect; `-`: n/a; `err`: see the JSON.",
        "",
    ]
    out.append(_md_row(["case", "style", "control", *[f"`{b}`" for b in report.bugs]]))
    out.append(_md_row(["---"] * (len(report.bugs) + 3)))
    for c in report.cases:
        cells = [_CELL[c.results.get(b, {}).get("verdict", "error")] for b in report.bugs]
        out.append(_md_row([c.name, c.style, c.control, *cells]))
    uncaught = report.uncaught()
    out += ["", f"{len(report.cases)} cases x {len(report.bugs)} bugs, {report.seconds:.0f} s."]
    if uncaught:
        out.append("Not caught: " + ", ".join(f"`{b}` ({s})" for b, s in uncaught) + ".")
    return "\n".join(out) + "\n"


def run(args: Any) -> int:
    """The ``refnpr kit mutants`` command: render, check, print the matrix (text, or Markdown
    with ``--markdown``), write ``--json``. Progress goes to stderr (none with ``-q``).

    Returns 0 when every control passes and every bug is caught by a case of each style it
    changes, 1 otherwise.
    """
    json_path = getattr(args, "json", None)
    if json_path is not None and Path(json_path).is_dir():
        raise ValueError(
            f"--json: {json_path!r} is a directory; give a file name such as "
            f"{str(Path(json_path) / 'mutants.json')!r}"
        )
    report = run_mutants(
        args.kit_dir,
        only=getattr(args, "only", None),
        bugs=getattr(args, "bugs", None),
        log=(lambda line: None)
        if getattr(args, "quiet", False)
        else lambda line: print(line, file=sys.stderr, flush=True),
    )
    if json_path is not None:
        from ._json import write_json

        write_json(json_path, report.to_json())
    print(format_markdown(report) if getattr(args, "markdown", False) else format_text(report))
    ok = report.controls_pass and not report.uncaught()
    return 0 if ok else 1
