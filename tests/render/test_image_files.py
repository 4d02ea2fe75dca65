"""Image files: reading with clear errors, atomic writes that restore signal handlers."""

import signal

import numpy as np
import pytest

from refnpr.image import atomic_file, read_image_file, write_png_atomic


def test_write_restores_the_signal_handlers(tmp_path):
    before = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGINT)}
    write_png_atomic(tmp_path / "a.png", np.zeros((3, 5, 4), np.uint8))
    assert {s: signal.getsignal(s) for s in before} == before


def test_a_python_handler_is_left_alone_during_the_write(tmp_path, monkeypatch):
    seen = []

    def mine(signum, frame):
        seen.append(signum)

    previous = signal.signal(signal.SIGTERM, mine)
    try:
        import imageio.v3 as iio

        real = iio.imwrite

        def spy(*args, **kwargs):
            seen.append(signal.getsignal(signal.SIGTERM))
            return real(*args, **kwargs)

        monkeypatch.setattr(iio, "imwrite", spy)
        write_png_atomic(tmp_path / "a.png", np.zeros((2, 2), np.uint8))
        assert seen == [mine] and signal.getsignal(signal.SIGTERM) is mine
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_atomic_file_removes_the_temporary_on_error(tmp_path):
    with pytest.raises(RuntimeError, match="boom"):
        with atomic_file(tmp_path / "r.json", suffix=".json") as tmp:
            tmp.write_text("{")
            raise RuntimeError("boom")
    assert list(tmp_path.iterdir()) == []
    with atomic_file(tmp_path / "r.json", suffix=".json") as tmp:
        tmp.write_text("{}")
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]


@pytest.mark.parametrize(
    ("content", "match"),
    [
        (b"", r"'.*x\.png' is an empty file; expected a PNG"),
        (b"hello", r"cannot read '.*x\.png': its contents are not an image format"),
        (b"\x89PNG\r\n\x1a\n\x00\x00", r"cannot read '.*x\.png': .*; expected a PNG"),
    ],
)
def test_read_errors_name_the_file(tmp_path, content, match):
    (tmp_path / "x.png").write_bytes(content)
    with pytest.raises(ValueError, match="texture: " + match):
        read_image_file(tmp_path / "x.png", what="texture")


def test_read_a_directory_or_nothing(tmp_path):
    with pytest.raises(ValueError, match=r"image: '.*' is a directory"):
        read_image_file(tmp_path)
    with pytest.raises(ValueError, match=r"image: file '.*nope\.png' does not exist"):
        read_image_file(tmp_path / "nope.png")


def test_write_refuses_odd_shapes(tmp_path):
    for shape in [(4, 4, 5), (4,), (0, 4, 3)]:
        with pytest.raises(ValueError, match=r"pixels: expected shape \(H, W\)"):
            write_png_atomic(tmp_path / "x.png", np.zeros(shape, np.uint8))
    assert list(tmp_path.iterdir()) == []
    write_png_atomic(tmp_path / "g.png", np.zeros((4, 4, 1), np.uint8))  # one channel: gray
