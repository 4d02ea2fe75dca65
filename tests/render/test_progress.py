"""Progress bars (tqdm) only on a terminal or with --progress; -q/--quiet silences commands."""

from __future__ import annotations

import pytest

import refnpr.cli as cli
from refnpr.cli import build_parser, main

pytest.importorskip("tqdm")


@pytest.fixture
def no_delay(monkeypatch):
    monkeypatch.setattr(cli, "_BAR_DELAY", 0.0)  # even a tiny render would draw its bar


def render(tmp_path, *extra):
    return main(["render", "--scene", "sphere", "--size", "16x12", "--spp", "1",
                 "-o", str(tmp_path / "o.png"), *extra])  # fmt: skip


def test_a_captured_render_draws_no_bar(tmp_path, capsys, no_delay):
    assert render(tmp_path) == 0
    out, err = capsys.readouterr()
    assert "\r" not in out + err and "wrote" in out
    assert render(tmp_path, "--progress") == 0  # forced: the bar is drawn
    assert "\r" in capsys.readouterr().err


def test_quiet_render_prints_nothing_even_with_progress(tmp_path, capsys, no_delay):
    assert render(tmp_path, "-q", "--progress") == 0
    assert capsys.readouterr() == ("", "")


def test_animate_bar_only_when_asked(tmp_path, capsys, monkeypatch):
    import refnpr.sequence as sequence

    def fake(scene, style, w, h, spp, *, out_dir, frames, exr, progress):
        result = sequence.SequenceResult(out_dir, [0, 1])
        for f in (0, 1):
            result._tick(f, "rendered", progress)
        return result

    monkeypatch.setattr(sequence, "render_sequence", fake)
    base = ["animate", "sphere", "-o", str(tmp_path / "f"), "--size", "8x8"]
    assert main(base) == 0
    out, err = capsys.readouterr()
    assert "\r" not in err and "wrote 2 of 2 frame(s)" in out
    assert main([*base, "--progress"]) == 0
    err = capsys.readouterr().err
    assert "\r" in err and "2/2" in err
    assert main([*base, "-q", "--progress"]) == 0
    assert capsys.readouterr() == ("", "")


def test_golden_quiet_prints_failures_and_the_count(capsys, monkeypatch):
    from types import SimpleNamespace as R

    import refnpr.golden as golden

    results = [R(name="a", passed=True, message="ok"), R(name="b", passed=False, message="off")]
    monkeypatch.setattr(golden, "check_suite", lambda suite, only=None: results)
    assert main(["golden", "-q"]) == 1
    assert capsys.readouterr().out.splitlines() == [
        f"FAIL {'b':32s} off",
        "1 passed, 1 failed",
    ]


def test_gallery_quiet_logs_no_line(tmp_path, monkeypatch, capsys):
    import refnpr.gallery as gallery

    seen = []
    monkeypatch.setattr(gallery, "build_gallery", lambda *a, log=None, **k: seen.append(log))
    assert main(["gallery", str(tmp_path), "-q"]) == 0
    assert main(["gallery", str(tmp_path)]) == 0
    assert seen[0] is None and callable(seen[1])


@pytest.mark.parametrize(
    "argv",
    [
        ["render"],
        ["animate", "s", "-o", "d"],
        ["golden"],
        ["gallery", "d"],
        ["kit", "export", "d"],
        ["kit", "check", "k", "r"],
        ["kit", "mutants", "k"],
        ["coherence", "s"],
        ["warmup"],
    ],
)
def test_every_command_that_prints_progress_takes_quiet(argv):
    assert build_parser().parse_args([*argv, "-q"]).quiet is True
    assert build_parser().parse_args([*argv, "--quiet"]).quiet is True
