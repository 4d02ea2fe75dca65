"""Frames and golden cases on Dask distributed: byte-identical to a serial run for stateless
styles (PNG, EXR and records), stateful styles in chunks with warm-up frames, golden checks and
updates with the serial results and files, the CLI options, and the missing-extra error.

One 2-worker LocalCluster serves the whole module (the CLI tests reach it through a patched
``open_client``), so the module costs one cluster start."""

import contextlib
import json
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")

from refnpr import distributed  # noqa: E402
from refnpr.cli import main  # noqa: E402
from refnpr.golden import check_suite, update_suite  # noqa: E402
from refnpr.render import RenderContext  # noqa: E402
from refnpr.scenes import load_scene  # noqa: E402
from refnpr.sequence import render_sequence  # noqa: E402
from refnpr.styles.toon import ToonStyle  # noqa: E402

from .test_sequence import SCENE_TOML, CountingToon, WindowToon  # noqa: E402

W, H = 40, 30


@pytest.fixture(scope="module")
def client():
    with distributed.open_client(workers=2) as c:
        # the workers import this module (its test styles travel by reference)
        paths = [str(p) for p in Path(__file__).resolve().parents[1:3]]
        c.run(lambda ps: [sys.path.insert(0, p) for p in ps if p not in sys.path] and None, paths)
        yield c


@pytest.fixture
def shared_cluster(client, monkeypatch):
    """open_client yields the module's client (and leaves it open): the CLI uses the cluster."""

    @contextlib.contextmanager
    def fake_open_client(workers=None, scheduler=None):
        assert (workers, scheduler) in ((2, None), (None, "tcp://example:8786"))
        yield client

    monkeypatch.setattr(distributed, "open_client", fake_open_client)
    return client


def write_scene(tmp_path, frames=8, style_track=True):
    text = SCENE_TOML.format(frames=frames, last=frames - 1, mid=(frames - 1) / 2)
    if not style_track:
        text = text[: text.rindex("[[animation.track]]")]
    path = tmp_path / "spin.toml"
    path.write_text(text)
    return path


def files(d):
    return {p.name: p.read_bytes() for p in sorted(Path(d).iterdir())}


def test_eight_frames_on_two_workers_are_the_serial_bytes(client, tmp_path):
    path = write_scene(tmp_path)
    serial = render_sequence(path, None, W, H, 1, out_dir=tmp_path / "s", exr=True)
    calls = []
    dist = distributed.render_sequence(
        path,
        None,
        W,
        H,
        1,
        out_dir=tmp_path / "d",
        exr=True,
        client=client,
        progress=lambda *a: calls.append(a),
    )
    assert dist.rendered == serial.rendered == list(range(8)) and not dist.stateful
    want, got = files(tmp_path / "s"), files(tmp_path / "d")
    assert sorted(got) == sorted(want) and len(got) == 24  # png, exr, json per frame
    for name in want:
        assert got[name] == want[name], name
    # the workers really shaded different frames: the style track changes n along the way
    assert len({want[f"frame_{f:05d}.png"] for f in range(8)}) == 8
    assert sorted(c[2] for c in calls) == list(range(8)) and [c[0] for c in calls] == list(
        range(1, 9)
    )
    assert {c[3] for c in calls} == {"rendered"}


def test_flow_frames_are_independent_tasks_with_the_serial_bytes(client, tmp_path):
    kw = dict(frames="10:13")
    render_sequence("xtoon_flow", None, 48, 27, 1, out_dir=tmp_path / "s", **kw)
    result = distributed.render_sequence(
        "xtoon_flow", None, 48, 27, 1, out_dir=tmp_path / "d", client=client, **kw
    )
    assert not result.stateful and result.rendered == [10, 11, 12]
    assert files(tmp_path / "d") == files(tmp_path / "s")


def test_mixed_serial_and_distributed_resume(client, tmp_path):
    path = write_scene(tmp_path)
    render_sequence(path, None, W, H, 1, out_dir=tmp_path / "full")
    out = tmp_path / "mixed"
    render_sequence(path, None, W, H, 1, out_dir=out, frames="0:3")
    (out / "frame_00001.png").write_bytes(b"damaged")
    dist = distributed.render_sequence(path, None, W, H, 1, out_dir=out, client=client)
    assert dist.skipped == [0, 2] and dist.rendered == [1, 3, 4, 5, 6, 7]
    assert files(out) == files(tmp_path / "full")
    again = render_sequence(path, None, W, H, 1, out_dir=out)  # serial accepts them all
    assert again.rendered == [] and again.skipped == list(range(8))


def no_style_track_scene(tmp_path):
    return load_scene(write_scene(tmp_path, style_track=False))


def test_stateful_chunks_equal_serial_when_the_state_spans_the_warmup(client, tmp_path):
    scene = no_style_track_scene(tmp_path)
    style = WindowToon(n=3)
    serial = render_sequence(scene, style, W, H, 1, out_dir=tmp_path / "s")
    dist = distributed.render_sequence(
        scene, style, W, H, 1, out_dir=tmp_path / "d", client=client, chunk=3, warmup=2
    )
    assert serial.stateful and dist.stateful and dist.rendered == list(range(8))
    s, d = files(tmp_path / "s"), files(tmp_path / "d")
    for f in range(8):
        assert d[f"frame_{f:05d}.png"] == s[f"frame_{f:05d}.png"], f
        record = json.loads(d[f"frame_{f:05d}.json"])
        # chunks [0, 3) [3, 6) [6, 8): state from 0, 1, 4; the first chunk's records are serial's
        want_from = {0: None, 1: None, 2: None, 3: 1, 4: 1, 5: 1, 6: 4, 7: 4}[f]
        assert record.get("state_from") == want_from
        if want_from is None:
            assert d[f"frame_{f:05d}.json"] == s[f"frame_{f:05d}.json"]
        else:
            serial_record = json.loads(s[f"frame_{f:05d}.json"])
            assert {k: v for k, v in record.items() if k != "state_from"} == serial_record
    # the default chunks: the range split over the 2 workers, [0, 4) and [4, 8)
    default = distributed.render_sequence(
        scene, style, W, H, 1, out_dir=tmp_path / "default", client=client, warmup=2
    )
    assert default.rendered == list(range(8))
    t = files(tmp_path / "default")
    assert all(t[f"frame_{f:05d}.png"] == s[f"frame_{f:05d}.png"] for f in range(8))
    states = [json.loads(t[f"frame_{f:05d}.json"]).get("state_from") for f in (3, 4, 7)]
    assert states == [None, 2, 2]
    # one warm-up frame is too few for a two-frame state: the chunks' first frames differ
    short = distributed.render_sequence(
        scene, style, W, H, 1, out_dir=tmp_path / "short", client=client, chunk=3, warmup=1
    )
    assert short.rendered == list(range(8))
    t = files(tmp_path / "short")
    differ = [f for f in range(8) if t[f"frame_{f:05d}.png"] != s[f"frame_{f:05d}.png"]]
    assert differ == [3, 6]


def test_stateful_chunks_of_a_whole_history_state_start_at_the_warmup(client, tmp_path):
    """CountingToon's state counts every frame before: in chunks it counts from the chunk's
    warm-up start (documented), and the record says where its state started."""
    scene = no_style_track_scene(tmp_path)
    style = CountingToon(n=2)
    out = tmp_path / "d"
    dist = distributed.render_sequence(
        scene, style, W, H, 1, out_dir=out, frames="2:8", client=client, chunk=3, warmup=1
    )
    assert dist.rendered == list(range(2, 8))
    import imageio.v3 as iio

    for f in range(2, 8):  # chunks [2, 5) from 1, [5, 8) from 4
        start = 1 if f < 5 else 4
        img, _ = RenderContext(scene.at(f), ToonStyle(n=2), W, H, 1).render_frame(
            scene.at(f), style, f - start
        )
        np.testing.assert_array_equal(iio.imread(out / f"frame_{f:05d}.png"), img.to_srgb8())
        assert json.loads((out / f"frame_{f:05d}.json").read_text())["state_from"] == start
    # a chunk whose frames are all done is not submitted; a damaged one is rendered alone
    (out / "frame_00006.json").unlink()
    again = distributed.render_sequence(
        scene, style, W, H, 1, out_dir=out, frames="2:8", client=client, chunk=3, warmup=1
    )
    assert again.rendered == [6] and again.skipped == [2, 3, 4, 5, 7]


SUITE = """
[defaults]
width = 32
height = 24
[[case]]
name = "a-toon"
scene = "sphere"
style = { name = "toon", n = 3 }
[[case]]
name = "b-changed"
scene = "sphere"
style = "toon"
[[case]]
name = "c-missing"
scene = "sphere"
[[case]]
name = "d-broken"
scene = "sphere"
style = { name = "toon", n = "three" }
[[case]]
name = "e-gbuffer"
kind = "gbuffer"
scene = "sphere"
"""


def make_suite(tmp_path, name="g"):
    d = tmp_path / name
    d.mkdir()
    (d / "suite.toml").write_text(SUITE)
    return d / "suite.toml"


def test_golden_check_and_update_on_two_workers_match_serial(client, tmp_path):
    suite = make_suite(tmp_path)
    update_suite(suite, only=["a-toon", "b-changed", "e-gbuffer"], log=lambda line: None)
    import imageio.v3 as iio

    b = iio.imread(suite.parent / "b-changed.png")
    b[8:16, 8:16, :3] = 255 - b[8:16, 8:16, :3]  # a golden file that no longer matches
    iio.imwrite(suite.parent / "b-changed.png", b, extension=".png")
    (suite.parent / "d-broken.png").write_bytes((suite.parent / "a-toon.png").read_bytes())
    serial = check_suite(suite, failure_dir=tmp_path / "f1")
    dist = distributed.check_suite(suite, failure_dir=tmp_path / "f2", client=client)

    def rows(results, root):
        return [(r.name, r.passed, r.message.replace(str(root), "FAIL")) for r in results]

    assert rows(dist, tmp_path / "f2") == rows(serial, tmp_path / "f1")
    assert [r.passed for r in serial] == [True, False, False, False, True]
    assert "render failed" in serial[3].message and "missing golden" in serial[2].message
    assert files(tmp_path / "f2" / "b-changed") == files(tmp_path / "f1" / "b-changed")
    assert sorted(p.name for p in (tmp_path / "f1").iterdir()) == ["b-changed"]
    # update: the same golden files (PNG bytes; npz channels, the zip holds a time stamp)
    other = make_suite(tmp_path, "g2")
    only = ["a-toon", "b-changed", "e-gbuffer"]
    update_suite(suite, only=only, log=lambda line: None)
    logged = []
    written = distributed.update_suite(other, only=only, log=logged.append, client=client)
    assert [p.name for p in written] == ["a-toon.png", "b-changed.png", "e-gbuffer.npz"]
    assert len(logged) == 3
    for name in ("a-toon.png", "b-changed.png"):
        assert (other.parent / name).read_bytes() == (suite.parent / name).read_bytes()
    with np.load(other.parent / "e-gbuffer.npz") as x, np.load(suite.parent / "e-gbuffer.npz") as y:
        assert sorted(x.files) == sorted(y.files)
        for k in x.files:
            np.testing.assert_array_equal(x[k], y[k])
    # a case that cannot render raises its own error, as serially
    with pytest.raises((TypeError, ValueError)) as serial_err:
        update_suite(other, only=["d-broken"], log=lambda line: None)
    with pytest.raises((TypeError, ValueError)) as dist_err:
        distributed.update_suite(other, only=["d-broken"], client=client, log=lambda line: None)
    assert type(dist_err.value) is type(serial_err.value)
    assert str(dist_err.value) == str(serial_err.value)


def test_cli_animate_and_golden_with_workers(shared_cluster, tmp_path, capsys):
    path = write_scene(tmp_path, frames=4)
    common = ["animate", str(path), "--size", f"{W}x{H}", "--spp", "1", "-q"]
    assert main([*common, "-o", str(tmp_path / "s")]) == 0
    assert main([*common, "-o", str(tmp_path / "d"), "--workers", "2"]) == 0
    assert files(tmp_path / "d") == files(tmp_path / "s")
    assert main([*common, "-o", str(tmp_path / "e"), "--scheduler", "tcp://example:8786"]) == 0
    assert files(tmp_path / "e") == files(tmp_path / "s")
    capsys.readouterr()
    assert main([*common, "-o", str(tmp_path / "x"), "--chunk", "2"]) == 2
    assert "--chunk / --warmup" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # argparse: not both
        main([*common, "-o", str(tmp_path / "x"), "--workers", "2", "--scheduler", "tcp://a:1"])
    suite = make_suite(tmp_path)
    assert main(["golden", "--update", "--suite", str(suite), "--only", "a-toon"]) == 0
    capsys.readouterr()
    args = ["golden", "--check", "--suite", str(suite), "--only", "a-toon", "c-missing"]
    assert main(args) == 1
    serial_out = capsys.readouterr().out
    assert main([*args, "--workers", "2"]) == 1
    assert capsys.readouterr().out == serial_out
    assert "1 passed, 1 failed" in serial_out


def test_numba_threads_per_worker(client):
    import numba

    got = client.run(numba.get_num_threads)
    assert sorted(got.values()) == [distributed.worker_threads(2)] * 2
    assert distributed.worker_threads(2, cores=16) == 8
    assert distributed.worker_threads(3, cores=2) == 1


def test_an_interrupted_run_cancels_its_futures(client, tmp_path):
    path = write_scene(tmp_path)

    def stop(done, total, frame, status):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        distributed.render_sequence(
            path, None, W, H, 1, out_dir=tmp_path / "d", client=client, progress=stop
        )
    assert len(list((tmp_path / "d").glob("*.png"))) == 1  # the frame that arrived
    # the client still works, and a rerun completes the directory
    rest = distributed.render_sequence(path, None, W, H, 1, out_dir=tmp_path / "d", client=client)
    assert len(rest.rendered) == 7


def test_open_client_closes_its_cluster_on_interrupt(monkeypatch):
    import distributed as dd

    made = []
    real = dd.LocalCluster

    def recording(*a, **k):
        made.append(real(*a, **k))
        return made[-1]

    monkeypatch.setattr(dd, "LocalCluster", recording)
    with pytest.raises(KeyboardInterrupt), distributed.open_client(workers=1) as c:
        assert len(c.scheduler_info()["workers"]) == 1
        raise KeyboardInterrupt
    assert made and made[0].status.name == "closed"


def test_argument_errors():
    with pytest.raises(ValueError, match="workers / scheduler: give one, not both"):
        with distributed.open_client(workers=2, scheduler="tcp://a:1"):
            pass
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="workers: expected a whole number >= 1"):
            with distributed.open_client(workers=bad):
                pass
    with pytest.raises(ValueError, match="warmup: expected a whole number >= 0"):
        distributed.render_sequence("sphere", out_dir="unused", warmup=-1)
    with pytest.raises(ValueError, match="chunk: expected a whole number >= 1"):
        distributed.render_sequence("sphere", out_dir="unused", chunk=0)


def test_missing_dask_names_the_extra(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)  # `import distributed` fails
    with pytest.raises(ValueError, match=r"workers: needs Dask .*refnpr\[distributed\]"):
        with distributed.open_client(workers=2):
            pass
    with pytest.raises(ValueError, match=r"scheduler: needs Dask .*refnpr\[distributed\]"):
        distributed.render_sequence("sphere", out_dir=tmp_path / "x", scheduler="tcp://a:1")
    path = write_scene(tmp_path, frames=2)
    code = main(["animate", str(path), "-o", str(tmp_path / "d"), "--workers", "2", "-q"])
    assert code == 2
    err = capsys.readouterr().err
    assert "refnpr animate: error: workers: needs Dask" in err and "refnpr[distributed]" in err
    assert not (tmp_path / "d").exists()  # failed before writing anything
    suite = make_suite(tmp_path)
    assert main(["golden", "--check", "--suite", str(suite), "--workers", "2"]) == 2
    assert "refnpr[distributed]" in capsys.readouterr().err


def test_the_contour_layer_is_as_stateful_as_its_base_style():
    """A contoured style passes the sequence protocol through: its frames are independent tasks
    exactly when its base style's are (halftone_light_orbit is engraving + contours)."""
    from refnpr.sequence import is_stateful
    from refnpr.styles import get_style, style_from_spec

    assert not is_stateful(style_from_spec(load_scene("halftone_light_orbit").style))
    assert not is_stateful(get_style("contoured", base="toon"))
    assert is_stateful(get_style("contoured", base=CountingToon(n=2)))
    assert is_stateful(get_style("contoured", base=WindowToon(n=2)))
