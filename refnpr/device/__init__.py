"""What kernels share that is not a paper's formula: scalar device functions, written once.

- :mod:`.vectors`: 3-vectors as tuples: dot products, normalization (plain, and max-scaled as
  ``formulas._shading_checks.unit_vectors``), the unit vector towards a point.
- :mod:`.lights`: the scene's lights as a record, the direction towards a light.
- :mod:`.sampling`: OpenGL texture sampling: GL_REPEAT taps, bilinear, a mip level, trilinear,
  anisotropic probes, the isotropic LOD.
- :mod:`.projection`: world -> clip -> pixel, as the rasterizer projects vertices.
- :mod:`.color`: the sRGB transfer functions (IEC 61966-2-1).

Every function here is a numba device function (:func:`refnpr._jit.njit`) that kernels call;
none validates (the public functions that call kernels do). Imports nothing of refnpr but
``refnpr._jit``; every other package may import it.
"""
