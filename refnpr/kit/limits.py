"""The limits ``refnpr kit check`` puts on an untrusted kit and its renders (docs/kit.md,
"A kit is untrusted input"). Tolerance ranges: :mod:`refnpr.kit.tolerance`; the case-name
pattern: :data:`refnpr.kit.check.CASE_NAME`."""

from __future__ import annotations

import re

__all__ = [
    "CHANNEL_NAME",
    "MAX_CHANNEL_COMPONENTS",
    "MAX_EXR_CHANNELS",
    "MAX_EXR_HEADER_BYTES",
    "MAX_FILE_BYTES",
    "MAX_GBUFFER_CHANNELS",
    "MAX_IMAGE_PIXELS",
    "MAX_IMAGE_SIDE",
    "MAX_JSON_BYTES",
    "MAX_JSON_DEPTH",
    "MAX_SPP",
]

#: A G-buffer channel name (``re.fullmatch``): it names ``RENDERS/<case>/<channel>.npy``.
CHANNEL_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")
#: Largest ``index.json`` or ``case.json`` (bytes).
MAX_JSON_BYTES = 8 << 20
#: Deepest nesting of arrays and objects in a JSON file (an exported case.json nests 8 deep).
MAX_JSON_DEPTH = 32
#: Largest ``width`` or ``height`` of a case (pixels).
MAX_IMAGE_SIDE = 8192
#: Largest ``width * height`` of a case (pixels: 2048 x 2048).
MAX_IMAGE_PIXELS = 1 << 22
#: Largest ``spp`` of a case (a square number n * n, n <= 8).
MAX_SPP = 64
#: Largest PNG, OpenEXR or ``.npy`` file read (bytes), of the kit or of the renders.
MAX_FILE_BYTES = 256 << 20
#: Largest OpenEXR header read (bytes) and most channels of an OpenEXR file.
MAX_EXR_HEADER_BYTES = 1 << 20
MAX_EXR_CHANNELS = 8
#: Most channels of a G-buffer case, and most components (last axis) of one channel.
MAX_GBUFFER_CHANNELS = 64
MAX_CHANNEL_COMPONENTS = 16
