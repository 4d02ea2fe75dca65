"""The built-in ``brick`` image: a procedural running-bond brick wall that tiles exactly.

Bricks, mortar joints, per-brick tone and surface grain are functions on the torus, so the
image repeats seamlessly along u and v (scikit-image's brick photograph, a perspective view
whose courses converge, cannot be made to meet across its borders). As in the photograph the
bricks' long side runs along the image rows (v) and the courses stack along the columns (u), so
the courses lie horizontally on the built-in room walls, whose u is vertical.
"""

from __future__ import annotations

import numpy as np

from ._checks import _int

__all__ = ["brick_texture"]

#: Defaults of the built-in ``brick``: 512 texels, 16 courses of 5 bricks (a 3.2 : 1 brick face,
#: mortar joints about 4 texels wide), one fixed seed.
SIZE, COURSES, BRICKS, MORTAR, SEED = 512, 16, 5, 4.0, 2002


def _periodic_noise(rng: np.random.Generator, size: int, cutoff: float) -> np.ndarray:
    """(size, size) float64 zero-mean, unit-std noise that tiles: white noise low-passed in the
    Fourier domain (a Gaussian of ``cutoff`` cycles per image), so it is periodic by
    construction."""
    white = rng.standard_normal((size, size))
    f = np.fft.fftfreq(size) * size  # cycles per image
    gain = np.exp(-0.5 * (f[:, None] ** 2 + f[None, :] ** 2) / cutoff**2)
    field = np.fft.ifft2(np.fft.fft2(white) * gain).real
    field -= field.mean()
    return field / max(float(field.std()), 1e-12)


def brick_texture(
    size: int = SIZE,
    *,
    courses: int = COURSES,
    bricks: int = BRICKS,
    mortar: float = MORTAR,
    seed: int = SEED,
) -> np.ndarray:
    """A tileable running-bond brick wall, 8-bit gray.

    Parameters
    ----------
    size : int >= 16
        Width and height in texels.
    courses : int >= 2, even
        Courses of bricks per repeat (even, so that the half-brick offset of running bond
        repeats too).
    bricks : int >= 1
        Bricks per course per repeat.
    mortar : float > 0
        Width of the mortar joints in texels.
    seed : int
        Seed of the per-brick tones and the surface grain (``numpy.random.default_rng``).

    Returns
    -------
    (size, size) uint8
        Darker bricks with individual tones, rounded faces (darker towards the joints), faint
        stains and pits, lighter grainy mortar; anti-aliased joint edges (one texel).
    """
    size, courses = _int("size", size, 16), _int("courses", courses, 2)
    bricks = _int("bricks", bricks, 1)
    if courses % 2:
        raise ValueError(
            f"courses: expected an even number (running bond shifts every other course by half "
            f"a brick, so an odd count does not repeat), got {courses}"
        )
    if isinstance(mortar, bool) or not isinstance(mortar, (int, float)) or not mortar > 0:
        raise ValueError(f"mortar: expected a joint width > 0 in texels, got {mortar!r}")
    rng = np.random.default_rng(seed)
    course_h = size / courses  # texels across a course
    brick_l = size / bricks  # texels along a brick
    t = np.arange(size) + 0.5  # texel centres
    across, along = t[:, None], t[None, :]  # wall layout: rows across courses, cols along them
    course = np.floor(across / course_h).astype(np.int64)
    shifted = along + (course % 2) * (0.5 * brick_l)  # running bond: odd courses by half a brick
    brick = np.floor(shifted / brick_l).astype(np.int64) % bricks
    lx = np.mod(shifted, brick_l)
    ly = across - course * course_h
    dist = np.minimum(np.minimum(lx, brick_l - lx), np.minimum(ly, course_h - ly))
    inside = dist - 0.5 * mortar  # signed distance (texels) to the brick face's border
    face_cover = np.clip(inside + 0.5, 0.0, 1.0)  # one-texel anti-aliased joint edges
    tone = rng.uniform(0.24, 0.38, size=(courses, bricks))[course % courses, brick]
    stain = _periodic_noise(rng, size, cutoff=12.0)
    grain = _periodic_noise(rng, size, cutoff=90.0)
    pits = np.clip(-grain - 2.2, 0.0, None)  # sparse dark pits where the grain is lowest
    crown = 1.0 - np.exp(-np.maximum(inside, 0.0) / 4.0)  # worn, rounded faces: dark edges
    face = tone + 0.10 * crown + 0.035 * stain + 0.01 * grain - 0.3 * pits
    joint = 0.72 + 0.05 * grain + 0.02 * stain
    wall = face_cover * face + (1.0 - face_cover) * joint
    image = np.clip(wall, 0.0, 1.0).T  # bricks long along the image rows (v), as the photograph
    return np.round(image * 255.0).astype(np.uint8)
