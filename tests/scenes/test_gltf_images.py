"""glTF embedded images (a buffer view with a mimeType, a data: URI) as material textures:
header checks before decoding, decoding equal to the same image as a file, renders and kit
export of a .glb that carries its texture, and malformed images with their messages.

The files are written here by hand: a textured quad, its PNG encoded with imageio.
"""

from __future__ import annotations

import base64
import dataclasses
import json
import pickle
import struct
import warnings
import zlib

import imageio.v3 as iio
import numpy as np
import pytest

from refnpr.scenes import load_scene
from refnpr.scenes.gltf import GltfError, GltfWarning, load_gltf
from refnpr.texture import EmbeddedImage, load_texture
from refnpr.texture.embedded import MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE, probe_image

from ._gltf_write import write_gltf


def stripes(h=16, w=16, channels=3) -> np.ndarray:
    """A seeded random (h, w, channels) uint8 image (no two rows alike)."""
    rng = np.random.default_rng(7)
    return rng.integers(0, 256, size=(h, w, channels), dtype=np.uint8)


def png_bytes(pixels: np.ndarray) -> bytes:
    return bytes(iio.imwrite("<bytes>", pixels, extension=".png"))


def png_header(width: int, height: int) -> bytes:
    """A PNG signature and IHDR chunk only (no image data): what a hostile file may declare."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    crc = zlib.crc32(b"IHDR" + ihdr)
    return b"\x89PNG\r\n\x1a\n" + struct.pack(">I", 13) + b"IHDR" + ihdr + struct.pack(">I", crc)


def jpeg_header(width: int, height: int) -> bytes:
    """SOI, an APP0 segment and a baseline SOF0 frame header of the given size."""
    app0 = b"\xff\xe0" + struct.pack(">H", 16) + b"JFIF\0\x01\x01\0\0\x01\0\x01\0\0"
    sof = b"\xff\xc0" + struct.pack(">HBHHB", 11, 8, height, width, 1) + b"\x01\x11\0"
    return b"\xff\xd8" + app0 + sof


def textured_quad(image: dict, blob_image: bytes | None, form="glb", path=None):
    """A unit quad facing +z, uv over [0, 2]^2 (the texture repeats twice), a camera on +z and
    a light; its material's baseColorTexture is ``image`` (an images[] entry; ``bufferView``
    "IMG" is replaced by the view holding ``blob_image``). Written as .glb or as .gltf with a
    data: URI buffer; returns the path."""
    pos = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], "<f4")
    uv = np.array([[0, 2], [2, 2], [2, 0], [0, 0]], "<f4")
    idx = np.array([0, 1, 2, 0, 2, 3], "<u2")
    blob = bytearray()
    views = []
    for data in (pos.tobytes(), uv.tobytes(), idx.tobytes(), blob_image):
        if data is None:
            continue
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob += data + b"\0" * (-len(data) % 4)
    image = dict(image)
    if image.get("bufferView") == "IMG":
        image["bufferView"] = 3
    doc = {
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"name": "quad", "mesh": 0},
            {"name": "cam", "camera": 0, "translation": [0, 0, 2.2]},
            {"name": "sun", "extensions": {"KHR_lights_punctual": {"light": 0}}},
        ],
        "meshes": [
            {
                "primitives": [
                    {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}
                ]
            }
        ],
        "materials": [
            {
                "pbrMetallicRoughness": {
                    "baseColorFactor": [0.5, 0.5, 0.5, 1.0],  # mid tones: every threshold shows
                    "baseColorTexture": {"index": 0},
                }
            }
        ],
        "textures": [{"source": 0}],
        "images": [image],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.1}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional"}]}},
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "bufferViews": views,
    }
    return write_gltf(doc, bytes(blob), path, "glb" if form == "glb" else "data")


def quiet(fn, *a, **k):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GltfWarning)
        return fn(*a, **k)


# -- the value type ----------------------------------------------------------------------------


@pytest.mark.parametrize("shape", [(5, 9), (7, 3, 3), (4, 6, 4)])
def test_probe_reads_the_size_the_decoder_gives(shape):
    pixels = np.arange(np.prod(shape)).reshape(shape).astype(np.uint8)
    for ext, mime in ((".png", "image/png"), (".jpg", "image/jpeg")):
        if ext == ".jpg" and len(shape) == 3 and shape[2] == 4:
            continue  # JPEG has no alpha
        data = bytes(iio.imwrite("<bytes>", pixels, extension=ext))
        assert probe_image(data) == (mime, shape[1], shape[0])
        image = EmbeddedImage("x.glb#images[0]", data)
        assert image.decode().shape[:2] == shape[:2]
        assert (image.width, image.height, image.mime_type) == (shape[1], shape[0], mime)


def test_embedded_image_is_a_string_named_by_content():
    a_bytes, b_bytes = png_bytes(stripes()), png_bytes(stripes()[::-1])
    a = EmbeddedImage("m.glb#images[0]", a_bytes, "image/png")
    import hashlib

    digest = hashlib.sha256(a_bytes).hexdigest()
    assert isinstance(a, str) and str(a) == f"m.glb#images[0]@sha256:{digest}"
    assert a.sha256 == digest and a.data == a_bytes
    assert a == EmbeddedImage("m.glb#images[0]", bytearray(a_bytes))
    assert a != EmbeddedImage("m.glb#images[0]", b_bytes)  # same name, other content
    assert len({a, EmbeddedImage("m.glb#images[0]", a_bytes)}) == 1
    back = pickle.loads(pickle.dumps(a))
    assert type(back) is EmbeddedImage and back.data == a_bytes and back == a
    assert "image/png" in repr(a) and "16x16" in repr(a)
    with pytest.raises(AttributeError, match="immutable"):
        a.name = "other"
    with pytest.raises(TypeError, match="expected the encoded image as bytes"):
        EmbeddedImage("n", "not bytes")


@pytest.mark.parametrize(
    "data, mime, message",
    [
        (png_header(MAX_IMAGE_SIDE + 1, 8), None, rf"{MAX_IMAGE_SIDE + 1} x 8 pixels, more than"),
        (png_header(9000, 9000), "image/png", "9000 x 9000 pixels, more than"),
        (jpeg_header(64, MAX_IMAGE_SIDE + 1), None, rf"64 x {MAX_IMAGE_SIDE + 1} pixels"),
        (png_header(0, 4), None, "the PNG header gives a size of 0x4"),
        (jpeg_header(16, 0), None, "height 0"),
        (b"GIF89a" + bytes(20), None, "neither a PNG nor a JPEG"),
        (png_header(4, 4), "image/jpeg", "declared 'image/jpeg' but the data is a PNG"),
        (png_header(4, 4), "image/gif", "mimeType 'image/gif' is not an image type"),
        (png_header(4, 4)[:20], None, r"no IHDR chunk first \(truncated"),
        (b"\xff\xd8\xff\xda\0\x02", None, "no frame header"),
        (jpeg_header(4, 4)[:22], None, "truncated"),
    ],
)
def test_header_refused_before_decoding(data, mime, message):
    """Sizes come from the header alone: the data here has no pixels to decode."""
    assert 9000 * 9000 > MAX_IMAGE_PIXELS
    with pytest.raises(ValueError, match=r"^bad\.png: .*" + message):
        EmbeddedImage("bad.png", data, mime)


def test_header_that_lies_is_refused_when_decoded():
    real = png_bytes(stripes(8, 8))
    image = EmbeddedImage("lie", png_header(4, 4) + real[33:])  # the IHDR of a 4x4 image
    with pytest.raises(ValueError, match=r"^screen: cannot decode 'lie@sha256:"):
        load_texture(image, param="screen")


def test_decoded_size_must_match_the_header(monkeypatch):
    """A decoder that returns another size than the header (which the limits were checked on)
    is refused rather than trusted."""
    image = EmbeddedImage("m.glb#images[0]", png_bytes(stripes(8, 8)))
    monkeypatch.setattr(iio, "imread", lambda *a, **k: np.zeros((9000, 8), np.uint8))
    with pytest.raises(ValueError, match=r"decodes to 8 x 9000 pixels but its header gives 8 x 8"):
        load_texture(image)


@pytest.mark.parametrize("channels", [1, 3, 4])
@pytest.mark.parametrize("tiling", [None, "periodic"])
def test_load_texture_equals_the_same_file(tmp_path, channels, tiling):
    pixels = stripes(12, 20, channels)
    pixels = pixels[..., 0] if channels == 1 else pixels
    file = tmp_path / "t.png"
    file.write_bytes(png_bytes(pixels))
    image = EmbeddedImage("m.glb#images[0]", file.read_bytes())
    for gray in (True, False):
        got = load_texture(image, gray=gray, tiling=tiling)
        want = load_texture(str(file), gray=gray, tiling=tiling)
        assert got.dtype == np.float32
        np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(load_texture(image, gray=False), pixels / np.float32(255))


# -- glTF files --------------------------------------------------------------------------------

IN_VIEW = {"bufferView": "IMG", "mimeType": "image/png"}


def data_uri(data: bytes, media="image/png") -> dict:
    return {"uri": f"data:{media};base64," + base64.b64encode(data).decode()}


@pytest.mark.parametrize("form", ["glb", "data-uri"])
def test_embedded_image_becomes_the_material_texture(tmp_path, form):
    data = png_bytes(stripes())
    if form == "glb":
        path = textured_quad(IN_VIEW, data, "glb", tmp_path / "m.glb")
    else:
        path = textured_quad(data_uri(data), None, "gltf", tmp_path / "m.gltf")
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        scene = load_gltf(path)
    assert not [w for w in record if "ignored" in str(w.message)]
    tex = scene.objects[0].material.texture
    assert isinstance(tex, EmbeddedImage)
    assert tex.data == data and tex.name == f"{path.name}#images[0]"
    np.testing.assert_array_equal(load_texture(tex, gray=False), stripes() / np.float32(255))


def test_image_shared_by_materials_is_read_once(tmp_path):
    path = textured_quad(IN_VIEW, png_bytes(stripes()), "glb", tmp_path / "m.glb")
    raw = path.read_bytes()
    (n,) = struct.unpack_from("<I", raw, 12)
    doc = json.loads(raw[20 : 20 + n])
    doc["materials"].append(dict(doc["materials"][0], name="second"))
    doc["meshes"][0]["primitives"].append(dict(doc["meshes"][0]["primitives"][0], material=1))
    _rewrite_glb(path, doc)
    a, b = quiet(load_gltf, path).objects
    assert a.material.texture is b.material.texture


def _rewrite_glb(path, doc):
    raw = path.read_bytes()
    (n,) = struct.unpack_from("<I", raw, 12)
    rest = raw[20 + n :]
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    out = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(js) + len(rest))
    path.write_bytes(out + struct.pack("<I4s", len(js), b"JSON") + js + rest)


def _edit(**image):
    return lambda doc: doc["images"][0].update(image) or doc


def _drop(key):
    return lambda doc: doc["images"][0].pop(key) and doc


MALFORMED_IMAGES = [
    ("no mimeType", _drop("mimeType"), r"images\[0\]\.mimeType: missing"),
    ("gif", _edit(mimeType="image/gif"), r"images\[0\]\.bufferView: mimeType 'image/gif'"),
    ("wrong type", _edit(mimeType="image/jpeg"), r"images\[0\]\.bufferView: declared 'image/jpeg'"),
    (
        "view index",
        _edit(bufferView=9),
        r"images\[0\]\.bufferView: 9 is not an index of bufferViews",
    ),
    (
        "view beyond buffer",
        lambda doc: doc["bufferViews"][3].update(byteLength=10**6) or doc,
        r"bufferViews\[3\]: byteOffset \d+ \+ byteLength 1000000",
    ),
    (
        "stride",
        lambda doc: doc["bufferViews"][3].update(byteStride=4) or doc,
        r"images\[0\]\.bufferView: bufferViews\[3\] has a byteStride \(4\); image data",
    ),
    ("both", _edit(uri="t.png"), r"images\[0\]: has both `uri` and `bufferView`"),
    (
        "neither",
        lambda doc: doc["images"][0].clear() or doc,
        r"images\[0\]: has neither `uri` nor `bufferView`",
    ),
    (
        "not an image",
        lambda doc: doc["bufferViews"][3].update(byteOffset=0) or doc,
        r"images\[0\]\.bufferView: the data is neither a PNG nor a JPEG",
    ),
    (
        "data uri type",
        lambda doc: (
            doc["images"].__setitem__(
                0, {"mimeType": "image/jpeg", **data_uri(png_bytes(stripes()))}
            )
            or doc
        ),
        r"images\[0\]\.uri: a data: URI of type 'image/png', but mimeType is 'image/jpeg'",
    ),
    (
        "data uri base64",
        lambda doc: doc["images"].__setitem__(0, {"uri": "data:image/png;base64,@@@"}) or doc,
        r"images\[0\]\.uri: invalid base64",
    ),
    (
        "huge header",
        lambda doc: doc["images"].__setitem__(0, data_uri(png_header(20000, 20000))) or doc,
        r"images\[0\]\.uri: the image header gives 20000 x 20000 pixels, more than",
    ),
]


@pytest.mark.parametrize(
    "label, edit, message", MALFORMED_IMAGES, ids=[m[0] for m in MALFORMED_IMAGES]
)
def test_malformed_images(tmp_path, label, edit, message):
    path = textured_quad(IN_VIEW, png_bytes(stripes()), "glb", tmp_path / "bad.glb")
    raw = path.read_bytes()
    (n,) = struct.unpack_from("<I", raw, 12)
    _rewrite_glb(path, edit(json.loads(raw[20 : 20 + n])))
    with pytest.raises(GltfError, match=r"bad\.glb: " + message):
        quiet(load_gltf, path)


def test_toml_scene_keeps_the_embedded_texture(tmp_path):
    data = png_bytes(stripes())
    textured_quad(IN_VIEW, data, "glb", tmp_path / "model.glb")
    (tmp_path / "s.toml").write_text('gltf = "model.glb"\n[materials."*"]\nspecular = 0.0\n')
    obj = quiet(load_scene, tmp_path / "s.toml").objects[0]
    assert isinstance(obj.material.texture, EmbeddedImage) and obj.material.texture.data == data
    assert obj.material.specular == (0.0, 0.0, 0.0)


# -- renders and the kit ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "style",
    [
        {"name": "threshold", "source": "image", "n": 2},
        {"name": "halftone", "screen": "material"},
    ],
    ids=["threshold", "halftone"],
)
def test_render_samples_the_embedded_image(tmp_path, style):
    """The .glb's texture is what the style samples: the render equals the one with the same
    image as a file (and differs from one with another image)."""
    from refnpr.render import render

    pixels = stripes(32, 32, 1)[..., 0]
    scene = quiet(load_gltf, textured_quad(IN_VIEW, png_bytes(pixels), "glb", tmp_path / "m.glb"))
    file, other = tmp_path / "t.png", tmp_path / "o.png"
    file.write_bytes(png_bytes(pixels))
    other.write_bytes(png_bytes(pixels.T.copy()))

    def with_texture(texture):
        objs = [
            dataclasses.replace(o, material=dataclasses.replace(o.material, texture=texture))
            for o in scene.objects
        ]
        return dataclasses.replace(scene, objects=tuple(objs))

    embedded = render(scene, style, 32, 32).rgba
    np.testing.assert_array_equal(embedded, render(with_texture(str(file)), style, 32, 32).rgba)
    assert np.abs(embedded - render(with_texture(str(other)), style, 32, 32).rgba).max() > 0.1


def test_kit_export_of_a_glb_with_an_embedded_texture(tmp_path):
    from refnpr.cli import main

    path = textured_quad(IN_VIEW, png_bytes(stripes(32, 32, 1)[..., 0]), "glb", tmp_path / "m.glb")
    kit = tmp_path / "kit"
    argv = ["kit", "export", str(kit), "--scene", str(path), "--style", "threshold"]
    argv += ["--param", 'source="image"', "--size", "32x24", "-q"]
    assert main(argv) == 0
    (case,) = [p for p in kit.rglob("case.json")]
    doc = json.loads(case.read_text())
    texture = quiet(load_gltf, path).objects[0].material.texture
    (obj,) = doc["objects"]
    assert obj["material"]["texture"] == str(texture)
    assert doc["style"]["params"]["object_textures"] == ["threshold_0"]


def test_base_colour_texture_is_the_colour_map_and_uv_less_primitives_beside_it(tmp_path):
    path = textured_quad(IN_VIEW, png_bytes(stripes()), "glb", tmp_path / "m.glb")
    scene = quiet(load_gltf, path)
    mat = scene.objects[0].material
    assert mat.color_texture is mat.texture and isinstance(mat.color_texture, EmbeddedImage)
    raw = path.read_bytes()
    (n,) = struct.unpack_from("<I", raw, 12)
    doc = json.loads(raw[20 : 20 + n])
    # a second primitive without TEXCOORD_0 and without a material: uv (0, 0), never sampled
    doc["meshes"][0]["primitives"].append({"attributes": {"POSITION": 0}, "indices": 2})
    _rewrite_glb(path, doc)
    a, b = quiet(load_gltf, path).objects
    assert b.material.color_texture is None
    assert b.mesh.uv.shape == (len(b.mesh.positions), 2) and not b.mesh.uv.any()
    # ... but one whose material has the map needs its uv
    doc["meshes"][0]["primitives"][1]["material"] = 0
    _rewrite_glb(path, doc)
    with pytest.raises(ValueError, match=r"meshes\[0\]\.primitives\[1\]\.attributes: the "):
        quiet(load_gltf, path)


def test_image_files_beside_the_gltf_are_sized_from_their_header(tmp_path):
    (tmp_path / "big.png").write_bytes(png_header(9000, 9000))  # no pixels to decode
    path = textured_quad({"uri": "big.png"}, None, "gltf", tmp_path / "m.gltf")
    with pytest.raises(ValueError, match=r"images\[0\]\.uri: 'big\.png': .*9000 x 9000 pixels"):
        quiet(load_gltf, path)
    (tmp_path / "t.bmp").write_bytes(b"BM" + bytes(64))
    path = textured_quad({"uri": "t.bmp"}, None, "gltf", tmp_path / "n.gltf")
    with pytest.raises(ValueError, match=r"'t\.bmp' is not a PNG or JPEG image"):
        quiet(load_gltf, path)
    (tmp_path / "ok.png").write_bytes(png_bytes(stripes()))
    path = textured_quad({"uri": "ok.png"}, None, "gltf", tmp_path / "o.gltf")
    assert quiet(load_gltf, path).objects[0].material.color_texture == str(tmp_path / "ok.png")


def test_sampler_modes_and_texture_transforms_are_named_as_ignored(tmp_path):
    path = textured_quad(IN_VIEW, png_bytes(stripes()), "glb", tmp_path / "m.glb")
    raw = path.read_bytes()
    (n,) = struct.unpack_from("<I", raw, 12)
    doc = json.loads(raw[20 : 20 + n])
    doc["samplers"] = [{"wrapS": 33071, "magFilter": 9728}]  # clamp, nearest
    doc["textures"][0]["sampler"] = 0
    info = doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]
    info["extensions"] = {"KHR_texture_transform": {"scale": [2, 2]}}
    _rewrite_glb(path, doc)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        load_gltf(path)
    text = " ".join(str(w.message) for w in record)
    assert "texture sampler wrap and filter modes" in text and "KHR_texture_transform" in text
