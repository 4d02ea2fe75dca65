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


def _rgba_with_a_transparent_pixel():
    rgba = np.zeros((4, 4, 4), np.uint8)
    rgba[..., 0], rgba[..., 3] = 200, 255
    rgba[0, 0] = (10, 20, 30, 0)
    return rgba


@pytest.mark.parametrize("kind", ["palette", "rgb-colour-key", "grey-colour-key"])
def test_png_transparency_of_a_trns_chunk_is_read(tmp_path, kind):
    """A palette PNG (as pngquant or oxipng write) or an RGB or grey PNG with a colour key
    keeps its transparency in a tRNS chunk, which imageio dropped: the transparent pixel read
    as opaque."""
    from PIL import Image as PILImage

    rgba = _rgba_with_a_transparent_pixel()
    path = tmp_path / f"{kind}.png"
    if kind == "palette":
        PILImage.fromarray(rgba).quantize().save(path)
        want = rgba
    elif kind == "rgb-colour-key":
        PILImage.fromarray(rgba[..., :3]).save(path, transparency=(10, 20, 30))
        want = rgba
    else:
        PILImage.fromarray(rgba[..., 0]).save(path, transparency=10)
        want = np.stack([rgba[..., 0], np.where(rgba[..., 0] == 10, 0, 255)], axis=-1)
    np.testing.assert_array_equal(read_image_file(path), want)


def test_an_image_too_large_to_decode_is_refused_from_its_header(tmp_path, monkeypatch):
    """A TIFF declares any size and imageio decodes it whole: an 875 KB file of 30000 x 30000
    zeros allocated gigabytes. The size is checked from the header first."""
    import imageio.v3 as iio

    import refnpr.image as image

    path = tmp_path / "big.tif"
    iio.imwrite(path, np.zeros((40, 30), np.uint8))
    monkeypatch.setattr(image, "MAX_DECODED_VALUES", 1000)
    with pytest.raises(ValueError, match=r"big\.tif': the image is too large: 40 x 30 values"):
        read_image_file(path, what="texture")
    monkeypatch.setattr(image, "MAX_DECODED_VALUES", 1200)
    assert read_image_file(path).shape == (40, 30)


@pytest.mark.parametrize("suffix", [".png", ".gif", ".webp", ".tif"])
@pytest.mark.parametrize("channels", [1, 3])
def test_a_file_of_several_images_is_refused_and_a_one_frame_file_is_its_image(
    tmp_path, suffix, channels
):
    """An animated PNG, GIF or WebP, or a multi-page TIFF, decodes to a stack of images, whose
    frames read as rows (a grey TIFF's three 8 x 8 pages made a 3 x 8 texture of 8 channels).
    It is refused, naming the count; a file of one frame is that frame (a one-frame GIF
    decoded as a (1, rows, cols, 3) stack)."""
    from PIL import Image

    rng = np.random.default_rng(1)
    shape = (8, 6, 3) if channels == 3 else (8, 6)
    frames = [rng.integers(0, 256, shape).astype(np.uint8) for _ in range(3)]
    if suffix == ".gif":  # GIF stores a palette: give each frame few colours
        frames = [(f // 128 * 255).astype(np.uint8) for f in frames]
    images = [Image.fromarray(f) for f in frames]
    several, one = tmp_path / f"several{suffix}", tmp_path / f"one{suffix}"
    extra = {"lossless": True} if suffix == ".webp" else {}
    images[0].save(several, save_all=True, append_images=images[1:], **extra)
    images[0].save(one, **extra)
    with pytest.raises(ValueError, match=r"several\.\w+': the file holds 3 images"):
        read_image_file(several, what="texture")
    got = read_image_file(one)
    want = frames[0] if got.ndim == len(shape) else np.repeat(frames[0][..., None], 3, axis=2)
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("suffix", [".png", ".gif", ".webp", ".tif"])
def test_several_images_are_refused_before_any_is_decoded(tmp_path, suffix, monkeypatch):
    """The count comes from the header (a TIFF's from its series' pages): a file of many
    pages, each under the size cap, is not decoded whole first."""
    import imageio.v3 as iio
    from PIL import Image

    images = [Image.fromarray(np.full((4, 5, 3), 60 * i, np.uint8)) for i in range(4)]
    path = tmp_path / f"several{suffix}"
    images[0].save(path, save_all=True, append_images=images[1:])

    def no_decode(*args, **kwargs):
        raise AssertionError("decoded before the count was checked")

    monkeypatch.setattr(iio, "imread", no_decode)
    with pytest.raises(ValueError, match="the file holds 4 images"):
        read_image_file(path)


def test_a_camera_jpeg_with_a_large_thumbnail_is_one_image(tmp_path):
    """Many cameras write a JPEG whose MPF header lists a second, smaller image (a "large
    thumbnail"); Pillow opens it as MPO with two frames. It is one photograph: read as the
    first image, as imageio reads it, not refused as several."""
    from PIL import Image

    rng = np.random.default_rng(2)
    main = Image.fromarray(rng.integers(0, 256, (16, 24, 3)).astype(np.uint8))
    path = tmp_path / "camera.jpg"
    main.save(path, format="MPO", save_all=True, append_images=[main.resize((6, 4))])
    assert Image.open(path).n_frames == 2
    assert read_image_file(path).shape == (16, 24, 3)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32])
def test_a_planar_tiff_reads_like_an_interleaved_one(tmp_path, dtype):
    """A TIFF may store colour planar (all reds, then greens, then blues); imageio then gives
    (3, rows, cols), which read as 3 rows of cols channels. It reads as (rows, cols, 3)."""
    import tifffile

    rgb = (np.random.default_rng(3).random((5, 7, 3)) * 200).astype(dtype)
    tifffile.imwrite(tmp_path / "planar.tif", np.moveaxis(rgb, -1, 0), photometric="rgb",
                     planarconfig="separate")  # fmt: skip
    tifffile.imwrite(tmp_path / "chunky.tif", rgb, photometric="rgb")
    np.testing.assert_array_equal(read_image_file(tmp_path / "planar.tif"), rgb)
    np.testing.assert_array_equal(read_image_file(tmp_path / "chunky.tif"), rgb)


@pytest.mark.parametrize("dtype", [np.uint8, bool, np.int32])
def test_an_image_holds_float_linear_rgba(dtype):
    from refnpr.image import Image

    with pytest.raises(TypeError, match=r"rgba: expected float linear RGBA in \[0, 1\], got dtype"):
        Image(np.full((1, 1, 4), 1, dtype=dtype))


def test_a_16_bit_grey_png_with_a_colour_key_keeps_its_16_bit_values(tmp_path):
    """Pillow cannot apply the colour key of a 16-bit grey PNG (it would clip the values to 8
    bits): such a file decodes as before, at 16 bits."""
    from PIL import Image as PILImage

    values = (np.arange(16, dtype=np.uint16) * 4000).reshape(4, 4)
    path = tmp_path / "g16.png"
    PILImage.fromarray(values).save(path, transparency=0)
    got = read_image_file(path)
    assert got.dtype == np.uint16
    np.testing.assert_array_equal(got, values)
