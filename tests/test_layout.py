"""The package layout is the architecture (DESIGN.md, "Architecture"): checked, not remembered.

* Every name of the documented public API imports from the same place it always has.
* Imports point one way between the top-level packages of refnpr (device <- formulas <- texture
  <- styles <- render <- cli; raster depends on nothing but the numba flags, the device layer
  and the formulas), the papers' packages inside
  ``styles`` and ``formulas`` do not import one another, and the module import graph has no
  cycle. The checker is run on small synthetic trees too, so it is shown to fail when it should.
* One package per paper: no flat ``_<paper>_*.py`` prefix modules are left.
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

import refnpr

ROOT = Path(refnpr.__file__).resolve().parent

PUBLIC_API = {
    "refnpr.cli": ("main",),
    "refnpr.compare": (
        "ImageMetrics",
        "compare_dirs",
        "compare_images",
        "difference_image",
        "load_image",
    ),
    "refnpr.formulas.halftone": (
        "apply_indication",
        "binary_threshold",
        "decode_stroke_map",
        "encode_stroke_map",
        "engraving_ramp",
        "engraving_screen",
        "layer_onsets",
        "smooth_threshold",
        "smooth_threshold_tone",
        "stroke_levels",
        "stroke_lighting",
    ),
    "refnpr.formulas.lighting": (
        "ambient",
        "diffuse",
        "illumination",
        "specular",
        "toon_ramp",
        "toon_ramp_texture",
    ),
    "refnpr.formulas.tamiss": (
        "CLAIM",
        "EMPTY",
        "FOUND",
        "LEGENDRE",
        "LOST",
        "N_REGRESSORS",
        "RouteResult",
        "StrokeFit",
        "StrokeHashTable",
        "StrokeStrip",
        "aggregate",
        "cg_solve",
        "extrude_stroke",
        "fit_fragments",
        "fit_stroke",
        "fit_strokes",
        "fragment_regressors",
        "hash_slot",
        "moment_matrix",
        "normalize_t",
        "probe_table",
        "visibility_prior",
        "visible_segments",
    ),
    "refnpr.formulas.threshold": (
        "DotToneTable",
        "combine_thresholds",
        "dot_dyadic_scale",
        "dot_function",
        "dot_threshold",
        "dot_tone_table",
        "dyadic_remap",
        "dyadic_scale",
        "dyadic_scale_from_gradient",
        "facing_strength",
        "hatch_coordinate",
        "hatch_threshold",
        "line_coverage",
        "line_threshold",
        "mip_threshold",
        "multiscale_line",
        "multiscale_line_cdf",
        "pcf_threshold",
        "step",
        "step_n",
        "strength_blend",
        "threshold_illumination",
        "tone_strength",
    ),
    "refnpr.formulas.xtoon": (
        "blend_normals",
        "cylinder_normals",
        "detail_depth",
        "detail_focus",
        "detail_highlight",
        "detail_orientation",
        "ellipsoid_normals",
        "shape_frame",
        "smoothed_normals",
        "sphere_normals",
        "toon_lookup",
        "toon_texture_backlight",
        "toon_texture_blur",
        "toon_texture_fade",
        "toon_texture_hue",
        "toon_texture_levels",
        "toon_texture_metal",
        "toon_texture_plastic",
        "toon_texture_receding",
    ),
    "refnpr.golden": (
        "CaseResult",
        "GoldenCase",
        "check_suite",
        "RenderCases",
        "load_suite",
        "render_case",
        "render_or_error",
        "update_suite",
    ),
    "refnpr.distributed": (
        "check_suite",
        "open_client",
        "render_sequence",
        "update_suite",
        "worker_threads",
    ),
    "refnpr.image": (
        "Image",
        "check_png_path",
        "linear_to_srgb",
        "srgb_to_linear",
        "write_png_atomic",
    ),
    "refnpr.raster": (
        "BUILTIN_CHANNELS",
        "Camera",
        "GBuffer",
        "Mesh",
        "box_resolve",
        "rasterize",
        "valid_channels",
    ),
    "refnpr.raster.camera": ("Camera",),
    "refnpr.raster.channels": (
        "INTERPOLATED",
        "attribute_names",
        "check_vertex_data",
        "interpolated_channels",
    ),
    "refnpr.raster.gbuffer": (
        "BUILTIN_CHANNELS",
        "GBuffer",
        "box_resolve",
    ),
    "refnpr.raster.mesh": (
        "Mesh",
        "RESERVED_NAMES",
    ),
    "refnpr.raster.rasterize": (
        "DEFAULT_TILE",
        "rasterize",
        "valid_channels",
    ),
    "refnpr.render": (
        "DEFAULT_STYLE",
        "render",
        "required_channels",
    ),
    "refnpr.coherence": (
        "CoherenceReport",
        "MotionField",
        "PairMetrics",
        "measure",
        "measure_strokes",
        "motion_field",
        "pair_metrics",
        "stroke_ends",
        "stroke_pair_metrics",
        "warp",
    ),
    "refnpr.sequence": (
        "SequenceResult",
        "frame_range",
        "is_stateful",
        "render_sequence",
        "scene_digest",
        "write_video",
    ),
    "refnpr.warmup": ("WARM_ROWS", "warm"),
    "refnpr.scenes": (
        "Animation",
        "Keyframe",
        "Track",
        "quaternion_from_axis_angle",
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
        "load_mesh",
        "load_scene",
        "mesh_from_spec",
        "parse_scene",
        "plane",
        "project_uv",
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
    ),
    "refnpr.scenes.knot": (
        "rotation_minimising_frames",
        "torus_knot",
        "torus_knot_curve",
    ),
    "refnpr.scenes.loading": (
        "from_trimesh",
        "load_mesh",
    ),
    "refnpr.scenes.primitives": (
        "icosphere",
        "spherical_uv",
        "torus",
        "uv_sphere",
    ),
    "refnpr.scenes.registry": (
        "MESH_BUILDERS",
        "mesh_from_spec",
    ),
    "refnpr.scenes.revolution": (
        "revolve",
        "vase",
        "vase_profile",
    ),
    "refnpr.scenes.room": (
        "plane",
        "room",
    ),
    "refnpr.scenes.scene": (
        "Light",
        "Material",
        "Scene",
        "SceneObject",
        "transform_matrix",
    ),
    "refnpr.scenes.teapot": (
        "read_bpt",
        "teapot",
        "teapot_patches",
    ),
    "refnpr.scenes.terrain": (
        "terrain",
        "terrain_height",
    ),
    "refnpr.scenes.toml_format": (
        "SceneFileError",
        "builtin_scene_path",
        "list_scenes",
        "load_scene",
        "parse_scene",
        "scene_frames",
    ),
    "refnpr.scenes.uv_projection": (
        "UV_PROJECTIONS",
        "project_uv",
        "require_uv",
    ),
    "refnpr.styles": (
        "ShadeContext",
        "Style",
        "get_style",
        "list_styles",
        "register",
        "style_from_spec",
    ),
    "refnpr.styles.base": (
        "ShadeContext",
        "Style",
        "get_style",
        "list_styles",
        "register",
        "style_from_spec",
    ),
    "refnpr.styles.contours": (
        "ContourLayer",
        "Contoured",
        "EdgeTable",
        "edge_table",
    ),
    "refnpr.styles.halftone": ("HalftoneStyle",),
    "refnpr.styles.smooth": ("SmoothStyle",),
    "refnpr.styles.tam": ("TamStyle",),
    "refnpr.styles.tamiss": (
        "AggregateHistory",
        "Aggregates",
        "BRUSHES",
        "EXTENTS",
        "FieldInputs",
        "Fragments",
        "HashStats",
        "PipelineResult",
        "Strips",
        "StrokeField",
        "StrokeGeometry",
        "TamissParams",
        "TamissStyle",
        "aggregate_exact",
        "aggregate_hashed",
        "brush_texture",
        "centreline",
        "drawn_segments",
        "extrude",
        "field_inputs",
        "gather_fragments",
        "keep_mask",
        "key32",
        "layer_scale",
        "pack_id",
        "rasterize_strips",
        "recentre",
        "run_pipeline",
        "seed_set",
        "stroke_geometry",
        "tam_ink",
        "unpack_id",
    ),
    "refnpr.styles.threshold": ("ThresholdStyle",),
    "refnpr.styles.toon": ("ToonStyle",),
    "refnpr.styles.xtoon": (
        "AbstractedNormals",
        "PRESETS",
        "XToonStyle",
        "abstract_normals",
        "resolve_texture",
    ),
    "refnpr.texture": (
        "BUILTIN_TEXTURES",
        "MipPyramid",
        "StrokeSet",
        "as_texture",
        "brick_set",
        "build_pyramid",
        "clahe_pyramid",
        "engraving_pyramid",
        "hatching_set",
        "level_weights",
        "load_stroke_layers",
        "load_texture",
        "normal_pyramid",
        "rank_equalize",
        "sample_level",
        "sample_trilinear",
        "stroke_map_pyramid",
        "stroke_set_from_layers",
        "texture_lod",
    ),
    "refnpr.texture.builtin": (
        "BUILTIN_TEXTURES",
        "load_texture",
    ),
    "refnpr.texture.pyramid": (
        "MipPyramid",
        "as_texture",
        "build_pyramid",
        "clahe_pyramid",
        "rank_equalize",
    ),
    "refnpr.texture.sample": (
        "level_weights",
        "sample_level",
        "sample_trilinear",
        "texture_lod",
    ),
    "refnpr.texture.screens": (
        "StrokeSet",
        "brick_set",
        "engraving_pyramid",
        "hatching_layer",
        "hatching_set",
        "level_sizes",
        "line_coverage",
        "load_stroke_layers",
        "normal_pyramid",
        "stroke_map_pyramid",
        "stroke_set_from_layers",
    ),
}


@pytest.mark.parametrize("module", sorted(PUBLIC_API))
def test_public_api_imports_from_its_documented_place(module):
    mod = importlib.import_module(module)
    missing = [name for name in PUBLIC_API[module] if not hasattr(mod, name)]
    assert not missing, f"{module} no longer provides {missing}"
    # each listed name is still declared public there
    assert set(PUBLIC_API[module]) <= set(mod.__all__), module


def test_documented_submodule_paths_still_import():
    # paths that the README, docs and notebooks use as modules, not only as names
    from refnpr.styles.tamiss import run_pipeline  # noqa: F401
    from refnpr.texture import screens

    assert callable(screens.hatching_set)
    for path in ("refnpr.styles.tam", "refnpr.styles.base", "refnpr.texture.screens"):
        importlib.import_module(path)


# --------------------------------------------------------------------------------------------
# import graph
# --------------------------------------------------------------------------------------------
#: Rank of each top-level part of refnpr: a module may import its own part and parts of lower
#: rank, never a part of the same or a higher rank (so raster and formulas, or texture and
#: scenes, do not import each other). ``refnpr`` itself (``__version__``) may be imported by all.
RANK = {
    "refnpr": -1,
    "_jit": 0,
    "_memory": 0,
    "_reading": 0,
    "_atomic": 1,
    "device": 1,
    "_kernels": 2,
    "formulas": 2,
    "exr": 2,
    "image": 3,
    "raster": 4,
    "texture": 4,
    "scenes": 5,
    "styles": 6,
    "render": 7,
    "compare": 8,
    "explore": 8,
    "sequence": 8,
    "warmup": 8,
    "coherence": 9,
    "golden": 9,
    "kit": 10,
    "gallery": 10,
    "distributed": 10,
    "cli": 11,
}
#: Names the root package exports on first use (module ``__getattr__``): ``refnpr.explore``
#: imports the renderer and ipywidgets only when called, so the root may name it lazily.
LAZY_ROOT_EXPORTS = {"explore"}
#: Stricter than the ranks: what the architecture (docs/architecture.md) says these may import.
ONLY = {
    "device": {"_jit"},
    "formulas": {"_jit", "device"},
    "raster": {"_jit", "_memory", "device", "formulas"},
    "_jit": set(),
    "_memory": set(),
    "_reading": set(),
    "_kernels": {"_jit", "device"},
    "refnpr": set(),
}
#: Which paper each package speaks for: a module of one paper must not import another paper's,
#: in any layer (the ``tam`` module is the documented path of the tamiss package's RPTAM style).
PAPER_OF = {
    **{("styles", p): p for p in ("threshold", "halftone", "xtoon", "tamiss")},
    ("styles", "tam"): "tamiss",
    **{("formulas", p): p for p in ("threshold", "halftone", "xtoon", "tamiss")},
    ("texture", "screens"): "halftone",
}


def paper_of(name: str) -> str | None:
    parts = name.split(".")
    return PAPER_OF.get(tuple(parts[1:3])) if len(parts) >= 3 else None


def module_files(root: Path, package: str) -> dict[str, Path]:
    """Dotted module name -> file, for every .py under ``root`` (the package ``package``)."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = [package, *path.relative_to(root).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _is_type_checking(node: ast.AST) -> bool:
    test = getattr(node, "test", None)
    return isinstance(node, ast.If) and (
        (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING")
        or (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")
    )


def _dynamic_target(node: ast.AST) -> str | None:
    """``importlib.import_module("x")`` / ``import_module("x")`` / ``__import__("x")``."""
    if not isinstance(node, ast.Call) or not node.args:
        return None
    f = node.func
    fname = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", None)
    arg = node.args[0]
    if fname in ("import_module", "__import__") and isinstance(arg, ast.Constant):
        return arg.value if isinstance(arg.value, str) else None
    return None


def imports_of(name: str, path: Path, modules: dict[str, Path], *, top_level_only: bool):
    """Modules of the package that ``name`` imports (``from a import b`` -> ``a.b`` when that is a
    module; dynamic imports by a constant name too). ``top_level_only``: only what runs at import
    time (not inside functions, not under ``if TYPE_CHECKING:``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    root = next(iter(modules)).split(".")[0]
    if top_level_only:
        nodes = []
        stack = list(tree.body)
        while stack:
            node = stack.pop()
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                continue
            if _is_type_checking(node):
                stack.extend(node.orelse)
                continue
            nodes.append(node)
            stack.extend(ast.iter_child_nodes(node))
    else:
        nodes = list(ast.walk(tree))
    found = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            targets = [
                f"{target}.{a.name}" if f"{target}.{a.name}" in modules else target
                for a in node.names
            ]
        elif _dynamic_target(node):
            targets = [_dynamic_target(node)]
        else:
            continue
        for t in targets:
            if t == root or t.startswith(root + "."):
                while t not in modules and "." in t:
                    t = t.rpartition(".")[0]
                found.add(t)
    return found


def layer_violations(root: Path, package: str) -> list[str]:
    """Every import (anywhere in a module, lazy ones included) that points up or sideways."""
    modules = module_files(root, package)
    bad = []
    for name, path in modules.items():
        src_parts = name.split(".")
        src = src_parts[1] if len(src_parts) > 1 else package
        for tgt_name in imports_of(name, path, modules, top_level_only=False):
            tgt_parts = tgt_name.split(".")
            tgt = tgt_parts[1] if len(tgt_parts) > 1 else package
            a, b = paper_of(name), paper_of(tgt_name)
            if a and b and a != b:
                bad.append(f"{name} imports {tgt_name}: one paper's package uses another's")
                continue
            if tgt == src or tgt == package:
                continue  # within a part, or the root package (__version__)
            if (
                name == package
                and tgt in LAZY_ROOT_EXPORTS
                and tgt_name not in imports_of(name, path, modules, top_level_only=True)
            ):
                continue  # refnpr.explore, imported on first use
            src_key = src if src in RANK else "refnpr"
            if tgt not in RANK:
                bad.append(f"{name} imports {tgt_name}: unknown part {tgt!r}; give it a RANK")
            elif src_key in ONLY and tgt not in ONLY[src_key]:
                bad.append(
                    f"{name} imports {tgt_name}: {src} may import only {sorted(ONLY[src_key])}"
                )
            elif RANK[tgt] >= RANK.get(src_key, -1):
                bad.append(f"{name} imports {tgt_name}: {tgt} is not below {src}")
    return bad


def import_cycles(root: Path, package: str) -> list[list[str]]:
    """Strongly connected components (size > 1, or a self-import) of the import-time graph."""
    modules = module_files(root, package)
    graph = {
        n: sorted(imports_of(n, p, modules, top_level_only=True) - {n}) for n, p in modules.items()
    }
    for n, p in modules.items():
        if n in imports_of(n, p, modules, top_level_only=True) and not p.name == "__init__.py":
            graph[n].append(n)
    index, low, on_stack, stack, out = {}, {}, set(), [], []

    def visit(v):  # Tarjan, recursive: the graph is a few hundred modules
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph.get(v, ()):
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_imports_point_one_way():
    assert layer_violations(ROOT, "refnpr") == []


def test_no_import_cycles():
    assert import_cycles(ROOT, "refnpr") == []


def _tree(tmp_path: Path, files: dict[str, str]) -> Path:
    root = tmp_path / "refnpr"
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root


def test_checker_reports_an_upward_import(tmp_path):
    root = _tree(
        tmp_path,
        {
            "__init__.py": "",
            "formulas/__init__.py": "",
            "formulas/x.py": "def f():\n    from refnpr.styles import base\n",  # lazy, still up
            "styles/__init__.py": "",
            "styles/base.py": "from refnpr.formulas import x\n",  # down: fine
            "texture/__init__.py": "from ..render import render\n",  # relative, up
            "render.py": "from .texture import y\n",
        },
    )
    bad = layer_violations(root, "refnpr")
    assert len(bad) == 2, bad
    assert any("refnpr.formulas.x imports refnpr.styles.base" in b for b in bad)
    assert any("refnpr.texture imports refnpr.render" in b for b in bad)


def test_checker_reports_papers_importing_each_other_and_sideways_parts(tmp_path):
    root = _tree(
        tmp_path,
        {
            "__init__.py": "",
            "raster/__init__.py": "from refnpr.image import png\n",  # raster: not image
            "image/__init__.py": "",
            "image/png.py": "",
            "raster/mesh.py": "from refnpr.texture import pyramid\n",  # same rank
            "texture/__init__.py": "",
            "texture/pyramid.py": "",
            "styles/__init__.py": "",
            "styles/_common.py": "",
            "styles/xtoon/__init__.py": "from .._common import x\n",  # its own layer: fine
            "styles/tamiss/__init__.py": "from ..xtoon import shape\n",
            "styles/xtoon/shape.py": "",
        },
    )
    bad = layer_violations(root, "refnpr")
    assert len(bad) == 3, bad
    assert any("raster may import only ['_jit', '_memory', 'device', 'formulas']" in b for b in bad)
    assert any("refnpr.raster.mesh imports refnpr.texture.pyramid" in b for b in bad)
    assert any("one paper's package uses another's" in b for b in bad)


def test_checker_reports_dynamic_and_cross_layer_paper_imports(tmp_path):
    root = _tree(
        tmp_path,
        {
            "__init__.py": "",
            "formulas/__init__.py": "",
            "formulas/tamiss/__init__.py": "",
            "styles/__init__.py": "",
            "styles/tam.py": "",
            "styles/xtoon/__init__.py": "from refnpr.formulas import tamiss\n",  # other paper
            "styles/xtoon/a.py": "from .. import tam\n",  # tamiss through its shim
            "texture/__init__.py": "import importlib\nR = importlib.import_module('refnpr.render')\n",
            "render.py": "",
        },
    )
    bad = layer_violations(root, "refnpr")
    assert len(bad) == 3, bad
    assert any("refnpr.styles.xtoon imports refnpr.formulas.tamiss" in b for b in bad)
    assert any("refnpr.styles.xtoon.a imports refnpr.styles.tam" in b for b in bad)
    assert any("refnpr.texture imports refnpr.render: render is not below" in b for b in bad)


def test_checker_reports_a_cycle_but_not_lazy_imports(tmp_path):
    root = _tree(
        tmp_path,
        {
            "__init__.py": "",
            "styles/__init__.py": "",
            "styles/a.py": "from . import b\n",
            "styles/b.py": "from .c import f\n",
            "styles/c.py": "from .a import g\n",
            "styles/d.py": "from . import e\n",
            "styles/e.py": "def h():\n    from . import d\n",  # lazy: no import-time cycle
            "styles/f.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from . import g\n",
            "styles/g.py": "from . import f\n",  # f imports g for type checkers only
        },
    )
    assert import_cycles(root, "refnpr") == [
        ["refnpr.styles.a", "refnpr.styles.b", "refnpr.styles.c"]
    ]


# --------------------------------------------------------------------------------------------
# one package per paper
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("layer", ["styles", "formulas"])
def test_no_prefix_modules_stand_in_for_packages(layer):
    flat = sorted(
        p.name
        for p in (ROOT / layer).glob("_*_*.py")
        if p.name.split("_")[1] in {"threshold", "halftone", "xtoon", "tamiss"}
    )
    assert flat == [], f"refnpr/{layer}: move {flat} into the paper's package"


@pytest.mark.parametrize(
    "package",
    [
        "styles/threshold",
        "styles/halftone",
        "styles/xtoon",
        "styles/tamiss",
        "formulas/threshold",
        "formulas/xtoon",
        "formulas/tamiss",
        "texture/screens",
    ],
)
def test_each_paper_has_its_package(package):
    assert (ROOT / package / "__init__.py").is_file()


def test_no_module_beside_a_package_of_the_same_name():
    shadowed = [
        p
        for p in ROOT.rglob("*.py")
        if p.name != "__init__.py" and (p.with_suffix("") / "__init__.py").exists()
    ]
    assert shadowed == [], f"remove {shadowed}: the package of the same name wins on import"


def test_numba_code_lives_in_kernel_modules():
    """numba code: kernels (``_kernels.py``), the device layer and the formulas' scalar
    functions (``f.scalar``); nowhere else."""
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT).parts
        if path.name.endswith("_kernels.py") or path.name == "_jit.py":
            continue
        if rel[0] in ("device", "formulas"):
            continue
        text = path.read_text(encoding="utf-8")
        assert "njit" not in text and "numba.jit" not in text, path
