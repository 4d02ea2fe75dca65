"""Execute notebooks and write them back with their outputs, small and deterministic.

Committed notebooks carry their outputs so that they read on a code host without running
(the tests still execute them). This script runs each notebook top to bottom in a fresh
kernel (nbclient) and writes it back in place, after:

* images: a PNG output over ``--max-image-bytes`` is shrunk (2 x 2 box averages, repeated)
  until it fits; other image types over the limit are dropped (their text/plain stays);
* text: stream and text outputs are cut to ``--max-text-chars``, with a note of how much, and
  the kernel's per-run cell file names (``/tmp/ipykernel_<pid>/<hash>.py``) become ``<cell>``;
* widgets: widget views and the notebook's widget state are dropped (only their text stays);
* metadata: no timings (``record_timing`` off, no ``execution`` entries), execution counts
  1, 2, ... in cell order, ``language_info`` reduced to the language name, missing cell ids
  filled from the cell's position, ``PYTHONHASHSEED=0`` in the kernel; JSON written the way
  nbformat writes it (sorted keys, one-space indent) through a temporary file.

A notebook over ``--max-notebook-bytes`` afterwards is an error (exit status 1), as is a cell
that raises (the notebook is then left as it was).

Usage::

    python notebooks/save_outputs.py                  # every notebooks/*.ipynb
    python notebooks/save_outputs.py notebooks/xtoon.ipynb --timeout 900
"""

from __future__ import annotations

import argparse
import base64
import io
import os
import re
import sys
import tempfile
from pathlib import Path

import nbformat
import numpy as np
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionError

HERE = Path(__file__).resolve().parent
MAX_IMAGE_BYTES = 150_000
MAX_TEXT_CHARS = 4_000
MAX_NOTEBOOK_BYTES = 2_000_000
WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
IMAGE_TYPES = ("image/png", "image/jpeg", "image/gif", "image/svg+xml")


def shrink_png(data: bytes, max_bytes: int) -> bytes:
    """``data`` re-encoded at half size (2 x 2 box mean) until it is at most ``max_bytes``.

    Parameters
    ----------
    data : bytes
        A PNG (gray, gray + alpha, RGB or RGBA; 8 or 16 bit).
    max_bytes : int
        The limit; a picture that reaches 16 pixels on its short side stops there.

    Returns
    -------
    bytes
        A PNG at most ``max_bytes`` long (or the 16-pixel one), ``data`` itself if it fits.
    """
    import imageio.v3 as iio

    if len(data) <= max_bytes:
        return data
    pixels = np.asarray(iio.imread(io.BytesIO(data), extension=".png"))
    dtype = pixels.dtype
    out = data
    while len(out) > max_bytes and min(pixels.shape[:2]) >= 32:
        h, w = (pixels.shape[0] // 2) * 2, (pixels.shape[1] // 2) * 2
        blocks = pixels[:h, :w].reshape(h // 2, 2, w // 2, 2, *pixels.shape[2:])
        pixels = np.rint(blocks.astype(np.float64).mean(axis=(1, 3))).astype(dtype)
        out = bytes(iio.imwrite("<bytes>", pixels, extension=".png"))
    return out


def _text(value) -> str:
    return "".join(value) if isinstance(value, list) else str(value)


#: The end of the file where a kernel keeps a cell's code (its process id and a hash), named in
#: warnings and tracebacks and different at every run; the path runs back to a space, a quote
#: or a parenthesis.
_CELL_FILE = re.compile(r"ipykernel_\d+[/\\]\d+\.py")
_PATH_STOP = frozenset("\"'()")


#: Terminal colour codes (in IPython's tracebacks).
_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def _stable(text: str) -> str:
    """``text`` without what differs between runs of the same cell (kernel file names, each
    path replaced by ``<cell>``). Linear in the text: a pattern that scans a path's characters
    before ``ipykernel_`` retries from every position, which took seconds on long outputs."""
    parts, end = [], 0
    for m in _CELL_FILE.finditer(text):
        start = m.start()
        while start > end and not (text[start - 1].isspace() or text[start - 1] in _PATH_STOP):
            start -= 1
        parts += [text[end:start], "<cell>"]
        end = m.end()
    return "".join(parts) + text[end:]


def _cut(text: str, limit: int) -> str:
    if len(text) <= limit:
        return text
    return text[:limit] + f"\n... ({len(text) - limit} characters cut by save_outputs.py)\n"


def tidy_output(output: dict, *, max_image_bytes: int, max_text_chars: int) -> dict | None:
    """One output made small; None when nothing of it is worth keeping."""
    kind = output.get("output_type")
    output.pop("transient", None)
    if kind == "stream":
        output["text"] = _cut(_stable(_text(output.get("text", ""))), max_text_chars)
        return output
    if kind == "error":
        output["traceback"] = [_stable(line) for line in output.get("traceback", [])]
        return output
    data = output.get("data", {})
    data.pop(WIDGET_VIEW, None)
    for mime in list(data):
        if mime == "image/png":
            raw = base64.b64decode(_text(data[mime]))
            small = shrink_png(raw, max_image_bytes)
            data[mime] = base64.b64encode(small).decode("ascii") + "\n"
            if small is not raw:
                output.get("metadata", {}).pop("image/png", None)  # its old width/height
        elif mime in IMAGE_TYPES:
            if len(_text(data[mime])) > max_image_bytes:
                del data[mime]
        elif mime.startswith("text/") or mime == "application/json":
            if isinstance(data[mime], (str, list)):
                data[mime] = _cut(_stable(_text(data[mime])), max_text_chars)
    return output if data else None


def tidy_notebook(nb, *, max_image_bytes: int, max_text_chars: int):
    """Outputs and metadata of an executed notebook made small and deterministic (in place)."""
    count = 0
    for i, cell in enumerate(nb.cells):
        cell.metadata.pop("execution", None)
        if not cell.get("id"):
            cell["id"] = f"cell-{i:03d}"
        if cell.cell_type != "code":
            continue
        count += 1
        cell.execution_count = count
        kept = []
        for output in cell.get("outputs", []):
            output = tidy_output(
                output, max_image_bytes=max_image_bytes, max_text_chars=max_text_chars
            )
            if output is not None:
                if "execution_count" in output:
                    output["execution_count"] = count
                kept.append(output)
        cell.outputs = kept
    nb.metadata.pop("widgets", None)
    language = nb.metadata.get("language_info", {}).get("name", "python")
    nb.metadata["language_info"] = {"name": language}
    return nb


def save_outputs(
    path: Path,
    *,
    timeout: int = 600,
    max_image_bytes: int = MAX_IMAGE_BYTES,
    max_text_chars: int = MAX_TEXT_CHARS,
    max_notebook_bytes: int = MAX_NOTEBOOK_BYTES,
) -> int:
    """Execute ``path`` and write it back with its outputs; returns the file's new size.

    Raises
    ------
    CellExecutionError
        A cell raised (the file is left unchanged).
    ValueError
        The notebook with its outputs would exceed ``max_notebook_bytes`` (left unchanged).
    """
    nb = nbformat.read(path, as_version=4)
    os.environ["PYTHONHASHSEED"] = "0"  # the kernel inherits it
    client = NotebookClient(
        nb,
        timeout=timeout,
        kernel_name="python3",
        record_timing=False,
        resources={"metadata": {"path": str(path.parent)}},
    )
    client.execute()
    tidy_notebook(nb, max_image_bytes=max_image_bytes, max_text_chars=max_text_chars)
    text = nbformat.writes(nb)
    if not text.endswith("\n"):
        text += "\n"
    size = len(text.encode("utf-8"))
    if size > max_notebook_bytes:
        raise ValueError(
            f"{path}: {size} bytes with its outputs, over --max-notebook-bytes "
            f"{max_notebook_bytes}; show smaller figures or lower --max-image-bytes"
        )
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".ipynb")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return size


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("notebooks", nargs="*", type=Path, help="default: notebooks/*.ipynb")
    parser.add_argument("--timeout", type=int, default=600, help="seconds per cell (600)")
    parser.add_argument("--max-image-bytes", type=int, default=MAX_IMAGE_BYTES)
    parser.add_argument("--max-text-chars", type=int, default=MAX_TEXT_CHARS)
    parser.add_argument("--max-notebook-bytes", type=int, default=MAX_NOTEBOOK_BYTES)
    args = parser.parse_args(argv)
    paths = args.notebooks or sorted(HERE.glob("*.ipynb"))
    status = 0
    for path in paths:
        if not path.is_file():
            print(f"{path}: no such notebook", file=sys.stderr)
            status = 1
            continue
        try:
            size = save_outputs(
                path,
                timeout=args.timeout,
                max_image_bytes=args.max_image_bytes,
                max_text_chars=args.max_text_chars,
                max_notebook_bytes=args.max_notebook_bytes,
            )
        except (CellExecutionError, ValueError) as exc:
            reason = _ANSI.sub("", str(exc)).strip().splitlines()[-1]
            print(f"{path}: not saved: {reason}", file=sys.stderr)
            status = 1
            continue
        print(f"{path}: {size / 1024:.0f} kB with outputs")
    return status


if __name__ == "__main__":
    raise SystemExit(main())
