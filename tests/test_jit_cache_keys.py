"""numba's disk cache, as refnpr uses it: entries keyed on the files a kernel calls into (so an
edited formula recompiles the kernels that call it), and an index that names a type which no
longer exists read as stale instead of raising."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import textwrap
from pathlib import Path

from numba.core import caching

from refnpr._jit import dependency_files
from refnpr.styles.xtoon import _kernels as xtoon_kernels


def test_dependencies_reach_formulas_device_functions_and_their_files():
    files = {Path(f).name for f in dependency_files(xtoon_kernels.shade_xtoon.body.py_func)}
    # the kernel's module, the X-Toon formulas (through f.scalar bound to module names), the
    # device layer's vectors and lights, and what those call
    assert {"_kernels.py", "__init__.py", "vectors.py", "lights.py", "scalars.py"} <= files


def test_editing_a_callee_in_another_file_recompiles_the_caller(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "formula.py").write_text(
        "from refnpr._jit import njit\n\n@njit\ndef f(x):\n    return 2.0 * x\n"
    )
    (pkg / "kernel.py").write_text(
        textwrap.dedent(
            """
            from refnpr._jit import njit
            from .formula import f

            @njit
            def k(x):
                return f(x) + 1.0
            """
        )
    )
    run = [sys.executable, "-c", "from pkg.kernel import k; print(k(1.0))"]
    env = {**os.environ, "PYTHONPATH": str(tmp_path), "NUMBA_CACHE_DIR": str(tmp_path / "c")}

    def value() -> str:
        out = subprocess.run(run, env=env, capture_output=True, text=True, check=True)
        return out.stdout.strip()

    assert value() == "3.0"
    assert value() == "3.0"  # from the cache
    (pkg / "formula.py").write_text(
        "from refnpr._jit import njit\n\n@njit\ndef f(x):\n    return 5.0 * x\n"
    )
    assert value() == "6.0"  # numba alone would load the cached 3.0


class _Gone:
    pass


def test_an_index_naming_a_missing_type_is_stale(tmp_path):
    import numba

    index = caching.IndexDataCacheFile(str(tmp_path), "kernel-1.py311", (1.0, 10))
    data = pickle.dumps(((1.0, 10), {(_Gone,): "kernel-1.py311.1.nbc"}), protocol=-1)
    data = data.replace(b"_Gone", b"_Lost")  # the class was renamed since the index was written
    with open(index._index_path, "wb") as f:
        pickle.dump(numba.__version__, f, protocol=-1)
        f.write(data)
    assert index._load_index() == {}
