"""Lit shading shared by the toon and smooth styles: Veryovka 2002 eqs. 1-4 and Lake et al.'s
ramp in one numba pass over the samples (``shading.lit_rgba``); the styles are
:mod:`refnpr.styles.toon` and :mod:`refnpr.styles.smooth`."""
