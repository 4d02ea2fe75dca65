"""Tests of refnpr.raster against an independent float64 ray-cast oracle (see ``oracle.py``)."""
