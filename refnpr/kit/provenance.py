"""Where a kit comes from: the refnpr version, the git commit of the checkout refnpr runs from,
the numpy and numba versions, the platform, and the golden suite the cases were exported from
(``index.json``'s ``provenance``; docs/kit.md).

Nothing here fails for want of information: a commit that cannot be read (an installed wheel, no
``.git``, a packed or unusual repository) is ``None``, as is the version of a missing package.
"""

from __future__ import annotations

import hashlib
import platform
import re
import sys
import tomllib
from importlib import metadata
from pathlib import Path
from typing import Any

from .. import __version__
from .content import printable

__all__ = ["git_commit", "provenance", "suite_entry", "describe_source", "describe"]

_SHA = re.compile(r"[0-9a-f]{40}([0-9a-f]{24})?")
_MAX_GIT_FILE = 1 << 20  # HEAD, a ref, packed-refs: small text files


def _read_small(path: Path) -> str | None:
    """A small text file's content, or None (absent, too big, unreadable, not UTF-8)."""
    try:
        if not path.is_file() or path.stat().st_size > _MAX_GIT_FILE:
            return None
        return path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None


def _git_dir(root: Path) -> Path | None:
    dot = root / ".git"
    if dot.is_dir():
        return dot
    text = _read_small(dot)  # a worktree or submodule: "gitdir: PATH"
    if text and text.startswith("gitdir:"):
        d = Path(text[len("gitdir:") :].strip())
        d = d if d.is_absolute() else root / d
        return d if d.is_dir() else None
    return None


def _resolve_ref(git: Path, ref: str) -> str | None:
    if not ref.startswith("refs/") or ".." in ref.split("/"):
        return None
    common = git
    text = _read_small(git / "commondir")  # a worktree's refs live in the main repository
    if text:
        c = Path(text.strip())
        common = c if c.is_absolute() else git / c
    for d in dict.fromkeys((git, common)):
        value = _read_small(d / ref)
        if value and _SHA.fullmatch(value.strip()):
            return value.strip()
        for line in (_read_small(d / "packed-refs") or "").splitlines():
            sha, _, name = line.partition(" ")
            if name.strip() == ref and _SHA.fullmatch(sha):
                return sha
    return None


def git_commit(root: Path | None = None) -> str | None:
    """The commit checked out in the git repository refnpr runs from, read from ``.git``
    without running git; None for an installed wheel or when it cannot be read. Local changes
    are not detected.

    Parameters
    ----------
    root : Path, optional
        The repository's top directory (default: :func:`refnpr.golden.source_checkout`).
    """
    from ..golden import source_checkout  # imported on use: refnpr kit diff renders nothing

    try:
        root = source_checkout() if root is None else Path(root)
        if root is None:
            return None
        git = _git_dir(root)
        if git is None:
            return None
        head = (_read_small(git / "HEAD") or "").strip()
        if head.startswith("ref:"):
            return _resolve_ref(git, head[len("ref:") :].strip())
        return head if _SHA.fullmatch(head) else None
    except (OSError, ValueError, RuntimeError):
        return None


def _version(package: str) -> str | None:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def _text(value: str) -> str:
    """A path as JSON-safe text (undecodable bytes of a file name as backslash escapes)."""
    return value.encode("utf-8", "backslashreplace").decode("utf-8")


def suite_entry(suite_path: str | Path) -> dict[str, Any]:
    """``{"packaged", "path", "sha256"}`` of a suite file: whether it is the suite installed with
    refnpr; its path (package-relative for that one, else absolute); a digest of the suite file
    and the files it includes (the case definitions, not the golden images: each case's
    ``expected`` hash covers those)."""
    from ..golden import SUITE_DIR, is_packaged_suite

    suite_path = Path(suite_path)
    packaged = is_packaged_suite(suite_path)
    files = [suite_path.name]
    try:
        includes = tomllib.loads(suite_path.read_text(encoding="utf-8")).get("include", [])
        files += [i for i in includes if isinstance(i, str)] if isinstance(includes, list) else []
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        pass
    h = hashlib.sha256()
    for name in files:
        try:
            data = (suite_path.parent / name).read_bytes()
        except OSError:
            data = b""
        h.update(f"{len(name.encode())}:{name}:{len(data)}:".encode() + data)
    if packaged:
        path = f"refnpr/{SUITE_DIR.name}/{suite_path.name}"
    else:
        path = _text(str(suite_path.absolute()))
    return {"packaged": packaged, "path": path, "sha256": f"sha256:{h.hexdigest()}"}


def provenance(suite_path: str | Path | None = None) -> dict[str, Any]:
    """The ``provenance`` object of ``index.json``: what wrote the kit, and on what.

    Returns
    -------
    dict
        ``refnpr`` (version), ``git_commit`` (hex or None), ``python``, ``numpy``, ``numba``
        (versions or None), ``platform`` (``platform.platform()``), ``machine`` and, given
        ``suite_path``, ``suite`` (:func:`suite_entry`).
    """
    out: dict[str, Any] = {
        "refnpr": __version__,
        "git_commit": git_commit(),
        "python": platform.python_version(),
        "numpy": _version("numpy"),
        "numba": _version("numba"),
        "platform": platform.platform(),
        "machine": platform.machine(),
    }
    if suite_path is not None:
        out["suite"] = suite_entry(suite_path)
    return out


def describe(prov: Any) -> str:
    """A provenance object in a few words: ``refnpr 0.1.0, git 0123456789ab`` (untrusted
    input: anything that is not a provenance object reads as ``provenance unknown``)."""
    if not isinstance(prov, dict) or not isinstance(prov.get("refnpr"), str):
        return "provenance unknown"
    commit = prov.get("git_commit")
    git = (
        f"git {commit[:12]}"
        if isinstance(commit, str) and _SHA.fullmatch(commit)
        else "git unknown"
    )
    return f"refnpr {printable(prov['refnpr'][:40])}, {git}"


def describe_source(suite_path: str | Path) -> str:
    """The line ``refnpr kit export`` starts with: this refnpr and the suite it exports."""
    from ..golden import is_packaged_suite

    suite_path = Path(suite_path)
    where = " (the suite installed with refnpr)" if is_packaged_suite(suite_path) else ""
    py = f"Python {sys.version_info.major}.{sys.version_info.minor}"
    return f"{describe(provenance())} ({py}); suite {str(suite_path.absolute())!r}{where}"
