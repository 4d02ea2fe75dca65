"""Nonsense given to the ``refnpr`` command: each is one ``error:`` line and exit status 2, and
never a stray output file. Cases run the command in a child process (``catalogue.cli``)."""

from __future__ import annotations

from pathlib import Path

from .catalogue import Case, Correct, Exits, cli, parametrize

SUITE = """
[defaults]
width = 16
height = 12

[[case]]
name = "a-toon"
scene = "sphere"
style = { name = "toon", n = 2 }
"""


def _render(*args: str):
    """``refnpr render ARGS -o out.png`` in ``tmp``; a case also owes that no out.png appears."""

    def run(tmp: Path):
        proc = cli("render", "-q", *args, "-o", "out.png", cwd=tmp)
        if proc.returncode != 0 and (tmp / "out.png").exists():
            proc.stderr += "\n(stray output: out.png was written)"
            proc.returncode = 0  # counted as "wrong" by the harness
        return proc

    return run


def _golden(*args: str):
    def run(tmp: Path):
        (tmp / "suite.toml").write_text(SUITE)
        return cli("golden", "--suite", "suite.toml", *args, cwd=tmp)

    return run


def _wrote(size: tuple[int, int]):
    def check(proc, tmp: Path) -> None:
        import imageio.v3 as iio

        assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-300:]}"
        assert iio.imread(tmp / "out.png").shape == (size[1], size[0], 4)

    return check


def _compare_self(tmp: Path):
    import imageio.v3 as iio
    import numpy as np

    (tmp / "d").mkdir()
    iio.imwrite(tmp / "d" / "s.png", np.zeros((4, 4, 4), np.uint8))
    return cli("compare", "d", "d", cwd=tmp)


CASES = [
    # --- style and parameters ----------------------------------------------------------------
    Case(
        "style-empty",
        "nonsense",
        'refnpr render --style ""',
        _render("--size", "8x8", "--style", ""),
        Exits(2, r"error: --style: expected a style name, got ''.*refnpr styles"),
        notes="used to render the scene's own style",
    ),
    Case(
        "style-blank",
        "nonsense",
        'refnpr render --style "  "',
        _render("--size", "8x8", "--style", "  "),
        Exits(2, r"error: --style: expected a style name, got ' +'"),
    ),
    Case(
        "param-name-overrides-style",
        "nonsense",
        "refnpr render --style toon --param name=smooth",
        _render("--size", "8x8", "--style", "toon", "--param", "name=smooth"),
        Exits(2, r"error: --param: 'name' is not a style parameter.*--style"),
        notes="used to render smooth, silently",
    ),
    Case(
        "param-name-without-style",
        "nonsense",
        "refnpr render --param name=smooth (scene's style)",
        _render("--size", "8x8", "--param", "name=smooth"),
        Exits(2, r"error: --param: 'name' is not a style parameter.*--style smooth"),
    ),
    Case(
        "param-two-values",
        "nonsense",
        "refnpr render --style toon --param $'n=3\\nt=0.9' (a newline in the value)",
        _render("--size", "8x8", "--style", "toon", "--param", "n=3\nt=0.9"),
        Exits(2, r"error: .*--param: the value of 'n' holds more than one TOML value"),
        notes="the value after the newline was dropped without a word",
    ),
    Case(
        "param-empty-key",
        "nonsense",
        "refnpr render --style toon --param =3",
        _render("--size", "8x8", "--style", "toon", "--param", "=3"),
        Exits(2, r"error: .*--param: .*KEY=VALUE.*'=3'"),
    ),
    Case(
        "param-empty-value",
        "nonsense",
        "refnpr render --style toon --param n=",
        _render("--size", "8x8", "--style", "toon", "--param", "n="),
        Exits(2, r"error: .*--param: .*'n=' has no value"),
    ),
    Case(
        "param-twice",
        "nonsense",
        "refnpr render --style toon --param n=2 --param n=3",
        _render("--size", "8x8", "--style", "toon", "--param", "n=2", "--param", "n=3"),
        Exits(2, r"error: --param: 'n' given twice \(2 and 3\)"),
    ),
    Case(
        "param-unknown",
        "messages",
        "refnpr render --style toon --param colour=1",
        _render("--size", "8x8", "--style", "toon", "--param", "colour=1"),
        Exits(2, r"error: .*colour.*(valid|known).*\bn\b"),
    ),
    Case(
        "style-unknown",
        "messages",
        "refnpr render --style tooon",
        _render("--size", "8x8", "--style", "tooon"),
        Exits(2, r"error: .*'tooon'.*toon"),
    ),
    Case(
        "param-overrides-scene-style",
        "nonsense",
        "refnpr render --scene veryovka_plane --param n=2 (the scene's threshold style takes n)",
        _render("--size", "8x8", "--scene", "veryovka_plane", "--param", "n=2"),
        Correct(_wrote((8, 8))),
        notes="--param alone overrides the scene's style parameters; not nonsense",
    ),
    Case(
        "param-without-any-style",
        "messages",
        "refnpr render --scene teapot --param n=3 (the teapot scene names no style)",
        _render("--size", "8x8", "--scene", "teapot", "--param", "n=3"),
        Exits(2, r"error: --param needs --style: the scene 'teapot' names no style"),
    ),
    # --- sizes and samples -------------------------------------------------------------------
    Case(
        "size-zero",
        "nonsense",
        "refnpr render --size 0x0",
        _render("--size", "0x0"),
        Exits(2, r"error: .*--size.*positive.*'0x0'"),
    ),
    Case(
        "size-one-number",
        "nonsense",
        "refnpr render --size 64",
        _render("--size", "64"),
        Exits(2, r"error: .*--size: expected WxH.*'64'"),
    ),
    Case(
        "size-words",
        "nonsense",
        "refnpr render --size axb",
        _render("--size", "axb"),
        Exits(2, r"error: .*--size: expected WxH.*'axb'"),
    ),
    Case(
        "size-three-numbers",
        "nonsense",
        "refnpr render --size 64x48x2",
        _render("--size", "64x48x2"),
        Exits(2, r"error: .*--size: expected WxH.*'64x48x2'"),
    ),
    Case(
        "size-negative",
        "nonsense",
        "refnpr render --size -8x8",
        _render("--size=-8x8"),
        Exits(2, r"error: .*--size.*positive.*'-8x8'"),
    ),
    Case(
        "size-fraction",
        "nonsense",
        "refnpr render --size 8.5x8",
        _render("--size", "8.5x8"),
        Exits(2, r"error: .*--size: expected WxH.*'8\.5x8'"),
    ),
    Case(
        "spp-zero",
        "nonsense",
        "refnpr render --spp 0",
        _render("--size", "8x8", "--spp", "0"),
        Exits(2, r"error: .*spp.*0"),
    ),
    Case(
        "spp-not-square",
        "nonsense",
        "refnpr render --spp 3",
        _render("--size", "8x8", "--spp", "3"),
        Exits(2, r"error: .*spp: expected a square"),
    ),
    # --- scenes ------------------------------------------------------------------------------
    Case(
        "scene-unknown",
        "messages",
        "refnpr render --scene kettle",
        _render("--size", "8x8", "--scene", "kettle"),
        Exits(2, r"error: .*'kettle'.*teapot"),
    ),
    Case(
        "scene-empty-name",
        "nonsense",
        'refnpr render --scene ""',
        _render("--size", "8x8", "--scene", ""),
        Exits(2, r"error: .*scene.*''.*(valid|names)"),
    ),
    Case(
        "scene-missing-file",
        "files",
        "refnpr render --scene nowhere.toml",
        _render("--size", "8x8", "--scene", "nowhere.toml"),
        Exits(2, r"error: .*'nowhere\.toml' does not exist"),
    ),
    Case(
        "scene-file-without-toml-suffix",
        "files",
        "refnpr render --scene notes.txt (an existing file without .toml)",
        lambda t: (
            (t / "notes.txt").write_text("x")
            and _render("--size", "8x8", "--scene", "notes.txt")(t)
        ),
        Exits(2, r"error: .*'notes\.txt'.*\.toml"),
    ),
    # --- golden ------------------------------------------------------------------------------
    Case(
        "golden-only-unknown",
        "messages",
        "refnpr golden --only nosuch",
        _golden("--only", "nosuch"),
        Exits(2, r"error: .*unknown case names \['nosuch'\].*a-toon"),
    ),
    Case(
        "golden-check-and-update",
        "nonsense",
        "refnpr golden --check --update",
        _golden("--check", "--update"),
        Exits(2, r"error: .*--update.*not allowed with.*--check"),
    ),
    Case(
        "golden-missing-suite-file",
        "files",
        "refnpr golden --suite nowhere.toml",
        lambda t: cli("golden", "--suite", "nowhere.toml", cwd=t),
        Exits(2, r"error: .*nowhere\.toml.*does not exist"),
    ),
    # --- compare options ---------------------------------------------------------------------
    Case(
        "compare-tolerance-out-of-range",
        "nonsense",
        "refnpr compare a b --tolerance 2",
        lambda t: cli("compare", "a", "b", "--tolerance", "2", cwd=t),
        Exits(2, r"error: .*--tolerance: expected a value in \[0, 1\], got '2'"),
    ),
    Case(
        "compare-tolerance-nan",
        "nonsense",
        "refnpr compare a b --tolerance nan",
        lambda t: cli("compare", "a", "b", "--tolerance", "nan", cwd=t),
        Exits(2, r"error: .*--tolerance: .*'nan'"),
    ),
    Case(
        "compare-same-directory",
        "nonsense",
        "refnpr compare d d (a directory against itself)",
        _compare_self,
        Exits(2, r"error: .*same directory"),
        notes="it would pass every image without comparing anything",
    ),
]

test_case = parametrize(CASES)
