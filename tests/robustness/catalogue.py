"""The bad-input catalogue: each case is an input a user could give and the outcome refnpr owes.

Outcome classes (``Outcome``):

* ``clear``   -- the expected exception type (``ValueError``/``TypeError``, or the CLI's exit
  status 2 with one ``error:`` line), whose message matches the case's pattern: it names the
  parameter or file, the value, what was expected (and the fix).
* ``correct`` -- no error, and the case's own check of the result passed (e.g. a finite image
  with the geometry where an oracle puts it).
* ``unclear`` -- an error, but of another type, or a message that does not match (a numpy or
  numba message, an internal variable, no file name).
* ``wrong``   -- no error where one was owed, or a result that fails its check (silently wrong
  or missing geometry, a stray file).
* ``crash``   -- a child process killed by a signal, out of memory or out of time.

Each test module defines ``CASES`` (a list of :class:`Case`) and calls :func:`parametrize`.
``python -m tests.robustness.report`` prints the counts by class and outcome (and writes
``docs/errors.md`` with ``--markdown``).
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

#: The classes of bad input.
CLASSES = ("sizes", "cache", "geometry", "messages", "nonsense", "files", "fuzz")
OUTCOMES = ("clear", "correct", "unclear", "wrong", "crash")


@dataclass(frozen=True)
class Raises:
    """The case must fail with ``type`` and a message matching ``match`` (``re.search``)."""

    type: type[BaseException] | tuple[type[BaseException], ...]
    match: str


@dataclass(frozen=True)
class Exits:
    """A CLI or child-process case: exit status ``code`` and stderr matching ``match``, with no
    Python traceback (``Traceback (most recent call last)`` never reaches a user)."""

    code: int
    match: str


@dataclass(frozen=True)
class Correct:
    """The case must succeed and ``check(result, tmp)`` must not raise (``AssertionError``)."""

    check: Callable[[Any, Path], None]


@dataclass(frozen=True)
class Case:
    """One bad input. ``run(tmp)`` performs it (``tmp``: an empty directory of its own) and
    returns the result (for ``Exits``: a ``subprocess.CompletedProcess``)."""

    id: str
    klass: str
    given: str
    run: Callable[[Path], Any]
    expect: Raises | Exits | Correct
    notes: str = field(default="")

    def __post_init__(self) -> None:
        if self.klass not in CLASSES:
            raise ValueError(f"case {self.id}: klass must be one of {CLASSES}, got {self.klass!r}")


@dataclass(frozen=True)
class Outcome:
    outcome: str
    detail: str  # the message (or why the result is wrong)


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def classify(case: Case, tmp: Path) -> Outcome:
    """Run ``case`` once and say which outcome class it fell into."""
    exp = case.expect
    try:
        result = case.run(tmp)
    except subprocess.TimeoutExpired as exc:
        return Outcome("crash", f"timed out after {exc.timeout} s")
    except MemoryError as exc:
        return Outcome("unclear", f"{type(exc).__name__}: {_one_line(exc)}")
    except Exception as exc:  # noqa: BLE001 -- classifying is the point
        msg = _one_line(exc)
        if isinstance(exp, Raises):
            if isinstance(exc, exp.type) and re.search(exp.match, msg):
                return Outcome("clear", msg)
            return Outcome("unclear", f"{type(exc).__name__}: {msg}")
        return Outcome(
            "unclear" if isinstance(exp, Exits) else "wrong", f"{type(exc).__name__}: {msg}"
        )
    if isinstance(exp, Raises):
        return Outcome("wrong", f"no error; returned {type(result).__name__}")
    if isinstance(exp, Exits):
        if not isinstance(result, subprocess.CompletedProcess):
            raise TypeError(f"case {case.id}: an Exits case must return a CompletedProcess")
        err = (
            result.stderr
            if isinstance(result.stderr, str)
            else result.stderr.decode("utf-8", "replace")
        )
        if result.returncode < 0 or result.returncode in (137, 139):
            return Outcome("crash", f"exit {result.returncode}: {_one_line(err)[-300:]}")
        if "Traceback (most recent call last)" in err:
            last = [ln for ln in err.strip().splitlines() if ln.strip()][-1:]
            return Outcome("unclear", f"traceback: {_one_line(' '.join(last))}")
        if result.returncode == exp.code and re.search(exp.match, _one_line(err)):
            return Outcome("clear", _one_line(err))
        if result.returncode == 0:
            return Outcome("wrong", f"exit 0: {_one_line(err)[-300:]}")
        return Outcome("unclear", f"exit {result.returncode}: {_one_line(err)[-300:]}")
    try:
        exp.check(result, tmp)
    except AssertionError as exc:
        return Outcome("wrong", f"check failed: {_one_line(exc)}")
    return Outcome("correct", "")


def expected_outcome(case: Case) -> str:
    return "correct" if isinstance(case.expect, Correct) else "clear"


def parametrize(cases: list[Case]):
    """The test every catalogue module runs: each case ends in the outcome it is owed."""
    ids = [c.id for c in cases]
    if len(set(ids)) != len(ids):
        raise ValueError(f"duplicate case ids: {sorted({i for i in ids if ids.count(i) > 1})}")

    @pytest.mark.parametrize("case", cases, ids=ids)
    def test_case(case: Case, tmp_path: Path) -> None:
        got = classify(case, tmp_path)
        want = expected_outcome(case)
        assert got.outcome == want, f"{case.id} ({case.given}): {got.outcome}: {got.detail}"

    return test_case


# ---------------------------------------------------------------------------------------------
# helpers for cases
# ---------------------------------------------------------------------------------------------
ROOT = Path(__file__).resolve().parents[2]


def cli(
    *args: str,
    timeout: float = 120.0,
    env: dict | None = None,
    limit_mb: int | None = None,
    cwd: Path | None = None,
) -> subprocess.CompletedProcess:
    """``python -m refnpr.cli ARGS`` in a child process (optionally under an address-space
    limit, so a size nobody checked cannot take the machine's memory)."""
    import os

    preexec = None
    if limit_mb is not None:

        def preexec():  # noqa: E306
            import resource

            resource.setrlimit(resource.RLIMIT_AS, (limit_mb << 20, limit_mb << 20))

    full_env = {**os.environ, **(env or {})}
    return subprocess.run(
        [sys.executable, "-m", "refnpr.cli", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=full_env,
        cwd=cwd,
        preexec_fn=preexec,
    )


def python(
    code: str,
    *,
    timeout: float = 120.0,
    env: dict | None = None,
    limit_mb: int | None = None,
    cwd: Path | None = None,
) -> subprocess.CompletedProcess:
    """``python -c CODE`` in a child process, like :func:`cli`."""
    import os

    preexec = None
    if limit_mb is not None:

        def preexec():  # noqa: E306
            import resource

            resource.setrlimit(resource.RLIMIT_AS, (limit_mb << 20, limit_mb << 20))

    return subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, **(env or {})},
        cwd=cwd,
        preexec_fn=preexec,
    )
