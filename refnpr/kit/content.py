"""A kit's files read as untrusted input, and the content hashes of its cases.

Reading (``refnpr kit diff``, and the export that hashes what it wrote): a file is opened only
inside the directory it belongs to, never through a symbolic link, only if it is a regular file
(no FIFO, device or ``/dev/zero``) and only up to a size limit; JSON is refused above a size and a
nesting depth, with duplicate keys, with NaN or infinite numbers. Every failure is a ValueError
naming the file.

Hashes (``index.json``, docs/kit.md): each file of a case directory has a SHA-256 digest written
``"sha256:<64 hex digits>"``; a case has four group digests, each the SHA-256 of a canonical JSON
text (:func:`canonical_json`):

* ``inputs``: ``{"case": case.json without "tolerance", "expected", "derived" and
  "description", "files": {path: digest}}`` over every file but case.json and the expected ones;
* ``tolerance``: ``case.json["tolerance"]``;
* ``expected``: ``{"expected": case.json["expected"], "files": {path: digest}}`` over the files
  that ``expected`` names (expected.png, expected.exr, expected/<channel>.npy);
* ``texts``: ``{"description": ..., "derived": ...}``, the prose of the case.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import stat
from pathlib import Path
from typing import Any

from .._reading import printable
from ._json import load_json
from .limits import MAX_FILE_BYTES, MAX_JSON_BYTES, MAX_JSON_DEPTH

__all__ = [
    "MAX_JSON_BYTES",
    "MAX_JSON_DEPTH",
    "MAX_FILE_BYTES",
    "MAX_CASE_FILES",
    "GROUPS",
    "printable",
    "quote",
    "canonical_json",
    "digest",
    "read_bytes",
    "read_json",
    "list_files",
    "case_files",
    "case_hashes",
    "is_digest",
]

# MAX_JSON_BYTES, MAX_JSON_DEPTH and MAX_FILE_BYTES are the limits `refnpr kit check` puts on
# an untrusted kit (refnpr.kit.limits); these two are the diff's own:
#: A case directory is refused with more files than this, or nested deeper than MAX_DIR_DEPTH.
MAX_CASE_FILES = 4096
MAX_DIR_DEPTH = 8
#: The group digests of a case, in the order they are reported.
GROUPS = ("inputs", "tolerance", "expected", "texts")
#: case.json keys that are not inputs (each is in another group).
_NOT_INPUTS = ("tolerance", "expected", "derived", "description")

_DIGEST = re.compile(r"sha256:[0-9a-f]{64}")
_CHUNK = 1 << 20


def quote(text: str) -> str:
    """``text`` escaped (:func:`printable`) in single quotes, for messages."""
    return f"'{printable(text)}'"


def canonical_json(value: Any) -> bytes:
    """The canonical JSON text hashed for a group digest: UTF-8 of ``json.dumps(value,
    sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False)``."""
    text = json.dumps(
        value, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False
    )
    return text.encode("utf-8", "surrogatepass")


def digest(data: bytes) -> str:
    """``"sha256:<hex>"`` of ``data``."""
    return f"sha256:{hashlib.sha256(data).hexdigest()}"


def is_digest(value: Any) -> bool:
    """Whether ``value`` is a digest string as this module writes it."""
    return isinstance(value, str) and bool(_DIGEST.fullmatch(value))


def _open(path: Path, what: str, limit: int) -> tuple[int, int]:
    """(fd, size) of a regular file, opened without following a symbolic link (the last path
    component; callers check the directories above it)."""
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise ValueError(f"{what}: {quote(str(path))} does not exist") from None
    except OSError as exc:
        if path.is_symlink():
            raise ValueError(
                f"{what}: {quote(str(path))} is a symbolic link; a kit holds plain files"
            ) from None
        raise ValueError(f"{what}: cannot open {quote(str(path))}: {exc.strerror}") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        raise ValueError(
            f"{what}: {quote(str(path))} is not a regular file (a directory, device or pipe)"
        )
    if st.st_size > limit:
        os.close(fd)
        raise ValueError(
            f"{what}: {quote(str(path))} is {st.st_size} bytes, over the limit of {limit}"
        )
    return fd, st.st_size


def read_bytes(path: str | Path, *, what: str, limit: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of a regular file (not through a symbolic link), at most ``limit`` bytes.

    Raises
    ------
    ValueError
        Naming ``what`` and the path: absent, a link, not a regular file, too big, unreadable.
    """
    fd, size = _open(Path(path), what, limit)
    with os.fdopen(fd, "rb") as f:
        data = f.read(min(size, limit) + 1)  # what the file holds, not the limit, is allocated
        if len(data) > size:  # grown since it was measured: read on, to the limit
            data += f.read(limit + 1 - len(data))
    if len(data) > limit:
        raise ValueError(f"{what}: {quote(str(path))} grew over the limit of {limit} bytes")
    return data


def _hash_file(path: Path, what: str) -> str:
    fd, _ = _open(path, what, MAX_FILE_BYTES)
    h, n = hashlib.sha256(), 0
    with os.fdopen(fd, "rb") as f:
        while chunk := f.read(_CHUNK):
            n += len(chunk)
            if n > MAX_FILE_BYTES:
                raise ValueError(f"{what}: {quote(str(path))} grew over the limit")
            h.update(chunk)
    return f"sha256:{h.hexdigest()}"


def read_json(
    path: str | Path,
    *,
    what: str,
    max_bytes: int = MAX_JSON_BYTES,
    max_depth: int = MAX_JSON_DEPTH,
) -> Any:
    """A JSON file read as untrusted input (see the module docstring for what is refused):
    :func:`refnpr.kit._json.load_json` with NaN, Infinity and overflowing numbers refused.

    Raises
    ------
    ValueError
        Naming ``what``, the file and the problem.
    """
    data = read_bytes(path, what=what, limit=max_bytes)
    return load_json(data, what=f"{what}: {quote(str(path))}", max_depth=max_depth, finite=True)


def list_files(case_dir: str | Path, *, what: str = "case") -> dict[str, Path]:
    """Every file under a case directory by its path relative to it (``/``-separated), sorted,
    read without following a symbolic link.

    Raises
    ------
    ValueError
        The directory is a symbolic link or holds one, a non-regular file, a file name that is not
        UTF-8, more than :data:`MAX_CASE_FILES` entries, directories deeper than MAX_DIR_DEPTH,
        or a directory that cannot be listed.
    """
    root = Path(case_dir)
    if root.is_symlink():
        raise ValueError(
            f"{what}: {quote(str(root))} is a symbolic link; a kit holds plain directories"
        )
    if not root.is_dir():
        raise ValueError(f"{what}: {quote(str(root))} is not a directory")
    files: dict[str, Path] = {}
    seen = 0

    def walk(d: Path, prefix: str, level: int) -> None:
        nonlocal seen
        if level > MAX_DIR_DEPTH:
            raise ValueError(
                f"{what}: directories nested deeper than {MAX_DIR_DEPTH} at {quote(prefix)}"
            )
        entries = []
        try:
            with os.scandir(d) as it:
                for e in it:
                    seen += 1
                    if seen > MAX_CASE_FILES:
                        raise ValueError(
                            f"{what}: more than {MAX_CASE_FILES} files and directories"
                        )
                    entries.append(e)
        except OSError as exc:
            raise ValueError(
                f"{what}: cannot list {quote(prefix or '.')}: {exc.strerror}"
            ) from None
        for e in sorted(entries, key=lambda e: e.name):
            rel = prefix + e.name
            try:
                rel.encode("utf-8")
            except UnicodeEncodeError:
                raise ValueError(f"{what}: the file name {quote(rel)} is not UTF-8") from None
            if e.is_symlink():
                raise ValueError(
                    f"{what}: {quote(rel)} is a symbolic link; a kit holds plain files"
                )
            if e.is_dir(follow_symlinks=False):
                walk(Path(e.path), rel + "/", level + 1)
            elif e.is_file(follow_symlinks=False):
                files[rel] = Path(e.path)
            else:
                raise ValueError(f"{what}: {quote(rel)} is not a regular file (a device or pipe)")

    walk(root, "", 0)
    return dict(sorted(files.items()))


def case_files(case_dir: str | Path, *, what: str = "case") -> dict[str, str]:
    """Digest of every file under a case directory (:func:`list_files`), by its path relative
    to it, sorted.

    Raises
    ------
    ValueError
        As :func:`list_files`; or a file over :data:`MAX_FILE_BYTES` or unreadable.
    """
    return {rel: _hash_file(path, what) for rel, path in list_files(case_dir, what=what).items()}


def _strings(value: Any) -> set[str]:
    if isinstance(value, str):
        return {value}
    if isinstance(value, list):
        return set().union(*(_strings(v) for v in value)) if value else set()
    if isinstance(value, dict):
        return set().union(*(_strings(v) for v in value.values())) if value else set()
    return set()


def expected_files(case: dict[str, Any], files: dict[str, str]) -> set[str]:
    """The files of ``files`` that ``case["expected"]`` names."""
    return _strings(case.get("expected")) & set(files)


def case_hashes(case: dict[str, Any], files: dict[str, str]) -> dict[str, str]:
    """The group digests of a case (:data:`GROUPS`; module docstring) from its parsed case.json
    and :func:`case_files`."""
    expected = expected_files(case, files)
    inputs = {k: v for k, v in files.items() if k not in expected and k != "case.json"}
    body = {k: v for k, v in case.items() if k not in _NOT_INPUTS}
    return {
        "inputs": digest(canonical_json({"case": body, "files": inputs})),
        "tolerance": digest(canonical_json(case.get("tolerance"))),
        "expected": digest(
            canonical_json(
                {"expected": case.get("expected"), "files": {k: files[k] for k in sorted(expected)}}
            )
        ),
        "texts": digest(
            canonical_json({"description": case.get("description"), "derived": case.get("derived")})
        ),
    }
