"""``refnpr kit diff OLD NEW``: which cases of a kit update a backend author must look at again.

Both kits are read as untrusted input (refnpr.kit.content): only files inside them, no symbolic
links, no ``..`` or absolute paths, bounded JSON, every name escaped when printed. Each case's
content hashes are computed from its files (so a kit exported before ``index.json`` carried
hashes is compared the same way, and a note says so); hashes recorded in ``index.json`` that do
not match the files give a warning.

A case is *added*, *removed*, *changed* (naming what: its ``inputs``, ``tolerance``,
``expected`` images or arrays, or only its ``texts``; the ``case.json`` keys and files that
differ) or *unchanged*. Exit status (:func:`run`): 0 identical, 1 changed, 2 an error (a kit or
a case that cannot be read).
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from . import KIT_FORMAT, KIT_VERSION
from .content import (
    GROUPS,
    case_files,
    case_hashes,
    digest,
    is_digest,
    printable,
    quote,
    read_bytes,
    read_json,
)
from .provenance import describe

__all__ = ["KitContent", "CaseContent", "CaseChange", "KitDiff", "read_kit", "diff_kits", "run"]

#: An index.json listing more cases than this is refused.
MAX_CASES = 10_000
#: Key changes kept per changed case (the rest are counted).
MAX_KEY_CHANGES = 50
#: ... of which the text output prints this many.
SHOWN_KEY_CHANGES = 12
#: Files of the kit itself (beside the case directories) that are compared.
KIT_FILES = ("case.schema.json", "index.schema.json")
#: How each group reads in the text output.
PART_WORDS = {
    "inputs": "inputs",
    "tolerance": "tolerance",
    "expected": "expected images",
    "texts": "derived texts",
}
EXIT_IDENTICAL, EXIT_CHANGED, EXIT_ERROR = 0, 1, 2

#: A case name (the pattern of refnpr kit check, ``CASE_NAME``), and the ``case`` of an index
#: entry: a case directory's case.json (no ``..``, no absolute path); both ``fullmatch``.
_NAME = re.compile(r"[a-z0-9][a-z0-9._-]{0,127}")
_CASE = re.compile(r"([a-z0-9][a-z0-9._-]{0,127})/case\.json")
_PLAIN_KEY = re.compile(r"[A-Za-z0-9_-]+")
_ABSENT = object()


@dataclass
class CaseContent:
    """One case of a kit as read: its ``case.json``, the digest of each file and the group
    digests (refnpr.kit.content)."""

    name: str
    case: dict[str, Any]
    files: dict[str, str]
    hashes: dict[str, str]


@dataclass
class KitContent:
    """A kit as read by :func:`read_kit`.

    ``cases`` holds the cases that could be read; ``broken`` the names listed in index.json
    whose directory could not be (each with an entry in ``errors``). ``recorded``: whether
    index.json carries content hashes for every case. ``kit_files``: digest of each of
    :data:`KIT_FILES` (None: absent).
    """

    path: Path
    label: str
    provenance: dict[str, Any] | None
    refnpr: str | None
    recorded: bool
    cases: dict[str, CaseContent] = field(default_factory=dict)
    broken: set[str] = field(default_factory=set)
    kit_files: dict[str, str | None] = field(default_factory=dict)
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    @property
    def names(self) -> set[str]:
        """Every case name index.json lists (readable or not)."""
        return set(self.cases) | self.broken


@dataclass
class CaseChange:
    """A case in both kits whose content differs.

    ``parts``: the groups whose digest changed, in :data:`refnpr.kit.content.GROUPS` order.
    ``keys``: up to :data:`MAX_KEY_CHANGES` differing ``case.json`` values as ``(key path, old,
    new)`` (``old`` / ``new`` absent: the key is only in the other kit); ``more_keys`` counts
    the rest. ``files``: ``added`` / ``removed`` / ``changed`` file paths (case.json aside).
    """

    name: str
    kind: str | None
    parts: list[str]
    keys: list[tuple[str, Any, Any]]
    more_keys: int
    files: dict[str, list[str]]


@dataclass
class KitDiff:
    """The result of :func:`diff_kits`; ``status`` is the exit status of ``refnpr kit diff``."""

    old: KitContent
    new: KitContent
    added: list[str]
    removed: list[str]
    changed: list[CaseChange]
    unchanged: list[str]
    kit_files: list[str]
    notes: list[str]
    errors: list[str]
    warnings: list[str]

    @property
    def identical(self) -> bool:
        return not (self.added or self.removed or self.changed or self.kit_files or self.errors)

    @property
    def status(self) -> int:
        if self.errors:
            return EXIT_ERROR
        return EXIT_IDENTICAL if self.identical else EXIT_CHANGED

    def as_dict(self) -> dict[str, Any]:
        """The diff as JSON data (``--json``)."""

        def kit(k: KitContent) -> dict[str, Any]:
            return {
                "path": str(k.path),
                "refnpr": k.refnpr,
                "provenance": k.provenance,
                "hashes_recorded": k.recorded,
                "cases": len(k.names),
            }

        return {
            "old": kit(self.old),
            "new": kit(self.new),
            "identical": self.identical,
            "status": self.status,
            "added": self.added,
            "removed": self.removed,
            "changed": [
                {
                    "name": c.name,
                    "kind": c.kind,
                    "parts": c.parts,
                    "keys": [
                        {"key": k, **_json_side("old", o), **_json_side("new", n)}
                        for k, o, n in c.keys
                    ],
                    "more_keys": c.more_keys,
                    "files": c.files,
                }
                for c in self.changed
            ],
            "unchanged": self.unchanged,
            "kit_files_changed": self.kit_files,
            "notes": self.notes,
            "warnings": self.warnings,
            "errors": self.errors,
        }

    def format(self) -> str:
        """The diff as the text ``refnpr kit diff`` prints (every name escaped)."""
        lines = [_kit_line("old", self.old), _kit_line("new", self.new)]
        lines += [f"note: {n}" for n in self.notes]
        lines += [f"warning: {w}" for w in self.warnings]
        if self.added:
            lines.append(f"added ({len(self.added)}): {', '.join(map(printable, self.added))}")
        if self.removed:
            lines.append(
                f"removed ({len(self.removed)}): {', '.join(map(printable, self.removed))}"
            )
        if self.changed:
            lines.append(f"changed ({len(self.changed)}):")
            for c in self.changed:
                lines += _change_lines(c)
        if self.kit_files:
            lines.append(f"kit files changed: {', '.join(self.kit_files)}")
        lines += [f"error: {e}" for e in self.errors]
        verdict = {EXIT_IDENTICAL: "identical", EXIT_CHANGED: "changed", EXIT_ERROR: "error"}
        lines.append(
            f"{len(self.added)} added, {len(self.removed)} removed, {len(self.changed)} changed, "
            f"{len(self.unchanged)} unchanged: {verdict[self.status]}"
        )
        return "\n".join(lines)


def _kit_line(side: str, k: KitContent) -> str:
    prov = k.provenance or ({"refnpr": k.refnpr} if k.refnpr else None)
    return f"{side}: {quote(str(k.path))}: {describe(prov)}; {len(k.names)} case(s)"


def _change_lines(c: CaseChange) -> list[str]:
    words = dict(PART_WORDS, expected="expected arrays") if c.kind == "gbuffer" else PART_WORDS
    out = [f"  {printable(c.name)}: {', '.join(words[p] for p in c.parts)}"]
    for key, old, new in c.keys[:SHOWN_KEY_CHANGES]:
        out.append(f"    {printable(key)}: {_change_text(old, new)}")
    more = c.more_keys + max(0, len(c.keys) - SHOWN_KEY_CHANGES)
    if more:
        out.append(f"    ... and {more} more key change(s) in case.json")
    for what in ("changed", "added", "removed"):
        if c.files[what]:
            shown = ", ".join(printable(f) for f in c.files[what][:8])
            extra = len(c.files[what]) - 8
            out.append(f"    files {what}: {shown}" + (f" and {extra} more" if extra > 0 else ""))
    return out


def _change_text(old: Any, new: Any, width: int = 60) -> str:
    """``old -> new``; two long texts as the part around their first difference."""
    if isinstance(old, str) and isinstance(new, str) and max(len(old), len(new)) > width:
        n = min(len(old), len(new))
        i = next((j for j in range(n) if old[j] != new[j]), n)
        lo = max(0, i - 20)
        a, b = old[lo : lo + width - 10], new[lo : lo + width - 10]
        dots = "..." if lo else ""
        return f"text differs from character {i}: {dots}{_short(a)} -> {dots}{_short(b)}"
    return f"{_short(old, width)} -> {_short(new, width)}"


def _short(value: Any, width: int = 60) -> str:
    """A JSON value in at most ``width`` characters, ASCII (control characters escaped)."""
    if value is _ABSENT:
        return "(absent)"
    text = json.dumps(value, ensure_ascii=True, allow_nan=False)
    return text if len(text) <= width else text[: width - 3] + "..."


def _json_side(side: str, value: Any) -> dict[str, Any]:
    """``{side: value}`` for the JSON output: the value when short, else its shortened text;
    nothing when absent."""
    if value is _ABSENT:
        return {}
    text = json.dumps(value, allow_nan=False)
    return {side: value if len(text) <= 400 else _short(value, 400)}


# -- reading ---------------------------------------------------------------------------------
def _directory(path: str | os.PathLike, label: str) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{label}: expected a kit directory path, got {type(path).__name__}")
    p = Path(path)
    if not p.is_dir():
        why = "it is a file" if p.exists() else "it does not exist"
        raise ValueError(
            f"{label}: {quote(str(path))} is not a kit directory ({why}); give a directory "
            "written by `refnpr kit export`"
        )
    return p.resolve()  # a link given on the command line is the user's own


def read_kit(path: str | os.PathLike, *, label: str = "kit") -> KitContent:
    """Read an exported kit as untrusted input: its index, each case's ``case.json`` and the
    digest of every file.

    Parameters
    ----------
    path : path
        The kit directory.
    label : str
        How messages name this kit (``old``, ``new``).

    Returns
    -------
    KitContent
        Problems with one case are in ``errors`` (and its name in ``broken``); the rest is read.

    Raises
    ------
    ValueError
        The directory, its index.json (absent, a link, too big or deep, not a refnpr kit index)
        cannot be read.
    TypeError
        ``path`` is not a path.
    """
    root = _directory(path, label)
    index = read_json(root / "index.json", what=f"{label} index.json")
    where = f"{label}: {quote(str(root / 'index.json'))}"
    if not isinstance(index, dict) or index.get("format") != KIT_FORMAT:
        raise ValueError(f'{where}: expected {{"format": "{KIT_FORMAT}", ...}}, not a refnpr kit')
    version = index.get("version")
    if version != KIT_VERSION or isinstance(version, bool):
        raise ValueError(
            f"{where}: kit format version {_short(version)}; this refnpr reads version "
            f"{KIT_VERSION}"
        )
    entries = index.get("cases")
    if not isinstance(entries, list):
        raise ValueError(f"{where}: 'cases' must be a list, got {_short(entries)}")
    if len(entries) > MAX_CASES:
        raise ValueError(f"{where}: {len(entries)} cases, over the limit of {MAX_CASES}")
    prov = index.get("provenance")
    refnpr = index.get("refnpr")
    kit = KitContent(
        path=root,
        label=label,
        provenance=prov if isinstance(prov, dict) else None,
        refnpr=refnpr if isinstance(refnpr, str) else None,
        recorded=True,
    )
    for i, entry in enumerate(entries):
        _read_entry(kit, root, i, entry)
    for name in KIT_FILES:
        if not (root / name).exists() and not (root / name).is_symlink():
            kit.kit_files[name] = None
            continue
        try:
            kit.kit_files[name] = digest(read_bytes(root / name, what=f"{label} {name}"))
        except ValueError as exc:
            kit.errors.append(str(exc))
    return kit


def _read_entry(kit: KitContent, root: Path, i: int, entry: Any) -> None:
    """Read the case of index.json's ``cases[i]`` into ``kit`` (errors recorded, not raised)."""
    label = kit.label
    if not isinstance(entry, dict):
        kit.errors.append(f"{label} index.json: cases[{i}] is not an object: {_short(entry)}")
        return
    name, rel = entry.get("name"), entry.get("case")
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        kit.errors.append(
            f"{label} index.json: cases[{i}].name must match [a-z0-9][a-z0-9._-]{{0,127}}, got "
            f"{_short(name)}"
        )
        return
    m = _CASE.fullmatch(rel) if isinstance(rel, str) else None
    if m is None:
        kit.errors.append(
            f"{label} index.json: case {name!r}: 'case' must be DIR/case.json with DIR a case "
            f"name (no '..', no absolute path), got {_short(rel)}"
        )
        kit.broken.add(name)
        return
    if name in kit.names:
        kit.errors.append(f"{label} index.json: case {name!r} is listed twice")
        return
    case_dir = root / m.group(1)
    what = f"{label} case {name!r}"
    try:
        if case_dir.is_symlink():
            raise ValueError(
                f"{what}: {quote(str(case_dir))} is a symbolic link; a kit holds plain directories"
            )
        if not case_dir.is_dir():
            raise ValueError(f"{what}: the kit has no directory {quote(m.group(1))}")
        files = case_files(case_dir, what=what)
        case = read_json(case_dir / "case.json", what=what)
        if not isinstance(case, dict):
            raise ValueError(f"{what}: case.json must be a JSON object, got {_short(case)[:40]}")
        hashes = case_hashes(case, files)
    except ValueError as exc:
        kit.errors.append(str(exc))
        kit.broken.add(name)
        return
    kit.cases[name] = CaseContent(name, case, files, hashes)
    _check_recorded(kit, name, entry, hashes, files)


def _check_recorded(
    kit: KitContent, name: str, entry: dict, hashes: dict[str, str], files: dict[str, str]
) -> None:
    """Compare the hashes index.json records for a case with those of its files."""
    rec_h, rec_f = entry.get("hashes"), entry.get("files")
    if rec_h is None and rec_f is None:
        kit.recorded = False
        return
    well_formed = (
        isinstance(rec_h, dict)
        and all(is_digest(rec_h.get(g)) for g in GROUPS)
        and isinstance(rec_f, dict)
        and all(isinstance(k, str) and is_digest(v) for k, v in rec_f.items())
    )
    if not well_formed:
        kit.recorded = False
        kit.warnings.append(
            f"{kit.label} index.json: case {name!r}: malformed 'hashes' or 'files'; compared "
            "its files directly"
        )
        return
    off = [g for g in GROUPS if rec_h[g] != hashes[g]]
    off_files = sorted(k for k in set(rec_f) | set(files) if rec_f.get(k) != files.get(k))
    if off or off_files:
        detail = ", ".join(off + [printable(f) for f in off_files[:5]])
        kit.warnings.append(
            f"{kit.label}: case {name!r}: its files do not match the hashes index.json records "
            f"({detail}): changed after export; the files are what is compared"
        )


# -- comparing -------------------------------------------------------------------------------
def _key(path: str, k: str) -> str:
    if _PLAIN_KEY.fullmatch(k):
        return f"{path}.{k}" if path else k
    return f"{path}[{json.dumps(k, ensure_ascii=True)}]"


def _key_changes(a: Any, b: Any, path: str, out: list, counter: list[int]) -> None:
    """Append ``(path, old, new)`` for each differing value of two JSON values (up to
    :data:`MAX_KEY_CHANGES`; ``counter[0]`` counts the rest). Lists of different lengths are
    one change."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            _key_changes(a.get(k, _ABSENT), b.get(k, _ABSENT), _key(path, k), out, counter)
        return
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _key_changes(x, y, f"{path}[{i}]", out, counter)
        return
    if type(a) is type(b) and a == b:
        return
    if len(out) < MAX_KEY_CHANGES:
        out.append((path or "(case.json)", a, b))
    else:
        counter[0] += 1


def _compare_case(name: str, a: CaseContent, b: CaseContent) -> CaseChange | None:
    parts = [g for g in GROUPS if a.hashes[g] != b.hashes[g]]
    fa = {k: v for k, v in a.files.items() if k != "case.json"}
    fb = {k: v for k, v in b.files.items() if k != "case.json"}
    files = {
        "changed": sorted(k for k in set(fa) & set(fb) if fa[k] != fb[k]),
        "added": sorted(set(fb) - set(fa)),
        "removed": sorted(set(fa) - set(fb)),
    }
    if not parts:  # equal content (case.json may differ in key order or white space)
        return None
    keys: list[tuple[str, Any, Any]] = []
    counter = [0]
    _key_changes(a.case, b.case, "", keys, counter)
    kind = b.case.get("kind")
    return CaseChange(name, kind if isinstance(kind, str) else None, parts, keys, counter[0], files)


def diff_kits(old: str | os.PathLike | KitContent, new: str | os.PathLike | KitContent) -> KitDiff:
    """Compare two exported kits case by case.

    Parameters
    ----------
    old, new : path or KitContent
        The kit a backend was tested against, and the updated one (directories written by
        ``refnpr kit export``, or :func:`read_kit` results).

    Returns
    -------
    KitDiff
        Cases added, removed, changed (with what changed) and unchanged, by name; changed kit
        files (the schemas); notes, warnings and errors (cases that could not be read).

    Raises
    ------
    ValueError
        A kit directory or its index.json cannot be read (see :func:`read_kit`).
    """
    a = old if isinstance(old, KitContent) else read_kit(old, label="old")
    b = new if isinstance(new, KitContent) else read_kit(new, label="new")
    notes = []
    for k in (a, b):
        if not k.recorded and k.cases:
            made = f"exported by refnpr {printable(k.refnpr[:40])}" if k.refnpr else "exported"
            notes.append(
                f"{k.label} kit {quote(str(k.path))}: its index.json records no content "
                f"hashes for some or all cases ({made} before kits carried them); their files "
                "were hashed and compared directly"
            )
    added = sorted(b.names - a.names)
    removed = sorted(a.names - b.names)
    changed, unchanged = [], []
    for name in sorted(a.names & b.names):
        if name in a.broken or name in b.broken:
            continue  # its error is listed
        change = _compare_case(name, a.cases[name], b.cases[name])
        if change is None:
            unchanged.append(name)
        else:
            changed.append(change)
    kit_files = [n for n in KIT_FILES if a.kit_files.get(n, None) != b.kit_files.get(n, None)]
    return KitDiff(
        old=a,
        new=b,
        added=added,
        removed=removed,
        changed=changed,
        unchanged=unchanged,
        kit_files=kit_files,
        notes=notes,
        errors=a.errors + b.errors,
        warnings=a.warnings + b.warnings,
    )


def run(args: Any) -> int:
    """``refnpr kit diff OLD NEW [--json FILE]``: print the diff; exit 0 identical, 1 changed,
    2 an error."""
    from ._json import write_json

    if args.json is not None and Path(args.json).is_dir():
        raise ValueError(
            f"--json: {quote(str(args.json))} is a directory; give a file name such as "
            f"{quote(str(Path(args.json) / 'diff.json'))}"
        )
    result = diff_kits(args.old, args.new)
    print(result.format())
    if args.json is not None:
        write_json(args.json, result.as_dict())
    return result.status
