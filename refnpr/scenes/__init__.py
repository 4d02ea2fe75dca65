"""Built-in procedural meshes, Newell's teapot, mesh loading, TOML scene files (the format is in
:mod:`refnpr.scenes.toml_format`), glTF 2.0 scenes (:mod:`refnpr.scenes.gltf`) and animated scenes (``scene.at(frame)`` is a frame's still).
World space is right-handed with +y up; meshes are counter-clockwise seen from outside.
"""

from .animation import Animation, Track
from .gltf import GltfError, GltfWarning, load_gltf
from .knot import rotation_minimising_frames, torus_knot, torus_knot_curve
from .loading import from_trimesh, load_mesh
from .primitives import icosphere, spherical_uv, torus, uv_sphere
from .registry import MESH_BUILDERS, mesh_from_spec
from .revolution import revolve, vase, vase_profile
from .room import plane, room
from .scene import Light, Material, Scene, SceneObject, transform_matrix
from .teapot import read_bpt, teapot, teapot_patches
from .terrain import terrain, terrain_height
from .toml_format import SceneFileError, builtin_scene_path, list_scenes, load_scene, parse_scene
from .tracks import Keyframe, quaternion_from_axis_angle
from .uv_projection import UV_PROJECTIONS, project_uv, require_uv

__all__ = [
    "Animation",
    "GltfError",
    "GltfWarning",
    "Keyframe",
    "Track",
    "Light",
    "MESH_BUILDERS",
    "Material",
    "Scene",
    "SceneFileError",
    "SceneObject",
    "UV_PROJECTIONS",
    "builtin_scene_path",
    "from_trimesh",
    "icosphere",
    "list_scenes",
    "load_gltf",
    "load_mesh",
    "load_scene",
    "mesh_from_spec",
    "parse_scene",
    "plane",
    "project_uv",
    "quaternion_from_axis_angle",
    "read_bpt",
    "require_uv",
    "revolve",
    "room",
    "rotation_minimising_frames",
    "spherical_uv",
    "teapot",
    "teapot_patches",
    "terrain",
    "terrain_height",
    "torus",
    "torus_knot",
    "torus_knot_curve",
    "transform_matrix",
    "uv_sphere",
    "vase",
    "vase_profile",
]
