"""Every notebook in notebooks/ runs top to bottom (executed, never skipped), and is committed
with its outputs (small images) so that it reads on a code host without running.

``notebooks/save_outputs.py`` writes the outputs; it is tested here on a notebook made in a
temporary directory (images shrunk to the limit, text cut, deterministic bytes).
"""

import base64
import json
import subprocess
import sys
from pathlib import Path

import imageio.v3 as iio
import nbformat
import numpy as np
import pytest
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
SAVE_OUTPUTS = ROOT / "notebooks" / "save_outputs.py"
MAX_NOTEBOOK_BYTES = 2_000_000


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_executes(path):
    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}
    )
    client.execute()  # raises CellExecutionError with the failing cell's traceback
    errors = [
        o
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.get("outputs", [])
        if o.get("output_type") == "error"
    ]
    assert not errors


def _png_outputs(nb) -> list[bytes]:
    return [
        base64.b64decode("".join(o["data"]["image/png"]))
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.get("outputs", [])
        if "image/png" in o.get("data", {})
    ]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_is_committed_with_its_outputs(path):
    size = path.stat().st_size
    assert size < MAX_NOTEBOOK_BYTES, f"{path.name}: {size} bytes; keep notebooks under 2 MB"
    nb = nbformat.read(path, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    unrun = [i for i, c in enumerate(code) if c.get("execution_count") is None]
    hint = f"run: python notebooks/save_outputs.py notebooks/{path.name}"
    assert not unrun, f"{path.name}: code cells {unrun} saved without running; {hint}"
    assert [c.execution_count for c in code] == list(range(1, len(code) + 1)), hint
    pngs = _png_outputs(nb)
    assert pngs, f"{path.name}: no image output; {hint}"
    for png in pngs:
        assert iio.imread(png).size > 0
    errors = [o for c in code for o in c.outputs if o.get("output_type") == "error"]
    assert not errors, f"{path.name}: saved with an error output"
    assert not any("execution" in c.metadata for c in nb.cells), "timings saved; " + hint


def _make_notebook(path: Path) -> None:
    big = np.random.default_rng(0).integers(0, 256, (600, 800, 3), dtype=np.uint8)
    np.save(path.parent / "big.npy", big)
    cells = [
        nbformat.v4.new_code_cell("import numpy as np\nfrom refnpr.image import Image"),
        nbformat.v4.new_code_cell("Image(np.full((8, 12, 4), 0.5, np.float32))"),
        nbformat.v4.new_code_cell("print('x' * 50_000)"),
        nbformat.v4.new_code_cell(
            "import imageio.v3 as iio\nfrom IPython.display import Image as PNG, display\n"
            "display(PNG(data=iio.imwrite('<bytes>', np.load('big.npy'), extension='.png')))"
        ),
        nbformat.v4.new_code_cell("import warnings\nwarnings.warn('from a cell')"),
    ]
    nb = nbformat.v4.new_notebook(cells=cells)
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    nbformat.write(nb, path)


def test_save_outputs_writes_small_deterministic_outputs(tmp_path):
    path = tmp_path / "demo.ipynb"
    _make_notebook(path)
    cmd = [sys.executable, str(SAVE_OUTPUTS), str(path), "--max-image-bytes", "200000"]
    first = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert first.returncode == 0, first.stderr
    saved = path.read_bytes()
    nb = nbformat.read(path, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert [c.execution_count for c in code] == [1, 2, 3, 4, 5]
    # the refnpr Image shows itself as its PNG (Image._repr_png_)
    (small,) = _png_outputs(nbformat.from_dict({"cells": [code[1]]}))
    assert iio.imread(small).shape == (8, 12, 4)
    # the large PNG (random noise, ~1.4 MB) is shrunk by halves until it fits
    big = _png_outputs(nbformat.from_dict({"cells": [code[3]]}))[0]
    assert len(big) <= 200_000
    assert iio.imread(big).shape == (150, 200, 3)  # 300 x 400 noise is still over the limit
    text = "".join(code[2].outputs[0]["text"])
    assert len(text) < 5_000 and "characters cut by save_outputs.py" in text
    warning = "".join(code[4].outputs[0]["text"])
    assert "from a cell" in warning and "ipykernel_" not in warning and "<cell>" in warning
    meta = json.loads(saved)["metadata"]
    assert meta["language_info"] == {"name": "python"} and "widgets" not in meta
    # a second run writes the same bytes
    second = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert second.returncode == 0, second.stderr
    assert path.read_bytes() == saved


def test_kernel_file_names_are_replaced_up_to_a_space_quote_or_parenthesis():
    sys.path.insert(0, str(SAVE_OUTPUTS.parent))
    try:
        from save_outputs import _stable
    finally:
        sys.path.remove(str(SAVE_OUTPUTS.parent))
    text = 'at /tmp/ipykernel_12/345.py:3 (C:\\T\\ipykernel_9\\8.py) "/a b/ipykernel_1/2.py"'
    assert _stable(text) == 'at <cell>:3 (<cell>) "/a <cell>"'
    long = "x" * 100_000 + " /t/ipykernel_1/2.py"
    assert _stable(long) == "x" * 100_000 + " <cell>"


def test_save_outputs_refuses_a_failing_or_oversized_notebook(tmp_path):
    path = tmp_path / "bad.ipynb"
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1 / 0")])
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    nbformat.write(nb, path)
    before = path.read_bytes()
    run = subprocess.run(
        [sys.executable, str(SAVE_OUTPUTS), str(path)], capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 1 and "not saved" in run.stderr and "ZeroDivisionError" in run.stderr
    assert path.read_bytes() == before
    path.write_text(nbformat.writes(nbformat.v4.new_notebook(cells=[
        nbformat.v4.new_code_cell("print('y' * 3000)")
    ])))  # fmt: skip
    before = path.read_bytes()
    cmd = [sys.executable, str(SAVE_OUTPUTS), str(path), "--max-notebook-bytes", "1000"]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert run.returncode == 1 and "over --max-notebook-bytes 1000" in run.stderr
    assert path.read_bytes() == before
