"""Scene files (TOML): reading built-in and user scenes.

A scene file has a few top-level keys and tables (unknown keys are errors)::

    name = "teapot"                        # optional; default: the file name
    description = "Newell's teapot ..."    # optional; one line, shown by list_scenes()
    ambient = [1.0, 1.0, 1.0]              # optional; l_a of Veryovka eq. 1 (or one number)
    background = [1.0, 1.0, 1.0, 1.0]      # optional; RGBA in [0, 1] (RGB means alpha 1)

    [camera]                               # required
    eye = [6.0, 4.5, 8.0]                  # required
    target = [0.0, 1.2, 0.0]               # required
    up = [0.0, 1.0, 0.0]                   # optional (default +y)
    fov_y = 35.0                           # optional, degrees (default 45)
    near = 0.1                             # optional (default 0.1)
    far = 100.0                            # optional (default 100)

    [style]                                # optional; passed to the renderer as a dict
    name = "toon"
    n = 3

    [[light]]                              # zero or more; none -> one default directional light
    kind = "directional"                   # "directional" (default) or "point"
    direction = [1.0, 1.0, 0.5]            # towards the light (directional)
    # position = [4.0, 6.0, 3.0]           # point lights only
    color = [1.0, 1.0, 1.0]                # optional (or one number)

    [[object]]                             # one or more
    name = "teapot"                        # optional; default: the mesh's name
    mesh = "teapot"                        # a built-in mesh (see MESH_BUILDERS) ...
    level = 10                             # ... and its builder's parameters
    # path = "bunny.obj"                   # ... or a mesh file, relative to this file
    # uv_projection = "box"                # optional: planar | box | spherical | cylindrical
    transform = { translate = [0, 0, 0], rotate_deg = [0, 30, 0], scale = 1.0 }
    # transform = { matrix = [[1,0,0,0], [0,1,0,0], [0,0,1,0], [0,0,0,1]] }   # alternatively

    [object.material]                      # optional; Material fields
    ambient = [0.15, 0.15, 0.15]           # m_a (or one number)
    diffuse = [0.8, 0.8, 0.8]              # m_d
    specular = [0.3, 0.3, 0.3]             # m_s
    shininess = 32.0
    texture = "brick"                      # a built-in texture name, or a path (has a suffix or
                                           # a slash) relative to this file
    uv_scale = [4.0, 4.0]                  # or one number
    color_texture = "albedo.png"           # a colour map multiplying m_a and m_d (smooth, toon)

    [animation]                            # optional: an animated scene (docs/animation.md)

A scene may take its content from a glTF 2.0 file (docs/scenes.md)::

    gltf = "model.glb"                     # or { path = "model.glb", camera = "Cam",
                                           #      animation = "Walk" }
    [camera]                               # optional: keys given replace the glTF camera's
    fov_y = 30.0
    [materials."*"]                        # optional: Material fields for every glTF object ...
    specular = 0.0
    [materials."wheel"]                    # ... or for one, by object name
    diffuse = [0.9, 0.2, 0.1]

Then ``[[light]]`` tables replace the file's lights, ``[[object]]`` tables add objects, and an
``[animation]`` table replaces the file's animation (whose frame rate is its ``fps``).

``transform`` applies ``scale``, then the rotations about x, y, z (degrees), then ``translate``
(:func:`~refnpr.scenes.transform_matrix`). A mesh file with several geometries (glTF) becomes
several objects named ``name[i]`` sharing the transform and material.

Errors are :class:`SceneFileError` (a ``ValueError``) whose message starts with the file and the
table, and names the key: ``teapot.toml: [[object]] #1 'teapot': level: expected an integer ...``.
"""

from __future__ import annotations

import dataclasses
import json
import tomllib
import warnings
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import fields
from importlib import resources
from pathlib import Path

from .._reading import read_regular
from ..formulas._validate import BEYOND_FLOAT_RANGE
from ..raster import Camera
from ..texture.builtin import BUILTIN_TEXTURES
from .animation import MAX_FRAMES, Animation, Track, check_keys_in_range
from .registry import mesh_from_spec
from .scene import Light, Material, Scene, SceneObject, transform_matrix
from .tracks import Keyframe, quaternion_from_axis_angle

__all__ = [
    "SceneFileError",
    "parse_scene",
    "load_scene",
    "list_scenes",
    "builtin_scene_path",
    "parse_toml_bytes",
    "scene_frames",
    "MAX_SCENE_FILE_BYTES",
]

_TOP_KEYS = tuple(
    "name description ambient background gltf materials camera style light object animation".split()
)
_GLTF_KEYS = ("path", "camera", "animation")
_CAMERA_KEYS = ("eye", "target", "up", "fov_y", "near", "far")
_LIGHT_KEYS = ("kind", "direction", "position", "color")
_MATERIAL_KEYS = tuple(f.name for f in fields(Material))
_TRANSFORM_KEYS = ("translate", "rotate_deg", "scale", "matrix")
_ANIMATION_KEYS = ("frames", "fps", "track")
_TRACK_KEYS = ("target", "interpolation", "keys", "integer")
_KEY_KEYS = ("frame", "time", "value", "quaternion", "axis", "angle_deg")
#: The largest TOML scene file read (bytes).
MAX_SCENE_FILE_BYTES = 64 << 20


class SceneFileError(ValueError):
    """A scene file (or dict) that cannot be turned into a Scene; the message names file and key."""


@contextmanager
def _where(source: str, where: str) -> Iterator[None]:
    """Re-raise ValueError, TypeError and OSError (a missing mesh file) as located SceneFileError."""
    try:
        yield
    except SceneFileError:
        raise
    except (ValueError, TypeError, OSError) as exc:
        raise SceneFileError(f"{source}: {where}: {exc}") from exc


def _table(source: str, where: str, value, keys: tuple[str, ...] | None, example="") -> dict:
    if not isinstance(value, Mapping):
        raise SceneFileError(
            f"{source}: {where}: expected a table{example}, got {type(value).__name__} {value!r}"
        )
    unknown = [key for key in value if keys is not None and key not in keys]
    if unknown:
        raise SceneFileError(
            f"{source}: {where}: unknown key {unknown[0]!r}; valid keys: {', '.join(keys)}"
        )
    return dict(value)


def _array_of_tables(source: str, key: str, value) -> list:
    if not isinstance(value, list):
        raise SceneFileError(
            f"{source}: {key}: expected an array of tables ([[{key}]]), got {type(value).__name__}"
        )
    return value


def _is_path(value: str) -> bool:
    """A texture or style value with a slash or a suffix names a file (built-in names have
    neither)."""
    return "/" in value or "\\" in value or bool(Path(value).suffix)


def _material(source: str, where: str, value, base_dir: Path) -> Material:
    spec = _table(source, where, value, _MATERIAL_KEYS)
    for key in ("texture", "color_texture"):
        texture = spec.get(key)
        if not isinstance(texture, str) or texture in BUILTIN_TEXTURES:
            continue
        if not _is_path(texture):
            raise SceneFileError(
                f"{source}: {where}: {key}: {texture!r} is not a built-in texture (they are "
                f"{', '.join(BUILTIN_TEXTURES)}) nor a file path (a path has a suffix or a "
                "slash and is relative to the scene file); use one of those names or give the "
                "image's path (e.g. 'textures/paper.png')"
            )
        path = base_dir / texture
        if path.is_dir():
            raise SceneFileError(
                f"{source}: {where}: {key}: {str(path)!r} is a directory; expected an image "
                "file (PNG, JPEG, TIFF or BMP) or a built-in texture name"
            )
        if not path.is_file():
            raise SceneFileError(
                f"{source}: {where}: {key}: file {str(path)!r} not found (a texture with a "
                "suffix or a slash is a path relative to the scene file; built-in texture names "
                "have neither)"
            )
        spec[key] = str(path)
    with _where(source, where):
        return Material(**spec)


def _transform(source: str, where: str, value):
    spec = _table(source, where, value, _TRANSFORM_KEYS)
    with _where(source, where):
        if "matrix" in spec:
            if len(spec) > 1:
                raise ValueError("matrix: give either `matrix` or translate/rotate_deg/scale")
            return spec["matrix"]
        return transform_matrix(**spec)


def parse_scene(data: Mapping, base_dir: str | Path = ".", *, source: str | None = None) -> Scene:
    """Build a Scene from parsed TOML (the format of this module's docstring).

    Parameters
    ----------
    data : mapping
        The parsed file (``tomllib.load``) or an equivalent dict.
    base_dir : str or Path
        Directory that relative mesh and texture paths are resolved against.
    source : str, optional
        File name that error messages (:class:`SceneFileError`, naming the table and the key)
        start with (default ``"<scene dict>"``).
    """
    src = "<scene dict>" if source is None else str(source)
    base = Path(base_dir)
    top = _table(src, "top level", data, _TOP_KEYS)
    content = _gltf_content(src, top, base) if "gltf" in top else None
    if "camera" not in top and content is None:
        raise SceneFileError(
            f"{src}: missing the [camera] table; add one with eye = [x, y, z] and "
            "target = [x, y, z] (optional: up, fov_y, near, far)"
        )
    cam = _table(src, "[camera]", top.get("camera", {}), _CAMERA_KEYS)
    if content is not None:  # [camera] keys override the glTF camera's
        cam = {k: getattr(content.camera, k) for k in _CAMERA_KEYS} | cam
    for key in ("eye", "target"):
        if key not in cam:
            raise SceneFileError(f"{src}: [camera]: missing key {key!r} (3 numbers)")
    with _where(src, "[camera]"):
        camera = Camera.look_at(**cam)
    lights = []
    default_lights = [{}] if content is None else []
    for i, spec in enumerate(_array_of_tables(src, "light", top.get("light", default_lights))):
        where = f"[[light]] #{i + 1}"
        spec = _table(src, where, spec, _LIGHT_KEYS)
        with _where(src, where):
            lights.append(Light(**spec))
    headlight = content is not None and "light" not in top and not content.lights
    if content is not None and "light" not in top:
        lights = list(content.lights)
    if headlight:  # the file has no lights: the headlight of the camera this scene renders from
        from .gltf import GltfWarning, camera_headlight

        lights = [camera_headlight(camera)]
        warnings.warn(
            f"{src}: gltf: no node of the file's scene places a KHR_lights_punctual light; "
            "refnpr adds a headlight (a white directional light from the scene's camera)",
            GltfWarning,
            stacklevel=3,
        )
    objects = [] if content is None else _override_materials(src, top, content, base)
    tables = {}  # object name -> the [[object]] table that made it
    for i, spec in enumerate(_array_of_tables(src, "object", top.get("object", []))):
        where = f"[[object]] #{i + 1}"
        spec = _table(src, where, spec, None)
        label = spec.get("name", spec.get("mesh", spec.get("path")))
        if isinstance(label, str):
            where += f" {label!r}"
        name = spec.pop("name", None)
        if name is not None and not isinstance(name, str):
            raise SceneFileError(f"{src}: {where}: name: expected a string, got {name!r}")
        transform = _transform(src, f"{where}: transform", spec.pop("transform", {}))
        material = _material(src, f"{where}: material", spec.pop("material", {}), base)
        with _where(src, where):
            meshes = mesh_from_spec(spec, base_dir=base)
        single = not isinstance(meshes, list)
        for j, mesh in enumerate([meshes] if single else meshes):
            obj_name = (name or mesh.name) if single else f"{name or 'object'}[{j}]"
            with _where(src, where):
                objects.append(SceneObject(mesh, transform, material, obj_name))
            tables.setdefault(obj_name, where)
    if not objects:
        raise SceneFileError(f"{src}: no [[object]] tables; a scene needs at least one object")
    style = _table(src, "[style]", top.get("style", {}), None)
    if "name" in style and not isinstance(style["name"], str):
        raise SceneFileError(f"{src}: [style]: name: expected a string, got {style['name']!r}")
    style = _resolve_style_paths(style, Path(base_dir))
    name = top.get("name", Path(src).stem if source is not None else "scene")
    if not isinstance(top.get("description", ""), str):
        raise SceneFileError(f"{src}: description: expected a string")
    background = top.get("background", (1.0, 1.0, 1.0, 1.0))
    if isinstance(background, list) and len(background) == 3:
        background = [*background, 1.0]
    with _where(src, "top level"):
        scene = Scene(
            objects=tuple(objects),
            camera=camera,
            lights=tuple(lights),
            ambient=top.get("ambient", (1.0, 1.0, 1.0)),
            background=background,
            name=name,
            style=style,
        )
    if content is not None and "animation" not in top and content.animation is not None:
        # a [camera] table that sets the pose (eye, target or up) replaces the file's moving
        # pose; one that sets only the lens (fov_y, near, far) keeps it
        posed = any(key in top.get("camera", {}) for key in ("eye", "target", "up"))
        kept = tuple(
            t
            for t in content.animation.tracks
            if not (t.target.startswith("camera.") and posed)
            and not (t.target.startswith("light[") and "light" in top)
        )
        gltf = top["gltf"] if isinstance(top["gltf"], str) else top["gltf"]["path"]
        for t in kept:
            part, which, _ = t.parts
            if part == "object" and which in tables:
                raise SceneFileError(
                    f"{src}: {tables[which]}: name: {which!r} is also the name of an object of "
                    f"{gltf!r} that its animation moves (track {t.target!r}); an animated "
                    "object needs a unique name: give this [[object]] another name"
                )
        if headlight:  # it follows the file's camera where that camera moves the scene's
            from .gltf import headlight_track

            kept += headlight_track(kept)
        animation = dataclasses.replace(content.animation, tracks=kept)
        with _where(src, "gltf: animations"):
            return dataclasses.replace(scene, animation=animation)
    if "animation" not in top:
        return scene
    animation = _animation(src, top["animation"])
    shown = src.replace("{", "{{").replace("}", "}}")
    try:
        animation.check_scene(scene, label=shown + ": [[animation.track]] #{n} {target!r}")
    except ValueError as exc:
        raise SceneFileError(str(exc)) from exc
    return dataclasses.replace(scene, animation=animation)


def _gltf_content(src: str, top: dict, base: Path) -> Scene:
    """The scene of the ``gltf`` key: a path, or a table with ``path`` and optional ``camera``
    and ``animation`` (names or indices) of :func:`~refnpr.scenes.gltf.load_gltf`."""
    from .gltf import load_gltf

    spec = top["gltf"]
    spec = {"path": spec} if isinstance(spec, str) else _table(src, "gltf", spec, _GLTF_KEYS)
    path = spec.pop("path", None)
    if not isinstance(path, str) or Path(path).suffix.lower() not in (".gltf", ".glb"):
        raise SceneFileError(
            f"{src}: gltf: expected the path of a .gltf or .glb file (relative to this file), "
            f"got {path!r}"
        )
    anim = top.get("animation")
    fps = anim.get("fps", 24.0) if isinstance(anim, Mapping) else 24.0
    full = base / path
    if not full.exists():  # a FIFO or a device exists: load_gltf names what it is
        raise SceneFileError(f"{src}: gltf: file {str(full)!r} not found")
    with _where(src, "gltf"):
        return load_gltf(full, fps=fps, headlight=False, **spec)


def _override_materials(src: str, top: dict, content: Scene, base: Path) -> list:
    """The glTF objects, each with the ``[materials]`` fields given for its name (or ``"*"``,
    all objects) replacing its material's."""
    table = _table(src, "[materials]", top.get("materials", {}), None)
    names = [o.name for o in content.objects]
    given = {}  # key -> its fields, checked (texture names, paths resolved) in its own table
    for key, value in table.items():
        if key != "*" and key not in names:
            raise SceneFileError(
                f"{src}: [materials]: no glTF object named {key!r}; objects: "
                + ", ".join(map(repr, names))
                + " (or '*' for all)"
            )
        where = f"[materials.{json.dumps(key, ensure_ascii=False)}]"
        checked = _material(src, where, value, base)  # a table of Material fields
        given[key] = {k: getattr(checked, k) for k in value}
    objects = []
    for obj in content.objects:
        fields_ = {**given.get("*", {}), **given.get(obj.name, {})}
        if not fields_:
            objects.append(obj)
            continue
        current = {f.name: getattr(obj.material, f.name) for f in fields(Material)}
        where = f"[materials.{json.dumps(obj.name, ensure_ascii=False)}]"
        with _where(src, where):
            objects.append(dataclasses.replace(obj, material=Material(**(current | fields_))))
    return objects


def _is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _key(src: str, where: str, spec, fps: float, rotation: bool) -> Keyframe:
    """One key of an ``[[animation.track]]``: at a ``frame`` or a ``time``; a rotation as a
    ``quaternion`` or an ``axis`` and ``angle_deg``."""
    _table(src, where, spec, _KEY_KEYS, " such as { frame = 0, value = [...] }")
    if ("frame" in spec) == ("time" in spec):
        raise SceneFileError(
            f"{src}: {where}: give exactly one of `frame = N` or `time = SECONDS`, got "
            + ("both" if "frame" in spec else "neither")
        )
    if "frame" in spec:
        frame = spec["frame"]
    else:
        t = spec["time"]
        if isinstance(t, bool) or not isinstance(t, (int, float)):
            raise SceneFileError(f"{src}: {where}: time: expected seconds (a number), got {t!r}")
        try:
            frame = t * fps
        except OverflowError:  # an integer beyond the float range
            raise SceneFileError(
                f"{src}: {where}: time: expected seconds (a finite number), got "
                f"{BEYOND_FLOAT_RANGE}"
            ) from None
    if rotation:
        has_q, has_aa = "quaternion" in spec, "axis" in spec or "angle_deg" in spec
        if "value" in spec or has_q == has_aa:
            raise SceneFileError(
                f"{src}: {where}: a rotation key needs `quaternion = [x, y, z, w]` or "
                "`axis = [x, y, z]` with `angle_deg = A`, exactly one of the two"
            )
        if not has_q and ("axis" not in spec or "angle_deg" not in spec):
            raise SceneFileError(
                f"{src}: {where}: an axis-angle key needs both `axis` and `angle_deg`"
            )
    else:
        extra = [k for k in ("quaternion", "axis", "angle_deg") if k in spec]
        if extra:
            raise SceneFileError(
                f"{src}: {where}: {extra[0]!r} is for rotation tracks; this track takes `value`"
            )
        if "value" not in spec:
            raise SceneFileError(f"{src}: {where}: missing `value`")
    with _where(src, where):
        if rotation and "quaternion" not in spec:
            return Keyframe(frame, quaternion_from_axis_angle(spec["axis"], spec["angle_deg"]))
        return Keyframe(frame, spec["quaternion" if rotation else "value"])


def _animation(src: str, value) -> Animation:
    """The ``[animation]`` table (docs/animation.md); a style track whose key values are all
    integers rounds its interpolated value (``style.n``)."""
    spec = _table(src, "[animation]", value, _ANIMATION_KEYS)
    if "frames" not in spec:
        raise SceneFileError(
            f"{src}: [animation]: missing key 'frames' (the number of frames, >= 1)"
        )
    frames, fps = spec["frames"], spec.get("fps", 24.0)
    with _where(src, "[animation]"):
        Animation(frames, fps)  # frames and fps checked before the keys use fps
    tracks = []
    for i, track in enumerate(_array_of_tables(src, "animation.track", spec.get("track", []))):
        where = f"[[animation.track]] #{i + 1}"
        track = _table(src, where, track, _TRACK_KEYS)
        target = track.get("target")
        if not isinstance(target, str):
            raise SceneFileError(
                f"{src}: {where}: target: expected a string such as 'camera.eye', got {target!r}"
            )
        where += f" {target!r}"
        keys = track.get("keys")
        if not isinstance(keys, list) or not keys:
            raise SceneFileError(
                f"{src}: {where}: keys: expected a non-empty array of tables "
                "[{ frame = 0, value = [...] }, ...], got "
                + ("nothing" if keys is None else repr(keys))
            )
        rotation = target.strip().endswith(".rotation") and target.strip().startswith("object")
        parsed = [
            _key(src, f"{where}: keys[{j}]", k, float(fps), rotation) for j, k in enumerate(keys)
        ]
        check_keys_in_range(f"{src}: {where}", parsed, frames, fps, error=SceneFileError)
        integer = track.get("integer")
        if integer is None:  # style keys are checked to have a value
            integer = target.strip().startswith("style.") and all(
                all(map(_is_int, v if isinstance(v, list) else [v]))
                for v in (k["value"] for k in keys)
            )
        with _where(src, where):
            tracks.append(Track(target, tuple(parsed), track.get("interpolation"), integer))
    with _where(src, "[animation]"):
        return Animation(frames, fps, tuple(tracks))


def _resolve_style_paths(value, base_dir: Path):
    """Style values that name existing files next to the scene file (a string with a slash or a
    suffix, as material textures) become paths, in tables and lists too."""
    if isinstance(value, dict):
        return {k: _resolve_style_paths(v, base_dir) for k, v in value.items()}
    if isinstance(value, list):
        return [_resolve_style_paths(v, base_dir) for v in value]
    if isinstance(value, str) and _is_path(value):
        path = base_dir / value
        if not Path(value).is_absolute() and path.is_file():
            return str(path)
    return value


def _data_dir() -> Path:
    return Path(str(resources.files(__package__).joinpath("data")))


def _read(path: Path, source: str) -> dict:
    """Parse a scene file; every failure is a SceneFileError naming ``source`` (and the line).
    Only a regular file of at most :data:`MAX_SCENE_FILE_BYTES` is read (a FIFO would block,
    a device such as ``/dev/zero`` never end)."""
    try:
        raw = read_regular(
            path.resolve(), what=f"{source}: the scene file", max_bytes=MAX_SCENE_FILE_BYTES
        )
    except (OSError, RuntimeError) as exc:  # resolve(): a symbolic link loop
        raise SceneFileError(f"{source}: cannot read the scene file ({exc})") from None
    except ValueError as exc:
        raise SceneFileError(str(exc)) from None
    return parse_toml_bytes(raw, source, what="TOML scene files", error=SceneFileError)


def parse_toml_bytes(
    raw: bytes, source: str, *, what: str = "TOML files", error: type[ValueError] = ValueError
) -> dict:
    """``raw`` parsed as TOML; an ``error`` naming ``source`` (and the line) if it is not UTF-8
    or not valid TOML. ``what`` names the kind of file in the message (``"suite files"``)."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise error(
            f"{source}: not a UTF-8 text file (byte 0x{raw[exc.start]:02x} on line {line}); "
            f"{what} must be UTF-8 encoded: re-save the file as UTF-8"
        ) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{source}: invalid TOML: {exc}") from None
    except RecursionError:  # tomllib parses nested arrays and tables recursively
        raise error(
            f"{source}: invalid TOML: arrays or inline tables nested too deeply to parse (a scene "
            "needs at most a few levels); check the file for runaway brackets"
        ) from None


def list_scenes() -> dict[str, str]:
    """Built-in scenes: name -> one-line description, sorted by name."""
    paths = sorted(_data_dir().glob("*.toml"))
    return {p.stem: str(_read(p, p.name).get("description", "")) for p in paths}


def scene_frames(name: str) -> int:
    """Number of frames of built-in scene ``name`` (1 for a still), read without building it."""
    path = builtin_scene_path(name)
    animation = _read(path, path.name).get("animation")
    if animation is None:
        return 1
    frames = animation.get("frames") if isinstance(animation, Mapping) else None
    if isinstance(frames, bool) or not isinstance(frames, int) or not 1 <= frames <= MAX_FRAMES:
        raise SceneFileError(
            f"{path.name}: [animation]: frames: expected an integer from 1 to {MAX_FRAMES}"
        )
    return frames


def builtin_scene_path(name: str) -> Path:
    """Path of the TOML file of built-in scene ``name`` (ValueError listing the names if unknown)."""
    path = _data_dir() / f"{name}.toml"
    if not isinstance(name, str) or "/" in name or "\\" in name or not path.is_file():
        raise ValueError(
            f"scene: unknown built-in scene {name!r}; valid names: {', '.join(list_scenes())} "
            "(or give the path of a .toml scene file)"
        )
    return path


def load_scene(name_or_path: str | Path, *, camera: str | int | None = None) -> Scene:
    """Load a built-in scene by name (see :func:`list_scenes`) or a scene file by path: a
    ``Path``, or a string that ends in ``.toml`` (any case) or contains a slash. A path ending
    in ``.gltf`` or ``.glb`` is read by :func:`refnpr.scenes.gltf.load_gltf` (docs/scenes.md).

    Parameters
    ----------
    name_or_path : str or Path
    camera : str or int, optional
        glTF scenes only: the camera (camera or node name, or node index) to render from;
        default the file's first camera.

    Raises
    ------
    ValueError
        An unknown built-in name (listing the valid names) or an invalid file
        (:class:`SceneFileError`, naming the file and the key): not UTF-8 or invalid TOML (with
        the line), a directory, or an existing file without ``.toml``; a malformed glTF file
        (:class:`~refnpr.scenes.gltf.GltfError`, naming the file and the glTF path of the field).
    FileNotFoundError
        If a scene file path does not exist.
    """
    from .gltf import is_gltf_path, load_gltf

    is_gltf = is_gltf_path(name_or_path)
    if camera is not None and not is_gltf:
        raise ValueError(
            f"camera: {camera!r} names a glTF camera, but scene {str(name_or_path)!r} is not a "
            ".gltf/.glb file (a TOML scene has one [camera] table)"
        )
    if is_gltf:
        return load_gltf(name_or_path, camera=camera)
    if isinstance(name_or_path, Path) or (
        isinstance(name_or_path, str)
        and (name_or_path.lower().endswith(".toml") or "/" in name_or_path or "\\" in name_or_path)
    ):
        path = Path(name_or_path)
        if path.is_dir():
            raise SceneFileError(
                f"scene: {str(path)!r} is a directory; expected a .toml scene file"
            )
        if not path.exists():  # a FIFO or a device exists: _read names what it is
            raise FileNotFoundError(f"scene: file {str(path)!r} does not exist")
        return parse_scene(_read(path, str(path)), path.parent, source=str(path))
    if not isinstance(name_or_path, str):
        raise TypeError(
            f"name_or_path: expected a scene name or a path, got {type(name_or_path).__name__}"
        )
    try:
        path = builtin_scene_path(name_or_path)
    except ValueError:
        if name_or_path and Path(name_or_path).is_file():
            raise SceneFileError(
                f"scene: {name_or_path!r} is a file but not a built-in scene, and scene file "
                "names end in .toml (a TOML scene), .gltf or .glb (glTF 2.0), in any case: "
                "rename it to the suffix of its format (built-in scenes: "
                f"{', '.join(list_scenes())})"
            ) from None
        raise
    return parse_scene(_read(path, path.name), path.parent, source=path.name)
