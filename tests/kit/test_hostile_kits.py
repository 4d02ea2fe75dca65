"""``refnpr kit check`` on hostile kits and renders: every outcome pinned.

A kit is untrusted input (docs/kit.md, "A kit is untrusted input"). Each row of the tables below
builds a small synthetic kit in ``tmp_path`` (two 16 x 16 image cases and one 16 x 12 G-buffer
case, with a perfect set of renders), damages one thing, and pins what happens:

* ``KIT`` rows: the whole kit is refused (``check_kit`` raises ValueError; ``refnpr kit check``
  exits 2 with the message on stderr, control characters escaped);
* ``CASE`` rows: the damaged case fails alone with a status and a message naming the file and
  key, the untouched cases still pass, ``refnpr kit check`` exits 1 (0 for a passing row).

The tests also check that nothing is read or written outside the kit, the renders and the report
directories, that no row decodes an image before checking its header size, and that every line
printed is free of control characters.
"""

from __future__ import annotations

import json
import os
import struct
import threading
import tracemalloc
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.cli import main
from refnpr.kit import limits, verdict
from refnpr.kit.check import CASE_NAME, CaseCheck, check_kit, format_table

from .conftest import SUITE

S = 16  # image cases are S x S
GB_W, GB_H = 16, 12
THRESHOLD = 2.0 / 255


# -- the synthetic kit -------------------------------------------------------------------------


def _write_exr(path: Path, channels: dict[str, np.ndarray]) -> None:
    import OpenEXR

    path.parent.mkdir(parents=True, exist_ok=True)
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION}, channels) as f:
        f.write(str(path))


def _rgba_exr(path: Path, rgba: np.ndarray) -> None:
    _write_exr(path, {n: np.ascontiguousarray(rgba[..., i]) for i, n in enumerate("RGBA")})


def _pattern(seed: int) -> np.ndarray:
    """(S, S, 4) uint8 opaque sRGB: a few flat blocks (SSIM is defined, pixels are distinct)."""
    rng = np.random.default_rng(seed)
    img = np.full((S, S, 4), 255, np.uint8)
    for y in range(0, S, 4):
        for x in range(0, S, 4):
            img[y : y + 4, x : x + 4, :3] = rng.integers(0, 256, 3)
    return img


def _image_case(root: Path, name: str, seed: int) -> dict:
    d = root / name
    d.mkdir(parents=True)
    png = _pattern(seed)
    iio.imwrite(d / "expected.png", png)
    _rgba_exr(d / "expected.exr", (png / 255.0).astype(np.float32))  # not linear: fine here
    case = {
        "name": name,
        "kind": "image",
        "width": S,
        "height": S,
        "spp": 1,
        "background": [1.0, 1.0, 1.0, 1.0],
        "style": {"name": "toon" if seed == 1 else "smooth", "params": {}},
        "expected": {"png": "expected.png", "linear": "expected.exr"},
        "tolerance": {
            "threshold": THRESHOLD,
            "max_frac_over": 0.0005,
            "min_ssim": 0.995,
            "position_deviation": 1,
        },
    }
    (d / "case.json").write_text(json.dumps(case))
    return {
        "name": name,
        "kind": "image",
        "style": case["style"]["name"],
        "case": f"{name}/case.json",
    }


def _gbuffer_case(root: Path, name: str) -> dict:
    d = root / name
    (d / "expected").mkdir(parents=True)
    rng = np.random.default_rng(3)
    arrays = {
        "tri_id": rng.integers(-1, 9, size=(GB_H, GB_W)).astype(np.int32),
        "depth": (1 + rng.random((GB_H, GB_W))).astype(np.float32),
        "normal": rng.normal(size=(GB_H, GB_W, 3)).astype(np.float32),
    }
    chans = {}
    for ch, a in arrays.items():
        np.save(d / "expected" / f"{ch}.npy", a)
        chans[ch] = {"file": f"expected/{ch}.npy", "dtype": str(a.dtype), "shape": list(a.shape)}
    case = {
        "name": name,
        "kind": "gbuffer",
        "width": GB_W,
        "height": GB_H,
        "spp": 1,
        "style": None,
        "expected": {"channels": chans, "format": "npy"},
        "tolerance": {"rtol": 1e-5, "atol": 1e-6, "discrete": {"tri_id": {"max_pixels": 0}}},
    }
    (d / "case.json").write_text(json.dumps(case))
    return {"name": name, "kind": "gbuffer", "style": None, "case": f"{name}/case.json"}


@dataclass
class Setup:
    """A kit, its perfect renders, and room outside both (``tmp``) for things pointed at."""

    tmp: Path
    kit: Path
    renders: Path

    # -- editing helpers used by the rows --

    def index(self) -> dict:
        return json.loads((self.kit / "index.json").read_text())

    def write_index(self, data) -> None:
        (self.kit / "index.json").write_text(json.dumps(data))

    def entry(self, name: str, **changes) -> None:
        idx = self.index()
        for c in idx["cases"]:
            if c["name"] == name:
                c.update(changes)
        self.write_index(idx)

    def case(self, name: str = "disc") -> dict:
        return json.loads((self.kit / name / "case.json").read_text())

    def write_case(self, data, name: str = "disc") -> None:
        (self.kit / name / "case.json").write_text(json.dumps(data))

    def edit_case(self, fn: Callable[[dict], None], name: str = "disc") -> None:
        data = self.case(name)
        fn(data)
        self.write_case(data, name)

    def replace_with_link(self, path: Path, target: Path) -> None:
        path.unlink()
        path.symlink_to(target)

    def replace_with_fifo(self, path: Path) -> None:
        path.unlink()
        os.mkfifo(path)


def _setup(tmp_path: Path) -> Setup:
    kit, renders = tmp_path / "kit", tmp_path / "renders"
    kit.mkdir()
    renders.mkdir()
    cases = [_image_case(kit, "good", 1), _image_case(kit, "disc", 2), _gbuffer_case(kit, "gbuf")]
    index = {"format": "refnpr-kit", "version": 1, "refnpr": "test", "cases": cases}
    (kit / "index.json").write_text(json.dumps(index))
    for name in ("good", "disc"):
        (renders / f"{name}.png").write_bytes((kit / name / "expected.png").read_bytes())
    (renders / "gbuf").mkdir()
    for f in (kit / "gbuf" / "expected").iterdir():
        (renders / "gbuf" / f.name).write_bytes(f.read_bytes())
    return Setup(tmp_path, kit, renders)


@pytest.fixture
def setup(tmp_path: Path) -> Setup:
    return _setup(tmp_path)


@pytest.fixture(autouse=True)
def _no_big_decode(monkeypatch):
    """Every test here: no image larger than 64 x 64 reaches a decoder (read with parsers
    independent of the checker's), so a regression fails fast instead of allocating gigabytes."""
    import OpenEXR

    real_png, real_exr = verdict._decode_png, OpenEXR.File

    def png(data: bytes, what: str):
        if data[12:16] == b"IHDR":
            w, h = struct.unpack(">II", data[16:24])
            assert w <= 64 and h <= 64, f"{what}: a {w}x{h} PNG reached the decoder"
        return real_png(data, what)

    def exr(path, *args, **kwargs):
        if isinstance(path, str) and not kwargs.get("header_only"):
            try:
                with real_exr(path, header_only=True) as f:
                    lo, hi = f.header()["dataWindow"]
            except Exception:  # noqa: BLE001 -- let the real call report a broken file
                lo = hi = np.zeros(2)
            assert (hi - lo + 1).max() <= 64, f"{path}: a large OpenEXR reached the decoder"
        return real_exr(path, *args, **kwargs)

    monkeypatch.setattr(verdict, "_decode_png", png)
    monkeypatch.setattr(OpenEXR, "File", exr)


# -- hostile files -----------------------------------------------------------------------------


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png_header_only(width: int, height: int) -> bytes:
    """A PNG signature and IHDR (8-bit RGBA) claiming ``width`` x ``height``, and no pixels."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + _png_chunk(b"IHDR", ihdr)


def png_huge_valid(width: int, height: int) -> bytes:
    """A complete, valid 1-bit gray PNG of ``width`` x ``height`` (all black): a few kilobytes
    that a decoder would turn into width x height bytes, and the checker into 32 x that."""
    row = b"\x00" + b"\x00" * ((width + 7) // 8)
    comp = zlib.compressobj(9)
    idat = b"".join(comp.compress(row) for _ in range(height)) + comp.flush()
    ihdr = struct.pack(">IIBBBBB", width, height, 1, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + _png_chunk(b"IHDR", ihdr)
        + _png_chunk(b"IDAT", idat)
        + _png_chunk(b"IEND", b"")
    )


def _exr_attr(name: str, kind: str, value: bytes) -> bytes:
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def exr_header_only(
    width: int, height: int, channels=("A", "B", "G", "R"), flags: int = 0
) -> bytes:
    """An OpenEXR header (scanline, FLOAT channels) claiming ``width`` x ``height``; no pixels."""
    chlist = b"".join(
        c.encode() + b"\0" + struct.pack("<iB3sii", 2, 0, b"", 1, 1) for c in channels
    )
    attrs = (
        _exr_attr("channels", "chlist", chlist + b"\0")
        + _exr_attr("compression", "compression", b"\0")
        + _exr_attr("dataWindow", "box2i", struct.pack("<iiii", 0, 0, width - 1, height - 1))
        + _exr_attr("displayWindow", "box2i", struct.pack("<iiii", 0, 0, width - 1, height - 1))
        + _exr_attr("lineOrder", "lineOrder", b"\0")
        + _exr_attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
        + _exr_attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0))
        + _exr_attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
    )
    return b"\x76\x2f\x31\x01" + struct.pack("<I", 2 | flags) + attrs + b"\0"


def npy_header_only(shape: tuple, dtype: str = "<f4") -> bytes:
    """A .npy header claiming ``shape`` and no data."""
    header = {"descr": dtype, "fortran_order": False, "shape": shape}
    import io

    f = io.BytesIO()
    np.lib.format.write_array_header_1_0(f, header)
    return f.getvalue()


def deep_json(depth: int) -> str:
    return "[" * depth + "]" * depth


# -- the tables --------------------------------------------------------------------------------


@dataclass(frozen=True)
class Kit:
    """The whole kit is refused: ValueError (exit 2) whose message holds ``fragment``."""

    fragment: str


@dataclass(frozen=True)
class Case:
    """Case ``name`` ends with ``status`` and ``fragment`` in its message; ``passed`` for a
    row whose damage is harmless (then the exit status is 0)."""

    status: str
    fragment: str
    name: str = "disc"
    passed: bool = False


def _huge_png_render(s: Setup) -> None:
    (s.renders / "disc.png").write_bytes(png_huge_valid(13000, 13000))


def _render_link_outside(s: Setup) -> None:
    outside = s.tmp / "outside.png"
    outside.write_bytes((s.kit / "disc" / "expected.png").read_bytes())  # would pass if read
    s.replace_with_link(s.renders / "disc.png", outside)


def _expected_link_outside(s: Setup) -> None:
    outside = s.tmp / "outside.png"
    outside.write_bytes((s.renders / "disc.png").read_bytes())  # would pass if read
    s.replace_with_link(s.kit / "disc" / "expected.png", outside)


def _exr_render(s: Setup, data: bytes) -> None:
    (s.renders / "disc.exr").write_bytes(data)


def _exr_only_y(s: Setup) -> None:
    _write_exr(s.renders / "disc.exr", {"Y": np.ones((S, S), np.float32)})


def _exr_nan(s: Setup) -> None:
    rgba = np.ones((S, S, 4), np.float32)
    rgba[3, 4, 1] = np.nan
    _rgba_exr(s.renders / "disc.exr", rgba)


def _npy_pickle(path: Path) -> None:
    np.save(path, np.array([{"a": 1}], dtype=object), allow_pickle=True)


def _rgb_render(s: Setup) -> None:
    png = iio.imread(s.renders / "disc.png")
    iio.imwrite(s.renders / "disc.png", png[..., :3])


def _truncated(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _set_tol(key, value, name="disc"):
    def edit(s: Setup) -> None:
        s.edit_case(lambda c: c["tolerance"].__setitem__(key, value), name)

    return edit


def _raw_tol(key: str, literal: str):
    """A tolerance value JSON cannot hold (NaN, Infinity), written as Python's json writes it."""

    def edit(s: Setup) -> None:
        text = (s.kit / "disc" / "case.json").read_text()
        c = json.loads(text)
        c["tolerance"][key] = "@@"
        (s.kit / "disc" / "case.json").write_text(json.dumps(c).replace('"@@"', literal))

    return edit


def _set(key, value, name="disc"):
    def edit(s: Setup) -> None:
        s.edit_case(lambda c: c.__setitem__(key, value), name)

    return edit


def _expected(key, value):
    def edit(s: Setup) -> None:
        s.edit_case(lambda c: c["expected"].__setitem__(key, value))

    return edit


def _index_name(name) -> Callable[[Setup], None]:
    def edit(s: Setup) -> None:
        idx = s.index()
        idx["cases"][1]["name"] = name
        s.write_index(idx)

    return edit


def _gb_render(ch: str, fn: Callable[[Path], None]) -> Callable[[Setup], None]:
    return lambda s: fn(s.renders / "gbuf" / f"{ch}.npy")


def _gb_channels(fn: Callable[[dict], None]) -> Callable[[Setup], None]:
    return lambda s: s.edit_case(lambda c: fn(c["expected"]["channels"]), "gbuf")


#: (id, damage, outcome): the index and what it names.
KIT_ROWS: list[tuple[str, Callable[[Setup], None], Kit]] = [
    ("name-dotdot-path", _index_name("../../../x/y"), Kit("'../../../x/y' is not a valid case name")),
    ("name-with-slash", _index_name("a/b"), Kit("'a/b' is not a valid case name")),
    ("name-with-dotdot-inside", _index_name("a..b"), Kit("'a..b' is not a valid case name")),
    ("name-absolute", _index_name("/tmp/x"), Kit("'/tmp/x' is not a valid case name")),
    ("name-unicode", _index_name("café"), Kit("'café' is not a valid case name")),
    ("name-upper-case", _index_name("Disc"), Kit("'Disc' is not a valid case name")),
    ("name-terminal-escape", _index_name("\x1b[2Jx"), Kit("'\\x1b[2Jx' is not a valid case name")),
    ("name-empty", _index_name(""), Kit("cases[1].name '' is not a valid case name")),
    ("name-not-a-string", _index_name(5), Kit("cases[1].name 5 is not a valid case name")),
    ("name-too-long", _index_name("a" * 129), Kit("is not a valid case name")),
    ("name-missing", lambda s: s.write_index({**s.index(), "cases": [{"case": "disc/case.json"}]}),
     Kit("cases[0].name None is not a valid case name")),
    ("names-duplicate", _index_name("good"), Kit("cases[1].name 'good' repeats cases[0]")),
    ("index-not-an-object", lambda s: s.write_index([1, 2]), Kit('expected {"format": "refnpr-kit"')),
    ("index-cases-not-a-list", lambda s: s.write_index({**s.index(), "cases": {"a": 1}}),
     Kit("'cases' must be a non-empty list")),
    ("index-cases-empty", lambda s: s.write_index({**s.index(), "cases": []}),
     Kit("'cases' must be a non-empty list")),
    ("index-entry-not-an-object", lambda s: s.write_index({**s.index(), "cases": [5]}),
     Kit("cases[0] is 5, not an object")),
    ("index-version-true", lambda s: s.write_index({**s.index(), "version": True}),
     Kit("kit format version True")),
    ("index-not-json", lambda s: (s.kit / "index.json").write_text("{nope"), Kit("not valid JSON")),
    ("index-not-utf8", lambda s: (s.kit / "index.json").write_bytes(b'{"a": "\xff"}'), Kit("not UTF-8")),
    ("index-repeated-key", lambda s: (s.kit / "index.json").write_text('{"format": 1, "format": 2}'),
     Kit("the key 'format' appears twice")),
    ("index-nested-100000-deep", lambda s: (s.kit / "index.json").write_text(deep_json(100_000)),
     Kit("JSON nested deeper than 32 levels")),
    ("index-nested-40-deep", lambda s: (s.kit / "index.json").write_text(deep_json(40)),
     Kit("JSON nested deeper than 32 levels")),
    ("index-fifo", lambda s: s.replace_with_fifo(s.kit / "index.json"), Kit("is not a regular file")),
    ("index-link-outside", lambda s: s.replace_with_link(s.kit / "index.json", s.tmp / "i.json"),
     Kit("leads outside the kit")),
    ("index-link-dev-zero", lambda s: s.replace_with_link(s.kit / "index.json", Path("/dev/zero")),
     Kit("leads outside the kit")),
]  # fmt: skip

#: (id, damage, outcome): one case's kit files.
KIT_CASE_ROWS: list[tuple[str, Callable[[Setup], None], Case]] = [
    ("case-path-not-a-string", lambda s: s.entry("disc", case=5),
     Case("kit", "case 'disc': case: expected a relative file path (a non-empty string), got 5")),
    ("case-path-dev-zero", lambda s: s.entry("disc", case="/dev/zero"),
     Case("kit", "'/dev/zero' is an absolute path")),
    ("case-path-dotdot", lambda s: s.entry("disc", case="../outside/case.json"),
     Case("kit", "has a '..' component")),
    ("case-path-backslash", lambda s: s.entry("disc", case="disc\\case.json"),
     Case("kit", "holds a NUL or a backslash")),
    ("case-path-nul", lambda s: s.entry("disc", case="disc/case.json\x00"),
     Case("kit", "holds a NUL or a backslash")),
    ("case-path-windows-drive", lambda s: s.entry("disc", case="C:/x/case.json"),
     Case("kit", "is an absolute path")),
    ("case-json-link-dev-zero", lambda s: s.replace_with_link(s.kit / "disc" / "case.json", Path("/dev/zero")),
     Case("kit", "leads outside the kit")),
    ("case-json-fifo", lambda s: s.replace_with_fifo(s.kit / "disc" / "case.json"),
     Case("kit", "is not a regular file; expected a regular file")),
    ("case-json-directory", lambda s: s.entry("disc", case="disc"),
     Case("kit", "'disc' is a directory")),
    ("case-json-absent", lambda s: (s.kit / "disc" / "case.json").unlink(), Case("kit", "does not exist")),
    ("case-json-nested-100000-deep", lambda s: (s.kit / "disc" / "case.json").write_text(deep_json(100_000)),
     Case("kit", "kit file 'disc/case.json': JSON nested deeper than 32 levels")),
    ("case-json-not-an-object", lambda s: s.write_case([1]), Case("kit", "expected a JSON object, got list")),
    ("case-json-huge-integer", lambda s: (s.kit / "disc" / "case.json").write_text("9" * 5000),
     Case("kit", "not valid JSON")),
    ("case-json-repeated-key", lambda s: (s.kit / "disc" / "case.json").write_text('{"kind": "image", "kind": 1}'),
     Case("kit", "the key 'kind' appears twice")),
    ("case-name-differs", _set("name", "good"), Case("kit", "name: 'good' differs from the name in index.json")),
    ("kind-unknown", _set("kind", "video"), Case("kit", "kind: expected 'image' or 'gbuffer', got 'video'")),
    ("kind-escape", _set("kind", "\x1b[31m"), Case("kit", "got '\\x1b[31m'")),
    ("width-missing", lambda s: s.edit_case(lambda c: c.pop("width")),
     Case("kit", "width: expected an integer in [1, 8192], got nothing (the key is missing)")),
    ("width-negative", _set("width", -16), Case("kit", "width: expected an integer in [1, 8192], got -16")),
    ("height-zero", _set("height", 0), Case("kit", "height: expected an integer in [1, 8192], got 0")),
    ("width-13000", _set("width", 13000), Case("kit", "got 13000")),
    ("width-float", _set("width", 16.0), Case("kit", "width: expected an integer in [1, 8192], got 16.0")),
    ("size-too-many-pixels", lambda s: s.edit_case(lambda c: c.update(width=4096, height=4096)),
     Case("kit", "4096 x 4096 = 16777216 pixels, more than the 4194304 allowed")),
    ("spp-not-square", _set("spp", 3), Case("kit", "spp: expected a square number n * n, got 3")),
    ("spp-huge", _set("spp", 10**6), Case("kit", "spp: expected an integer in [1, 64]")),
    ("tolerance-missing", lambda s: s.edit_case(lambda c: c.pop("tolerance")),
     Case("kit", "tolerance: expected an object, got None")),
    ("tolerance-a-list", _set("tolerance", [1, 2]), Case("kit", "tolerance: expected an object, got [1, 2]")),
    ("position-deviation-1e30", _set_tol("position_deviation", 1e30),
     Case("kit", "kit file 'disc/case.json': tolerance.position_deviation: expected an integer in [0, 8], got 1e+30")),
    ("position-deviation-10**30", _set_tol("position_deviation", 10**30),
     Case("kit", "tolerance.position_deviation: expected an integer in [0, 8], got 1000000000000")),
    ("position-deviation-9", _set_tol("position_deviation", 9),
     Case("kit", "tolerance.position_deviation: expected an integer in [0, 8], got 9")),
    ("position-deviation-negative", _set_tol("position_deviation", -1),
     Case("kit", "tolerance.position_deviation: expected an integer in [0, 8], got -1")),
    ("threshold-nan", _raw_tol("threshold", "NaN"),
     Case("kit", "tolerance.threshold: expected a finite number in [0, 1], got nan")),
    ("max-frac-over-infinity", _raw_tol("max_frac_over", "Infinity"),
     Case("kit", "tolerance.max_frac_over: expected a finite number in [0, 1], got inf")),
    ("threshold-1e400", _raw_tol("threshold", "1e400"), Case("kit", "tolerance.threshold: expected a finite number")),
    ("threshold-bool", _set_tol("threshold", True), Case("kit", "tolerance.threshold: expected a finite number in [0, 1], got True")),
    ("min-ssim-string", _set_tol("min_ssim", "0.9"), Case("kit", "tolerance.min_ssim: expected a finite number in [-1, 1], got '0.9'")),
    ("threshold-missing", lambda s: s.edit_case(lambda c: c["tolerance"].pop("threshold")),
     Case("kit", "tolerance.threshold: expected a finite number in [0, 1], got nothing (the key is missing)")),
    ("tolerance-unknown-key", _set_tol("max_psnr", 30.0), Case("kit", "tolerance: unknown key(s) ['max_psnr'] for a image case")),
    ("compare-on-other", _set_tol("compare_on", "linear"), Case("kit", "tolerance.compare_on: this refnpr compares")),
    ("gbuffer-atol-huge", _set_tol("atol", 1e300, "gbuf"),
     Case("kit", "tolerance.atol: expected a finite number in [0, 1e+06], got 1e+300", name="gbuf")),
    ("gbuffer-max-pixels-negative", _set_tol("discrete", {"tri_id": {"max_pixels": -1}}, "gbuf"),
     Case("kit", "tolerance.discrete.tri_id.max_pixels: expected an integer in [0, 2147483647], got -1", name="gbuf")),
    ("gbuffer-discrete-a-list", _set_tol("discrete", [1], "gbuf"),
     Case("kit", "tolerance.discrete: expected an object", name="gbuf")),
    ("background-a-string", _set("background", "white"),
     Case("kit", "background: expected 4 finite numbers (linear RGBA), got 'white'")),
    ("background-nan", lambda s: s.edit_case(lambda c: c.__setitem__("background", [1, 1, float("nan"), 1])),
     Case("kit", "background: expected 4 finite numbers")),
    ("expected-missing", _set("expected", None),
     Case("kit", "expected.png: expected a file name relative to case.json, got no expected object")),
    ("expected-png-not-a-string", _expected("png", 5), Case("kit", "expected.png: expected a file name relative to case.json, got 5")),
    ("expected-png-absolute", _expected("png", "/etc/passwd"), Case("kit", "expected.png: '/etc/passwd' is an absolute path")),
    ("expected-png-dotdot", _expected("png", "../good/expected.png"), Case("kit", "expected.png: '../good/expected.png' has a '..' component")),
    ("expected-png-link-outside", _expected_link_outside, Case("kit", "leads outside the kit")),
    ("expected-png-fifo", lambda s: s.replace_with_fifo(s.kit / "disc" / "expected.png"), Case("kit", "is not a regular file")),
    ("expected-png-garbage", lambda s: (s.kit / "disc" / "expected.png").write_bytes(b"GIF89a"),
     Case("kit", "kit file 'disc/expected.png': cannot read: not a PNG file")),
    ("expected-png-wrong-size", lambda s: iio.imwrite(s.kit / "disc" / "expected.png", np.zeros((S, S + 1, 4), np.uint8)),
     Case("kit", "kit file 'disc/expected.png' is 17x16, the case is 16x16 (refused from its header")),
    ("expected-png-truncated", lambda s: _truncated(s.kit / "disc" / "expected.png"), Case("kit", "cannot read")),
    ("gbuffer-channels-not-an-object", _gb_channels(lambda ch: ch.clear()),
     Case("kit", "expected.channels: expected an object of 1 to 64 channels", name="gbuf")),
    ("gbuffer-channel-name-path", _gb_channels(lambda ch: ch.__setitem__("../../x", {"file": "expected/depth.npy"})),
     Case("kit", "channel name '../../x' does not match", name="gbuf")),
    ("gbuffer-channel-file-missing-key", _gb_channels(lambda ch: ch.__setitem__("depth", {})),
     Case("kit", "expected.channels.depth.file: expected a file name, got None", name="gbuf")),
    ("gbuffer-expected-pickle", lambda s: _npy_pickle(s.kit / "gbuf" / "expected" / "depth.npy"),
     Case("kit", "expected a boolean, integer or float array", name="gbuf")),
    ("gbuffer-expected-wrong-shape", lambda s: np.save(s.kit / "gbuf" / "expected" / "depth.npy", np.zeros((5, 5), np.float32)),
     Case("kit", "kit file 'gbuf/expected/depth.npy' has shape (5, 5)", name="gbuf")),
    ("gbuffer-expected-absolute", _gb_channels(lambda ch: ch.__setitem__("depth", "/etc/passwd")),
     Case("kit", "'/etc/passwd' is an absolute path", name="gbuf")),
]  # fmt: skip

#: (id, damage, outcome): the renders.
RENDER_ROWS: list[tuple[str, Callable[[Setup], None], Case]] = [
    ("render-absent", lambda s: (s.renders / "disc.png").unlink(), Case("missing", "no render 'disc.png'")),
    ("render-13000x13000-valid-png", _huge_png_render,
     Case("size", "render 'disc.png' is 13000x13000, the case is 16x16 (refused from its header, not decoded)")),
    ("render-13000x13000-header-only", lambda s: (s.renders / "disc.png").write_bytes(png_header_only(13000, 13000)),
     Case("size", "is 13000x13000, the case is 16x16")),
    ("render-link-outside", _render_link_outside, Case("unreadable", "leads outside the renders directory")),
    ("render-link-dev-zero", lambda s: s.replace_with_link(s.renders / "disc.png", Path("/dev/zero")),
     Case("unreadable", "leads outside the renders directory")),
    ("render-fifo", lambda s: s.replace_with_fifo(s.renders / "disc.png"), Case("unreadable", "is not a regular file")),
    ("render-directory", lambda s: ((s.renders / "disc.png").unlink(), (s.renders / "disc.png").mkdir()),
     Case("unreadable", "is a directory")),
    ("render-empty-file", lambda s: (s.renders / "disc.png").write_bytes(b""), Case("unreadable", "not a PNG file")),
    ("render-garbage", lambda s: (s.renders / "disc.png").write_bytes(b"\x1b[2J" * 10), Case("unreadable", "no PNG signature")),
    ("render-jpeg-named-png", lambda s: iio.imwrite(s.renders / "disc.png", np.zeros((S, S, 3), np.uint8), extension=".jpg"),
     Case("unreadable", "no PNG signature")),
    ("render-truncated-png", lambda s: _truncated(s.renders / "disc.png"), Case("unreadable", "truncated")),
    ("render-zero-size-ihdr", lambda s: (s.renders / "disc.png").write_bytes(png_header_only(0, 16)),
     Case("unreadable", "the PNG header gives a size of 0x16")),
    ("render-rgb-without-alpha", _rgb_render, Case("ok", "frac_over_position=0.00000", passed=True)),
    ("render-wrong-size", lambda s: iio.imwrite(s.renders / "disc.png", np.zeros((S - 1, S, 4), np.uint8)),
     Case("size", "render 'disc.png' is 16x15, the case is 16x16")),
    ("exr-13000x13000-header-only", lambda s: _exr_render(s, exr_header_only(13000, 13000)),
     Case("size", "render 'disc.exr' is 13000x13000, the case is 16x16 (refused from its header")),
    ("exr-only-y-channel", _exr_only_y, Case("unreadable", "has channels ['Y']; expected R, G, B (and A)")),
    ("exr-garbage-after-magic", lambda s: _exr_render(s, b"\x76\x2f\x31\x01" + b"\x02\x00\x00\x00junk"),
     Case("unreadable", "the OpenEXR header is truncated or corrupt")),
    ("exr-multi-part", lambda s: _exr_render(s, exr_header_only(S, S, flags=0x1000)),
     Case("unreadable", "expected a single-part scanline or tiled image")),
    ("exr-header-without-pixels", lambda s: _exr_render(s, exr_header_only(S, S)), Case("unreadable", "cannot read")),
    ("exr-too-many-channels", lambda s: _exr_render(s, exr_header_only(S, S, tuple("ABCDEFGHIJ"))),
     Case("unreadable", "more than 8 channels")),
    ("exr-nan", _exr_nan, Case("unreadable", "render 'disc.exr' holds NaN or inf")),
    ("gbuffer-render-absent", lambda s: __import__("shutil").rmtree(s.renders / "gbuf"),
     Case("missing", "no render directory 'gbuf'", name="gbuf")),
    ("gbuffer-render-a-file", lambda s: (__import__("shutil").rmtree(s.renders / "gbuf"), (s.renders / "gbuf").write_text("x")),
     Case("unreadable", "render 'gbuf' is not a directory", name="gbuf")),
    ("gbuffer-render-dir-link-outside", lambda s: (__import__("shutil").move(s.renders / "gbuf", s.tmp / "gb"), (s.renders / "gbuf").symlink_to(s.tmp / "gb")),
     Case("unreadable", "leads outside the renders directory", name="gbuf")),
    ("gbuffer-channel-absent", _gb_render("normal", Path.unlink),
     Case("channels", "render 'gbuf' lacks channel(s) ['normal']", name="gbuf")),
    ("gbuffer-wrong-channel-count", _gb_render("normal", lambda p: np.save(p, np.zeros((GB_H, GB_W, 2), np.float32))),
     Case("size", "channel 'normal': render 'gbuf/normal.npy' has shape (12, 16, 2), the kit (12, 16, 3) (refused from its header", name="gbuf")),
    ("gbuffer-huge-header", _gb_render("depth", lambda p: p.write_bytes(npy_header_only((100_000, 100_000)))),
     Case("size", "has shape (100000, 100000), the kit (12, 16)", name="gbuf")),
    ("gbuffer-pickle", _gb_render("depth", _npy_pickle), Case("unreadable", "expected a boolean, integer or float array", name="gbuf")),
    ("gbuffer-truncated", _gb_render("depth", _truncated), Case("unreadable", "(truncated or corrupt)", name="gbuf")),
    ("gbuffer-not-npy", _gb_render("depth", lambda p: p.write_bytes(b"\x1b]0;title\x07")), Case("unreadable", "not a readable .npy file", name="gbuf")),
    ("gbuffer-channel-link-dev-zero", _gb_render("depth", lambda p: (p.unlink(), p.symlink_to("/dev/zero"))),
     Case("unreadable", "leads outside the renders directory", name="gbuf")),
    ("gbuffer-fortran-order", _gb_render("normal", lambda p: np.save(p, np.asfortranarray(np.load(p)))),
     Case("ok", "all channels within tolerance", name="gbuf", passed=True)),
]  # fmt: skip


def _printable_everywhere(text: str) -> None:
    bad = [c for c in text if not (c.isprintable() or c == "\n")]
    assert not bad, f"unescaped characters printed: {bad!r}"


def _run_cli(s: Setup, capsys, *extra: str) -> tuple[int, str, str]:
    code = main(["kit", "check", str(s.kit), str(s.renders), *extra])
    out, err = capsys.readouterr()
    _printable_everywhere(out + err)
    return code, out, err


@pytest.mark.parametrize(("damage", "outcome"), [pytest.param(d, o, id=i) for i, d, o in KIT_ROWS])
def test_a_hostile_index_refuses_the_kit(setup, capsys, damage, outcome):
    damage(setup)
    with pytest.raises(ValueError) as info:
        check_kit(setup.kit, setup.renders)
    assert outcome.fragment in str(info.value)
    _printable_everywhere(str(info.value))
    code, out, err = _run_cli(setup, capsys)
    assert code == 2 and outcome.fragment in err and out == ""


def _assert_case_row(s: Setup, capsys, outcome: Case) -> None:
    results = {r.name: r for r in check_kit(s.kit, s.renders)}
    assert list(results) == ["good", "disc", "gbuf"] or outcome.status == "missing"
    r = results[outcome.name]
    assert (r.status, r.passed) == (outcome.status, outcome.passed), r.message
    assert outcome.fragment in r.message, r.message
    _printable_everywhere(r.message)
    others = [x for n, x in results.items() if n != outcome.name]
    assert all(x.passed for x in others), [(x.name, x.message) for x in others]
    code, out, _ = _run_cli(s, capsys)
    assert code == (0 if outcome.passed else 1)
    assert outcome.passed or outcome.fragment in out  # the table shows why a case fails


@pytest.mark.parametrize(
    ("damage", "outcome"), [pytest.param(d, o, id=i) for i, d, o in KIT_CASE_ROWS]
)
def test_a_hostile_case_fails_alone(setup, capsys, damage, outcome):
    damage(setup)
    _assert_case_row(setup, capsys, outcome)


@pytest.mark.parametrize(
    ("damage", "outcome"), [pytest.param(d, o, id=i) for i, d, o in RENDER_ROWS]
)
def test_a_hostile_render_fails_alone(setup, capsys, damage, outcome):
    damage(setup)
    _assert_case_row(setup, capsys, outcome)


# -- the rows' claims, checked where a table cannot ------------------------------------------


def test_the_pattern_of_case_names_and_every_name_of_the_suite():
    """Every case of the golden suite (the names ``refnpr kit export`` writes) has a valid name;
    the pattern refuses path tricks."""
    from refnpr.golden import load_suite

    names = [c.name for c in load_suite(SUITE)]
    assert names and all(CASE_NAME.fullmatch(n) and ".." not in n for n in names), names
    for bad in ("", ".", "..", ".hidden", "-x", "a/b", "a\\b", "A", "é", "a b", "a" * 129, "x\n"):
        assert CASE_NAME.fullmatch(bad) is None, bad
    for good in ("a", "0", "xtoon-fig5e-sphere-w050", "torus_knot-toon", "v1.2", "a" * 128):
        assert CASE_NAME.fullmatch(good), good


def test_a_huge_render_is_refused_before_any_big_allocation(setup, monkeypatch):
    """The 13000 x 13000 PNG (a few kB on disk) is never decoded: the decoder is not called
    and the check allocates less than 16 MB (decoding would take 169 MB, float64 5.4 GB)."""
    _huge_png_render(setup)
    calls = []
    real = verdict._decode_png  # the guard of _no_big_decode

    def decode(data: bytes, what: str):
        calls.append(what)
        if "disc.png" in what:  # fail here rather than allocate gigabytes
            raise AssertionError("the 13000 x 13000 render reached the decoder")
        return real(data, what)

    monkeypatch.setattr(verdict, "_decode_png", decode)
    results, peak = _checked_with_peak(setup)
    assert results["disc"].status == "size"
    assert "render 'disc.png'" not in calls and "render 'good.png'" in calls
    assert peak < 16 << 20, peak


def _checked_with_peak(setup) -> tuple[dict, int]:
    """``check_kit`` of the setup's kit and renders, by case name, and its peak of traced
    allocations (bytes)."""
    tracemalloc.start()
    try:
        results = {r.name: r for r in check_kit(setup.kit, setup.renders)}
        return results, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_position_deviation_is_capped_so_the_compare_is_bounded(setup):
    """The largest allowed deviation (8) runs; the next integer is refused without comparing."""
    _set_tol("position_deviation", 8)(setup)
    assert check_kit(setup.kit, setup.renders)[1].passed
    _set_tol("position_deviation", 9)(setup)
    r = check_kit(setup.kit, setup.renders)[1]
    assert r.status == "kit" and r.metrics == {}


def test_reads_stop_at_the_size_limits(setup, monkeypatch):
    monkeypatch.setattr(limits, "MAX_JSON_BYTES", 200)
    with pytest.raises(
        ValueError, match=r"kit_dir: .*index.json' has \d+ bytes, more than the 200 bytes"
    ):
        check_kit(setup.kit, setup.renders)
    monkeypatch.setattr(limits, "MAX_JSON_BYTES", 8 << 20)
    monkeypatch.setattr(limits, "MAX_FILE_BYTES", 100)
    results = {r.name: r for r in check_kit(setup.kit, setup.renders)}
    assert (
        results["disc"].status == "kit"
        and "more than the 100 bytes allowed" in results["disc"].message
    )


def test_a_fifo_never_blocks(setup):
    """A FIFO in place of case.json, the expected PNG or the render is refused without being
    opened (opening a FIFO for reading blocks until a writer comes)."""
    setup.replace_with_fifo(setup.kit / "disc" / "case.json")
    setup.replace_with_fifo(setup.renders / "good.png")
    done = []
    t = threading.Thread(
        target=lambda: done.append(check_kit(setup.kit, setup.renders)), daemon=True
    )
    t.start()
    t.join(timeout=60)
    assert done, "kit check blocked on a FIFO"
    results = {r.name: r for r in done[0]}
    assert results["disc"].status == "kit" and results["good"].status == "unreadable"


def test_nothing_is_written_outside_the_report_directory(setup, tmp_path):
    """A case name that climbs out (refused), and the report beside the kit for valid names:
    every file written lies under the report directory."""
    before = {p for p in tmp_path.rglob("*")}
    _index_name("../../../escape/y")(setup)
    with pytest.raises(ValueError, match="not a valid case name"):
        check_kit(setup.kit, setup.renders, report_dir=tmp_path / "report")
    assert not (tmp_path / "report").exists() and not (tmp_path.parent / "escape").exists()
    _index_name("disc")(setup)
    check_kit(
        setup.kit, setup.renders, report_dir=tmp_path / "report", json_path=tmp_path / "c.json"
    )
    new = {p for p in tmp_path.rglob("*")} - before
    assert new and all(
        p.is_relative_to(tmp_path / "report") or p == tmp_path / "c.json" for p in new
    )


@pytest.mark.parametrize(
    ("where", "fragment"),
    [
        ("kit/report", "report_dir: .* overlaps the kit"),
        ("kit", "report_dir: .* overlaps the kit"),
        (".", "report_dir: .* overlaps the kit"),  # the report directory would hold the kit
        ("renders", "report_dir: .* overlaps the renders directory"),
        ("renders/report", "report_dir: .* overlaps the renders directory"),
    ],
)
def test_a_report_directory_overlapping_the_kit_or_the_renders_is_refused(
    setup, capsys, where, fragment
):
    report = setup.tmp / where
    with pytest.raises(ValueError, match=fragment):
        check_kit(setup.kit, setup.renders, report_dir=report)
    assert not (setup.kit / "report").exists() and not (setup.renders / "report").exists()
    code, _, err = _run_cli(setup, capsys, "--report", str(report))
    assert code == 2 and "overlaps" in err


def test_a_json_file_inside_the_kit_is_refused(setup):
    before = (setup.kit / "index.json").read_bytes()
    with pytest.raises(ValueError, match="json_path: .* lies inside the kit"):
        check_kit(setup.kit, setup.renders, json_path=setup.kit / "index.json")
    assert (setup.kit / "index.json").read_bytes() == before


def test_control_characters_are_escaped_in_everything_printed(setup, capsys):
    """A render file whose name holds terminal escapes, a kit value with them, and a CaseCheck
    built by hand: the table, the note and the messages show them escaped."""
    (setup.renders / "\x1b[2Jclear\u202e.png").write_bytes(b"x")
    _set("kind", "\x1b]0;pwned\x07")(setup)
    code, out, _ = _run_cli(setup, capsys)
    assert code == 1
    assert "\\x1b[2Jclear\\u202e.png" in out and "\\x1b]0;pwned\\x07" in out
    c = CaseCheck("x", "image", False, "kit", "bell \x07 and \x9b and \u2028")
    assert c.message == "bell \\x07 and \\x9b and \\u2028"
    _printable_everywhere(format_table([c]))


def test_memory_is_released_as_the_report_streams(setup, monkeypatch):
    """The checker hands the report one case at a time: when the report draws case k, the
    visual of case k - 1 is already gone (only the generator's current case is alive)."""
    import gc
    import weakref

    from refnpr.kit import report

    seen: list[weakref.ref] = []
    alive_at_each_step = []

    def fake_write_report(report_dir, cases, *, kit_dir, renders_dir):
        out = []
        for check, vis in cases:
            gc.collect()
            alive_at_each_step.append(sum(r() is not None for r in seen))
            seen.append(weakref.ref(vis))
            out.append(check)
            del vis
        return out

    monkeypatch.setattr(report, "write_report", fake_write_report)
    check_kit(setup.kit, setup.renders, report_dir=setup.tmp / "report")
    assert alive_at_each_step == [0, 0, 0]


def test_an_animated_png_render_decodes_its_first_frame_only(setup):
    """An APNG passes the header check (its IHDR is the case's size) and would decode to a
    stack of every frame; only the first frame is read, so 400 frames cost one."""
    first = iio.imread(setup.renders / "disc.png")
    frames = np.repeat(first[None], 400, axis=0)
    frames[1:, 0, 0, 0] ^= 1  # distinct frames, so the encoder keeps them all
    iio.imwrite(setup.renders / "disc.png", frames, extension=".png")
    assert iio.imread(setup.renders / "disc.png", extension=".png").shape[0] == 400
    results, peak = _checked_with_peak(setup)
    assert results["disc"].passed, results["disc"].message
    assert peak < 400 * first.nbytes  # the 400 frames alone, undecoded to float
