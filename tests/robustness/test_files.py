"""Bad files given to refnpr: textures, screens, scenes, suites, golden and candidate images,
and output paths (including a write interrupted by a signal).

Every case uses only the public API or the ``refnpr`` command, so the catalogue also runs
against older code (to count what was broken).
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

from .catalogue import Case, Correct, Exits, Raises, cli, parametrize

# ---------------------------------------------------------------------------------------------
# helpers: files to give
# ---------------------------------------------------------------------------------------------
SCENE = "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n[[object]]\nmesh = 'uv_sphere'\n"


def _png(path: Path, shape=(12, 16, 4), dtype=np.uint8, value: int | None = None) -> Path:
    """A valid PNG written with imageio (not refnpr), deterministic noise or a constant."""
    import imageio.v3 as iio

    rng = np.random.default_rng(7)
    hi = 2 if dtype == np.bool_ else (65536 if dtype == np.uint16 else 256)
    a = rng.integers(0, hi, shape) if value is None else np.full(shape, value)
    path.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(path, a.astype(dtype), extension=".png")
    return path


def _text(path: Path, text: str = "these are notes, not an image\n") -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def _truncated(path: Path) -> Path:
    _png(path, (64, 64, 4))
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    return path


def _load_texture(make):
    def run(tmp: Path):
        from refnpr.texture import load_texture

        return load_texture(str(make(tmp)))

    return run


def _load_scene(make):
    def run(tmp: Path):
        from refnpr.scenes import load_scene

        return load_scene(str(make(tmp)))

    return run


def _bytes(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _mkdir(path: Path) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    return path


# ---------------------------------------------------------------------------------------------
# golden suites
# ---------------------------------------------------------------------------------------------
SUITE = """
[defaults]
width = 16
height = 12

[[case]]
name = "a-toon"
scene = "sphere"
style = { name = "toon", n = 2 }

[[case]]
name = "b-smooth"
scene = "sphere"
style = { name = "smooth" }
"""


def _suite(tmp: Path, extra: str = "") -> Path:
    """A two-case suite in ``tmp/g`` with both golden files written by ``update_suite``."""
    from refnpr.golden import update_suite

    suite = _text(tmp / "g" / "suite.toml", SUITE + extra)
    update_suite(suite, log=lambda *_: None)
    return suite


def _golden_corrupt(tmp: Path):
    from refnpr.golden import check_suite

    suite = _suite(tmp)
    _text(suite.parent / "a-toon.png", "not a png")
    return check_suite(suite, failure_dir=tmp / "fail")


def _check_corrupt(results, tmp: Path) -> None:
    by = {r.name: r for r in results}
    assert set(by) == {"a-toon", "b-smooth"}, f"results for {sorted(by)}"
    assert not by["a-toon"].passed, "a corrupt golden file passed"
    assert "a-toon.png" in by["a-toon"].message, by["a-toon"].message
    assert by["b-smooth"].passed, by["b-smooth"].message


def _golden_corrupt_cli(tmp: Path):
    suite = _suite(tmp)
    _truncated(suite.parent / "a-toon.png")
    return cli("golden", "--suite", str(suite), cwd=tmp)


def _check_corrupt_cli(proc, tmp: Path) -> None:
    assert "Traceback" not in proc.stderr, proc.stderr[-400:]
    assert proc.returncode == 1, f"exit {proc.returncode}: {proc.stderr[-300:]}"
    fail = [ln for ln in proc.stdout.splitlines() if ln.startswith("FAIL")]
    assert len(fail) == 1 and "a-toon" in fail[0] and "a-toon.png" in fail[0], proc.stdout
    assert "truncated" in fail[0], fail[0]
    assert "1 passed, 1 failed" in proc.stdout, proc.stdout


def _check_packaged_suite(proc, tmp: Path) -> None:
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-400:]}"
    assert proc.stdout.startswith("PASS sphere-toon3"), proc.stdout
    assert "1 passed, 0 failed" in proc.stdout, proc.stdout
    assert not any(tmp.iterdir()), f"wrote into the working directory: {list(tmp.iterdir())}"


def _golden_size(tmp: Path):
    from refnpr.golden import check_suite

    suite = _suite(tmp)
    _png(suite.parent / "a-toon.png", (10, 20, 4))
    return check_suite(suite, only=["a-toon"], failure_dir=tmp / "fail")


def _check_size(results, tmp: Path) -> None:
    (r,) = results
    assert not r.passed
    for part in ("16x12", "20x10", "a-toon.png"):
        assert part in r.message, f"{part!r} not in {r.message!r}"


def _golden_npz_corrupt(tmp: Path):
    from refnpr.golden import check_suite

    extra = '\n[[case]]\nname = "c-gb"\nkind = "gbuffer"\nscene = "sphere"\nchannels = ["depth"]\n'
    suite = _suite(tmp, extra)
    _text(suite.parent / "c-gb.npz", "not a zip")
    return check_suite(suite, failure_dir=tmp / "fail")


def _check_npz(results, tmp: Path) -> None:
    by = {r.name: r for r in results}
    assert set(by) == {"a-toon", "b-smooth", "c-gb"}, sorted(by)
    assert not by["c-gb"].passed and "c-gb.npz" in by["c-gb"].message, by["c-gb"].message
    assert by["a-toon"].passed and by["b-smooth"].passed


def _non_utf8_suite(tmp: Path):
    from refnpr.golden import load_suite

    path = tmp / "suite.toml"
    path.write_bytes(b'[[case]]\nname = "caf\xe9"\nscene = "sphere"\n')
    return load_suite(path)


# ---------------------------------------------------------------------------------------------
# compare (the command: per-image failures are reported, not raised)
# ---------------------------------------------------------------------------------------------
def _compare(setup):
    def run(tmp: Path):
        ref, cand = _mkdir(tmp / "ref"), _mkdir(tmp / "cand")
        setup(ref, cand)
        return cli("compare", str(ref), str(cand), cwd=tmp)

    return run


def _same(ref: Path, cand: Path, name: str = "s.png", **kw) -> None:
    _png(ref / name, **kw)
    _png(cand / name, **kw)


def _size_pair(ref: Path, cand: Path) -> None:
    _png(ref / "s.png", (12, 16, 4))
    _png(cand / "s.png", (24, 32, 4))


def _check_size_cli(proc, tmp: Path) -> None:
    assert "Traceback" not in proc.stderr, proc.stderr[-400:]
    assert proc.returncode == 1, f"exit {proc.returncode}"
    out = proc.stdout + proc.stderr
    for part in ("16x12", "32x24", str(Path("ref") / "s.png"), str(Path("cand") / "s.png")):
        assert part in out, f"{part!r} not in output:\n{out}"


def _corrupt_candidate(ref: Path, cand: Path) -> None:
    _same(ref, cand, "good.png")
    _png(ref / "bad.png")
    _truncated(cand / "bad.png")


def _check_corrupt_candidate(proc, tmp: Path) -> None:
    assert "Traceback" not in proc.stderr, proc.stderr[-400:]
    assert proc.returncode == 1, f"exit {proc.returncode}: {proc.stderr[-300:]}"
    out = proc.stdout + proc.stderr
    assert "bad.png" in out and "truncated" in out, out
    assert "1 passed, 1 failed" in proc.stdout, out


def _passes(proc, tmp: Path) -> None:
    assert "Traceback" not in proc.stderr, proc.stderr[-400:]
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stdout[-300:]} {proc.stderr}"
    assert "1 passed, 0 failed" in proc.stdout, proc.stdout


def _sixteen_bit(ref: Path, cand: Path) -> None:
    _png(ref / "s.png", (12, 16), np.uint8, value=200)
    _png(cand / "s.png", (12, 16), np.uint16, value=200 * 257)


def _grey_vs_rgba(ref: Path, cand: Path) -> None:
    _png(ref / "s.png", (12, 16, 4), np.uint8, value=90)
    a = np.full((12, 16, 4), 90, np.uint8)
    a[..., 3] = 255
    import imageio.v3 as iio

    iio.imwrite(ref / "s.png", a, extension=".png")
    _png(cand / "s.png", (12, 16), np.uint8, value=90)


def _one_bit(ref: Path, cand: Path) -> None:
    _png(ref / "s.png", (12, 16), np.uint8, value=255)
    _png(cand / "s.png", (12, 16), np.bool_, value=1)


def _extra(ref: Path, cand: Path) -> None:
    _same(ref, cand)
    _png(cand / "stray-extra.png")


def _check_extra(proc, tmp: Path) -> None:
    _passes(proc, tmp)
    assert "stray-extra.png" in proc.stdout + proc.stderr, "extra candidate file not mentioned"


def _empty_candidate(ref: Path, cand: Path) -> None:
    _png(ref / "s.png")


def _check_empty_candidate(proc, tmp: Path) -> None:
    assert proc.returncode == 1, f"exit {proc.returncode}"
    out = proc.stdout + proc.stderr
    assert "missing" in out and "no .png files" in out, out


def _compare_out_is_file(tmp: Path):
    ref, cand = _mkdir(tmp / "ref"), _mkdir(tmp / "cand")
    _same(ref, cand)
    _text(tmp / "report")
    return cli("compare", str(ref), str(cand), "--out", "report", cwd=tmp)


def _compare_json_is_dir(tmp: Path):
    ref, cand = _mkdir(tmp / "ref"), _mkdir(tmp / "cand")
    _same(ref, cand)
    _mkdir(tmp / "metrics.json")
    return cli("compare", str(ref), str(cand), "--json", "metrics.json", cwd=tmp)


def _compare_size_api(tmp: Path):
    from refnpr.compare import compare_dirs

    ref, cand = _mkdir(tmp / "ref"), _mkdir(tmp / "cand")
    _size_pair(ref, cand)
    return compare_dirs(ref, cand)


def _check_size_api(results, tmp: Path) -> None:
    (m,) = results
    assert m.status == "size", m.status
    text = " ".join(str(v) for v in vars(m).values())
    for part in ("16x12", "32x24"):
        assert part in text, f"{part!r} not among the metrics' fields: {vars(m)}"


# ---------------------------------------------------------------------------------------------
# writes interrupted by a signal, or failing
# ---------------------------------------------------------------------------------------------
# SIGINT as an interactive user has it: a shell starts background jobs with SIGINT ignored, and
# an ignored signal is inherited (Python then installs no KeyboardInterrupt handler).
_CHILD = """
import signal
signal.signal(signal.SIGINT, signal.default_int_handler)
import numpy as np
from refnpr.image import write_png_atomic
a = np.random.default_rng(0).integers(0, 256, (3000, 3000, 4), dtype=np.uint8)
write_png_atomic({target!r}, a)
"""


def _interrupted(sig: int):
    """Start a slow PNG write in a child, signal it once its temporary file exists."""

    def run(tmp: Path) -> dict:
        target = tmp / "big.png"
        proc = subprocess.Popen(
            [sys.executable, "-c", _CHILD.format(target=str(target))],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        seen = False
        try:
            deadline = time.monotonic() + 90.0
            while time.monotonic() < deadline and proc.poll() is None:
                if any(p.name.startswith(".big.") for p in tmp.iterdir()):
                    seen = True
                    break
                time.sleep(0.005)
            if seen:
                time.sleep(0.2)  # well inside the write (about a second for this image)
                proc.send_signal(sig)
            _, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        return {"seen": seen, "rc": proc.returncode, "err": err, "files": sorted(tmp.iterdir())}

    return run


def _check_interrupted(result: dict, tmp: Path) -> None:
    import imageio.v3 as iio

    assert result["seen"], f"the temporary file never appeared (exit {result['rc']})"
    stray = [p.name for p in result["files"] if p.name != "big.png"]
    assert not stray, f"left behind: {stray}"
    if (tmp / "big.png").exists():  # the rename won the race: then it must be complete
        assert iio.imread(tmp / "big.png").shape == (3000, 3000, 4)
    assert result["rc"] != 0, "the child ignored the signal"


def _write_in_thread(tmp: Path) -> list[str]:
    from refnpr.image import write_png_atomic

    errors: list[BaseException] = []

    def work() -> None:
        try:
            write_png_atomic(tmp / "t.png", np.zeros((4, 4, 4), np.uint8))
        except BaseException as exc:  # noqa: BLE001 -- reported by the check
            errors.append(exc)

    t = threading.Thread(target=work)
    t.start()
    t.join(60)
    if errors:
        raise errors[0]
    return sorted(p.name for p in tmp.iterdir())


def _check_thread(names: list[str], tmp: Path) -> None:
    assert names == ["t.png"], names


def _bad_shape_write(tmp: Path) -> tuple[str, list[str]]:
    from refnpr.image import write_png_atomic

    try:
        write_png_atomic(tmp / "x.png", np.zeros((4, 4, 7), np.uint8))  # 7 channels
        error = ""
    except (ValueError, TypeError, OSError) as exc:
        error = f"{type(exc).__name__}: {exc}"
    return error, sorted(p.name for p in tmp.iterdir())


def _check_refused(result: tuple[str, list[str]], tmp: Path) -> None:
    error, names = result
    assert names == [], f"left behind: {names} (error: {error or 'none'})"
    assert error.startswith("ValueError: pixels:") and "(4, 4, 7)" in error, error


def _animated(path: Path) -> Path:
    from PIL import Image

    frames = [Image.fromarray(np.full((4, 4, 3), 80 * i, np.uint8)) for i in range(3)]
    frames[0].save(path, save_all=True, append_images=frames[1:])
    return path


def _render(*args: str):
    def run(tmp: Path):
        return cli("render", "--size", "8x8", "-q", *args, cwd=tmp)

    return run


def _render_in(setup, *args: str):
    def run(tmp: Path):
        setup(tmp)
        return cli("render", "--size", "8x8", "-q", *args, cwd=tmp)

    return run


def _scene_with_bad_material_texture(tmp: Path) -> None:
    _text(tmp / "bad.png")
    _text(
        tmp / "s.toml",
        "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n"
        "[style]\nname = 'threshold'\nsource = 'image'\n"
        "[[object]]\nmesh = 'uv_sphere'\n[object.material]\ntexture = 'bad.png'\n",
    )


# ---------------------------------------------------------------------------------------------
CASES = [
    # --- textures and screens ----------------------------------------------------------------
    Case(
        "texture-text-as-png",
        "files",
        "load_texture of a text file named notes.png",
        _load_texture(lambda t: _text(t / "notes.png")),
        Raises(ValueError, r"notes\.png.*not .*image.*PNG"),
    ),
    Case(
        "texture-text-file",
        "files",
        "load_texture of notes.txt (a text file)",
        _load_texture(lambda t: _text(t / "notes.txt")),
        Raises(ValueError, r"notes\.txt.*PNG"),
    ),
    Case(
        "texture-truncated-png",
        "files",
        "load_texture of a PNG cut in half",
        _load_texture(lambda t: _truncated(t / "cut.png")),
        Raises(ValueError, r"cut\.png.*truncated"),
    ),
    Case(
        "texture-empty-file",
        "files",
        "load_texture of a 0-byte empty.png",
        _load_texture(lambda t: _text(t / "empty.png", "")),
        Raises(ValueError, r"empty\.png.*(empty|PNG)"),
    ),
    Case(
        "texture-directory",
        "files",
        "load_texture of a directory",
        _load_texture(lambda t: _mkdir(t / "textures")),
        Raises(ValueError, r"textures.*is a directory"),
    ),
    Case(
        "texture-animated-png",
        "files",
        "load_texture of an animated PNG of 3 frames",
        _load_texture(lambda t: _animated(t / "anim.png")),
        Raises(ValueError, r"anim\.png.*holds 3 images.*single image"),
    ),
    Case(
        "texture-unknown-name",
        "messages",
        "load_texture('bricks') (neither built-in nor a file)",
        lambda t: __import__("refnpr.texture", fromlist=["x"]).load_texture("bricks"),
        Raises(ValueError, r"'bricks'.*brick.*gravel"),
    ),
    Case(
        "texture-missing-file",
        "files",
        "load_texture('missing.png') (no such file)",
        lambda t: __import__("refnpr.texture", fromlist=["x"]).load_texture(str(t / "missing.png")),
        Raises(ValueError, r"missing\.png.*brick.*(existing|no such)"),
    ),
    Case(
        "cli-halftone-screen-truncated",
        "files",
        "refnpr render --style halftone --param screen=cut.png (truncated PNG)",
        _render_in(
            lambda t: _truncated(t / "cut.png"), "--style", "halftone", "--param", "screen=cut.png"
        ),
        Exits(2, r"error: screen: cannot read .cut\.png.*truncated"),
    ),
    Case(
        "cli-threshold-texture-text",
        "files",
        "refnpr render --style threshold --param source=image --param texture=notes.png (text)",
        _render_in(
            lambda t: _text(t / "notes.png"),
            "--style",
            "threshold",
            "--param",
            "source=image",
            "--param",
            "texture=notes.png",
        ),
        Exits(2, r"error: .*notes\.png.*PNG"),
    ),
    Case(
        "scene-material-texture-text",
        "files",
        "scene file whose material texture bad.png is a text file, threshold source=image",
        _render_in(_scene_with_bad_material_texture, "--scene", "s.toml"),
        Exits(2, r"error: .*bad\.png.*PNG"),
    ),
    # --- scene files -------------------------------------------------------------------------
    Case(
        "scene-not-utf8",
        "files",
        "load_scene of a Latin-1 encoded scene file",
        _load_scene(lambda t: _bytes(t / "latin1.toml", SCENE.encode() + b"name = 'caf\xe9'\n")),
        Raises(ValueError, r"latin1\.toml.*UTF-8.*line 6"),
    ),
    Case(
        "scene-invalid-toml",
        "files",
        "load_scene of a file with a TOML syntax error on line 2",
        _load_scene(lambda t: _text(t / "broken.toml", "[camera]\neye = [0, 0,, 1]\n")),
        Raises(ValueError, r"broken\.toml.*line 2"),
    ),
    Case(
        "scene-directory",
        "files",
        "load_scene of a directory named scenes.toml",
        _load_scene(lambda t: _mkdir(t / "scenes.toml")),
        Raises((ValueError, OSError), r"scenes\.toml.*is a directory"),
    ),
    Case(
        "scene-binary-cli",
        "files",
        "refnpr render --scene garbage.toml (binary bytes)",
        _render_in(
            lambda t: _bytes(t / "garbage.toml", bytes(range(256))), "--scene", "garbage.toml"
        ),
        Exits(2, r"error: garbage\.toml.*UTF-8"),
    ),
    Case(
        "scene-material-texture-directory",
        "files",
        "scene file whose material texture is a directory tex/",
        _load_scene(
            lambda t: (
                _mkdir(t / "tex")
                and _text(t / "s.toml", SCENE + "[object.material]\ntexture = 'tex/'\n")
            )
        ),
        Raises(ValueError, r"s\.toml.*texture.*is a directory"),
    ),
    # --- golden suites and golden files ------------------------------------------------------
    Case(
        "golden-corrupt-png",
        "files",
        "check_suite where one golden PNG is a text file",
        _golden_corrupt,
        Correct(_check_corrupt),
        notes="that case fails with the path; the other case is still checked",
    ),
    Case(
        "golden-corrupt-png-cli",
        "files",
        "refnpr golden --suite S where one golden PNG is truncated",
        _golden_corrupt_cli,
        Correct(_check_corrupt_cli),
    ),
    Case(
        "golden-corrupt-npz",
        "files",
        "check_suite where a G-buffer golden .npz is not a zip file",
        _golden_npz_corrupt,
        Correct(_check_npz),
    ),
    Case(
        "golden-size-mismatch",
        "messages",
        "check_suite where the golden PNG is 20x10 and the case renders 16x12",
        _golden_size,
        Correct(_check_size),
    ),
    Case(
        "golden-outside-checkout",
        "files",
        "refnpr golden --check --only sphere-toon3 run in an empty directory (no --suite)",
        lambda t: cli("golden", "--check", "--only", "sphere-toon3", cwd=t),
        Correct(_check_packaged_suite),
        notes="the suite installed with refnpr is the default, from any directory",
    ),
    Case(
        "golden-suite-file-missing",
        "files",
        "refnpr golden --suite sub/suite.toml where sub/ does not exist",
        lambda t: cli("golden", "--suite", "sub/suite.toml", cwd=t),
        Exits(2, r"error: suite: 'sub/suite\.toml' does not exist.*leave --suite out"),
    ),
    Case(
        "kit-export-suite-file-missing",
        "files",
        "refnpr kit export KIT --suite nowhere.toml",
        lambda t: cli("kit", "export", str(t / "kit"), "--suite", "nowhere.toml", cwd=t),
        Exits(2, r"error: suite: 'nowhere\.toml' does not exist"),
    ),
    Case(
        "golden-suite-directory",
        "files",
        "refnpr golden --suite golden (a directory)",
        lambda t: _mkdir(t / "golden") and cli("golden", "--suite", "golden", cwd=t),
        Exits(2, r"error: .*'golden' is a directory.*suite\.toml"),
    ),
    Case(
        "golden-suite-not-utf8",
        "files",
        "load_suite of a Latin-1 encoded suite file",
        _non_utf8_suite,
        Raises(ValueError, r"suite\.toml.*UTF-8"),
    ),
    # --- compare -----------------------------------------------------------------------------
    Case(
        "compare-size-mismatch-cli",
        "messages",
        "refnpr compare where the candidate is 32x24 and the reference 16x12",
        _compare(_size_pair),
        Correct(_check_size_cli),
    ),
    Case(
        "compare-size-mismatch-api",
        "messages",
        "compare_dirs where the candidate is 32x24 and the reference 16x12",
        _compare_size_api,
        Correct(_check_size_api),
    ),
    Case(
        "compare-corrupt-candidate",
        "files",
        "refnpr compare where one candidate PNG is truncated",
        _compare(_corrupt_candidate),
        Correct(_check_corrupt_candidate),
        notes="reported as that image's failure; the others are still compared",
    ),
    Case(
        "compare-16bit-candidate",
        "files",
        "refnpr compare of an 8-bit gray reference with the same image as 16-bit PNG",
        _compare(_sixteen_bit),
        Correct(_passes),
    ),
    Case(
        "compare-gray-candidate",
        "files",
        "refnpr compare of an opaque RGBA reference with the same image as gray PNG",
        _compare(_grey_vs_rgba),
        Correct(_passes),
    ),
    Case(
        "compare-1bit-candidate",
        "files",
        "refnpr compare of a white reference with a white 1-bit PNG",
        _compare(_one_bit),
        Correct(_passes),
    ),
    Case(
        "compare-extra-candidate",
        "messages",
        "refnpr compare where the candidate directory has a file the reference lacks",
        _compare(_extra),
        Correct(_check_extra),
    ),
    Case(
        "compare-empty-candidate-dir",
        "messages",
        "refnpr compare with an empty candidate directory",
        _compare(_empty_candidate),
        Correct(_check_empty_candidate),
    ),
    Case(
        "compare-missing-reference-dir",
        "files",
        "refnpr compare nodir cand",
        lambda t: _mkdir(t / "cand") and cli("compare", "nodir", "cand", cwd=t),
        Exits(2, r"error: .*'nodir'.*(does not exist|not a directory)"),
    ),
    Case(
        "compare-empty-reference-dir",
        "files",
        "refnpr compare of an empty reference directory",
        lambda t: _mkdir(t / "ref") and _mkdir(t / "cand") and cli("compare", "ref", "cand", cwd=t),
        Exits(2, r"error: .*no \.png files in 'ref'"),
    ),
    Case(
        "compare-out-is-file",
        "files",
        "refnpr compare --out report, where report is a file",
        _compare_out_is_file,
        Exits(2, r"error: --out: 'report' is (a file|not a directory)"),
    ),
    Case(
        "compare-json-is-directory",
        "files",
        "refnpr compare --json metrics.json, where metrics.json is a directory",
        _compare_json_is_dir,
        Exits(2, r"error: --json: 'metrics\.json' is a directory"),
    ),
    # --- outputs -----------------------------------------------------------------------------
    Case(
        "write-sigterm",
        "files",
        "SIGTERM while write_png_atomic writes a 3000x3000 PNG (child process)",
        _interrupted(15),
        Correct(_check_interrupted),
        notes="no temporary file left; the target absent or complete",
    ),
    Case(
        "write-sigint",
        "files",
        "SIGINT while write_png_atomic writes a 3000x3000 PNG (child process)",
        _interrupted(2),
        Correct(_check_interrupted),
    ),
    Case(
        "write-from-thread",
        "files",
        "write_png_atomic called from a worker thread (no signal handlers there)",
        _write_in_thread,
        Correct(_check_thread),
    ),
    Case(
        "write-seven-channels",
        "files",
        "write_png_atomic of a (4, 4, 7) uint8 array",
        _bad_shape_write,
        Correct(_check_refused),
        notes="used to write x.png as a stack of images; now refused, no file written",
    ),
    Case(
        "output-existing-directory",
        "files",
        "refnpr render -o out.png where out.png is a directory",
        lambda t: _mkdir(t / "out.png") and _render("-o", "out.png")(t),
        Exits(2, r"error: .*'out\.png' is a directory"),
    ),
    Case(
        "output-trailing-slash",
        "files",
        "refnpr render -o renders/ (a directory name)",
        _render("-o", "renders/"),
        Exits(2, r"error: .*'renders/' .*(directory|file name)"),
    ),
    Case(
        "output-jpeg",
        "files",
        "refnpr render -o out.jpg",
        _render("-o", "out.jpg"),
        Exits(2, r"error: .*'out\.jpg'.*\.png"),
    ),
    Case(
        "output-parent-is-file",
        "files",
        "refnpr render -o notes.txt/x.png, where notes.txt is a file",
        lambda t: _text(t / "notes.txt") and _render("-o", "notes.txt/x.png")(t),
        Exits(2, r"error: .*'notes\.txt' is (a file|not a directory)"),
    ),
]

test_case = parametrize(CASES)
